"""The set-up of one unit simulation, piece by piece, on the specimen (L 100, h 20, t 0.5,
w = b = 5 mm, 101 nodes): meshing (`build_unit`), a variant of the mesh, a system of a new
and of a known DOF ordering, supernodes, a push control, a state from positions, a probe;
and the time `simulate_unit` spends in them (each outermost call of these set-up functions
timed inside 30 warm simulations, the smallest sum) next to its whole time.

    .venv/bin/python bench/bench_setup.py

Each figure is the minimum over many calls (BENCH_REPS, default 2000): the machine is
shared, and the minimum is what the code costs when nothing else runs. A simulation's
set-up sum includes the timer's own overhead (about 0.2 us per timed call, ~100 calls).
"""

from __future__ import annotations

import os
import sys
import time

import numpy as np

os.environ.setdefault("NUMBA_NUM_THREADS", "1")
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

from bench.timing import best_time  # noqa: E402

REPS = int(os.environ.get("BENCH_REPS", "2000"))
UNIT_RUNS = int(os.environ.get("BENCH_UNIT_RUNS", "30"))


def best(fn, reps=REPS):
    """The fastest of ``reps`` calls of ``fn`` (s) (`bench.timing.best_time`)."""
    return best_time(fn, reps)


def specimen():
    from snapmorph.units import UnitGeometry

    return UnitGeometry(L=0.1, h=0.02, t=0.5e-3, w=5e-3, b=5e-3)


def piece_times():
    """{name: s per call} of the set-up pieces on the specimen's mesh."""
    from snapmorph.solver.problem import make_control, state_from
    from snapmorph.solver.states import DisplacementProbe
    from snapmorph.units.geometry import build_unit

    g = specimen()
    model = build_unit(g)
    st = model.structure
    X = st.reference_positions.copy()

    def new_ordering():
        st._orderings = (st._cache, {})  # forget the orderings: the next one is built anew
        return st.reduced_system(normalized=True)

    def supernodes():
        st._supernodes_memo = None
        return st.supernodes()

    return {
        "build_unit": best(lambda: build_unit(g), REPS // 5),
        "UnitModel.variant": best(lambda: model.variant(actuator=False)),
        "reduced_system, new ordering": best(new_ordering),
        "reduced_system, known ordering": best(lambda: st.reduced_system(normalized=True)),
        "supernodes (rebuilt)": best(supernodes),
        "make_control": best(lambda: make_control(st, model.apex, (0.0, -1.0), 0.01, "mgdc")),
        "state_from positions": best(lambda: state_from(st, X)),
        "DisplacementProbe": best(lambda: DisplacementProbe(st, model.apex)),
    }


#: the set-up functions timed inside a simulation: (module, function or Class.method)
SETUP = [
    ("snapmorph.units.geometry", "build_unit"),
    ("snapmorph.units.geometry", "UnitModel.variant"),
    ("snapmorph.solver.structure", "Structure.reduced_system"),
    ("snapmorph.solver.structure", "Structure.initial_state"),
    ("snapmorph.solver.problem", "make_control"),
    ("snapmorph.solver.problem", "state_from"),
    ("snapmorph.solver.states", "DisplacementProbe.__init__"),
    ("snapmorph.solver.constraints", "ConstrainedStructure.supernodes"),
    ("snapmorph.solver.constraints", "ConstrainedStructure.fixed_components"),
    ("snapmorph.solver.constraints", "ConstrainedStructure.copy"),
    ("snapmorph.solver.constraints", "ConstrainedStructure.positions_of"),
]


def _timed(spent, fn, depth):
    """``fn`` adding its time to ``spent[0]`` when no other timed call is running."""
    def timed(*args, **kw):
        if depth[0]:
            return fn(*args, **kw)
        depth[0] = 1
        t0 = time.perf_counter()
        try:
            return fn(*args, **kw)
        finally:
            spent[0] += time.perf_counter() - t0
            depth[0] = 0
    return timed


def unit_times():
    """(min s of a warm simulate_unit, min s of its set-up) of the specimen, set-up timed in
    separate runs (the timers wrap the functions where every module refers to them)."""
    import importlib

    from snapmorph.units import simulate_unit

    g = specimen()
    for _ in range(3):
        simulate_unit(g)
    whole = best(lambda: simulate_unit(g), UNIT_RUNS)
    spent, depth = [0.0], [0]
    for modname, name in SETUP:
        module = importlib.import_module(modname)
        if "." in name:
            cls_name, attr = name.split(".")
            cls = getattr(module, cls_name)
            setattr(cls, attr, _timed(spent, cls.__dict__[attr], depth))
            continue
        fn = getattr(module, name)
        wrapped = _timed(spent, fn, depth)
        for m in list(sys.modules.values()):
            if getattr(m, "__name__", "").startswith("snapmorph"):
                for key, value in list(vars(m).items()):
                    if value is fn:
                        setattr(m, key, wrapped)
    setup = np.inf
    for _ in range(UNIT_RUNS):
        spent[0] = 0.0
        simulate_unit(g)
        setup = min(setup, spent[0])
    return whole, setup


def main():
    for name, t in piece_times().items():
        print(f"{name:32s} {t * 1e6:8.1f} us")
    whole, setup = unit_times()
    print(f"{'simulate_unit (specimen)':32s} {whole * 1e3:8.2f} ms  (min of {UNIT_RUNS})")
    print(f"{'  of which set-up':32s} {setup * 1e3:8.2f} ms  (min of {UNIT_RUNS})")


if __name__ == "__main__":
    main()
