"""Banded LDL^T (`solver.banded`) against the sparse LDL^T (`solver.sparse`, QDLDL with AMD)
on real stiffness matrices: the planar unit, the 3-D unit and the 2-D unit at several meshes,
and sheets tiled from 2-D units (a square grid of rods, two crossing arches per cell, rigid
joints; `sheet_structure`) up to ~10^5 DOFs. One thread, best of BENCH_RUNS runs in CPU time.

K is assembled at a slightly perturbed stress-free state (every structural entry nonzero),
the banded one by the system's own assembly, the sparse one straight into the CSC values
(copied from the band, `SparseLDLT.from_band`), and shifted by sigma I to be indefinite: both factorisations
must count the same negative pivots (and dense eigvalsh for n <= 3000).

    .venv/bin/python bench/bench_sparse.py              # ~2 min: to ~2 10^4 DOFs, + 18 x 18
    BENCH_SPARSE_BIG=1 .venv/bin/python bench/bench_sparse.py   # + the sheets between

Columns: n; bw (the band's width) and env (entries of the banded envelope); nnz(L) of the
sparse factor; banded factor, sparse first factor (AMD ordering, symbolic analysis and
numeric factor, from the pattern), sparse refactor (same pattern) and solve times (ms, one
right-hand side); neg: negative pivots (banded / sparse / dense); the rule's choice.
"""

from __future__ import annotations

import os

os.environ.setdefault("NUMBA_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import sys  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))

RUNS = int(os.environ.get("BENCH_RUNS", "5"))
BIG = os.environ.get("BENCH_SPARSE_BIG", "") not in ("", "0")


def sheet_structure(nx, ny, nodes=21, L=0.1, h=0.02, t=0.5e-3, w=5e-3, E=2.2e9, nu=0.38):
    """A sheet of nx x ny 2-D units (`units.unit2d`'s cell, simplified): grid lines of rods
    along x and y (cells of side L, ``nodes`` per cell side, odd), rigidly jointed where they
    cross; in every cell two sinusoidal arches of height h between opposite side midpoints,
    jointed to the grid at their feet and to each other at the apex. Held: one corner (xyz),
    the next along x (yz), the next along y (z). Returns the `solver.Structure3D`."""
    from snapmorph.units.frame3d import Mesh3D
    from snapmorph.units.shapes import arch_height

    m = nodes - 1
    if m % 2:
        raise ValueError("nodes must be odd (a node at every side's midpoint)")
    mesh = Mesh3D(E=E, nu=nu)
    sx = np.linspace(0.0, nx * L, nx * m + 1)
    sy = np.linspace(0.0, ny * L, ny * m + 1)
    rows = [mesh.add_rod(f"x{j}", np.stack([sx, np.full_like(sx, j * L), 0 * sx], 1), w, t)
            for j in range(ny + 1)]
    cols = [mesh.add_rod(f"y{i}", np.stack([np.full_like(sy, i * L), sy, 0 * sy], 1), w, t)
            for i in range(nx + 1)]
    for j in range(ny + 1):
        for i in range(nx + 1):
            mesh.bond(rows[j][i * m], cols[i][j * m])
    u = np.linspace(0.0, L, nodes)
    z = arch_height(u, 0.0, L, h)
    c = np.full_like(u, 0.5 * L)
    k = m // 2
    for j in range(ny):
        for i in range(nx):
            ax = mesh.add_rod(f"ax{i}_{j}", np.stack([i * L + u, j * L + c, z], 1), w, t)
            ay = mesh.add_rod(f"ay{i}_{j}", np.stack([i * L + c, j * L + u, z], 1), w, t)
            mesh.bond(ax[k], ay[k])
            mesh.bond(ax[0], cols[i][j * m + k])
            mesh.bond(ax[-1], cols[i + 1][j * m + k])
            mesh.bond(ay[0], rows[j][i * m + k])
            mesh.bond(ay[-1], rows[j + 1][i * m + k])
    mesh.fixes += [(int(rows[0][0]), "xyz"), (int(rows[0][-1]), "yz"), (int(rows[-1][0]), "z")]
    return mesh.to_structure()


def _best(fn, runs):
    """Best of ``runs`` calls in CPU time (one thread: the machine is shared, and CPU time
    counts only this process's work)."""
    best = np.inf
    for _ in range(runs):
        t0 = time.process_time()
        fn()
        best = min(best, time.process_time() - t0)
    return best


def _perturbed_state(st, rng):
    q = st.initial_state()
    n3 = 3 * st.n_nodes if hasattr(st, "n_edges") else q.shape[0]
    q[:n3] += 1e-7 * rng.standard_normal(n3)
    q[n3:] += 1e-5 * rng.standard_normal(q.shape[0] - n3)
    return q


def measure(label, st, runs=RUNS):
    """One row of the table (a dict), the system's K assembled both ways."""
    from snapmorph.solver.banded import band_to_dense, ldlt_factor_envelope, ldlt_solve_envelope
    from snapmorph.solver.sparse import SparseLDLT, choose_factorisation, envelope_flops

    rng = np.random.default_rng(1)
    sysm = st.reduced_system()
    q = _perturbed_state(st, rng)
    sysm.evaluate(q)
    n, heights = sysm.n, sysm.heights
    # an indefinite K: shift by a small fraction of the mean diagonal entry
    sigma = 2e-4 * float(np.mean(np.abs(sysm.band[0])))
    sysm.band[0] -= sigma
    band0 = sysm.band.copy(order="K")
    work = band0.copy(order="K")

    def banded():
        work[...] = band0
        return ldlt_factor_envelope(work, heights, 1e-13)

    status_b, neg_b, _ = banded()
    t_copy = _best(lambda: work.__setitem__(Ellipsis, band0), runs)
    t_band = max(_best(banded, runs) - t_copy, 0.0)
    rhs = rng.standard_normal((n, 1))
    t_bsolve = _best(lambda: ldlt_solve_envelope(work, heights, rhs.copy()), runs)

    f = SparseLDLT.for_system(sysm)
    if hasattr(sysm, "model_arrays"):  # 3-D: the assembly, and the copy onto the pattern
        t_asm_csc = _best(lambda: f.from_band(band0), runs)
        t_asm_band = _best(lambda: sysm.evaluate(q), runs)
    else:
        t_asm_csc = t_asm_band = float("nan")
    f.from_band(band0)
    status_s, neg_s, _ = f.factor()
    t_refac = _best(f.factor, runs)
    # the first factorisation from the element DOF lists alone: pattern, entry maps, AMD
    # ordering and symbolic analysis (`SparseLDLT(...)`), then the numeric factor
    t_first = _best(lambda: SparseLDLT.for_system(sysm), max(1, runs // 2)) + t_refac
    t_ssolve = _best(lambda: f.solve(rhs[:, 0]), runs)
    x = f.solve(rhs[:, 0])
    A = f.matrix()
    res = float(np.linalg.norm(A @ x - rhs[:, 0]) / (abs(A).max() * np.linalg.norm(x)))
    neg_d = None
    if n <= 3000:
        neg_d = int(np.sum(np.linalg.eigvalsh(band_to_dense(band0)) < 0.0))
        assert neg_d == neg_s or status_s != 0, (label, neg_d, neg_s)
    choice = choose_factorisation(n, heights, f.indices.size, f.factor_flops, f.nnz_factor)
    quick = choose_factorisation(n, heights, f.indices.size)
    return dict(label=label, n=n, bw=sysm.bandwidth, env=int(np.sum(heights)),
                env_flops=envelope_flops(heights), nnzK=int(f.indices.size),
                nnzL=f.nnz_factor, flops=f.factor_flops, band=t_band, bsolve=t_bsolve,
                first=t_first, refac=t_refac, ssolve=t_ssolve,
                asm_csc=t_asm_csc, asm_band=t_asm_band, neg=(neg_b, neg_s, neg_d),
                status=(int(status_b), int(status_s)), res=res, choice=choice, quick=quick)


def cases(big=BIG):
    from snapmorph.units.frame3d import UnitGeometry
    from snapmorph.units.geometry import UnitGeometry as PlanarGeometry
    from snapmorph.units.geometry import build_unit
    from snapmorph.units.unit2d import build_unit_2d
    from snapmorph.units.unit3d import build_unit_3d

    gp = PlanarGeometry(L=0.1, h=0.02, t=0.5e-3, w=5e-3, b=5e-3)
    g3 = UnitGeometry(L=0.1, h=0.02, t=0.5e-3, w=5e-3, b=5e-3)
    g2 = UnitGeometry(L=0.1, h=0.04, t=0.5e-3, w=5e-3)
    out = [("planar unit 201", lambda: build_unit(gp, nodes=201).structure)]
    for nodes in (41, 81, 161, 321):
        out.append((f"3-D unit {nodes}", lambda k=nodes: build_unit_3d(g3, nodes=k).structure))
    out.append(("2-D unit 41", lambda: build_unit_2d(g2, nodes=41).structure))
    # the 18 x 18 sheet (~10^5 DOFs) always: `make bench` measures the sparse factorisation
    # there (issue 25)
    sheets = [(1, 1), (2, 2), (4, 4), (16, 1), (8, 8)] + ([(32, 4), (12, 12), (16, 16)]
                                                          if big else []) + [(18, 18)]
    for nx, ny in sheets:
        out.append((f"sheet {nx}x{ny}", lambda a=nx, b=ny: sheet_structure(a, b)))
    return out


def main():
    print(f"banded LDL^T vs sparse LDL^T (QDLDL + AMD), one thread, best of {RUNS} runs; "
          f"CPU times in ms{'' if BIG else ' (BENCH_SPARSE_BIG=1 for sheets to ~10^5 DOFs)'}")
    head = (f"{'case':16s} {'n':>7s} {'bw':>4s} {'env':>9s} {'nnz(L)':>8s} | {'banded':>8s} "
            f"{'b.solve':>7s} | {'first':>8s} {'refac':>8s} {'solve':>6s} | {'neg b/s/dense':>15s}"
            f" {'choice':>7s}")
    print(head)
    print("-" * len(head))
    rows = []
    for label, build in cases():
        r = measure(label, build())
        rows.append(r)
        nb, ns, nd = r["neg"]
        neg = f"{nb}/{ns}/{'-' if nd is None else nd}"
        print(f"{label:16s} {r['n']:7d} {r['bw']:4d} {r['env']:9d} {r['nnzL']:8d} | "
              f"{1e3 * r['band']:8.2f} {1e3 * r['bsolve']:7.2f} | {1e3 * r['first']:8.2f} "
              f"{1e3 * r['refac']:8.2f} {1e3 * r['ssolve']:6.2f} | {neg:>15s} "
              f"{r['choice']:>7s}", flush=True)
    print("\nthe 3-D K (ms): assembled into the band / copied from it onto the CSC pattern")
    for r in rows:
        if np.isfinite(r["asm_csc"]):
            print(f"  {r['label']:16s} {1e3 * r['asm_band']:8.2f} / {1e3 * r['asm_csc']:8.2f}"
                  f"   (sparse solve: relative residual {r['res']:.1e})")
    return rows


if __name__ == "__main__":
    main()
