"""DesignMap.load: the default map, and clear errors for files that are not usable maps."""

import numpy as np
import pytest

import snapmorph.maps.designmap as designmap
from maps_synthetic import synthetic_dataset
from snapmorph.maps import DesignMap, MapFileError
from snapmorph.pipeline.dataset import write_netcdf


def test_load_reads_a_map(dm, synthetic_path):
    assert dm.path == synthetic_path
    assert dm.ranges == {"h_over_L": (0.05, 0.5), "t_over_L": (0.0025, 0.01), "w_over_L": (0.02, 0.08)}
    assert dm.samples == 17 and dm.attrs["schema_version"] == 3  # written by today's pipeline
    assert dm.states == ("released", "actuated")
    assert "synthetic.nc" in repr(dm)


def test_default_map_and_fallback(tmp_path, monkeypatch, synthetic_path):
    monkeypatch.setattr(designmap, "DEFAULT_MAP", tmp_path / "default.nc")
    monkeypatch.setattr(designmap, "CI_MAP", tmp_path / "ci.nc")
    with pytest.raises(FileNotFoundError, match="make maps"):
        DesignMap.load()
    (tmp_path / "ci.nc").write_bytes(synthetic_path.read_bytes())
    with pytest.warns(UserWarning, match="coarse CI map"):
        assert DesignMap.load().path == tmp_path / "ci.nc"
    (tmp_path / "default.nc").write_bytes(synthetic_path.read_bytes())
    assert DesignMap.load().path == tmp_path / "default.nc"


def test_missing_file(tmp_path):
    with pytest.raises(FileNotFoundError, match="nothing.nc"):
        DesignMap.load(tmp_path / "nothing.nc")


def _write(tmp_path, ds, name="bad.nc"):
    path = tmp_path / name
    write_netcdf(ds, path)
    return path


def _expect(path, match):
    with pytest.raises(MapFileError, match=match) as info:
        DesignMap.load(path)
    assert str(path) in str(info.value)
    assert isinstance(info.value, ValueError)


def test_corrupt_files(tmp_path, synthetic_path):
    junk = tmp_path / "junk.nc"
    junk.write_bytes(np.random.default_rng(0).bytes(5000))
    _expect(junk, "not a readable netCDF file")
    cut = tmp_path / "cut.nc"
    cut.write_bytes(synthetic_path.read_bytes()[:4000])
    _expect(cut, "not a readable netCDF file")


def test_wrong_schema_versions(tmp_path):
    ds = synthetic_dataset()
    ds.attrs["schema_version"] = np.int32(4)
    _expect(_write(tmp_path, ds, "v4.nc"), "schema version 4 is newer than this snapmorph reads")
    ds.attrs["schema_version"] = np.int32(0)
    _expect(_write(tmp_path, ds, "v0.nc"), "schema version 0 is not supported")
    del ds.attrs["schema_version"]
    _expect(_write(tmp_path, ds, "none.nc"), "no 'schema_version' attribute")


def test_missing_variable_or_attribute(tmp_path):
    _expect(_write(tmp_path, synthetic_dataset().drop_vars("S"), "noS.nc"), r"missing variables \['S'\]")
    ds = synthetic_dataset()
    del ds.attrs["b_over_L"]
    _expect(_write(tmp_path, ds, "nob.nc"), r"missing global attributes \['b_over_L'\]")


def test_partial_or_float_status(tmp_path):
    ds = synthetic_dataset()
    ds["status"][0, 0, 0] = -1
    _expect(_write(tmp_path, ds, "pending.nc"), "1 points are still pending")
    ds = synthetic_dataset()
    ds["status"] = ds["status"].astype(float)
    path = tmp_path / "float.nc"
    ds.to_netcdf(path, engine="netcdf4")
    _expect(path, "status has dtype float64, expected an integer")


def test_wrong_dimensions(tmp_path):
    ds = synthetic_dataset()
    ds["theta"] = ds["theta"].transpose("w_over_L", "t_over_L", "h_over_L")
    _expect(_write(tmp_path, ds, "transposed.nc"), "variable theta has dimensions")


def test_schema_1_maps_load_with_a_warning_and_answer_only_the_actuated_state(tmp_path):
    from snapmorph.maps import MapDomainError, OldSchemaWarning
    from snapmorph.maps.schema import OPTIONAL_VARS

    ds = synthetic_dataset().drop_vars([*OPTIONAL_VARS, "base_shape_released"])
    ds.attrs["schema_version"] = np.int32(1)
    path = _write(tmp_path, ds, "v1.nc")
    with pytest.warns(OldSchemaWarning, match="schema version 1: it holds no released state"):
        dm = DesignMap.load(path)
    assert dm.states == ("actuated",)
    assert np.isfinite(dm.at(0.4, 0.005, 0.05, state="actuated")["theta"])
    with pytest.raises(MapDomainError, match=r"has no released state; rebuild it \(`make maps`\)"):
        dm.at(0.4, 0.005, 0.05)
    with pytest.raises(MapDomainError, match="no variable 'theta_end'"):
        dm.value("theta_end", 0.4, 0.005, 0.05, state="actuated")
    # a schema-2 file without the released variables is refused
    ds = synthetic_dataset().drop_vars("S_released")
    _expect(_write(tmp_path, ds, "noSrel.nc"), r"missing variables \['S_released'\]")
