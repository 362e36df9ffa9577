"""The `slow` mark follows tests/durations.json (tests/conftest.py): checked on a scratch
suite with a copy of the conftest and a durations file of its own."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

from tests.conftest import SLOW_SECONDS, measured

HERE = Path(__file__).resolve().parent


def test_the_durations_file_is_measured_for_this_suite():
    times = measured()
    assert times, "tests/durations.json is missing: make test-durations"
    assert all(isinstance(v, (int, float)) and v >= 0 for v in times.values())
    assert any(v >= SLOW_SECONDS for v in times.values())


def test_marks_follow_the_measured_times(tmp_path):
    suite = tmp_path / "suite"
    suite.mkdir()
    shutil.copy(HERE / "conftest.py", suite / "conftest.py")
    (suite / "test_x.py").write_text(
        "import pytest, time\n"
        "def test_measured_slow(): pass\n"
        "@pytest.mark.slow\n"
        "def test_hand_marked_but_fast(): pass\n"
        "@pytest.mark.slow\n"
        "def test_not_measured_keeps_its_mark(): pass\n"
        "def test_sleeps(): time.sleep(0.3)\n")
    (suite / "durations.json").write_text(json.dumps({
        "test_x.py::test_measured_slow": SLOW_SECONDS + 1,
        "test_x.py::test_hand_marked_but_fast": 0.01}))

    def run(*args):
        p = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider",
                            "--rootdir", str(suite), *args], cwd=suite, capture_output=True,
                           text=True, timeout=120)
        return p.returncode, p.stdout

    code, out = run("-m", "slow", "--collect-only")
    assert "test_measured_slow" in out and "test_not_measured_keeps_its_mark" in out
    assert "test_hand_marked_but_fast" not in out and "test_sleeps" not in out
    code, out = run("--record-durations", str(suite / "durations.json"))
    assert code == 0, out
    times = json.loads((suite / "durations.json").read_text())
    assert set(times) == {f"test_x.py::{n}" for n in ("test_measured_slow", "test_sleeps",
                                                     "test_hand_marked_but_fast",
                                                     "test_not_measured_keeps_its_mark")}
    assert 0.3 <= times["test_x.py::test_sleeps"] < 5
    assert times["test_x.py::test_measured_slow"] < SLOW_SECONDS  # measured again: fast now
