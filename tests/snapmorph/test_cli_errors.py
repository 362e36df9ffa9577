"""Bad command-line input: every case ends with exit status 2 and ONE line on stderr that names
the option (and, for numbers, its unit), with no traceback. Output folders are created.

Every case is refused before any simulation runs (paths, values and files are checked first),
so the whole file runs in a few seconds; a few cases run through the installed console script
to check the real entry point too.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from snapmorph.cli import main

GOOD_UNITS = "unit,L_mm,h_mm,t_mm,w_mm,side\n1,100,20,0.5,5,1\n2,60,0,0.5,5,0\n3,100,20,0.5,5,-1\n"
HEADER = "unit,L_mm,h_mm,t_mm,w_mm,side\n"


@pytest.fixture
def files(tmp_path):
    """Paths the cases use: good units.csv, a plain file, a folder, bad units files."""
    f = {"dir": tmp_path / "folder", "file": tmp_path / "plain.txt", "units": tmp_path / "u.csv",
         "target": tmp_path / "target.csv", "tmp": tmp_path}
    f["dir"].mkdir()
    f["file"].write_text("not a folder\n")
    f["units"].write_text(GOOD_UNITS)
    f["target"].write_text("x_mm,y_mm\n0,0\n100,40\n200,0\n")
    bad = {
        "neg_L": HEADER + "1,-100,20,0.5,5,1\n",
        "zero_t": HEADER + "1,100,20,0,5,1\n",
        "text_h": HEADER + "1,100,abc,0.5,5,1\n",
        "nan_w": HEADER + "1,100,20,0.5,nan,1\n",
        "spacer_side1": HEADER + "1,100,0,0.5,5,1\n",
        "arch_side0": HEADER + "1,100,20,0.5,5,0\n",
        "side2": HEADER + "1,100,20,0.5,5,2\n",
        "missing_col": "unit,L_mm,h_mm\n1,100,20\n",
        "empty": "",
        "header_only": HEADER,
        "short_row": HEADER + "1,100,20,0.5\n",
        "bad_placement": "# placement x0_mm=abc y0_mm=0 angle_deg=0\n" + GOOD_UNITS,
        "h_ge_L": HEADER + "1,100,120,0.5,5,1\n",
        "w_too_wide": HEADER + "1,100,20,0.5,60,1\n",
        "many": HEADER + "".join(f"{i},100,20,0.5,5,1\n" for i in range(1, 13)),
    }
    for name, text in bad.items():
        p = tmp_path / f"{name}.csv"
        p.write_text(text)
        f[name] = p
    (tmp_path / "binary.csv").write_bytes(b"\x00\xff\xfe\x80garbage")
    f["binary"] = tmp_path / "binary.csv"
    (tmp_path / "bad_target.csv").write_text("x_mm,y_mm\n0,0\n1,two\n")
    f["bad_target"] = tmp_path / "bad_target.csv"
    return f


# (id, argv with {placeholders}, words the one-line message must contain)
CASES = [
    # --- the parser itself
    ("no-such-command", ["bogus"], ["invalid choice", "bogus"]),
    ("fk-no-units", ["fk"], ["--units"]),
    ("array-none-of-units-paper", ["array"], ["--units", "--paper-three"]),
    # --- fk: paths
    ("fk-units-missing", ["fk", "--units", "{tmp}/nope.csv"], ["--units", "no such file"]),
    ("fk-units-folder", ["fk", "--units", "{dir}"], ["--units", "folder"]),
    ("fk-plot-under-file", ["fk", "--units", "{units}", "--plot", "{file}/s.png"],
     ["--plot", "is a file"]),
    ("fk-plot-bad-suffix", ["fk", "--units", "{units}", "--plot", "{tmp}/s.xyz"],
     ["--plot", "figure type"]),
    ("fk-plot-is-folder", ["fk", "--units", "{units}", "--plot", "{dir}"], ["--plot", "folder"]),
    ("fk-csv-is-folder", ["fk", "--units", "{units}", "--csv", "{dir}"], ["--csv", "folder"]),
    ("fk-csv-under-file", ["fk", "--units", "{units}", "--csv", "{file}/a/b.csv"],
     ["--csv", "is a file"]),
    ("fk-map-missing", ["fk", "--units", "{units}", "--map", "{tmp}/none.nc"],
     ["--map", "no such file"]),
    ("fk-overlay-missing", ["fk", "--units", "{units}", "--overlay", "{tmp}/none.csv"],
     ["--overlay", "no such file"]),
    ("fk-overlay-not-numbers", ["fk", "--units", "{units}", "--overlay", "{bad_target}"],
     ["bad_target.csv", "line 3", "not a number"]),
    # --- fk: state
    ("fk-state-length", ["fk", "--units", "{units}", "--state", "10"], ["--state", "3 characters"]),
    ("fk-state-chars", ["fk", "--units", "{units}", "--state", "1x1"], ["--state", "0/1"]),
    ("fk-state-spacer-1", ["fk", "--units", "{units}", "--state", "111"],
     ["--state", "spacer", "h_mm = 0"]),
    ("fk-all-with-state", ["fk", "--units", "{units}", "--all", "--state", "101"],
     ["--state", "--all"]),
    ("fk-all-too-many", ["fk", "--units", "{many}", "--all"], ["--all", "2^12", "at most 10"]),
    ("fk-source-choice", ["fk", "--units", "{units}", "--source", "guess"], ["--source", "guess"]),
    # --- fk: units.csv contents (column and unit named)
    ("csv-negative-L", ["fk", "--units", "{neg_L}"], ["line 2", "L_mm", "> 0 mm"]),
    ("csv-zero-t", ["fk", "--units", "{zero_t}"], ["line 2", "t_mm", "> 0 mm"]),
    ("csv-text-h", ["fk", "--units", "{text_h}"], ["line 2", "h_mm", "mm"]),
    ("csv-nan-w", ["fk", "--units", "{nan_w}"], ["line 2", "w_mm", "finite", "mm"]),
    ("csv-spacer-side-1", ["fk", "--units", "{spacer_side1}"], ["line 2", "h_mm = 0", "side"]),
    ("csv-arch-side-0", ["fk", "--units", "{arch_side0}"], ["line 2", "side = 0", "h_mm"]),
    ("csv-side-2", ["fk", "--units", "{side2}"], ["line 2", "side", "'2'"]),
    ("csv-missing-column", ["fk", "--units", "{missing_col}"], ["missing column", "t_mm"]),
    ("csv-empty", ["fk", "--units", "{empty}"], ["no units"]),
    ("csv-header-only", ["fk", "--units", "{header_only}"], ["no units"]),
    ("csv-short-row", ["fk", "--units", "{short_row}"], ["line 2", "fields"]),
    ("csv-bad-placement", ["fk", "--units", "{bad_placement}"], ["line 1", "placement", "x0_mm"]),
    ("csv-h-ge-L", ["fk", "--units", "{h_ge_L}"], ["line 2", "h"]),
    ("csv-w-too-wide", ["fk", "--units", "{w_too_wide}"], ["line 2", "mm"]),
    ("csv-binary", ["fk", "--units", "{binary}"], ["binary.csv"]),
    # --- array: numbers (option, unit, range)
    ("array-b-over-L-big", ["array", "--units", "{units}", "--b-over-L", "0.7"],
     ["--b-over-L", "[0, 0.5)", "0.7"]),
    ("array-b-over-L-text", ["array", "--units", "{units}", "--b-over-L", "abc"],
     ["--b-over-L", "number"]),
    ("array-b-negative", ["array", "--paper-three", "--b", "-1"], ["--b", "mm", "-1"]),
    ("array-b-nan", ["array", "--paper-three", "--b", "nan"], ["--b", "mm", "finite"]),
    ("array-nodes-small", ["array", "--units", "{units}", "--nodes", "3"], ["--nodes", "[11, 100000]"]),
    ("array-nodes-float", ["array", "--units", "{units}", "--nodes", "1.5"],
     ["--nodes", "integer"]),
    ("array-E-negative", ["array", "--units", "{units}", "--E", "-1"], ["--E", "Pa", "-1"]),
    ("array-E-zero", ["array", "--units", "{units}", "--E", "0"], ["--E", "Pa", "(0, 1e+13]"]),
    ("array-E-inf", ["array", "--units", "{units}", "--E", "inf"], ["--E", "Pa", "finite"]),
    ("array-E-huge", ["array", "--units", "{units}", "--E", "1e200"], ["--E", "Pa"]),
    # --- array: paths, states, combinations
    ("array-units-missing", ["array", "--units", "{tmp}/none.csv"], ["--units", "no such file"]),
    ("array-plot-under-file", ["array", "--units", "{units}", "--plot", "{file}/p.png"],
     ["--plot", "is a file"]),
    ("array-plot-bad-suffix", ["array", "--units", "{units}", "--plot", "{tmp}/p.txt"],
     ["--plot", "figure type"]),
    ("array-csv-is-folder", ["array", "--units", "{units}", "--csv", "{dir}"], ["--csv", "folder"]),
    ("array-out-under-file", ["array", "--paper-three", "--out", "{file}/study"],
     ["--out", "is a file"]),
    ("array-out-is-file", ["array", "--paper-three", "--out", "{file}"], ["--out", "is a file"]),
    ("array-state-spacer-1", ["array", "--units", "{units}", "--state", "111"],
     ["--state", "spacer"]),
    ("array-state-length", ["array", "--units", "{units}", "--state", "1"], ["--state", "3"]),
    ("array-order-text", ["array", "--units", "{units}", "--state", "101", "--order", "a,b"],
     ["--order", "0-based"]),
    ("array-order-range", ["array", "--units", "{units}", "--state", "101", "--order", "2,7"],
     ["--order", "0 .. 2"]),
    ("array-order-missing", ["array", "--units", "{units}", "--state", "101", "--order", "2"],
     ["--order", "missing"]),
    ("array-all-no-units", ["array", "--paper-three", "--all"], ["--all"]),
    ("array-all-too-many", ["array", "--units", "{many}", "--all", "--out", "{tmp}/s"],
     ["--all", "2^12", "at most 8"]),
    ("array-study-with-state", ["array", "--paper-three", "--state", "101"], ["--state"]),
    ("array-b-with-units", ["array", "--units", "{units}", "--b", "5"], ["--b", "--paper-three"]),
    ("array-overlay-no-units", ["array", "--paper-M", "--overlay", "{target}"],
     ["--overlay", "--units"]),
    ("array-bad-units-file", ["array", "--units", "{spacer_side1}"], ["line 2", "side"]),
    # --- figures
    ("figures-out-under-file", ["figures", "--out", "{file}/figs"], ["--out", "is a file"]),
    ("figures-only-choice", ["figures", "--only", "nothing"], ["--only", "nothing"]),
    ("figures-map-missing", ["figures", "--map", "{tmp}/none.nc"], ["--map", "no such file"]),
]


def _fill(argv, files):
    return [a.format(**{k: str(v) for k, v in files.items()}) for a in argv]


def test_at_least_forty_cases():
    assert len(CASES) >= 40


@pytest.mark.parametrize("argv,words", [(c[1], c[2]) for c in CASES], ids=[c[0] for c in CASES])
def test_bad_input_exits_2_with_one_line(argv, words, files, capsys):
    code = main(_fill(argv, files))
    out, err = capsys.readouterr()
    lines = err.strip().splitlines()
    assert code == 2, (code, out, err)
    assert len(lines) == 1, err
    assert "Traceback" not in err
    assert lines[0].startswith("snapmorph"), lines[0]
    for w in words:
        assert w in lines[0], (w, lines[0])


def test_output_folders_are_created(files, capsys):
    """One rule: missing parent folders of --plot / --csv are created."""
    from tests.design import synthetic_map

    dm = synthetic_map.write(files["tmp"] / "synthetic.nc")
    plot = files["tmp"] / "new" / "deeper" / "s.png"
    csv = files["tmp"] / "other" / "s.csv"
    assert main(["fk", "--units", str(files["units"]), "--state", "100", "--plot", str(plot),
                 "--csv", str(csv), "--map", str(dm)]) == 0, capsys.readouterr().err
    assert plot.stat().st_size > 1000 and csv.read_text().startswith("x_mm,y_mm")


def test_failed_path_check_leaves_no_file(files, capsys):
    """The write probe of a refused run does not leave an empty file behind."""
    out = files["tmp"] / "probe" / "s.csv"
    assert main(["fk", "--units", str(files["units"]), "--state", "1x1", "--csv", str(out)]) == 2
    assert not out.exists()


def _console_script():
    exe = Path(sys.executable).with_name("snapmorph")
    return [str(exe)] if exe.exists() else [sys.executable, "-m", "snapmorph"]


@pytest.mark.parametrize("argv,words", [
    (["fk", "--units", "{tmp}/nope.csv"], ["--units"]),
    (["array", "--units", "{units}", "--E", "-2"], ["--E", "Pa"]),
    (["fk", "--units", "{units}", "--plot", "{file}/x.png"], ["--plot"]),
], ids=["missing-file", "negative-E", "plot-under-file"])
def test_console_script_one_line(argv, words, files):
    """The same through the installed `snapmorph` entry point, in a clean process."""
    env = dict(os.environ, PYTHONWARNINGS="ignore")
    p = subprocess.run(_console_script() + _fill(argv, files), capture_output=True, text=True,
                       timeout=120, env=env)
    assert p.returncode == 2, p.stderr
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in p.stderr, p.stderr
    assert all(w in lines[0] for w in words), lines[0]
