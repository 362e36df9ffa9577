"""The unit's metrics do not depend on how finely its path is sampled.

The second-order predictor (`solver.mgdc`) lets the push's steps grow, so its samples are
fewer (26 for the specimen instead of 34). Whatever a metric reads between the samples is
located by displacement-controlled solves. Each case here is a map point where a coarser
path gave a different answer: a sample-resolution metric, or a crossing stepped over in one
step. It is checked against the same unit pushed with 300 first steps (15x finer)."""

import numpy as np
import pytest

from snapmorph.pipeline.kinds.unit import _joint_length
from snapmorph.units import UnitGeometry, simulate_unit
from snapmorph.units.push_through import zero_crossings

L = 0.1


def _unit(h, t, w, b):
    """The map's unit at (h/L, t/L, w/L, b/L) (L = 100 mm, its joint)."""
    return UnitGeometry(L=L, h=h * L, t=t * L, w=w * L, b=b * L, E=2.2e9,
                        joint_length=_joint_length(L))


def test_a_crossing_whose_counts_differ_while_d_increases_is_read_by_its_slope():
    """F_min between two samples, the zero after it: the sample nearer the zero is the one
    before the minimum (1 negative eigenvalue), yet the zero is the stable state (iii)."""
    d = np.array([1.56, 1.97, 2.50])
    F = np.array([0.25, -0.196, 0.214])
    neg = np.array([1, 1, 0])
    assert zero_crossings(d, F, neg=neg) == [(1, -1), (2, 1)]
    # equal counts still decide, whatever the slope (a snap-back crossing)
    assert zero_crossings(d, F, neg=np.array([1, 1, 1])) == [(1, -1), (2, -1)]


@pytest.mark.parametrize("point", [(0.05, 0.01125, 0.07, 0.05), (0.05, 0.0125, 0.07, 0.05)])
def test_a_unit_whose_minimum_is_stepped_over_with_its_second_zero_is_bistable(point):
    """Two points of the default map where one step went from below the minimum of F to
    past its second zero; they were called monostable (the path then pushed on to 10 h)."""
    g = _unit(*point)
    coarse, fine = simulate_unit(g), simulate_unit(g, steps=300)
    assert fine.status == "ok" and fine.bistable
    assert coarse.status == "ok" and coarse.bistable, coarse.reason
    assert coarse.d_second == pytest.approx(fine.d_second, rel=1e-9)


@pytest.mark.parametrize("point", [(0.07, 0.0125, 0.1, 0.05), (0.09, 0.0125, 0.08, 0.05),
                                   (0.06, 0.01, 0.07, 0.05)])
def test_the_largest_strain_is_located_between_the_samples(point):
    """The strain peaks between state (ii) and the samples after it: read off the samples,
    it came out 1.0-1.7 % low at these points."""
    g = _unit(*point)
    coarse, fine = simulate_unit(g), simulate_unit(g, steps=300)
    assert coarse.strain_max == pytest.approx(fine.strain_max, rel=1e-6)
    assert coarse.strain_where == fine.strain_where


@pytest.mark.parametrize("point", [(0.27, 0.005, 0.07, 0.0), (0.06, 0.01, 0.05, 0.05)])
def test_the_snap_back_load_is_the_first_maximum_whatever_the_steps(point):
    """With steps that grow, the snap-back push stepped past its first maximum and F_back
    came out 1.2-2.4 % off at these points."""
    g = _unit(*point)
    coarse, fine = simulate_unit(g), simulate_unit(g, steps=300)
    assert np.isfinite(fine.F_back)
    assert coarse.F_back == pytest.approx(fine.F_back, rel=1e-6)


@pytest.mark.parametrize("point, name", [((0.08, 0.01125, 0.06, 0.05), "F_min"),
                                         ((0.06, 0.0125, 0.09, 0.0), "F_back"),
                                         ((0.07, 0.00875, 0.07, 0.05), "F_back")])
def test_a_sharp_extremum_between_far_samples_is_located(point, name):
    """The polynomial through far samples put two solves side by side 6e-5 m from the
    extremum (F_min 8.8e-4 too shallow here, F_back 3.4e-3 low); their slope now says so
    and Brent's search takes over."""
    g = _unit(*point)
    coarse, fine = simulate_unit(g), simulate_unit(g, steps=300)
    assert getattr(coarse, name) == pytest.approx(getattr(fine, name), rel=1e-6)
