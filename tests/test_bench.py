"""The benchmarks' own checks (`make bench`): what they compare must not crash on the maps."""

import sys
from pathlib import Path

import numpy as np
import xarray as xr

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from bench.bench_pipeline import same_values  # noqa: E402


def test_the_resume_check_compares_maps_with_text_variables():
    """The kill -9 / resume bench compares the resumed map with the uninterrupted one: a map
    holds a text variable (strain_where) beside NaN-bearing numbers (it crashed on it)."""
    with xr.open_dataset(ROOT / "maps" / "data" / "ci.nc") as ds:
        a = ds.load()
    assert any(a[v].values.dtype.kind == "U" for v in a.data_vars)
    assert any(np.isnan(a[v].values).any() for v in a.data_vars
               if a[v].values.dtype.kind == "f")
    b = a.copy(deep=True)
    assert same_values(a, b)
    text = next(v for v in a.data_vars if a[v].values.dtype.kind == "U")
    b[text].values.flat[0] = "elsewhere"
    assert not same_values(a, b)
    c = a.copy(deep=True)
    number = next(v for v in a.data_vars if a[v].values.dtype.kind == "f")
    c[number].values.flat[np.flatnonzero(np.isfinite(c[number].values))[0]] += 1.0
    assert not same_values(a, c)
