"""Issue 22, "real drawings in, real parts out", end to end through `snapmorph design`: files
that Inkscape, FreeCAD, LibreCAD wrote (tests/data/targets) give a design of the drawn length
whose predicted shape overlays the target in the drawing's own coordinates, or a one-line
refusal that says why; unit and scale slips exit 2; nested sheets, STL molds and the
assembly sheet come out checked; --tol-mm governs when it is the stricter."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from snapmorph.cli import main
from snapmorph.design.target_io import read_target_file
from snapmorph.design.targets import deviation
from snapmorph.design.units import read_units_csv

CORPUS = Path(__file__).resolve().parents[1] / "data" / "targets"
MANIFEST = {(e["file"], e.get("select")): e for e in
            json.loads((CORPUS / "manifest.json").read_text())}
TW = ("--t", "0.5", "--w", "5")


def _run(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def _ends_match(points_mm, entry, tol_mm):
    """The curve's ends are the manifest's (either way round where the file fixes no
    direction)."""
    a, b = np.asarray(entry["start_mm"]), np.asarray(entry["end_mm"])
    s, e = points_mm[0], points_mm[-1]
    same = np.hypot(*(s - a)) <= tol_mm and np.hypot(*(e - b)) <= tol_mm
    swapped = np.hypot(*(s - b)) <= tol_mm and np.hypot(*(e - a)) <= tol_mm
    return same or (entry["direction"] == "either" and swapped)


# a sample of the corpus: every kind of file and of what real programs put in them
DESIGNED = [
    ("svg/group_scale15_arc90.inkscape.svg", None),      # group transform scale(1.5)
    ("svg/layer_flip_matrix_hook.inkscape.svg", None),   # layer flipped by a matrix
    ("svg/nested_transforms_sine.inkscape.svg", None),   # translate, rotate, scale nested
    ("svg/v092_c270.inkscape.svg", None),                # px viewBox, width in mm, 270 deg
    ("svg/two_candidates.inkscape.svg", "curveA"),       # two curves, one selected
    ("dxf/inkscape/group_rotate30_hook.r14.dxf", None),  # Inkscape R14: LWPOLYLINE + 3 SPLINEs
    ("dxf/freecad/hook_line_arc.r14.dxf", None),         # FreeCAD LINE + ARC chain
    ("dxf/librecad/drawn_polyline_sine.dxf", None),      # drawn with LibreCAD's polyline
    ("dxf/librecad/insunits_1_inch.dxf", None),          # $INSUNITS inch
    ("dxf/synthetic/ocs_lwpolyline_neg_z.dxf", None),    # mirrored OCS (extrusion 0,0,-1)
    ("csv/arc90_inches.csv", None),                      # header 'x (in),y (in)'
]


@pytest.mark.slow
@pytest.mark.parametrize("name, select", DESIGNED)
def test_corpus_file_designed_in_its_own_frame(tmp_path, capsys, name, select):
    """The design is of the drawn length (read within 0.5 %, the array within 0.5 % of it)
    and the right orientation: the predicted shape written in the file's own coordinates
    (overlay.svg for an SVG, overlay.dxf in the DXF's unit otherwise) lies within tol of the
    target written beside it, which is the curve as read, ends where the drawing has them."""
    entry = MANIFEST[(name, select)]
    out = tmp_path / "out"
    code, stdout, err = _run(capsys, "design", CORPUS / name, *TW, "--out", out,
                             "--no-progress", "--no-verify", *(("--select", select)
                                                               if select else ()))
    assert code == 0, err + stdout
    length = entry["length_mm"]
    tf = read_target_file(CORPUS / name, select=select)
    assert tf.length_mm == pytest.approx(length, rel=0.005)
    array_mm = sum(u.L for u in read_units_csv(out / "units.csv")) * 1e3
    assert array_mm == pytest.approx(length, rel=0.005)
    svg = name.endswith(".svg")
    overlay = out / ("overlay.svg" if svg else "overlay.dxf")
    target = read_target_file(overlay, select="target" if svg else "TARGET").points
    predicted = read_target_file(overlay, select="predicted" if svg else "PREDICTED").points
    np.testing.assert_allclose(target, tf.points, atol=1e-9)  # m: the curve as read
    assert deviation(predicted, target)[0] <= 0.01 + 1e-6  # --tol 1 %, best placement
    page = (target * 1e3) * ([1, -1] if entry["frame"] == "svg-page-mm-ydown" else [1, 1])
    assert _ends_match(page, entry, max(entry["tol_mm"], 0.05))
    np.testing.assert_allclose(np.loadtxt(out / "target.csv", delimiter=",", skiprows=1),
                               tf.points * 1e3, atol=1e-5)
    twin = ("dxf/inkscape/" + Path(name).name.replace(".inkscape.svg", ".r14.dxf"), None)
    if svg and twin in MANIFEST and MANIFEST[twin]["expect"] == "read":
        # the overlay's DXF puts the curve where Inkscape's own DXF export of the file does
        dxf = read_target_file(out / "overlay.dxf", select="TARGET").points * 1e3
        assert _ends_match(dxf, MANIFEST[twin], 0.1)


@pytest.mark.parametrize("name, words", [
    ("svg/two_candidates.inkscape.svg", ["2 open curves", "--select", "path#curveA",
                                         "196.35 mm", "path#curveB", "314.16 mm"]),
    ("svg/closed_only.inkscape.svg", ["closed"]),
    ("dxf/freecad/helix_spline.r14.dxf", ["not planar"]),
    ("svg/tiny_arc.inkscape.svg", ["9.7 mm long", "shortest unit", "50.0 mm"]),
    ("dxf/freecad/arc_in_metres.r12.dxf", ["0.196 mm long", "is the file in metres (196.3 mm)"]),
    ("csv/metres_in_mm_header.csv", ["0.338 mm long", "is the file in metres"]),
    ("dxf/librecad/unitless_metres.dxf", ["is the file in metres (338.4 mm)"]),
])
def test_corpus_file_refused_in_one_line(tmp_path, capsys, name, words):
    """Refused before anything is designed or written: exit 2, one line naming why."""
    out = tmp_path / "out"
    code, stdout, err = _run(capsys, "design", CORPUS / name, *TW, "--out", out,
                             "--no-progress", "--no-verify")
    assert code == 2, stdout
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err
    assert all(w in err for w in words), err
    assert not (out / "units.csv").exists()
    assert "TOLERANCE MISSED" not in stdout


def test_unit_slips_exit_2_with_the_likely_unit(tmp_path, capsys):
    """Inches under an x_mm header (the arc read 25.4 times too short) and a mm drawing
    declared in metres (1000 times too long): exit 2, one line, the likely unit, never a
    design that misses by thousands of per cent."""
    inches = tmp_path / "arc_inches_as_mm.csv"
    text = (CORPUS / "csv" / "arc90_inches.csv").read_text()
    inches.write_text(text.replace("x (in),y (in)", "x_mm,y_mm"))
    code, stdout, err = _run(capsys, "design", inches, *TW, "--out", tmp_path / "a",
                             "--no-verify")
    assert code == 2 and len(err.strip().splitlines()) == 1
    assert "7.73 mm long" in err and "inches (196.3 mm)" in err
    code, stdout, err = _run(capsys, "design", CORPUS / "dxf/librecad/insunits_0_unitless.dxf",
                             *TW, "--units", "m", "--out", tmp_path / "b", "--no-verify")
    assert code == 2 and len(err.strip().splitlines()) == 1
    assert "mm long: far longer than the longest array" in err
    assert "is the file in mm but read as metres (338.5 mm)?" in err
    assert not (tmp_path / "a" / "units.csv").exists() and not (tmp_path / "b").exists()


@pytest.mark.parametrize("argv, words", [
    (("--units", "in", "--select", "curveA"), ["--units in", "SVG", "own units"]),
    (("--select", "nothing"), ["nothing called 'nothing'", "curveA"]),
    (("--select", "curveA", "--select", "curveB"), ["--select is given 2 times for 1 target"]),
    (("--tol-mm", "0"), ["--tol-mm", "mm"]),
    (("--bed", "600xwide"), ["--bed", "WIDTHxHEIGHT", "mm"]),
    (("--kerf", "3"), ["--kerf", "mm", "[0, 2]"]),
])
def test_new_options_fail_in_one_line(tmp_path, capsys, argv, words):
    code, _, err = _run(capsys, "design", CORPUS / "svg/two_candidates.inkscape.svg", *TW,
                        "--out", tmp_path / "o", "--no-verify", *argv)
    assert code == 2 and len(err.strip().splitlines()) == 1 and "Traceback" not in err
    assert all(w in err for w in words), err


@pytest.mark.slow
def test_workshop_output_nested_checked_and_stl_watertight(tmp_path, capsys):
    """--bed 600x400 --kerf 0.15, verified: every sheet passes the inside-the-sheet and
    overlap checks read back from the DXF, the molds are watertight STL solids beside their
    DXF profiles, the assembly sheet is written, and the overlay also holds the simulated
    array."""
    import trimesh
    from sheet_files import sheet_problems

    out = tmp_path / "hook"
    code, stdout, err = _run(capsys, "design", CORPUS / "dxf/freecad/hook_line_arc.r14.dxf",
                             *TW, "--out", out, "--no-progress", "--bed", "600x400",
                             "--kerf", "0.15")
    assert code == 0, err + stdout
    assert "simulated array (ok" in stdout and "warning:" not in stdout
    sheets = sorted(out.glob("sheet-*.dxf"))
    assert sheets and not (out / "base.dxf").exists()
    for sheet in sheets:
        problems, _ = sheet_problems(sheet, (600, 400))
        assert not problems, problems
    arched = [i + 1 for i, u in enumerate(read_units_csv(out / "units.csv")) if not u.is_spacer]
    assert sorted(p.name for p in out.glob("mold-*.stl")) == sorted(f"mold-{i}.stl"
                                                                    for i in arched)
    for i in arched:
        mesh = trimesh.load(out / f"mold-{i}.stl")
        assert mesh.is_watertight and mesh.volume > 0
    assert (out / "molds.dxf").is_file() and (out / "molds.svg").is_file()
    steps = (out / "assembly.txt").read_text()
    assert all(f"arch {i} on unit {i}" in steps for i in arched)
    assert (out / "assembly.png").is_file() and (out / "assembly.svg").is_file()
    simulated = read_target_file(out / "overlay.dxf", select="SIMULATED").points
    target = read_target_file(out / "overlay.dxf", select="TARGET").points
    assert deviation(simulated, target)[0] <= 0.01


@pytest.mark.slow
def test_a_part_longer_than_a_common_bed_warns_without_bed(tmp_path, capsys):
    code, stdout, err = _run(capsys, "design",
                             CORPUS / "svg/group_nonuniform_sinepoly.inkscape.svg", *TW,
                             "--out", tmp_path / "long", "--no-progress", "--no-verify")
    assert code == 0, err + stdout
    assert "warning:" in stdout and "larger than a 600 x 400 mm laser bed" in stdout


@pytest.mark.slow
def test_tol_mm_governs_when_stricter(tmp_path, capsys):
    """The hook (338.5 mm) with --tol 1 % and --tol-mm 1: 1 mm (0.30 %) governs and is met in
    mm; with --tol-mm 10 the 1 % governs."""
    hook = CORPUS / "dxf/freecad/hook_line_arc.r14.dxf"
    base = ("design", hook, *TW, "--no-progress", "--no-verify", "--no-drawings", "--tol", "0.01")
    code, stdout, _ = _run(capsys, *base, "--out", tmp_path / "a", "--tol-mm", "1")
    assert code == 0
    assert "tolerance 0.30 % = 1.00 mm" in stdout and "the absolute 1.00 mm governs" in stdout
    line = next(ln for ln in stdout.splitlines() if "governs" in ln)
    assert float(line.rsplit(", ", 1)[1].split(" mm")[0]) <= 1.0  # met (x %, y mm)
    code, stdout, _ = _run(capsys, *base, "--out", tmp_path / "b", "--tol-mm", "10")
    assert code == 0 and "1.00 % governs, stricter than the absolute 10.00 mm" in stdout


def test_tol_mm_missed_exits_1(tmp_path, capsys, synthetic_map_path):
    """An absolute tolerance the units cannot meet (0.01 mm on 428 mm, stricter than --tol):
    exit 1, TOLERANCE MISSED against the absolute one, in mm."""
    target = tmp_path / "M.csv"
    target.write_text("x_mm,y_mm\n0,0\n100,40\n200,15\n300,50\n400,0\n")
    code, stdout, _ = _run(capsys, "design", target, *TW, "--tol-mm", "0.01", "--out",
                           tmp_path / "o", "--map", synthetic_map_path, "--min-barrier", "0",
                           "--no-verify", "--no-drawings", "--max-units", "6")
    assert code == 1
    line = next(ln for ln in stdout.splitlines() if ln.startswith("TOLERANCE MISSED"))
    assert "= 0.01 mm" in line and "the absolute 0.01 mm governs, stricter than 1.00 %" in line
    assert "TOLERANCE MISSED" in (tmp_path / "o" / "units.csv").read_text()


@pytest.mark.slow
def test_fk_and_tolerance_read_the_drawing_itself(tmp_path, capsys):
    """After designing curveA of an SVG with two curves, `fk --overlay`, `fk --nearest` and
    `tolerance --target` take the same SVG with --select: the overlay lies on the designed
    base (the largest distance within the design's 1 %), the nearest state is the designed
    one; without --select they refuse in one line naming the option and the candidates."""
    svg = CORPUS / "svg/two_candidates.inkscape.svg"
    out = tmp_path / "A"
    code, stdout, err = _run(capsys, "design", svg, *TW, "--select", "curveA", "--out", out,
                             "--no-progress", "--no-verify", "--no-drawings")
    assert code == 0, err
    units = out / "units.csv"
    code, stdout, err = _run(capsys, "fk", "--units", units, "--overlay", svg, "--select",
                             "curveA", "--plot", tmp_path / "fk.png")
    assert code == 0, err
    line = next(ln for ln in stdout.splitlines() if ln.startswith("overlay"))
    assert float(line.split("largest distance to the base ")[1].split(" mm")[0]) <= 1.97
    code, stdout, err = _run(capsys, "fk", "--units", units, "--nearest", svg, "--select",
                             "curveA")
    every = "".join("0" if u.is_spacer else "1" for u in read_units_csv(units))
    assert code == 0 and f"nearest state {every}" in stdout, err
    code, stdout, err = _run(capsys, "tolerance", units, "--target", svg, "--select", "curveA",
                             "--n", "100", "--plot", tmp_path / "tol.png")
    assert code == 0 and (tmp_path / "tol.png").is_file(), err
    for argv in (("fk", "--units", units, "--overlay", svg),
                 ("tolerance", units, "--target", svg)):
        code, _, err = _run(capsys, *argv)
        assert code == 2 and len(err.strip().splitlines()) == 1
        assert "--select" in err and "path#curveB" in err and "314.16 mm" in err
    code, _, err = _run(capsys, "fk", "--units", units, "--overlay", svg, "--select", "curveA",
                        "--target-units", "in")
    assert code == 2 and "--target-units in" in err and "SVG" in err
