"""The bad-input corpus (issue 16): `tests/bad_inputs_corpus.txt`, >= 150 cases over the public
API and the CLI. Each case must end in a clear error that names the parameter — a ValueError
(API) or exit status 2 with one line on stderr and no traceback (CLI) — within a wall-time
limit (no hangs).

The cases run in a worker process (`python tests/test_bad_inputs.py --worker`) that reports
each result on stdout; the parent kills and restarts the worker when a case exceeds the limit,
so one hang costs CASE_LIMIT seconds and is reported as "hang", not a stuck test run.

Cases listed in `tests/bad_inputs_open.md` are known to fail (code owned elsewhere, routed by
the lead): they run like every other case and are marked xfail(strict=True), so a fix shows up
as XPASS-failure until the line is removed from that file.
"""

from __future__ import annotations

import json
import os
import re
import select
import subprocess
import sys
import time
from pathlib import Path

import pytest

HERE = Path(__file__).resolve().parent
CORPUS = HERE / "bad_inputs_corpus.txt"
OPEN = HERE / "bad_inputs_open.md"
CASE_LIMIT = 30.0  # s: wall-time limit of one case
FIRST_LIMIT = 120.0  # s: the first case also pays for the imports
MARK = "@@bad-input@@ "


def load_corpus(path=CORPUS):
    """[(id, [words], code)] from the corpus file."""
    cases, seen = [], set()
    for n, line in enumerate(path.read_text().splitlines(), start=1):
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        parts = line.split("|", 2)
        if len(parts) != 3:
            raise ValueError(f"{path}, line {n}: expected 'id | words | code'")
        cid, words, code = (p.strip() for p in parts)
        if cid in seen:
            raise ValueError(f"{path}, line {n}: duplicate id {cid}")
        seen.add(cid)
        cases.append((cid, [w.strip() for w in words.split(",") if w.strip()], code))
    return cases


def open_cases(path=OPEN):
    """Ids listed as known failures in bad_inputs_open.md (lines starting '- `id`')."""
    if not path.exists():
        return {}
    out = {}
    for line in path.read_text().splitlines():
        m = re.match(r"\s*[-*]\s+`([^`]+)`\s*(.*)", line)
        if m:
            out[m.group(1)] = m.group(2).strip(" :—-")
    return out


# ------------------------------------------------------------------------------- the worker
def _fixtures(tmp):
    """Files the CLI cases use and the names the API cases use."""
    tmp = Path(tmp)
    (tmp / "folder").mkdir(exist_ok=True)
    (tmp / "plain.txt").write_text("not a folder\n")
    (tmp / "garbage.txt").write_text("this is not a csv, nor a map\n\x01\x02 1,2,three\n")
    (tmp / "units.csv").write_text("unit,L_mm,h_mm,t_mm,w_mm,side\n1,100,20,0.5,5,1\n"
                                   "2,60,0,0.5,5,0\n3,100,20,0.5,5,-1\n")
    (tmp / "target.csv").write_text("x_mm,y_mm\n0,0\n100,40\n200,15\n300,50\n400,0\n")
    (tmp / "two.svg").write_text(  # two open curves: a target file needs --select
        '<svg xmlns="http://www.w3.org/2000/svg" width="400mm" height="300mm" '
        'viewBox="0 0 400 300"><path id="a" d="M 0 250 A 200 200 0 0 0 200 50"/>'
        '<path id="b" d="M 0 280 L 300 280"/></svg>')
    (tmp / "metres.csv").write_text("x_mm,y_mm\n0,0\n0.1,0.04\n0.2,0.015\n0.3,0.05\n0.4,0\n")
    (tmp / "tiny.csv").write_text("x_mm,y_mm\n0,0\n3,1\n6,1.5\n9.5,1\n")
    places = {"tmp": tmp, "units": tmp / "units.csv", "file": tmp / "plain.txt",
              "dir": tmp / "folder", "target": tmp / "target.csv", "garbage": tmp / "garbage.txt",
              "svg2": tmp / "two.svg", "metres": tmp / "metres.csv", "tiny": tmp / "tiny.csv"}
    return {k: str(v) for k, v in places.items()}


def _namespace(tmp):
    import numpy as np

    from snapmorph.design import Unit, forward_kinematics, inverse_design, spacer
    from snapmorph.maps import DesignMap
    from snapmorph.solver import Structure
    from snapmorph.units import UnitGeometry, simulate_unit

    cache = {}

    def dm():
        if "dm" not in cache:
            sys.path.insert(0, str(HERE.parent))
            from tests.design import synthetic_map

            cache["dm"] = DesignMap.load(synthetic_map.write(Path(tmp) / "synthetic.nc"))
        return cache["dm"]

    x = np.linspace(0.0, 0.1, 11)
    rod_xy = np.stack([x, 0.01 * np.sin(np.pi * x / 0.1)], axis=1)

    def rod():
        st = Structure()
        r = st.add_rod(rod_xy, width=5e-3, thickness=5e-4, E=2.2e9)
        st.fix(int(r.nodes[0]), "xz")
        st.fix(int(r.nodes[-1]), "xz")
        return st, r

    return {"np": np, "Unit": Unit, "spacer": spacer, "forward_kinematics": forward_kinematics,
            "inverse_design": inverse_design, "Structure": Structure,
            "UnitGeometry": UnitGeometry, "simulate_unit": simulate_unit,
            "DesignMap": DesignMap, "U": Unit(L=0.1, h=0.02, t=5e-4, w=5e-3, side=1),
            "SP": spacer(L=0.06, t=5e-4, w=5e-3),
            "G": UnitGeometry(L=0.1, h=0.02, t=5e-4, w=5e-3), "ROD": rod_xy, "rod": rod,
            "dm": dm, "PTS": np.array([[0, 0], [0.1, 0.04], [0.2, 0.015], [0.3, 0.05],
                                       [0.4, 0.0]]), "TMP": str(tmp)}


def _short(text, n=300):
    text = " ".join(str(text).split())
    return text if len(text) <= n else text[:n] + "..."


def run_case(case, places, ns_factory):
    """(ok, detail) for one case, run in this process."""
    import contextlib
    import io
    import shlex

    cid, words, code = case
    out, err = io.StringIO(), io.StringIO()
    if code.startswith("$"):
        from snapmorph.cli import main

        argv = [a.format(**places) for a in shlex.split(code[1:])]
        try:
            with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
                status = main(argv)
        except BaseException as exc:  # noqa: BLE001 - anything escaping main is a defect
            return False, f"exception escaped main: {type(exc).__name__}: {_short(exc)}"
        lines = [ln for ln in err.getvalue().strip().splitlines() if ln.strip()]
        if status != 2:
            return False, f"exit {status} (expected 2); stderr: {_short(err.getvalue())}"
        if "Traceback" in err.getvalue():
            return False, f"traceback on stderr: {_short(err.getvalue())}"
        if len(lines) != 1:
            return False, f"{len(lines)} lines on stderr (expected 1): {_short(err.getvalue())}"
        message = lines[0]
    else:
        ns = ns_factory()
        try:
            with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
                exec(compile(code, cid, "exec"), ns)
        except ValueError as exc:
            message = str(exc)
        except FileNotFoundError as exc:  # the standard error for a missing file is clear too
            message = str(exc)
        except BaseException as exc:  # noqa: BLE001
            return False, f"{type(exc).__name__} (expected ValueError): {_short(exc)}"
        else:
            return False, "accepted (no error)"
    missing = [w for w in words if w not in message]
    if missing:
        return False, f"message does not name {missing}: {_short(message)}"
    return True, _short(message)


def worker(start: int, tmp: str) -> None:
    """Run the corpus from case `start`, one protocol line per event on stdout."""
    cases = load_corpus()
    proto = sys.__stdout__
    places = _fixtures(tmp)
    ns_cache = {}

    def ns_factory():
        if "ns" not in ns_cache:
            ns_cache["ns"] = _namespace(tmp)
        return dict(ns_cache["ns"])

    for i in range(start, len(cases)):
        proto.write(MARK + json.dumps({"start": i}) + "\n")
        proto.flush()
        try:
            ok, detail = run_case(cases[i], places, ns_factory)
        except BaseException as exc:  # noqa: BLE001 - a broken fixture, not the case
            ok, detail = False, f"corpus set-up failed: {type(exc).__name__}: {_short(exc)}"
        proto.write(MARK + json.dumps({"done": i, "ok": ok, "detail": detail}) + "\n")
        proto.flush()


# Who owns the code behind each group of cases (for routing the open ones).
OWNERS = [("st.", "solver (`solver/structure.py`, `solver/continuation.py`)"),
          ("geom.", "unit model (`units/geometry.py`)"), ("sim.", "unit driver (`units/planar.py`)"),
          ("unit.", "`design/units.py`"), ("dm.", "maps (`maps/designmap.py`)"),
          ("fk.", "design kinematics (`design/kinematics.py`)"),
          ("inv.", "inverse design (`design/inverse.py`)"),
          ("cli.unit.", "`snapmorph/commands/unit.py`"),
          ("cli.unit3d.", "`snapmorph/commands/unit3d.py`"),
          ("cli.unit2d.", "`snapmorph/commands/unit2d.py`"),
          ("cli.design.", "`snapmorph/commands/design.py`"),
          ("cli.maps.", "`snapmorph/commands/maps.py`"), ("cli.", "`snapmorph/commands/`")]


def write_open(lines, summary, path=OPEN):
    """Write bad_inputs_open.md: the failing cases grouped by the code that owns them."""
    groups = {}
    for line in lines:
        cid = re.match(r"- `([^`]+)`", line).group(1)
        owner = next(o for p, o in OWNERS if cid.startswith(p))
        text = re.sub(r"/tmp/[\w./-]*?(?=/[\w.-]+\.\w+\b)", "TMP", line)
        groups.setdefault(owner, []).append(text if len(text) < 260 else text[:257] + "...")
    out = ["# Open cases of the bad-input corpus", "",
           "Cases of `tests/bad_inputs_corpus.txt` that do not yet end in a clear error naming",
           "the parameter (ValueError for the API; exit 2 and one line naming the option for the",
           "CLI). `tests/test_bad_inputs.py` runs them like every other case and marks the ids",
           "listed here xfail(strict=True): a fix shows up as an XPASS failure until its line is",
           "removed. Re-make this file with `python tests/test_bad_inputs.py --write-open`.", "",
           f"Last run: {summary}", ""]
    for owner, items in groups.items():
        out += [f"## {owner}", ""] + items + [""]
    path.write_text("\n".join(out))


# ------------------------------------------------------------------------------- the parent
def run_corpus(tmp, limit=CASE_LIMIT, first_limit=FIRST_LIMIT):  # noqa: C901
    """{id: (ok, detail, seconds)} for the whole corpus; hangs become ("hang", ...)."""
    cases = load_corpus()
    results = {}
    start = 0
    env = dict(os.environ, PYTHONPATH=str(HERE.parent) + os.pathsep + os.environ.get("PYTHONPATH", ""),
               MPLBACKEND="Agg", TQDM_DISABLE="1")
    while start < len(cases):
        proc = subprocess.Popen([sys.executable, str(Path(__file__).resolve()), "--worker",
                                 str(start), str(tmp)], stdout=subprocess.PIPE,
                                stderr=subprocess.DEVNULL, text=True, env=env, cwd=str(tmp),
                                start_new_session=True)
        current, t0, budget = None, time.monotonic(), first_limit
        try:
            while True:
                remaining = budget - (time.monotonic() - t0)
                if remaining <= 0:
                    break
                ready, _, _ = select.select([proc.stdout], [], [], remaining)
                if not ready:
                    continue
                line = proc.stdout.readline()
                if not line:  # worker ended
                    break
                if not line.startswith(MARK):
                    continue
                msg = json.loads(line[len(MARK):])
                if "start" in msg:
                    current, t0 = msg["start"], time.monotonic()
                    budget = first_limit if current == start else limit
                else:
                    results[cases[msg["done"]][0]] = (msg["ok"], msg["detail"],
                                                      time.monotonic() - t0)
                    current = None
        finally:
            if proc.poll() is None:
                # The worker's own session: also ends the processes it started (dask).
                try:
                    os.killpg(proc.pid, 9)
                except ProcessLookupError:
                    pass
            proc.wait()
        if current is not None:  # the case running when time ran out (or the worker died)
            seconds = time.monotonic() - t0
            died = seconds < budget
            results[cases[current][0]] = (
                False, ("worker died" if died else f"hang: no answer within {budget:.0f} s"),
                seconds)
            start = current + 1
        elif len(results) < len(cases):
            done = {cid for cid in results}
            rest = [i for i, c in enumerate(cases) if c[0] not in done]
            if not rest:
                break
            if rest[0] == start:  # the worker died before its first case
                results[cases[start][0]] = (False, "worker failed to start", 0.0)
                start += 1
            else:
                start = rest[0]
        else:
            break
    return results


CASES = load_corpus()
OPEN_CASES = open_cases()


def _params():
    for cid, words, code in CASES:
        marks = []
        if cid in OPEN_CASES:
            marks.append(pytest.mark.xfail(strict=True, reason="open (tests/bad_inputs_open.md): "
                                           + OPEN_CASES[cid]))
        yield pytest.param(cid, id=cid, marks=marks)


@pytest.fixture(scope="module")
def corpus_results(tmp_path_factory):
    return run_corpus(tmp_path_factory.mktemp("bad_inputs"))


def test_corpus_size_and_coverage():
    """>= 150 cases, over every public entry point and every CLI command."""
    assert len(CASES) >= 150
    codes = " ".join(c[2] for c in CASES)
    for name in ("Structure", "simulate_unit", "UnitGeometry", "dm()", "forward_kinematics",
                 "inverse_design", "Unit(", "$ unit", "$ design", "$ maps", "$ fk", "$ array",
                 "$ figures"):
        assert name in codes, name
    unknown = set(OPEN_CASES) - {c[0] for c in CASES}
    assert not unknown, f"bad_inputs_open.md lists ids not in the corpus: {sorted(unknown)}"


@pytest.mark.parametrize("cid", list(_params()))
def test_bad_input(cid, corpus_results):
    ok, detail, seconds = corpus_results[cid]
    assert ok, f"{cid}: {detail} ({seconds:.1f} s)"


if __name__ == "__main__":
    # Run as a script, Python puts tests/ first on the path, where tests/solver etc. would
    # shadow the real packages: use the repository root instead.
    sys.path[:] = [p for p in sys.path if Path(p or ".").resolve() != HERE]
    sys.path.insert(0, str(HERE.parent))
    if len(sys.argv) >= 2 and sys.argv[1] == "--worker":
        worker(int(sys.argv[2]), sys.argv[3])
    else:  # a report: python tests/test_bad_inputs.py [--write-open]
        import tempfile

        with tempfile.TemporaryDirectory() as tmp:
            res = run_corpus(tmp)
        bad = {k: v for k, v in res.items() if not v[0]}
        lines = [f"- `{cid}`: {detail} ({sec:.1f} s)" for cid, (ok, detail, sec) in res.items()
                 if not ok]
        hangs = sum(1 for v in bad.values() if v[1].startswith("hang"))
        summary = (f"{len(res)} cases: {len(res) - len(bad)} clear errors, {len(bad)} failing "
                   f"({hangs} hangs)")
        print("\n".join(lines + [summary]))
        if "--write-open" in sys.argv:
            write_open(lines, summary)
            print(f"wrote {OPEN}")
