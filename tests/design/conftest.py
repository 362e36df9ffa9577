"""Fixtures: a synthetic schema-conformant design map (see synthetic_map.py)."""

from __future__ import annotations

import pytest

import synthetic_map


@pytest.fixture(scope="session")
def synthetic_map_path(tmp_path_factory):
    return synthetic_map.write(tmp_path_factory.mktemp("maps") / "synthetic.nc")


@pytest.fixture(scope="session")
def design_map(synthetic_map_path):
    """The synthetic map, loaded through maps.DesignMap."""
    from snapmorph.maps import DesignMap

    return DesignMap.load(synthetic_map_path)


@pytest.fixture(scope="session")
def lookup(design_map):
    from snapmorph.design.lookup import MapLookup

    return MapLookup(design_map)


@pytest.fixture(scope="session")
def dm():
    """The committed default design map (its deprecation and provenance warnings hushed)."""
    import warnings

    from snapmorph.design.lookup import load_map

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return load_map()
