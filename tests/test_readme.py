"""The README walk-through runs as written, so it cannot go stale.

Every fenced ```sh block is run line by line, as a person pasting it would, except that
`snapmorph ...` runs as `<venv python> -m snapmorph ...` (the same entry point as the console
script) and `. .venv/bin/activate` is checked, not sourced; only `make maps` / `make test`
themselves are skipped (the main job and the whole suite). A comment line `# -> ...` after a
command says in words what it prints; the text it quotes in backticks must appear in the output,
and every `build/...` path it names must exist afterwards. Every ```python block runs in a fresh interpreter.

Commands run in a scratch folder that sees the repository's `examples/` (so `build/` lands
there), Makefile lines in the repository.
"""

from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
SKIP_MAKE = {"maps", "test"}
TIMEOUT = 900


def blocks(text):
    """[(language, [lines], first line number)] of the fenced code blocks."""
    out, lang, body, start = [], None, [], 0
    for n, line in enumerate(text.splitlines(), start=1):
        m = re.match(r"^```\s*([A-Za-z0-9_+-]*)\s*$", line)
        if m and lang is None:
            lang, body, start = (m.group(1) or "text").lower(), [], n + 1
        elif line.strip() == "```" and lang is not None:
            out.append((lang, body, start))
            lang = None
        elif lang is not None:
            body.append(line)
    assert lang is None, "README has an unclosed code block"
    return out


def shell_steps(lines, first):
    """[(line number, command, expectations)] of one sh block."""
    steps = []
    for k, raw in enumerate(lines):
        line = raw.strip()
        if not line:
            continue
        if line.startswith("# ->"):
            assert steps, f"README line {first + k}: '# ->' before any command"
            steps[-1][2].append(line[4:].strip())
            continue
        if line.startswith("#"):
            continue
        command = re.split(r"\s+#\s", line, maxsplit=1)[0].strip()  # drop a trailing comment
        steps.append((first + k, command, []))
    return steps


def _sh_blocks():
    return [(b, n) for lang, b, n in blocks(README.read_text()) if lang in ("sh", "bash", "shell")]


def _py_blocks():
    return [(b, n) for lang, b, n in blocks(README.read_text()) if lang in ("python", "py")]


@pytest.fixture(scope="module")
def workdir(tmp_path_factory):
    d = tmp_path_factory.mktemp("readme")
    (d / "examples").symlink_to(ROOT / "examples")
    return d


def _env():
    env = dict(os.environ, MPLBACKEND="Agg", PYTHONPATH=str(ROOT), TQDM_DISABLE="1")
    env["PATH"] = str(Path(sys.executable).parent) + os.pathsep + env.get("PATH", "")
    return env


def run_step(command, workdir):
    """Run one README command; return (exit status, stdout + stderr)."""
    argv = shlex.split(command)
    if argv[0] == "make":
        if any(t in SKIP_MAKE for t in argv[1:]):
            return None, ""
        argv, cwd = ["make", "-C", str(ROOT)] + argv[1:], ROOT
    elif argv[0] in (".", "source"):
        assert len(argv) == 2 and argv[1] == ".venv/bin/activate", command
        assert (ROOT / ".venv" / "bin" / "activate").is_file()
        assert (ROOT / ".venv" / "bin" / "snapmorph").is_file(), "no console script in .venv"
        return 0, ""
    elif argv[0] in ("snapmorph", ".venv/bin/snapmorph"):
        argv, cwd = [sys.executable, "-m", "snapmorph"] + argv[1:], workdir
    elif argv[0] in ("python", "python3", ".venv/bin/python"):
        argv, cwd = [sys.executable] + argv[1:], workdir
    else:
        raise AssertionError(f"README command the walk-through test cannot run: {command!r}")
    p = subprocess.run(argv, cwd=cwd, capture_output=True, text=True, timeout=TIMEOUT,
                       env=_env())
    return p.returncode, p.stdout + p.stderr


def test_readme_has_a_walk_through():
    steps = [s for b, n in _sh_blocks() for s in shell_steps(b, n)]
    text = " ".join(c for _, c, _ in steps)
    for needed in (".venv/bin/activate", "snapmorph unit", "snapmorph design", "snapmorph fk",
                   "snapmorph array", "snapmorph maps info", "--overlay"):
        assert needed in text, needed
    assert sum(1 for s in steps if s[2]) >= 5, "commands should show their expected output"


def test_readme_shell_blocks_run(workdir):
    for body, first in _sh_blocks():
        for lineno, command, expect in shell_steps(body, first):
            code, out = run_step(command, workdir)
            if code is None:
                continue
            assert code == 0, f"README line {lineno}: {command}\n{out[-3000:]}"
            for e in expect:
                for path in re.findall(r"build/[\w./-]+\.\w+", e):
                    assert (workdir / path).is_file(), f"README line {lineno}: no {path}"
                for frag in re.findall(r"`([^`]+)`", e):
                    if frag.startswith("build/"):
                        continue
                    assert frag in out, (f"README line {lineno}: {command}: expected "
                                         f"{frag!r} in the output:\n{out[-3000:]}")


@pytest.mark.parametrize("index", range(len(_py_blocks())))
def test_readme_python_blocks_run(index, workdir):
    body, first = _py_blocks()[index]
    p = subprocess.run([sys.executable, "-c", "\n".join(body)], cwd=workdir,
                       capture_output=True, text=True, timeout=TIMEOUT, env=_env())
    assert p.returncode == 0, f"README python block at line {first}:\n{p.stderr[-3000:]}"


def test_example_units_fit_the_example_target(tmp_path):
    """examples/units_M.csv (a design of examples/target_M.csv, committed) still fits it:
    drawn in the target's frame by its placement line, every target point lies within 5 % of
    the target's length of the predicted base."""
    import numpy as np

    from snapmorph.design import chain
    from snapmorph.design.targets import arc_length, distances_to_polyline, read_target_csv
    from snapmorph.design.units import read_placement, read_units_csv

    units = read_units_csv(ROOT / "examples" / "units_M.csv")
    placement = read_placement(ROOT / "examples" / "units_M.csv")
    assert placement is not None
    target, _ = read_target_csv(ROOT / "examples" / "target_M.csv")
    ch = chain(units, [not u.is_spacer for u in units], start=placement[:2],
               start_angle=placement[2])
    gap = distances_to_polyline(target, ch.xy).max()
    assert gap < 0.05 * arc_length(target), gap
    assert np.allclose(ch.xy[0], placement[:2])
