"""The failure classes of issue 26, run on the code of a reference commit and on this tree.

    .venv/bin/python tests/units/reference_check.py [--ref ecfa12b]

Each case runs in a fresh process, once in the reference tree (the commit's files under
build/bench-ref/<commit>, extracted by bench/against_reference.py) and once here; printed:
the case, what the reference answers and what this tree answers. The committed tests
(tests/units/test_failure_classes.py) check the same cases on this tree only.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

IMPORTS = {
    "reference": "from solver.unit import UnitGeometry, simulate_unit\n"
                 "import solver.structure as structure",
    "current": "from snapmorph.units import UnitGeometry, simulate_unit\n"
               "import snapmorph.solver.structure as structure",
}

#: name -> a snippet printing one JSON line (the answer to compare)
CASES = {
    "step cap (MGDC stopped at 30 steps)": r'''
push = structure.Structure.push
structure.Structure.push = lambda self, *a, **k: push(self, *a, **dict(k, max_steps=30))
r = simulate_unit(UnitGeometry(L=0.1, h=0.02, t=0.5e-3, w=5e-3, b=5e-3))
print(json.dumps([r.status[:120], len(r.curve[1])]))
''',
    "snap-back crossing, second state past 3 h (b/L = 0.31)": r'''
g = UnitGeometry(L=0.1, h=0.017120933, t=0.48361934e-3, w=5e-3, b=0.031255470)
out = []
for n in (101, 201):
    r = simulate_unit(g, nodes=n)
    out.append([n, r.status[:80], r.d_second / g.h, r.S, float(min(r.curve[1]) / r.F_cr)])
print(json.dumps(out))
''',
    "tall arch (h/L = 0.82, time limit 20 s)": r'''
g = UnitGeometry(L=0.1, h=0.08188, t=0.928e-3, w=5e-3, b=0.00388)
r = simulate_unit(g, time_limit=20)
print(json.dumps([r.status[:60], r.reason[-60:], len(r.curve[1])]))
''',
}

#: a unit at extreme scale: the specimen's proportions at base length L (m), modulus E (Pa)
EXTREME = r'''
try:
    L, E = {L!r}, {E!r}
    r = simulate_unit(UnitGeometry(L=L, h=0.2 * L, t=0.005 * L, w=0.05 * L, b=0.05 * L, E=E,
                                   joint_length=0.03175 * L))
    print(json.dumps(["result", r.status[:80], r.F_cr]))
except Exception as exc:
    print(json.dumps([type(exc).__name__, str(exc)[:100]]))
'''
for _L, _E in ((1e153, 2.2e9), (1e-300, 2.2e9), (0.1, 1e-300)):
    CASES[f"L = {_L:g} m, E = {_E:g} Pa"] = EXTREME.format(L=_L, E=_E)


def run(which: str, tree: Path, snippet: str):
    env = dict(os.environ, NUMBA_NUM_THREADS="1")
    if which == "reference":
        env["PYTHONPATH"] = str(tree)
    code = "import json\n" + IMPORTS[which] + "\n" + snippet
    out = subprocess.run([sys.executable, "-c", code], cwd=tree, env=env, capture_output=True,
                         text=True)
    lines = out.stdout.strip().splitlines()
    return json.loads(lines[-1]) if lines else ["crashed", out.stderr.strip()[-200:]]


def main(argv=None):
    from bench.against_reference import reference_tree

    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--ref", default="ecfa12b")
    args = p.parse_args(argv)
    tree = reference_tree(args.ref)
    for name, snippet in CASES.items():
        print(f"{name}:\n  {args.ref}: {run('reference', tree, snippet)}\n"
              f"  now:     {run('current', ROOT, snippet)}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
