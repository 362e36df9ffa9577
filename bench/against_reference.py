"""The unit's path, timed beside the code of a reference commit in the same run.

    .venv/bin/python bench/against_reference.py [--ref ecfa12b] [--rounds 5]

The reference tree is the commit's files (`git archive`) under ``build/bench-ref/<commit>``,
run from there (its own top-level packages, its own numba cache). Each round runs the same
cases in two fresh processes, reference then current, so that both see the same machine
phase; a process warms the kernels first and then times warm calls. Printed: the specimen
(L 100, h 20, t 0.5, w = b = 5 mm) and 20 points of the default map grid, the median over
rounds of each process's median, and their ratio; and the same in CPU time (the process's
own, which a machine loaded by other work distorts least).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tarfile
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: the cases, run in a fresh process; {imports} differ between the trees
CASES = r'''
import json, statistics, sys, time
{imports}
g = UnitGeometry(L=0.1, h=0.02, t=0.5e-3, w=5e-3, b=5e-3)
simulate_unit(g)                     # kernels compiled or loaded from the cache
spec, spec_cpu = [], []
for _ in range({repeat}):
    t0, c0 = time.perf_counter(), time.process_time(); r = simulate_unit(g)
    spec.append(time.perf_counter() - t0); spec_cpu.append(time.process_time() - c0)
points = [tuple(p) for p in json.loads(sys.argv[1])]
solve_point(*points[0])              # the map's own settings warmed up too
t0, c0 = time.perf_counter(), time.process_time()
recs = [solve_point(*p) for p in points]
total, total_cpu = time.perf_counter() - t0, time.process_time() - c0
print(json.dumps({{"specimen_s": statistics.median(spec), "points_s": total,
                  "specimen_cpu_s": statistics.median(spec_cpu), "points_cpu_s": total_cpu,
                  "specimen": [r.status, r.F_cr, r.theta_deg],
                  "statuses": [int(rec["status"]) for rec in recs]}}))
'''

IMPORTS = {
    "reference": "from solver.unit import UnitGeometry, simulate_unit\n"
                 "from pipeline.point import solve_point",
    "current": "from snapmorph.units import UnitGeometry, simulate_unit\n"
               "from snapmorph.pipeline.kinds.unit import solve_point",
}


def map_points(n=20):
    """n points (h/L, t/L, w/L, b/L, resolution) spread evenly over the default map grid's
    points at b/L = 0 (the grid both trees' maps share), at its own resolution."""
    from snapmorph.pipeline.kinds.unit import preset

    grid = preset("default")
    pts = [p for p in grid.points() if float(p[3]) == 0.0]
    step = max(len(pts) // n, 1)
    return [(*map(float, p), grid.resolution) for p in pts[::step][:n]]


def reference_tree(commit: str) -> Path:
    """The files of ``commit`` under build/bench-ref/<commit> (extracted once)."""
    out = ROOT / "build" / "bench-ref" / commit
    if not (out / "solver").is_dir():
        out.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile() as fh:
            subprocess.run(["git", "-C", str(ROOT), "archive", commit], stdout=fh, check=True)
            fh.seek(0)
            with tarfile.open(fileobj=fh) as tar:
                tar.extractall(out)
    return out


def run_case(which: str, tree: Path, points, repeat: int) -> dict:
    env = dict(os.environ, NUMBA_NUM_THREADS="1")
    if which == "reference":
        env["PYTHONPATH"] = str(tree)
    code = CASES.format(imports=IMPORTS[which], repeat=repeat)
    out = subprocess.run([sys.executable, "-c", code, json.dumps(points)], cwd=tree, env=env,
                         capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--ref", default="ecfa12b", help="reference commit (default ecfa12b)")
    p.add_argument("--rounds", type=int, default=int(os.environ.get("BENCH_ROUNDS", "5")))
    p.add_argument("--repeat", type=int, default=7, help="warm specimen calls per process")
    args = p.parse_args(argv)
    tree = reference_tree(args.ref)
    points = map_points()
    runs = {"reference": [], "current": []}
    run_case("reference", tree, points[:1], 1)  # compiles the reference tree's kernels once
    for _ in range(args.rounds):
        for which in ("reference", "current"):
            runs[which].append(run_case(which, tree if which == "reference" else ROOT,
                                        points, args.repeat))
    keys = ("specimen_s", "points_s", "specimen_cpu_s", "points_cpu_s")
    med = {w: {k: statistics.median(r[k] for r in rs) for k in keys} for w, rs in runs.items()}
    ref, cur = med["reference"], med["current"]
    print(f"unit path against {args.ref} ({args.rounds} alternating rounds of fresh processes, "
          f"median of medians, one thread):")
    print(f"  specimen: {ref['specimen_s'] * 1e3:.1f} ms ({args.ref}) vs "
          f"{cur['specimen_s'] * 1e3:.1f} ms now: x{ref['specimen_s'] / cur['specimen_s']:.2f}")
    print(f"  20 default-map points: {ref['points_s']:.3f} s vs {cur['points_s']:.3f} s: "
          f"x{ref['points_s'] / cur['points_s']:.2f}")
    print(f"  CPU time (this process only; what a loaded machine blurs least): specimen "
          f"{ref['specimen_cpu_s'] * 1e3:.1f} vs {cur['specimen_cpu_s'] * 1e3:.1f} ms: "
          f"x{ref['specimen_cpu_s'] / cur['specimen_cpu_s']:.2f}; 20 points "
          f"{ref['points_cpu_s']:.3f} vs {cur['points_cpu_s']:.3f} s: "
          f"x{ref['points_cpu_s'] / cur['points_cpu_s']:.2f}")
    a, b = runs["reference"][-1], runs["current"][-1]
    same = a["statuses"] == b["statuses"]
    print(f"  statuses of the 20 points {'identical' if same else 'DIFFER'}; specimen "
          f"{args.ref} {a['specimen']} vs now {b['specimen']}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
