"""Random geometries over the whole valid domain (issue 16): no hang, no "bistable" with an
unstable state (iii), no NaN in "ok" results. `make fuzz` runs 3,000 of them."""

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
