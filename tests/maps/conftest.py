"""Fixtures of the maps tests: the synthetic map of `maps_synthetic`, written and loaded once."""

import pytest

from maps_synthetic import synthetic_dataset
from snapmorph.pipeline.dataset import write_netcdf


@pytest.fixture(scope="session")
def synthetic_path(tmp_path_factory):
    path = tmp_path_factory.mktemp("maps") / "synthetic.nc"
    write_netcdf(synthetic_dataset(), path)
    return path


@pytest.fixture(scope="session")
def dm(synthetic_path):
    from snapmorph.maps import DesignMap

    return DesignMap.load(synthetic_path)
