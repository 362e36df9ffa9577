"""The committed CI snapshot: a valid map, and what the pipeline recomputes today (`make check-maps`)."""

import pytest

from snapmorph.maps import CI_MAP, DesignMap
from snapmorph.cli import main


def test_ci_snapshot_is_a_valid_map():
    assert CI_MAP.is_file(), f"{CI_MAP} is missing: run `make maps-ci` and commit it"
    from snapmorph.maps.schema import SCHEMA_VERSION

    dm = DesignMap.load(CI_MAP)
    assert dm.attrs["grid"] == "ci"
    assert dm.schema_version == SCHEMA_VERSION, "stale snapshot: run `make maps-ci`"
    ok = dm.dataset.status.values == 0
    assert ok.sum() >= ok.size // 2
    # the released state exists wherever the released unit is still bistable
    standing = ok & (dm.dataset.self_standing.values == 1)
    assert standing.sum() >= ok.sum() // 2
    assert (dm.dataset.theta_released.values[standing] < dm.dataset.theta.values[standing]).all()


@pytest.mark.slow
def test_ci_snapshot_matches_a_fresh_build(capsys):
    """Fails when the solver's results changed: regenerate with `make maps-ci` if intended."""
    rc = main(["maps", "check", "--grid", "ci", "--against", str(CI_MAP), "--no-progress"])
    out = capsys.readouterr().out
    assert rc == 0, out


def test_default_map_F_cr_is_smooth_along_h():
    """No point of the committed default map sits off its neighbours in h: the force
    maximum's search once took a solve that had jumped to another equilibrium, and two
    points read F_cr 52 % and 53 % above their neighbours. F_cr L^2/EI varies smoothly with
    h/L (its largest second difference relative to the value is 0.5 % today)."""
    import numpy as np

    from snapmorph.maps import DEFAULT_MAP

    dm = DesignMap.load(DEFAULT_MAP)
    F = dm.dataset.F_cr.transpose("h_over_L", ...).values
    mid = 0.5 * (F[:-2] + F[2:])
    with np.errstate(invalid="ignore"):
        dev = np.abs(F[1:-1] - mid) / np.abs(mid)
    assert np.nanmax(dev) < 0.03, np.nanmax(dev)
