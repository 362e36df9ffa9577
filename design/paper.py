"""The paper's forward-kinematics and inverse-design cases (Sections 3 and 4), for the examples
and `make figures`.

- Three identical units, t = 0.5, h = 20, w = 5, L = 100 mm: their 2³ = 8 states (Fig. "fk").
- The asymmetric M from five equally spaced points (Fig. "inverse_experiment" a-f).
- The S of circular arms joined by a straight (Fig. "inverse_experiment" g-j).

The paper gives neither the M's points nor the S's radii. Our choices, made once from the
paper's description and not tuned to its Table 3:
- M: x = 0, 100, 200, 300, 400 mm, y = 0, 40, 15, 50, 0 mm (a shallow M, right hump higher);
- S: each arm a half circle (an S turns 180° one way, then 180° back) of radius 125 mm in four
  equal segments, and a 100 mm straight between the arms.
Sheet t = 0.5 mm and strip w = 5 mm throughout, as the paper's specimens.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from snapmorph.design.inverse import inverse_design
from snapmorph.design.kinematics import all_snap_patterns
from snapmorph.design.lookup import MapLookup, load_map
from snapmorph.design.units import Unit

T, W = 0.5e-3, 5e-3

#: three-unit forward kinematics (m)
FK_UNIT = dict(L=100e-3, h=20e-3, t=T, w=W)

#: M target points (mm) and the paper's control points: the ends, the centre, and the one added
#: between the left-most and the centre point
M_POINTS_MM = np.array([[0.0, 0.0], [100.0, 40.0], [200.0, 15.0], [300.0, 50.0], [400.0, 0.0]])
M_PAPER_CONTROLS_MM = (100.0, 200.0)
#: Table 3, M: (L, h) mm of the four arched units; a 67.3 mm spacer between units 2 and 3
TABLE3_M = ((72.6, 6.9), (73.8, 11.3), (129.4, 21.1), (133.2, 31.3))
TABLE3_M_SPACER = 67.3

#: S: arm radius (m), turning of each arm (deg), segments per arm, straight (m)
S_RADIUS, S_ARM_TURN_DEG, S_SEGMENTS, S_STRAIGHT = 0.125, 180.0, 4, 0.100
#: Table 3, S: every unit (L, h) mm
TABLE3_S = (106.7, 25.8)


# --- forward kinematics ---------------------------------------------------------------------------
def three_units(design_map=None, source: str = "map") -> dict:
    """{state: Chain} of the paper's three identical units. From the map, b is the map's b/L
    times L (0 for the default map, as the paper's parametric study), released units (the
    actuated state (iii) on a schema-1 map, which has no other); simulated, b = w as the
    paper's specimens."""
    kw = {}
    if source == "map":
        dm = design_map if design_map is not None else load_map()
        b = MapLookup(dm).b_over_L * FK_UNIT["L"]
        if "released" not in getattr(dm, "states", ("released",)):
            kw["state"] = "actuated"  # a schema-1 map has only state (iii) with the actuator
    else:
        dm, b = None, W
    unit = Unit(**FK_UNIT, side=1, b=b)
    return all_snap_patterns([unit] * 3, source=source, design_map=dm, chains=True, **kw)


# --- the M ----------------------------------------------------------------------------------------
def design_M(design_map=None, controls: str = "paper", refine: bool = False, tol: float = 0.01):
    """Inverse design of the M; controls "paper" (the paper's procedure with its 4 control
    points) or "auto" (the tolerance-driven design of `inverse_design`)."""
    dm = design_map if design_map is not None else load_map()
    kw = {"controls": np.array(M_PAPER_CONTROLS_MM) * 1e-3} if controls == "paper" else {}
    return inverse_design(M_POINTS_MM * 1e-3, t=T, w=W, design_map=dm, tol=tol, refine=refine,
                          **kw)


def compare_M(d, design_map=None) -> str:
    """Our arched units beside Table 3's, in order, with h/L (the scale-free comparison)."""
    ours = [(u.L * 1e3, u.h * 1e3, u.side) for u in d.units if not u.is_spacer]
    spacers = [u.L * 1e3 for u in d.units if u.is_spacer]
    lines = [f"{'unit':>4}  {'Table 3 L, h mm':>15}  {'ours L, h mm':>14}  side  "
             f"{'Table 3 h/L':>11}  {'ours h/L':>8}"]
    for i in range(max(len(ours), len(TABLE3_M))):
        p = TABLE3_M[i] if i < len(TABLE3_M) else None
        o = ours[i] if i < len(ours) else None
        lines.append(
            f"{i + 1:>4}  {f'{p[0]:.1f}, {p[1]:.1f}' if p else '':>15}  "
            f"{f'{o[0]:.1f}, {o[1]:.1f}' if o else '':>14}  {f'{o[2]:+d}' if o else '':>4}  "
            f"{f'{p[1] / p[0]:.3f}' if p else '':>11}  {f'{o[1] / o[0]:.3f}' if o else '':>8}")
    lines.append(f"spacers: Table 3 {TABLE3_M_SPACER} mm; ours "
                 f"{', '.join(f'{s:.1f}' for s in spacers) or 'none'} mm")
    lines.append("Table 3's units in our map: " + ", ".join(
        _in_map(L, h, design_map) for L, h in TABLE3_M))
    return "\n".join(lines)


def _in_map(L_mm, h_mm, design_map) -> str:
    """'θ over S' of a Table 3 unit in our map, as text."""
    lk = MapLookup(design_map if design_map is not None else load_map())
    L, h = L_mm * 1e-3, h_mm * 1e-3
    try:
        theta, S = lk.theta_S(h / L, T / L, W / L)
    except ValueError:
        return "(not in the map)"
    return f"{theta:.1f}° over {S * L * 1e3:.1f} mm"


# --- the S ----------------------------------------------------------------------------------------
def s_control_points(R=S_RADIUS, turn=S_ARM_TURN_DEG, n=S_SEGMENTS, straight=S_STRAIGHT):
    """(points (2n + 2, 2) m, tangents (2n + 2,) deg): left-turning arm, straight, right arm."""
    pts, ang = [], []
    for i in range(n + 1):
        a = math.radians(turn * i / n)
        pts.append((R * math.sin(a), R * (1 - math.cos(a))))
        ang.append(turn * i / n)
    a = math.radians(turn)
    p = np.array(pts[-1]) + straight * np.array([math.cos(a), math.sin(a)])
    c = p + R * np.array([math.sin(a), -math.cos(a)])  # centre of the right-turning arm
    for i in range(n + 1):
        b = a - math.radians(turn * i / n)
        pts.append(tuple(c + R * np.array([-math.sin(b), math.cos(b)])))
        ang.append(turn - turn * i / n)
    return np.array(pts), np.array(ang)


def design_S(design_map=None, **shape):
    """Inverse design of the S from control points with tangents (no spline)."""
    dm = design_map if design_map is not None else load_map()
    pts, ang = s_control_points(**shape)
    return inverse_design(pts, t=T, w=W, tangents=ang, design_map=dm)


def table3_S_unit_in_map(design_map=None):
    """(θ deg, S mm) our map gives for Table 3's S unit (106.7, 25.8) mm; ValueError if the
    map does not cover it."""
    lk = MapLookup(design_map if design_map is not None else load_map())
    L, h = TABLE3_S[0] * 1e-3, TABLE3_S[1] * 1e-3
    theta, S = lk.theta_S(h / L, T / L, W / L)
    return theta, S * L * 1e3


def compare_S(d, design_map=None) -> str:
    """Our S unit beside Table 3's."""
    u = next(u for u in d.units if not u.is_spacer)
    lines = [f"every arched unit: ours (L, h) = ({u.L * 1e3:.1f}, {u.h * 1e3:.1f}) mm, "
             f"h/L = {u.h / u.L:.3f}; Table 3 ({TABLE3_S[0]}, {TABLE3_S[1]}) mm, "
             f"h/L = {TABLE3_S[1] / TABLE3_S[0]:.3f}"]
    try:
        theta, S = table3_S_unit_in_map(design_map)
        lines.append(f"Table 3's unit in our map: θ = {theta:.1f}° over S = {S:.1f} mm, so an arm "
                     f"of {S_SEGMENTS} such units would turn {S_SEGMENTS * theta:.0f}°")
    except ValueError as exc:
        lines.append(f"Table 3's unit is not covered by our map: {exc}")
    return "\n".join(lines)


# --- figures --------------------------------------------------------------------------------------
def write_figures(out, design_map=None) -> list[Path]:
    """The paper's Section 3-4 figures into `out`: fk_states.png, inverse_M.png, inverse_S.png
    (with the M's and S's units.csv and drawings under out/inverse_M/, out/inverse_S/)."""
    from snapmorph.design.drawings import write_drawings
    from snapmorph.design.plots import plot_design, plot_states
    from snapmorph.design.units import write_units_csv

    out = Path(out)
    dm = design_map if design_map is not None else load_map()
    paths = [plot_states({k: c.xy for k, c in three_units(dm).items()}, out / "fk_states.png",
                         title="three units t = 0.5, h = 20, w = 5, L = 100 mm: the 8 states")]
    for name, d in (("M", design_M(dm, "paper")), ("S", design_S(dm))):
        paths.append(plot_design(d, out / f"inverse_{name}.png"))
        paths.append(write_units_csv(d.units, out / f"inverse_{name}" / "units.csv"))
        paths += write_drawings(d.units, out / f"inverse_{name}", bed_length_mm=600.0)
    return paths


# --- the scripts in examples/ -----------------------------------------------------------------------
def example_parser(doc: str, out: str):
    """The command line of an example script: --map and --out (default `out`); `doc`'s first
    line is its description."""
    import argparse

    p = argparse.ArgumentParser(description=doc.splitlines()[0])
    p.add_argument("--map", default=None, help="design map (default: the committed one)")
    p.add_argument("--out", default=out)
    return p


def written(design, out=None):
    """`design`, after writing units.csv, design.png and the drawings (a 600 mm laser bed)
    into `out` when given."""
    if out is not None:
        design.write(out, bed_length_mm=600.0)
    return design


# --- the paper's angle convention (issue 11, item 4) ------------------------------------------
def design_S_paper(design_map=None, **shape):
    """The S designed as the paper did: one unit per circular segment, entering the map with
    theta_end (`inverse_design(..., theta_convention="paper")`); reproduces Table 3's S unit.
    The design over-curves about twice (its notes say so)."""
    import warnings

    dm = design_map if design_map is not None else load_map()
    pts, ang = s_control_points(**shape)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the note in the design says it
        return inverse_design(pts, t=T, w=W, tangents=ang, design_map=dm,
                              theta_convention="paper")


def conventions(design_map=None, verify: bool = True) -> dict:
    """{"paper": design, "ours": design} of the paper's S, by the paper's convention (theta_end,
    Table 3) and by ours (θ, tolerance-driven), each simulated as a whole array when verify."""
    from snapmorph.design.verification import verify_design

    dm = design_map if design_map is not None else load_map()
    pts, ang = s_control_points()
    out = {"paper": design_S_paper(dm),
           "ours": inverse_design(pts, t=T, w=W, tangents=ang, design_map=dm)}
    if verify:
        for d in out.values():
            verify_design(d)
    return out


def conventions_table(designs: dict) -> str:
    """Text: units, h/L, predicted and simulated deviation of the two conventions, Table 3."""
    lines = [f"{'convention':<10} {'arched (L, h) mm':<22} {'h/L':>6} {'turn/unit':>9} "
             f"{'predicted':>9} {'simulated':>9}"]
    for name, d in designs.items():
        arched = [u for u in d.units if not u.is_spacer]
        u = arched[0]
        turns = np.degrees(np.diff(d._chain.angles))
        turn = max(abs(x) for x in turns)
        sim = (f"{100 * d.verification['deviations']['best'][0]:8.1f}%"
               if d.verification is not None else "        -")
        lines.append(f"{name:<10} {f'({u.L * 1e3:.1f}, {u.h * 1e3:.1f}) x {len(arched)}':<22} "
                     f"{u.h / u.L:6.3f} {turn:8.1f}° {100 * d.max_deviation:8.1f}% {sim}")
    lines.append(f"Table 3 S: ({TABLE3_S[0]}, {TABLE3_S[1]}) mm, h/L = "
                 f"{TABLE3_S[1] / TABLE3_S[0]:.3f}; deviations are % of the target length "
                 "(best rigid placement)")
    return "\n".join(lines)


def plot_conventions(designs: dict, path) -> Path:
    """Side by side: the S designed by the paper's convention and by ours; target, predicted
    (map) and simulated whole array for each."""
    from snapmorph.design.plots import _plt, _save

    plt = _plt()
    fig, axes = plt.subplots(1, len(designs), figsize=(6 * len(designs), 6), squeeze=False)
    for ax, (name, d) in zip(axes[0], designs.items()):
        T_ = d.target * 1e3
        ax.plot(T_[:, 0], T_[:, 1], "-", color="0.6", lw=5, alpha=0.6, label="target")
        P = d.predicted * 1e3
        ax.plot(P[:, 0], P[:, 1], "-", color="C0", lw=1.5, label="predicted (map)")
        title = (f"{'paper convention (theta_end), Table 3' if name == 'paper' else 'our convention (θ)'}"
                 f"\npredicted {100 * d.max_deviation:.1f} %")
        if d.verification is not None:
            Q = d.verification["xy"] * 1e3
            ax.plot(Q[:, 0], Q[:, 1], ":", color="C3", lw=2, label="simulated array")
            title += f", simulated {100 * d.verification['max_deviation']:.1f} %"
        u = next(u for u in d.units if not u.is_spacer)
        title += f" of the length\nunits (L, h) = ({u.L * 1e3:.1f}, {u.h * 1e3:.1f}) mm"
        ax.set_title(title, fontsize=9)
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_xlabel("x (mm)")
        ax.set_ylabel("y (mm)")
        ax.legend(fontsize=8, loc="lower right")
    return _save(fig, path)
