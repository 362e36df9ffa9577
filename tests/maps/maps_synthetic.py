"""A synthetic three-axis map (b/L = 0) whose fields the interpolation reproduces exactly.

theta = 10 + 150 h + 3 ln t + 2 ln w and S = 1 - 0.5 h + 0.01 ln t are linear, and
F_cr = 40 exp(2 h) t^-0.5 w^0.25 is log-linear, in the interpolation coordinates
(h, ln t, ln w), so any off-grid query must return the formula's value. Points with
h < h_b(t) = 0.125 + 8 t are monostable; one interior point failed (status 2). The released
state turns RELEASED_TURN degrees less (theta_released, linear too) and exists where the
released unit is self-standing, h >= 0.3; theta_end is half of each theta.
"""

import math

import numpy as np

from snapmorph.pipeline.batch import new_block
from snapmorph.pipeline.dataset import assemble
from snapmorph.pipeline.kinds.unit import SPEC, Grid

GRID = Grid(h_over_L=tuple(round(0.05 * k, 10) for k in range(1, 11)),  # 0.05 .. 0.5
            t_over_L=(0.0025, 0.005, 0.0075, 0.01), w_over_L=(0.02, 0.05, 0.08), samples=17)
FAILED = (0.35, 0.005, 0.05)  # status 2
RELEASED_TURN = 1.5  # degrees
H_STANDING = 0.3  # self-standing from here up


def theta_released(h, t, w):
    return theta(h, t, w) - RELEASED_TURN


def S_released(h, t, w):
    return S(h, t, w) + 0.002


def theta(h, t, w):
    return 10 + 150 * h + 3 * np.log(t) + 2 * np.log(w)


def S(h, t, w):
    return 1 - 0.5 * h + 0.01 * np.log(t)


def F_cr(h, t, w):
    return 40 * np.exp(2 * h) * t**-0.5 * w**0.25


def boundary(t):
    return 0.125 + 8 * t


def shape(h, t, w, samples=GRID.samples, released=False):
    th = math.radians(theta_released(h, t, w) if released else theta(h, t, w))
    s = np.linspace(0, 1, samples)
    return np.column_stack([np.sin(th * s) / th, (1 - np.cos(th * s)) / th])


def synthetic_dataset(grid=GRID):
    pts = grid.points()
    total = new_block(SPEC, np.arange(grid.size), grid.options)
    for i, (h, t, w) in enumerate(pts):
        if np.allclose((h, t, w), FAILED):
            total["status"][i] = 2
            continue
        total["F_cr"][i] = F_cr(h, t, w)
        total["d_cr"][i] = 0.3 * h
        total["bifurcation"][i] = 0
        if h < boundary(t):
            total["status"][i] = 1
            continue
        total["status"][i] = 0
        total["bistable"][i] = 1
        total["self_standing"][i] = 1 if h >= H_STANDING else 0
        total["theta"][i] = theta(h, t, w)
        total["theta_end"][i] = theta(h, t, w) / 2
        total["S"][i] = S(h, t, w)
        if h >= H_STANDING:
            total["theta_released"][i] = theta_released(h, t, w)
            total["theta_end_released"][i] = theta_released(h, t, w) / 2
            total["S_released"][i] = S_released(h, t, w)
            total["base_shape_released"][i] = shape(h, t, w, grid.samples, released=True)
        for name, k in (("d_unstable", 0.9), ("d_second", 1.7), ("energy_barrier", 2.0), ("energy_stored", 1.0)):
            total[name][i] = k * h
        total["base_shape"][i] = shape(h, t, w, grid.samples)
    total["solve_time"][:] = 0.01
    prov = {"created": "2026-01-01T00:00:00+00:00", "package_version": "0.1.0", "git_commit": "test"}
    return assemble(SPEC, grid, total, grid.options, prov)
