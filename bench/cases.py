"""Benchmark cases, importable by the benchmark driver and by tests."""

from validation.arch import clamped_arch


def clamped_arch_push():
    """The clamped arch of issue 2's benchmark: 101 nodes, h/t = 10, MGDC to 2.2 h."""
    h = 10 * 0.5e-3
    st, mid, _ = clamped_arch(h)
    return st.push(mid, (0.0, -1.0), 2.2 * h, method="mgdc")


def specimen_unit(**kw):
    from snapmorph.units import UnitGeometry, simulate_unit

    return simulate_unit(UnitGeometry(L=0.1, h=0.02, t=0.5e-3, w=5e-3, b=5e-3), **kw)


def cantilever_push(n_nodes):
    """A cantilever of ``n_nodes`` nodes pushed at its tip to PL^2/EI = 10 (scaling study)."""
    import numpy as np

    from snapmorph.solver import Structure

    ds = 1.0 / (n_nodes - 1.5)
    s = -0.5 * ds + ds * np.arange(n_nodes)
    st = Structure()
    rod = st.add_rod(np.stack([s, np.zeros_like(s)], 1), width=1e-2, thickness=5e-4,
                     E=12.0 / (1e-2 * 5e-4**3))
    st.fix(0, "xz")
    st.fix(1, "xz")
    return st.push(rod.nodes[-1], (0.0, -1.0), 0.8106, method="mgdc", steps=20, critical=False)
