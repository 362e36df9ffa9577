"""Short reprs: printing a result in a notebook or a log shows a summary line, not kilobytes of
arrays (issue 15)."""

from __future__ import annotations

import numpy as np
import pytest

LIMIT = 400  # characters


def _unit():
    from snapmorph.design import Unit

    return Unit(L=0.1, h=0.02, t=5e-4, w=5e-3)


def _path():
    from snapmorph.solver import Structure

    x = np.linspace(0, 0.1, 41)
    st = Structure()
    rod = st.add_rod(np.stack([x, 0.01 * np.sin(np.pi * x / 0.1)], 1), width=5e-3,
                     thickness=5e-4, E=2.2e9)
    st.fix(rod.nodes[0], "xz")
    st.fix(rod.nodes[-1], "xz")
    return st.push(rod.nodes[20], direction=(0.0, -1.0), distance=0.02, method="mgdc")


def _rod():
    from snapmorph.solver import Structure

    x = np.linspace(0, 0.1, 41)
    return Structure().add_rod(np.stack([x, 0 * x + 1e-3 * np.sin(np.pi * x / 0.1)], 1),
                               width=5e-3, thickness=5e-4, E=2.2e9)


def _unit_result():
    from snapmorph.units import UnitGeometry, simulate_unit

    return simulate_unit(UnitGeometry(L=0.1, h=0.02, t=5e-4, w=5e-3), nodes=41)


def _design_map(tmp_path):
    from snapmorph.maps import DesignMap
    from tests.design import synthetic_map

    return DesignMap.load(synthetic_map.write(tmp_path / "s.nc"))


def _chain(tmp_path):
    from snapmorph.design import chain
    from snapmorph.design.lookup import MapLookup

    return chain([_unit(), _unit()], "11", lookup=MapLookup(_design_map(tmp_path)))


def _array_result():
    from snapmorph.design.arrays import simulate_array

    return simulate_array([_unit(), _unit()], "10", nodes=41)


CASES = [
    pytest.param(lambda tmp: _path(), id="solver.Path"),
    pytest.param(lambda tmp: _unit_result(), id="UnitResult"),
    pytest.param(lambda tmp: _design_map(tmp), id="DesignMap"),
    pytest.param(lambda tmp: _unit(), id="design.Unit"),
    pytest.param(lambda tmp: _rod(), id="solver.Rod"),
    pytest.param(_chain, id="design.Chain"),
    pytest.param(lambda tmp: _array_result(), id="ArrayResult"),
]


@pytest.mark.parametrize("make", CASES)
def test_repr_is_short(make, tmp_path):
    text = repr(make(tmp_path))
    assert len(text) <= LIMIT, f"{len(text)} characters: {text[:200]}..."
