"""Speed of the 3-D rods (`solver.Structure3D`) against the planar solver.

A cantilever strip of 101 nodes (t = 0.5 mm, w = 10 mm, L = 0.1 m) loaded at the tip in its
stiff direction, through lateral–torsional buckling: ms per Newton iteration and the whole
MGDC path with the critical point located and the branch switched; the planar solver's
101-node cantilever per iteration for scale (per degree of freedom).

Per iteration, two ways: the general path (``evaluate`` + ``factor`` + ``solve``, three
Python calls) and the fused kernel the path followers call (``fused_newton``: assemble,
banded LDL^T with inertia, solve and update in one compiled call). The 3-D and planar
systems are timed in alternating rounds and each figure is the best round, in CPU time
(``time.process_time``): on a shared machine the best round is the least disturbed one.
dismech-python is not on the package index here: no comparison.
"""

from __future__ import annotations

import os
import statistics
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))
os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402

RUNS = int(os.environ.get("BENCH_RUNS", "7"))
L, T, W, E, NU = 0.1, 0.5e-3, 10e-3, 2.2e9, 0.38


def ltb_structure(n=101):
    """The lateral–torsional buckling cantilever (`validation.strip3d`): (structure, rod)."""
    from validation.strip3d import ltb_cantilever

    return ltb_cantilever(n, L, T, W)[:2]


def ltb_push(n=101):
    st, rod = ltb_structure(n)
    r = st.rods[0]
    P = 4.013 * np.sqrt(r.EI1[0] * r.GJ[0]) / L**2
    d_cr = P * L**3 / (3 * r.EI2[0])
    return st.push(rod.nodes[-1], direction=(0.0, 0.0, -1.0), distance=2.0 * d_cr), r


def general_iteration(system, q, repeats):
    """CPU time (s) per evaluate + factor + solve at q, mean over ``repeats``."""
    t0 = time.process_time()
    for _ in range(repeats):
        system.evaluate(q)
        system.factor()
        system.solve(system.grad)
    return (time.process_time() - t0) / repeats


def fused_iteration(system, q, repeats):
    """CPU time (s) per fused Newton iteration from q (a full step, q copied each time)."""
    P = np.zeros(system.n)
    t0 = time.process_time()
    for _ in range(repeats):
        q_work = q.copy()
        system.fused_newton(q_work, 0.0, P, -1.0)
    return (time.process_time() - t0) / repeats


def per_iteration(sys3, q3, sys2, q2, rounds=25):
    """Best-round CPU times (s) per iteration: {(kind, "3d"|"planar"): t}, the 3-D and
    planar systems timed in alternating rounds (first round discarded: warm-up)."""
    out = {}
    for kind, fn in (("general", general_iteration), ("fused", fused_iteration)):
        t3, t2 = [], []
        for _ in range(rounds + 1):
            t3.append(fn(sys3, q3, 40))
            t2.append(fn(sys2, q2, 400))
        out[kind, "3d"] = min(t3[1:])
        out[kind, "planar"] = min(t2[1:])
    return out


def main():
    from snapmorph.solver import Structure

    st, rod = ltb_structure()
    sysm = st.reduced_system()
    q = st.initial_state()
    q[st.node_dofs(rod.nodes[-1])[2]] -= 1e-4

    x = np.linspace(0.0, L, 101)
    planar = Structure()
    planar.add_rod(np.stack([x, 0 * x], 1), width=W, thickness=T, E=E)
    planar.fix(0, "xz")
    planar.fix(1, "xz")
    psys = planar.reduced_system()
    qp = planar.initial_state()
    qp[-1] -= 1e-4
    times = per_iteration(sysm, q, psys, qp)
    for kind in ("general", "fused"):
        t3, t2 = times[kind, "3d"], times[kind, "planar"]
        print(f"{kind:7s} path: 3-D strip, 101 nodes, {sysm.n} DOFs (bandwidth {sysm.bandwidth}): "
              f"{t3 * 1e3:.3f} ms per Newton iteration, {t3 / sysm.n * 1e6:.3f} us per DOF; "
              f"planar rod, {psys.n} DOFs (bandwidth {psys.bandwidth}): {t2 * 1e3:.4f} ms, "
              f"{t2 / psys.n * 1e6:.3f} us per DOF -> 3-D / planar per DOF: "
              f"x{(t3 / sysm.n) / (t2 / psys.n):.1f} (goal <= x3)")

    ltb_push()
    times = []
    for _ in range(max(1, RUNS // 2)):
        t0 = time.perf_counter()
        path, r = ltb_push()
        times.append(time.perf_counter() - t0)
    bif = path.bifurcations[0]
    ratio = bif.F * L**2 / np.sqrt(r.EI1[0] * r.GJ[0])
    iters = int(path.info["total_iterations"]) + len(path) - 1
    print(f"LTB path, 101 nodes, MGDC to 2 x the critical deflection: median "
          f"{statistics.median(times):.2f} s, {len(path)} steps, {iters} Newton iterations, "
          f"{path.info.get('critical_seconds', float('nan')):.2f} s locating/switching; "
          f"P_cr L^2 / sqrt(EI1 GJ) = {ratio:.4f} (Prandtl 4.013), status {path.status}")
    print("dismech-python: not available from the package index on this machine "
          "(no comparison run)")


if __name__ == "__main__":
    main()
