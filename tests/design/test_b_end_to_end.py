"""b (the extra flat length of the arch ends) end to end: units.csv's b_mm through
`snapmorph array` (a whole-array simulation) and `snapmorph fk`, inverse design at b on the
committed default map (the unit lengths its b/L range allows, the design table, the laser-cut
parts' flat ends), and the one-line refusals naming b."""

import math
import warnings

import ezdxf
import numpy as np
import pytest
from scipy.integrate import quad

from snapmorph.design import inverse_design
from snapmorph.design.map_model import map_at_b
from snapmorph.design.targets_scale import check_scale, unit_length_range

T, W = 0.5e-3, 5e-3
ONE = "unit,L_mm,h_mm,t_mm,w_mm,side{}\n1,100,20,0.5,5,1{}\n"


def _units_csv(tmp_path, b_mm=None):
    path = tmp_path / ("units.csv" if b_mm is None else f"units_b{b_mm:g}.csv")
    path.write_text(ONE.format("", "") if b_mm is None else ONE.format(",b_mm", f",{b_mm:g}"))
    return path


def _end_direction_deg(csv_path) -> float:
    xy = np.loadtxt(csv_path, delimiter=",", skiprows=1)
    e = xy[-1] - xy[-2]
    return math.degrees(math.atan2(e[1], e[0]))


def test_array_command_simulates_the_b_of_units_csv(tmp_path, capsys, dm):
    """The paper's unit (L 100, h 20, t 0.5, w 5 mm) simulated as a one-unit array from a
    units.csv with b_mm = 5 and from one without: the released end turns by the map's θ at
    b/L = 0.05 and 0 (the map: single-unit simulations, an independent model), 6.9° apart."""
    from snapmorph.cli import main

    turned = {}
    for b_mm in (None, 5.0):
        out = tmp_path / f"base_{b_mm}.csv"
        assert main(["array", "--units", str(_units_csv(tmp_path, b_mm)), "--snapped", "1",
                     "--csv", str(out), "--no-fk"]) == 0
        turned[b_mm] = _end_direction_deg(out)
    capsys.readouterr()
    theta = {b: dm.at(0.2, 0.005, 0.05, b_over_L=bL)["theta"] for b, bL in ((None, 0.0),
                                                                          (5.0, 0.05))}
    assert theta[5.0] - theta[None] > 6.0
    for b in turned:
        assert turned[b] == pytest.approx(theta[b], abs=0.01)


def test_array_refuses_b_over_L_beside_a_b_mm_column(tmp_path, capsys):
    from snapmorph.cli import main

    assert main(["array", "--units", str(_units_csv(tmp_path, 5.0)), "--b-over-L", "0.05"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "--b-over-L" in err and "b_mm" in err


def test_array_help_says_units_csv_carries_b(capsys):
    from snapmorph.cli import main

    assert main(["array", "--help"]) == 0
    text = " ".join(capsys.readouterr().out.split())
    assert "no b column" not in text
    assert "b_mm" in text and "--b-over-L" in text


def test_fk_refuses_a_b_outside_the_maps_range_naming_b(tmp_path, capsys):
    from snapmorph.cli import main

    assert main(["fk", "--units", str(_units_csv(tmp_path, 6.0))]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert "b = 6 mm (b/L = 0.06)" in err and "b/L in [0, 0.05], b in [0, 5] mm" in err


def _arc(radius=0.25, turn=1.2):
    th = np.linspace(0, turn, 40)
    return np.column_stack([radius * np.sin(th), radius * (1 - np.cos(th))])


def test_design_at_b_keeps_every_unit_inside_the_maps_b_over_L(dm, tmp_path):
    """b = 5 mm on the default map (b/L up to 0.05): every unit at least 100 mm long. Before,
    the design tried shorter units and failed with the map's b_over_L range error."""
    lo_b0 = unit_length_range(T, W, dm)[0]
    view = map_at_b(dm, 5e-3, W)
    assert lo_b0 < 0.1
    assert unit_length_range(T, W, view)[0] == pytest.approx(0.1, rel=1e-12)  # 5 mm / 0.05
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        d = inverse_design(_arc(), t=T, w=W, design_map=dm, b=5e-3, verify=True)
    arched = [u for u in d.units if not u.is_spacer]
    assert arched and all(u.b == 5e-3 and u.L >= 0.1 * (1 - 1e-9) for u in arched)
    assert d.met and d.verification["status"] == "ok"
    # the printed table carries b as units.csv does
    table = d.table().splitlines()
    assert table[0].split()[-1] == "b_mm"
    assert [line.split()[-1] for line in table[1:]] == \
        ["-" if u.is_spacer else "5.00" for u in d.units]
    # the laser-cut parts: arch blanks of flat ends b + w (engraved) and the sinusoid over
    # L - 2(b + w) between them, base holes L - 2(b + w) long
    d.write(tmp_path / "out", stl=False, assembly=False)
    doc = ezdxf.readfile(tmp_path / "out" / "arches.dxf")
    lines = [np.array([p[:2] for p in pl.get_points()]) for pl in
             doc.modelspace().query("LWPOLYLINE")]
    blanks = [c for c in lines if len(c) == 4]
    marks = sorted(float(c[0, 0]) for c in lines if len(c) == 2)
    assert len(blanks) == len(arched) == 1
    u, c = arched[0], blanks[0]
    la = u.L - 2 * (u.b + u.w)
    arc = quad(lambda x: math.hypot(1.0, math.pi * u.h / la * math.sin(2 * math.pi * x / la)),
               0, la, epsabs=1e-13)[0]
    x0, x1 = c[:, 0].min(), c[:, 0].max()
    assert x1 - x0 == pytest.approx((2 * (u.b + u.w) + arc) * 1e3, abs=1e-6)
    assert marks == pytest.approx([x0 + 10.0, x1 - 10.0], abs=1e-9)  # b + w = 10 mm
    base = ezdxf.readfile(tmp_path / "out" / "base.dxf")
    holes = sorted(np.ptp(np.array([p[:2] for p in pl.get_points()])[:, 0])
                   for pl in base.modelspace().query("LWPOLYLINE")
                   if pl.dxf.layer == "CUT" and pl.closed and
                   np.ptp(np.array([p[:2] for p in pl.get_points()])[:, 1]) ==
                   pytest.approx(2 * W * 1e3))
    assert holes == pytest.approx(sorted((u.L - 2 * (u.b + u.w)) * 1e3 for u in arched),
                                  abs=1e-6)


def test_a_target_too_short_for_b_is_refused_naming_b(dm):
    view = map_at_b(dm, 5e-3, W)
    with pytest.raises(ValueError, match=r"at t = 0.5 mm, w = 5 mm, b = 5 mm \(100.0 mm\)"):
        check_scale(0.08, T, W, design_map=view)
    check_scale(0.08, T, W, design_map=dm)  # 80 mm is a unit at b = 0


def test_the_paper_procedure_at_b_names_the_b_over_L_range(dm):
    """The biarc (paper) procedure asks the map for the θ range of short units: with b their
    b/L is past the map's, which it says (it said "no bistable unit")."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(ValueError, match=r"has b/L = 0.0881 with its flat ends b, outside "
                                             r"the map's b/L range \[0, 0.05\]"):
            inverse_design(np.array([[0, 0], [100, 40], [200, 15], [300, 50], [400, 0]]) * 1e-3,
                           t=T, w=W, design_map=dm, b=5e-3, controls=[0.1, 0.2], verify=False)
