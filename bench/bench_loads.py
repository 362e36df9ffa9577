"""Speed of the dead-load solver: `follow_load` on heavy cantilevers, on the clamped arch
through its limit point, and on a long multi-unit strip under its own weight.

The strip is a stand-in for the 8-unit S array of issue 23 (L = 106.7 mm, h = 25.8 mm,
t = 0.5 mm, w = 5 mm, the paper's Table 3; the array itself is built in part B): eight
arch-on-base units in state (i) on one continuous base rod (4w solid ends, 2w hollow
middles), every arch bonded to the base over its flat ends by exact ties, about 161 nodes
per unit, clamped at its start, under the paper's PETG self-weight (rho = 1.3e3 kg/m^3)
in its plane: "horizontal" (a cantilever, gravity across it) and "standing" (clamped at
its foot, gravity along it: it shortens, then bends over). Its size is the array's; the
shape is not the morphed one. ``follow_load`` to the full weight, at 1x, 3x and 10x size.
The S array itself (part B): all snapped, upright under PETG self-weight, ``follow_load``
from its morphed state to factor 1 and to 10 (`s_array`).
Run: ``.venv/bin/python bench/bench_loads.py`` (also part of ``make bench``).
"""

from __future__ import annotations

import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))
os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from bench.timing import median_time  # noqa: E402
from snapmorph.solver import Structure  # noqa: E402
from snapmorph.solver.materials import PAPER_PETG  # noqa: E402

RUNS = int(os.environ.get("BENCH_RUNS", "5"))


def unit_strip(n_units=8, per_unit=161, L=0.1067, h=0.0258, t=0.5e-3, w=5e-3, scale=1.0,
               material=PAPER_PETG, down=(0.0, -1.0)):
    """The multi-unit strip of the module doc (lengths times ``scale``), along +x from its
    clamped start, gravity along ``down``. Returns (structure, free end node)."""
    L, h, t, w = (scale * v for v in (L, h, t, w))
    x0 = w  # b = 0: the flat ends are w long
    n_base = max(int(round(0.45 * per_unit)), 8)  # base edges per unit
    xb = np.linspace(0.0, L, n_base + 1)
    flat = xb[xb <= x0 + 1e-12 * L]
    if flat[-1] < x0 - 1e-12 * L:  # a base node at the end of the flat part
        xb = np.sort(np.concatenate([xb, [x0, L - x0]]))
        flat = xb[xb <= x0 + 1e-12 * L]
    la = L - 2 * x0
    n_arch = per_unit - n_base - 2 * len(flat) + 2
    u = np.linspace(0.0, 1.0, 4001)
    xs, zs = x0 + la * u, 0.5 * h * (1 - np.cos(2 * np.pi * u))
    s = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(xs), np.diff(zs)))])
    target = np.linspace(0.0, s[-1], n_arch)
    xa = np.interp(target, s, xs)
    arch = np.stack([np.concatenate([flat[:-1], xa, L - flat[::-1][1:]]),
                     np.concatenate([0 * flat[:-1], 0.5 * h * (1 - np.cos(2 * np.pi * (xa - x0) / la)),
                                     0 * flat[1:]])], 1)
    base_x = np.concatenate([xb[:-1] + k * L for k in range(n_units)] + [[n_units * L]])
    halves = np.stack([0.75 * base_x[:-1] + 0.25 * base_x[1:],
                       0.25 * base_x[:-1] + 0.75 * base_x[1:]], axis=1) % L
    width = np.where((halves < x0) | (halves > L - x0), 4.0 * w, 2.0 * w)
    st = Structure()
    base = st.add_rod(np.stack([base_x, 0 * base_x], 1), width, t, material.E)
    for k in range(n_units):
        rod = st.add_rod(arch + [k * L, 0.0], w, t, material.E)
        for j, x in enumerate(arch[:, 0] + k * L):
            if arch[j, 1] == 0.0:  # a flat node: bond it to the base node under it
                i = int(np.argmin(np.abs(base_x - x)))
                if abs(base_x[i] - x) < 1e-9 * L:
                    st.tie(int(rod.nodes[j]), int(base.nodes[i]))
    st.clamp(int(base.nodes[0]), toward=int(base.nodes[1]))
    st.add_gravity(material, direction=down)
    return st, int(base.nodes[-1])


def main():
    from validation.arch import L_SPAN, T, clamped_arch
    from validation.heavy_cantilever import heavy_cantilever

    print(f"dead loads (follow_load, MGDC; median of {RUNS} warm runs, NUMBA_NUM_THREADS=1)")
    for n, alpha in ((101, 10.0), (401, 10.0)):
        st = heavy_cantilever(n, alpha)
        med, best, path = median_time(lambda: st.follow_load(1.0), RUNS, warm=True)
        print(f"heavy cantilever, {n} nodes, q L^3 / EI = {alpha:g} to factor 1: median "
              f"{med * 1e3:.0f} ms (best {best * 1e3:.0f} ms), {len(path)} steps, "
              f"{path.info['total_iterations']} iterations, status {path.status}")
    h = 10 * T
    st, mid, EI = clamped_arch(h)
    st.add_load(mid, (0.0, -1000.0 * EI * h / L_SPAN**3))
    med, best, path = median_time(lambda: st.follow_load(1.0), RUNS, warm=True)
    print(f"clamped arch (101 nodes, h/t = 10) under a central dead load through its limit "
          f"point down to factor 0: median {med * 1e3:.0f} ms (best {best * 1e3:.0f} ms), "
          f"{len(path)} steps, limit load factor {path.limit_load_factor:.6f}")
    for orientation, down in (("horizontal", (0.0, -1.0)), ("standing", (-1.0, 0.0))):
        for scale in (1.0, 3.0, 10.0):
            st, tip = unit_strip(scale=scale, down=down)
            med, best, path = median_time(lambda: st.follow_load(1.0), max(RUNS // 2, 1),
                                          warm=True)
            move = np.linalg.norm(path.positions[-1][tip] - st.reference_positions[tip])
            print(f"8-unit strip stand-in x{scale:g} ({st.n_nodes} nodes, "
                  f"{8 * 0.1067 * scale:.2f} m, PETG self-weight, {orientation}) to factor 1: "
                  f"median {med:.2f} s (best {best:.2f} s; target for the S array <= 5 s), "
                  f"{len(path)} steps, free end moved {move * 1e3:.0f} mm, status "
                  f"{path.status.split(':')[0]}")

    s_array()


def s_array(material=None):
    """The issue's target on the array itself: the Table 3 S (`design.array_study.
    table3_S_units`: 8 units of (106.7, 25.8) mm and a 100 mm straight, 101 nodes per unit),
    all snapped (not timed), then held upright under PETG self-weight from its morphed state:
    `follow_load` to factor 1 (the sag) and to 10 (the search for the first snap-back)."""
    from snapmorph.design.array_study import table3_S_units
    from snapmorph.design.arrays import simulate_array
    from snapmorph.solver.materials import PETG

    material = material or PETG
    units = table3_S_units()
    r = simulate_array(units, E=material.E)
    st = r.model.structure(clamp=True)
    st.add_gravity(material, direction=(0.0, -1.0))
    end = int(r.model.base_nodes[-1])
    for factor in (1.0, 10.0):
        med, best, path = median_time(lambda: st.follow_load(factor, start=r.positions),
                                      max(RUNS // 2, 1), warm=True)
        sag = np.linalg.norm(path.positions[-1][end] - r.positions[end])
        lim = path.limit_load_factor
        print(f"Table 3 S array, all snapped ({st.n_nodes} nodes, {r.model.length:.3f} m), "
              f"upright under {material.name} self-weight, follow_load to factor {factor:g}: "
              f"median {med:.2f} s (best {best:.2f} s; target <= 5 s), {len(path)} steps, "
              f"free end moved {sag * 1e3:.1f} mm, limit load factor "
              f"{'none' if lim is None else f'{lim:.4f}'}, status {path.status.split(':')[0]}")


if __name__ == "__main__":
    main()
