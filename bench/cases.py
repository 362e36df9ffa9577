"""Benchmark cases, importable by the benchmark driver and by tests."""

from solver.reference_models import clamped_arch


def clamped_arch_push():
    """The clamped arch of issue 2's benchmark: 101 nodes, h/t = 10, MGDC to 2.2 h."""
    h = 10 * 0.5e-3
    st, mid, _ = clamped_arch(h)
    return st.push(mid, (0.0, -1.0), 2.2 * h, method="mgdc")


def specimen_unit(**kw):
    from solver.unit import UnitGeometry, simulate_unit

    return simulate_unit(UnitGeometry(L=0.1, h=0.02, t=0.5e-3, w=5e-3, b=5e-3), **kw)
