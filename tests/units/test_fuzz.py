"""Random geometries over the whole valid domain (issue 16): no hang, no "bistable" with an
unstable state (iii), no NaN in "ok" results. `make fuzz` runs 1,000 of them at 101 and 201
nodes."""

import os
import sys

import pytest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from fuzz_units import run  # noqa: E402


@pytest.mark.slow
def test_random_geometries_over_the_valid_domain():
    bad, counts, slowest = run(300, seed=1, time_limit=1.0, nodes=41)
    assert not bad, bad[:5]
    assert sum(counts.values()) == 300
    assert counts.get("ok", 0) >= 30, counts  # the sweep does reach bistable units
    assert slowest < 1.0 + 30.0


def test_a_sample_at_two_resolutions_has_no_flag_flips_and_no_monostable_cut_path():
    bad, counts, _ = run(4, seed=3, time_limit=5.0, nodes=41, compare=81)
    assert not bad, bad[:3]
    assert sum(v for k, v in counts.items() if " / " not in k) == 4


def test_failed_simulations_are_recorded_with_their_geometry_and_ratios(tmp_path):
    """``--failures``: every simulation that ends "not converged" or "timeout" (an answer
    is not a failure) is written with its geometry, its ratios to L, the resolution and the
    reason, so that the failures can be checked against the documented classes
    (docs/model-notes.md item 11)."""
    import json

    from fuzz_units import ANSWERS, main

    out = tmp_path / "sub" / "failures.json"
    # a limit of a microsecond cuts every simulation with an arch short (a timeout)
    main(["--n", "12", "--seed", "5", "--nodes", "41", "--time-limit", "1e-6", "--every", "50",
          "--failures", str(out)])
    records = json.loads(out.read_text())
    assert len(records) >= 10
    for r in records:
        assert not r["status"].startswith(ANSWERS) and r["nodes"] == 41
        assert r["geometry"]["L"] > 0 and 0 <= r["b_over_L"] < 0.5 and r["reason"]
        assert abs(r["h_over_L"] - r["geometry"]["h"] / r["geometry"]["L"]) < 1e-12
