"""Random unit geometries over the whole valid domain of `units.UnitGeometry`.

    python tests/units/fuzz_units.py --n 3000        # `make fuzz`

Each geometry is drawn log-uniformly in L (1 mm to 10 m), t/L (1e-5 to 0.05), w/L and
b/L inside the domain's edges, E (1 to 1e200 Pa), uniformly in h/span (0 to 1), with random
joint and bond lengths, and simulated with a wall-time limit. Checked: every call returns
within its limit (plus a margin), with a known status; every "ok" result is bistable with
finite numbers and its state (iii) is stable when re-checked independently (negative
eigenvalues of the tangent stiffness with the apex unloaded); "bistable" never comes with
another status; "monostable" only on a path that ran its course (3 h at least, never a cut
path). ``--nodes 101 --compare 201``: each geometry at both resolutions; an answer that flips
(bistable at one, not at the other) is a problem.

    python tests/units/fuzz_units.py --n 1000 --nodes 101 --compare 201 --time-limit 20
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))

#: seconds a call may overrun its time limit: the limit is checked between solver steps and
#: between the stages of simulate_unit; one Newton solve or a numba compilation cannot be cut
MARGIN = 30.0
PREFIXES = ("ok", "monostable", "second state unstable", "timeout", "not converged")
#: the answered statuses (the rest are failures); their change between two resolutions is a
#: flag flip
ANSWERS = ("ok", "monostable", "second state unstable")


def failure_record(kw, nodes, status, reason, seconds):
    """One failed simulation, for ``--failures``: the geometry (SI) and its ratios to L (b/L
    and h/span where the documented failure classes lie, docs/model-notes.md item 11)."""
    L = kw["L"]
    span = L - 2 * (kw["b"] + kw["w"])
    return {"nodes": nodes, "status": status, "reason": reason, "seconds": round(seconds, 2),
            "h_over_L": kw["h"] / L, "h_over_span": kw["h"] / span if span > 0 else None,
            "t_over_L": kw["t"] / L, "w_over_L": kw["w"] / L, "b_over_L": kw["b"] / L,
            "geometry": kw}


def random_geometry(rng):
    """Keyword arguments of one valid UnitGeometry (retries until valid)."""
    from snapmorph.units.geometry import (MIN_FLAT_FRACTION, MIN_SECTION_FRACTION, MIN_SPAN_FRACTION,
                                MIN_WIDTH_FRACTION, geometry_problem)

    while True:
        L = 10 ** rng.uniform(-3, 1)
        t = L * 10 ** rng.uniform(math.log10(MIN_SECTION_FRACTION), math.log10(0.05))
        flat = L * 10 ** rng.uniform(math.log10(MIN_FLAT_FRACTION),
                                     math.log10(0.5 * (1 - MIN_SPAN_FRACTION)))
        w = flat * 10 ** rng.uniform(math.log10(max(MIN_WIDTH_FRACTION * L / flat, 1e-6)), 0)
        b = max(flat - w, 0.0) if rng.random() < 0.8 else 0.0
        span = L - 2 * (b + w)
        h = span * rng.uniform(0.0, 1.0) if rng.random() < 0.97 else 0.0
        E = 10 ** rng.uniform(0, 200)
        kw = dict(L=L, h=h, t=t, w=w, b=b, E=E)
        if rng.random() < 0.5:
            kw["joint_length"] = 0.0 if rng.random() < 0.3 else rng.uniform(0, 0.3) * span
        if rng.random() < 0.3:
            kw["bond_length"] = (b + w) * rng.uniform(0.05, 1.0)
        if not geometry_problem(**kw):
            return kw


def check_one(kw, time_limit, nodes, record=None):
    """Simulate one geometry; returns (problems list, status prefix, seconds). ``record``:
    called with a `failure_record` when the simulation fails (not an answer)."""
    from snapmorph.solver.stability import state_stability
    from snapmorph.units import UnitGeometry, simulate_unit
    from snapmorph.units.geometry import build_unit
    from snapmorph.units.planar import E_INTERNAL, L_INTERNAL

    g = UnitGeometry(**kw)
    t0 = time.perf_counter()
    try:
        r = simulate_unit(g, nodes=nodes, time_limit=time_limit, critical=False,
                          check_self_standing=False)
    except Exception as exc:  # a valid geometry must never raise
        if record:
            record(failure_record(kw, nodes, "raised", f"{type(exc).__name__}: {exc}", 0.0))
        return [f"raised {type(exc).__name__}: {exc}"], "raised", time.perf_counter() - t0
    dt = time.perf_counter() - t0
    problems = []
    prefix = next((p for p in PREFIXES if r.status.startswith(p)), None)
    if record and prefix not in ANSWERS:
        record(failure_record(kw, nodes, prefix or r.status, r.status, dt))
    if prefix is None:
        problems.append(f"unknown status {r.status!r}")
    if dt > time_limit + MARGIN:
        problems.append(f"took {dt:.1f} s with time_limit {time_limit} s")
    if r.bistable and r.status != "ok":
        problems.append(f"bistable with status {r.status!r}")
    if r.status == "monostable" and g.h > 0:
        # an answer only from a path that ran its course: 3 h, or the geometric limit where
        # that is nearer (a cut path is a failure, never "monostable")
        from snapmorph.units.planar import push_limit

        d_end = float(r.curve[0][-1]) if len(r.curve[0]) else 0.0
        if not d_end >= min(3.0 * g.h, push_limit(g)) * (1.0 - 1e-9):
            problems.append(f"monostable on a path that ended at d = {d_end / g.h:.4g} h")
    if problems:
        print(f"  problem: {kw}: {problems}", flush=True)
    if r.status == "ok":
        vals = [r.F_cr, r.d_cr, r.d_unstable, r.d_second, r.S, r.theta_deg, r.energy_barrier,
                r.energy_stored]
        if not r.bistable:
            problems.append("ok but not bistable")
        if not np.all(np.isfinite(vals)) or not np.all(np.isfinite(r.base_shape)):
            problems.append(f"NaN/inf in an ok result: {vals}")
        else:
            # independent stability check of state (iii), at the reference scale
            gi = g.scaled(L_INTERNAL / g.L)
            import dataclasses

            gi = dataclasses.replace(gi, E=E_INTERNAL)
            m = build_unit(gi, nodes=nodes if nodes else 101)
            pos = m.structure.reference_positions.copy()
            pos[m.arch_nodes] = r.shapes["iii"]["arch"] * (L_INTERNAL / g.L)
            pos[m.base_nodes] = r.shapes["iii"]["base"] * (L_INTERNAL / g.L)
            try:
                s = state_stability(m.structure, pos, m.apex)
                if s.negative_force != 0:
                    problems.append(f"bistable with {s.negative_force} negative eigenvalues in (iii)")
            except ValueError as exc:
                problems.append(f"bistable with a singular state (iii): {exc}")
    return problems, prefix or r.status, dt


def run(n, seed=0, time_limit=5.0, nodes=41, log=None, compare=None, every=100,
        failures=None):
    """Fuzz n geometries; returns (problems [(kw, list)], status counts, slowest seconds).
    ``compare``: a second resolution each geometry is also simulated at: an answer at both
    that differs (bistable at one, not at the other) is a flag flip, a problem; counts then
    holds "<status at nodes> / <status at compare>" pairs too. ``failures``: a list that
    receives one record per failed simulation (timeout, not converged, raised): the
    geometry, its ratios, the resolution, the status and its reason."""
    rng = np.random.default_rng(seed)
    bad, counts, slowest = [], {}, 0.0
    record = None if failures is None else failures.append
    for i in range(n):
        kw = random_geometry(rng)
        problems, prefix, dt = check_one(kw, time_limit, nodes, record)
        counts[prefix] = counts.get(prefix, 0) + 1
        slowest = max(slowest, dt)
        if compare:
            more, other, dt2 = check_one(kw, time_limit, compare, record)
            slowest = max(slowest, dt2)
            problems += [f"at {compare} nodes: {m}" for m in more]
            pair = f"{prefix} / {other}"
            counts[pair] = counts.get(pair, 0) + 1
            if prefix in ANSWERS and other in ANSWERS and prefix != other:
                problems.append(f"flag flip: {prefix} at {nodes} nodes, {other} at {compare}")
        if problems:
            bad.append((kw, problems))
        if log and (i + 1) % every == 0:
            log(f"{i + 1}/{n}: {counts}, slowest {slowest:.1f} s, {len(bad)} problems")
    return bad, counts, slowest


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--n", type=int, default=3000)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--time-limit", type=float, default=5.0)
    p.add_argument("--nodes", type=int, default=41)
    p.add_argument("--compare", type=int, default=None,
                   help="a second resolution (e.g. --nodes 101 --compare 201): flag flips")
    p.add_argument("--every", type=int, default=100, help="progress line every N geometries")
    p.add_argument("--failures", default=None,
                   help="write every failed simulation (status, reason, geometry) to this "
                        "JSON file")
    a = p.parse_args(argv)
    t0 = time.perf_counter()
    failures = [] if a.failures else None
    bad, counts, slowest = run(a.n, a.seed, a.time_limit, a.nodes,
                               log=lambda m: print(m, flush=True), compare=a.compare,
                               every=a.every, failures=failures)
    if a.failures:
        import json

        os.makedirs(os.path.dirname(os.path.abspath(a.failures)), exist_ok=True)
        with open(a.failures, "w") as fh:
            json.dump(failures, fh, indent=1)
        print(f"{len(failures)} failed simulations written to {a.failures}")
    print(f"{a.n} geometries in {time.perf_counter() - t0:.0f} s: {counts}; slowest "
          f"{slowest:.1f} s (limit {a.time_limit} s); {len(bad)} with problems")
    for kw, problems in bad[:20]:
        print("  ", kw, problems)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
