"""Speed of the 3-D rods (`solver.Structure3D`) against the planar solver.

A cantilever strip of 101 nodes (t = 0.5 mm, w = 10 mm, L = 0.1 m) loaded at the tip in its
stiff direction, through lateral–torsional buckling: ms per Newton iteration (assemble +
banded LDL^T with inertia + solve) and the whole MGDC path with the critical point located
and the branch switched; the planar solver's 101-node cantilever per iteration for scale
(per degree of freedom). dismech-python is not on the package index here: no comparison.
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
    from solver import Structure3D

    x = np.linspace(0.0, L, n)
    st = Structure3D()
    rod = st.add_rod(np.stack([x, 0 * x, 0 * x], 1), width=W, thickness=T, E=E, nu=NU,
                     normal=(0.0, 1.0, 0.0))
    st.clamp(rod.nodes[0], toward=rod.nodes[1])
    return st, rod


def ltb_push(n=101):
    st, rod = ltb_structure(n)
    r = st.rods[0]
    P = 4.013 * np.sqrt(r.EI1[0] * r.GJ[0]) / L**2
    d_cr = P * L**3 / (3 * r.EI2[0])
    return st.push(rod.nodes[-1], direction=(0.0, 0.0, -1.0), distance=2.0 * d_cr), r


def per_iteration(system, q, repeats=200):
    """Median time (s) of evaluate + factor + solve at q."""
    times = []
    for _ in range(5):
        t0 = time.perf_counter()
        for _ in range(repeats):
            system.evaluate(q)
            system.factor()
            system.solve(system.grad)
        times.append((time.perf_counter() - t0) / repeats)
    return statistics.median(times)


def main():
    from solver import Structure

    st, rod = ltb_structure()
    sysm = st.reduced_system()
    q = st.initial_state()
    q[st.node_dofs(rod.nodes[-1])[2]] -= 1e-4
    per_iteration(sysm, q, 2)
    t3 = per_iteration(sysm, q)

    x = np.linspace(0.0, L, 101)
    planar = Structure()
    planar.add_rod(np.stack([x, 0 * x], 1), width=W, thickness=T, E=E)
    planar.fix(0, "xz")
    planar.fix(1, "xz")
    psys = planar.reduced_system()
    qp = planar.initial_state()
    qp[-1] -= 1e-4
    per_iteration(psys, qp, 2)
    t2 = per_iteration(psys, qp, 2000)
    print(f"3-D strip, 101 nodes, {sysm.n} DOFs (bandwidth {sysm.bandwidth}): "
          f"{t3 * 1e3:.2f} ms per Newton iteration (assemble + LDL^T + solve), "
          f"{t3 / sysm.n * 1e6:.2f} us per DOF")
    print(f"planar rod, 101 nodes, {psys.n} DOFs (bandwidth {psys.bandwidth}): "
          f"{t2 * 1e3:.3f} ms per iteration (general path), {t2 / psys.n * 1e6:.2f} us per DOF"
          f"  -> 3-D / planar per DOF: x{(t3 / sysm.n) / (t2 / psys.n):.1f} (goal <= x3)")

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
