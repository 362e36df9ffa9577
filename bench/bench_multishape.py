"""Multi-shape design speed and accuracy (issue 24): a two-target design of about 12 units
(target <= 30 s), `nearest_state` for 16 units (target <= 1 s) and 20 units, and a table of
the generated test family (`design.target_sets.target_family(10)`, the sets the tests check):
units, deviation predicted (map) and simulated (whole array), best placement, % of length."""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # small dense solves; threads only contend

import statistics  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
import warnings  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))

T, W = 0.5e-3, 5e-3


def wave_pair():
    """A wave (+90°, -180°, +180°, -90°) and its mirror image, 1.75 m (the family's sizing
    rule for 270° each way): about 12 units."""
    from snapmorph.design.target_sets import turning_curve

    pieces = [(1, 90), (2, -180), (2, 180), (1, -90)]
    return [turning_curve(pieces, 1.75), turning_curve([(f, -t) for f, t in pieces], 1.75)]


def random_array(n, seed):
    import numpy as np

    from snapmorph.design import Unit

    rng = np.random.default_rng(seed)
    units = []
    for _ in range(n):
        L = float(rng.uniform(0.06, 0.15))
        if rng.random() < 0.15:
            units.append(Unit(L=L, h=0.0, t=T, w=W, side=0))
        else:
            units.append(Unit(L=L, h=L * float(rng.uniform(0.08, 0.4)), t=T, w=W,
                              side=int(rng.choice([-1, 1]))))
    state = [bool(rng.random() < 0.5) and not u.is_spacer for u in units]
    return units, state


def bench_nearest(dm, n, seed):
    import numpy as np

    from snapmorph.design import chain, nearest_state
    from snapmorph.design.lookup import MapLookup
    from snapmorph.design.targets import Target, place_rigid

    units, state = random_array(n, seed)
    xy = chain(units, state, lookup=MapLookup(dm)).xy
    wobble = 0.002 * np.sin(np.linspace(0, 11, len(xy)))[:, None]
    target = Target.from_polyline(place_rigid(xy + wobble, (0.05, -0.02), 0.7))
    nearest_state(units, target, design_map=dm)  # warm (map caches)
    times, cpu, r = [], [], None
    for _ in range(5):
        t0, c0 = time.perf_counter(), time.process_time()
        r = nearest_state(units, target, design_map=dm)
        times.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)
    arched = sum(not u.is_spacer for u in units)
    print(f"nearest_state, {n} units ({arched} arched, 2^{arched} = {2 ** arched} states), target "
          f"from one state moved and perturbed by 2 mm: median {statistics.median(times):.3f} s "
          f"wall, {statistics.median(cpu):.3f} s CPU (target <= 1 s); {r.nodes} tree nodes, "
          f"found the state: {r.pattern == tuple(state)}, deviation "
          f"{100 * r.deviation[0]:.3f} %")
    # a target that is no state of the array: a smooth curve through four points, same length
    length = sum(u.L for u in units)
    pts = np.array([[0.0, 0.0], [0.3, 0.15], [0.6, -0.1], [1.0, 0.2]])
    other = Target.from_points(pts * length / Target.from_points(pts).length)
    t0, c0 = time.perf_counter(), time.process_time()
    r = nearest_state(units, other, design_map=dm)
    print(f"  a target that is no state of it (a smooth curve, same length): "
          f"{time.perf_counter() - t0:.3f} s wall, {time.process_time() - c0:.3f} s CPU, "
          f"{r.nodes} tree nodes, deviation {100 * r.deviation[0]:.2f} %")


def main():
    warnings.simplefilter("ignore")
    from snapmorph.design import inverse_design_multi, verify_multi
    from snapmorph.design.lookup import load_map
    from snapmorph.design.target_sets import target_family

    dm = load_map()
    print(f"machine load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores (wall times "
          "grow with it; CPU time is this process's own)")
    pair = wave_pair()
    inverse_design_multi(pair[:2], t=T, w=W, design_map=dm)  # warm-up (imports, map caches)
    t0, c0 = time.perf_counter(), time.process_time()
    md = inverse_design_multi(pair, t=T, w=W, tol=0.02, design_map=dm)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    n = sum(not u.is_spacer for u in md.units)
    print(f"two-target design, a wave (+90/-180/+180/-90 deg) and its mirror image, 1750 mm: "
          f"{n} units + {len(md.units) - n} spacers, {len(md.history)} layouts, {wall:.1f} s "
          f"wall, {cpu:.1f} s CPU (target <= 30 s); predicted "
          + ", ".join(f"{100 * d:.2f} %" for d in md.max_deviations)
          + f"; patterns {', '.join(md.states)}")
    c0 = time.process_time()
    verify_multi(md)
    print(f"  whole-array verification of both patterns: "
          f"{sum(v['time'] for v in md.verification):.1f} s wall, {time.process_time() - c0:.1f} s "
          "CPU, simulated " + ", ".join(f"{100 * v['max_deviation']:.2f} % ({v['status']})"
                                        for v in md.verification))
    for n_units, seed in ((16, 3), (20, 4)):
        bench_nearest(dm, n_units, seed)
    print(f"{'set':<44} {'units':>5} {'sp':>3} {'predicted % (best)':>22} "
          f"{'simulated % (best)':>22} {'met':>4} {'design s':>8} {'sim s':>6}")
    for s in target_family(10):
        t0 = time.perf_counter()
        md = inverse_design_multi(s["targets"], t=T, w=W, tol=0.02, design_map=dm)
        td = time.perf_counter() - t0
        verify_multi(md)
        n = sum(not u.is_spacer for u in md.units)
        pred = " ".join(f"{100 * d:.2f}" for d in md.max_deviations)
        sim = " ".join(f"{100 * d:.2f}" for d in md.simulated_deviations)
        ok = md.met_all and all(v["status"] == "ok" and v["max_deviation"] <= 0.025
                                for v in md.verification)
        print(f"{s['name']:<44} {n:>5} {len(md.units) - n:>3} {pred:>22} {sim:>22} "
              f"{'yes' if ok else 'NO':>4} {td:8.1f} {sum(v['time'] for v in md.verification):6.1f}"
              f"  {' '.join(md.states)}", flush=True)


if __name__ == "__main__":
    main()
