"""Shapes that hold (issue 23): the paper's arrays held upright under PETG self-weight.

    .venv/bin/python -m studies.array_loads [nodes]      # a markdown table on stdout

The paper's three units (L 100, h 20, t 0.5, w 5, b 5 mm) in each of their 8 states, and
the Table 3 S array (four (106.7, 25.8) mm units on each side of a 100 mm straight, b = 0)
flat and all snapped; each at its size and scaled 3x and 10x -- every length (L, h, t, w,
b, the spacer) times the factor, so the shapes are the same and self-weight counts the
factor times more (weight per length ~ f^2, EI ~ f^4: q L^3 / EI ~ f). Upright: the array
stands in a vertical plane clamped at its start, its first edge horizontal, gravity in its
plane (`simulate_array(..., gravity=True, orientation="upright")`), PETG of the Eastman
datasheet (`solver.materials.PETG`: E 1.80 GPa, 1230 kg/m^3, allowable strain 2.67 %).

Every size is simulated from scratch (snapped unit by unit, then loaded): the actuator's
glued stem (`units.geometry`, 1/8 in) is a physical part and keeps its size, so the meshes
of the scaled units are not the scaled meshes.
Columns: the free end's sag (mm, and over the array length; "at the snap" where the array
does not carry its full weight: the sag at the largest load it carries), which units keep their state
at full weight, the first snap-back (`LoadedArray.limit_factor`: the factor on the weight at
which a unit snaps back, looked for up to 10; "-" none), that load in N (factor x weight),
the largest surface strain while snapping (the snap path, any size: strain is scale free)
and at full weight, and the time of the two `follow_load` runs.
"""

from __future__ import annotations

import sys
import time

import numpy as np

from snapmorph.design.array_loads import load_array
from snapmorph.design.array_study import (all_array_states, paper_three_units, scaled_units,
                                          table3_S_units)
from snapmorph.design.arrays import simulate_array
from snapmorph.design.interference import interference
from snapmorph.solver.materials import PETG

SCALES = (1.0, 3.0, 10.0)
MAX_FACTOR = 10.0


def unloaded_states(name, units, nodes=None, material=PETG) -> dict:
    """{state: ArrayResult} of the arrays the study loads: every state of the three units,
    the S flat and all snapped."""
    if name == "three units":
        return all_array_states(units, nodes=nodes, E=material.E)
    arched = [not u.is_spacer for u in units]
    return {"flat": simulate_array(units, [False] * len(units), nodes=nodes, E=material.E),
            "all snapped": simulate_array(units, arched, nodes=nodes, E=material.E)}


def loaded_rows(name, units, nodes=None, scales=SCALES, material=PETG,
                orientation="upright"):
    """[dict] one row per (scale, state) (`unloaded_states` of the scaled units)."""
    rows = []
    for f in scales:
        states = unloaded_states(name, scaled_units(units, f), nodes, material)
        for key, r in states.items():
            if r.status != "ok":
                raise SystemExit(f"{name} x{f:g}, state {key}: {r.status}")
            t0 = time.perf_counter()
            ld = load_array(r.model, r.positions, orientation=orientation, material=material,
                            max_factor=MAX_FACTOR)
            snap = max((s.strain_max for s in r.snaps), default=0.0)
            lost = [i + 1 for i, ok in enumerate(ld.held) if not ok]
            rows.append(dict(array=name, scale=f, state=key, weight=ld.total_load,
                             sag=ld.sag_m, length=r.model.length, status=ld.status,
                             held="all" if not lost else "lost: " + ", ".join(map(str, lost)),
                             limit=ld.limit_factor, limit_unit=ld.limit_unit,
                             limit_load=ld.limit_load, strain_snap=snap,
                             strain=ld.strain_max, carried=ld.path.status == "ok",
                             overlaps=[str(o) for o in r.interference + interference(
                                 r.model, ld.positions, f"{key} loaded")],
                             time=time.perf_counter() - t0))
    return rows


def table(rows) -> str:
    lines = ["| array | size | state | weight (N) | sag (mm) | sag / length | units held "
             "at 1 x weight | first snap-back (x weight, unit) | limit load (N) | strain "
             "snapping / at weight (%) | follow_load (s) |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lim = ("-" if r["limit"] is None else f"{r['limit']:.4g} (unit {r['limit_unit'] + 1})")
        sag = f"{r['sag'] * 1e3:.4g}" + ("" if r["carried"] else " (at the snap)")
        load = "-" if r["limit_load"] is None else f"{r['limit_load']:.3g}"
        lines.append(f"| {r['array']} | {r['scale']:g}x | {r['state']} | {r['weight']:.3g} | "
                     f"{sag} | {r['sag'] / r['length']:.3g} | {r['held']} | "
                     f"{lim} | {load} | {100 * r['strain_snap']:.2f} / "
                     f"{100 * r['strain']:.2f} | {r['time']:.2f} |")
    return "\n".join(lines)


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    nodes = int(argv[0]) if argv else None
    t0 = time.perf_counter()
    rows = loaded_rows("three units", paper_three_units(), nodes)
    rows += loaded_rows("Table 3 S", table3_S_units(), nodes)
    print(f"### Upright under PETG self-weight (nodes per unit: {nodes or 101}; "
          f"{time.perf_counter() - t0:.0f} s in all)\n")
    print(table(rows))
    overlaps = sorted({f"{r['array']} {r['scale']:g}x, {o}" for r in rows for o in r["overlaps"]})
    print(f"\nOverlapping parts (every state reached, and loaded): {len(overlaps)}")
    for o in overlaps:
        print(f"- {o}")
    return rows


if __name__ == "__main__":
    main()
