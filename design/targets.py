"""Target shapes for inverse design: reading, validating, and measuring deviations.

Targets are polylines in m. A CSV target has columns x, y (in mm unless its header says
otherwise: `design.targets_csv`); a third column headed tangent_deg, the tangent direction in
degrees, makes its rows control points with tangents.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np


def read_target_csv(path, units=None):
    """(points (N, 2) in m, tangent angles (N,) in degrees or None) from a CSV target: units
    from the header (x_mm, x (in), x_m, x_cm) or `units`, else mm; a third column only when its
    header names it (`design.targets_csv`)."""
    from snapmorph.design.targets_csv import read_csv

    path = Path(path)
    if not path.is_file():
        raise ValueError(f"target file not found: {path}")
    mm, tangents, _, _ = read_csv(path, units=units)
    return mm * 1e-3, tangents


def check_points(points, minimum: int, what: str = "target points") -> np.ndarray:
    """Points as a finite (N, 2) float array with at least `minimum` distinct rows."""
    p = _point_array(points, what)
    _check_finite(p, what)
    if len(p) < minimum:
        raise ValueError(f"{what}: need at least {minimum} points, got {len(p)}")
    step = np.hypot(*np.diff(p, axis=0).T)
    if np.any(step <= 1e-9 * max(np.ptp(p[:, 0]), np.ptp(p[:, 1]), 1e-12)):
        i = int(np.flatnonzero(step <= 1e-9 * max(np.ptp(p[:, 0]), np.ptp(p[:, 1]), 1e-12))[0])
        raise ValueError(f"{what}: points {i + 1} and {i + 2} coincide")
    return p


def _point_array(points, what) -> np.ndarray:
    """Points as an (N, 2) float array, or a ValueError naming `what`."""
    try:
        p = np.asarray(points, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{what} must be an (N, 2) array of numbers (m)") from None
    if p.ndim != 2 or p.shape[1] != 2:
        raise ValueError(f"{what} must be an (N, 2) array (x, y in m), got shape {p.shape}")
    return p


def _check_finite(p: np.ndarray, what) -> None:
    if not np.all(np.isfinite(p)):
        bad = int(np.flatnonzero(~np.all(np.isfinite(p), axis=1))[0])
        raise ValueError(f"{what}: point {bad + 1} is not finite (NaN or inf): {p[bad].tolist()}")


def arc_length(xy: np.ndarray) -> float:
    """Length of a polyline (m)."""
    return float(np.sum(np.hypot(*np.diff(xy, axis=0).T)))


def resample(xy: np.ndarray, n: int) -> np.ndarray:
    """n points uniformly in arc length along a polyline."""
    s = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(xy, axis=0).T))])
    u = np.linspace(0.0, s[-1], n)
    return np.stack([np.interp(u, s, xy[:, 0]), np.interp(u, s, xy[:, 1])], axis=-1)


def distances_to_polyline(points: np.ndarray, xy: np.ndarray) -> np.ndarray:
    """Distance (m) from each point (P, 2) to the polyline xy (K, 2)."""
    a = xy[:-1]
    ab = xy[1:] - a
    L2 = np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-300)
    ax = points[:, None, 0] - a[None, :, 0]
    ay = points[:, None, 1] - a[None, :, 1]
    u = np.clip((ax * ab[:, 0] + ay * ab[:, 1]) / L2, 0.0, 1.0)
    dx = ax - u * ab[:, 0]
    dy = ay - u * ab[:, 1]
    return np.sqrt(np.min(dx * dx + dy * dy, axis=1))


def deviation(predicted: np.ndarray, target: np.ndarray, n: int = 400):
    """(max, rms) distance between two curves, as fractions of the target's length.

    Symmetric: n points spread uniformly along each curve are measured against the other one;
    max is the Hausdorff distance of the two samplings, rms the root mean square of all 2n
    distances.
    """
    length = arc_length(target)
    d = deviation_vector(predicted, target, n) * length
    return float(np.max(d)) / length, float(np.sqrt(np.mean(d * d))) / length


def deviation_vector(predicted: np.ndarray, target: np.ndarray, n: int = 400) -> np.ndarray:
    """The 2n distances of `deviation`, over the target length (least-squares residuals)."""
    length = arc_length(target)
    t = resample(target, n)
    p = resample(predicted, n)
    return np.concatenate([distances_to_polyline(t, predicted),
                           distances_to_polyline(p, target)]) / length


def self_intersects(xy: np.ndarray) -> bool:
    """True when two non-adjacent segments of the polyline cross."""
    a, b = xy[:-1], xy[1:]
    n = len(a)
    if n < 3:
        return False

    def orient(p, q, r):
        return (q[..., 0] - p[..., 0]) * (r[..., 1] - p[..., 1]) - \
               (q[..., 1] - p[..., 1]) * (r[..., 0] - p[..., 0])

    i, j = np.triu_indices(n, k=2)
    keep = ~((i == 0) & (j == n - 1) & np.allclose(xy[0], xy[-1]))
    i, j = i[keep], j[keep]
    o1 = orient(a[i], b[i], a[j])
    o2 = orient(a[i], b[i], b[j])
    o3 = orient(a[j], b[j], a[i])
    o4 = orient(a[j], b[j], b[i])
    return bool(np.any((o1 * o2 < 0) & (o3 * o4 < 0)))


# --------------------------------------------------------------------------- any planar curve
#: samples of a Target's dense polyline (uniform in arc length)
TARGET_SAMPLES = 2001


class Target:
    """An open planar curve, parametrised by arc length (SI).

    `xy` (K, 2) m, uniform in arc length; `s` (K,) arc length from the start (m); `angle` (K,)
    the tangent direction (rad, unwrapped: a spiral keeps counting past 360°); `length` (m).
    Build with `Target.from_points` (a smooth curve through points in any orientation) or
    `Target.from_polyline` (a curve that already is dense, e.g. sampled biarcs).
    """

    def __init__(self, xy: np.ndarray, angle: np.ndarray, points: np.ndarray | None = None):
        self.xy = np.asarray(xy, dtype=float)
        self.angle = np.asarray(angle, dtype=float)
        self.s = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(self.xy, axis=0).T))])
        self.length = float(self.s[-1])
        self.points = self.xy if points is None else np.asarray(points, dtype=float)

    # --- construction ---------------------------------------------------------------------
    @classmethod
    def from_points(cls, points, what: str = "target points") -> "Target":
        """The curve through (N, 2) points (m, N >= 2, any orientation): a straight line for
        two points, otherwise a parametric cubic spline x(u), y(u) with u the chord length
        (not-a-knot), resampled uniformly in its true arc length. Refuses NaN, coincident
        points, zero length and self-intersection with a ValueError saying which."""
        p = _finite_points(points, what)
        if len(p) == 2:
            step = np.hypot(*(p[1] - p[0]))
            if step <= 0:
                raise ValueError(f"{what}: the target has zero length (both points coincide)")
            u = np.linspace(0.0, 1.0, TARGET_SAMPLES)[:, None]
            xy = p[0] + u * (p[1] - p[0])
            ang = np.full(TARGET_SAMPLES, math.atan2(*(p[1] - p[0])[::-1]))
            return cls(xy, ang, p)
        p = check_points(p, 3, what)
        from scipy.interpolate import CubicSpline

        u = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(p, axis=0).T))])
        spline = CubicSpline(u, p, axis=0)
        fine = np.linspace(0.0, u[-1], 8 * TARGET_SAMPLES)
        xy = spline(fine)
        s = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(xy, axis=0).T))])
        u_even = np.interp(np.linspace(0.0, s[-1], TARGET_SAMPLES), s, fine)
        xy = spline(u_even)
        d = spline(u_even, 1)
        ang = np.unwrap(np.arctan2(d[:, 1], d[:, 0]))
        target = cls(xy, ang, p)
        target._check_simple(what)
        return target

    @classmethod
    def from_polyline(cls, xy, what: str = "target") -> "Target":
        """A curve given densely (a polyline with many points, e.g. sampled arcs): resampled
        uniformly in arc length; tangent directions from the segments."""
        p = check_points(_finite_points(xy, what), 2, what)
        s = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(p, axis=0).T))])
        u = np.linspace(0.0, s[-1], TARGET_SAMPLES)
        seg = np.diff(p, axis=0)
        seg_ang = np.unwrap(np.arctan2(seg[:, 1], seg[:, 0]))
        mid = 0.5 * (s[1:] + s[:-1])
        ang = np.interp(u, mid, seg_ang) if len(mid) > 1 else np.full_like(u, seg_ang[0])
        xy = np.stack([np.interp(u, s, p[:, 0]), np.interp(u, s, p[:, 1])], axis=-1)
        target = cls(xy, ang, p)
        target._check_simple(what)
        return target

    def _check_simple(self, what):
        if self.length <= 0:
            raise ValueError(f"{what}: the target has zero length")
        if self_intersects(resample(self.xy, 600)):
            raise ValueError(f"{what}: the target crosses itself; an array's base cannot")

    # --- queries ----------------------------------------------------------------------------
    @property
    def start(self) -> np.ndarray:
        return self.xy[0].copy()

    @property
    def start_angle(self) -> float:
        return float(self.angle[0])

    @property
    def total_turn_deg(self) -> float:
        """Signed turning from start to end tangent (degrees, > 0 left)."""
        return math.degrees(self.angle[-1] - self.angle[0])

    def at_fraction(self, u) -> np.ndarray:
        """Points at fractions u (0..1) of the arc length, (len(u), 2) m."""
        s = np.asarray(u, dtype=float) * self.length
        return np.stack([np.interp(s, self.s, self.xy[:, 0]),
                         np.interp(s, self.s, self.xy[:, 1])], axis=-1)


def _finite_points(points, what):
    p = _point_array(points, what)
    if len(p) < 2:
        raise ValueError(f"{what}: need at least 2 points, got {len(p)}")
    _check_finite(p, what)
    if np.all(p == p[0]):
        raise ValueError(f"{what}: the target has zero length (all points coincide)")
    return p


def place_rigid(xy: np.ndarray, start, angle: float) -> np.ndarray:
    """A polyline that starts at (0, 0) heading +x, moved to start heading `angle` (rad)."""
    c, s = math.cos(angle), math.sin(angle)
    return xy @ np.array([[c, s], [-s, c]]) + np.asarray(start, dtype=float)


def best_rigid_placement(xy: np.ndarray, target: np.ndarray, start=(0.0, 0.0),
                         angle: float = 0.0, n: int = 200, kabsch: bool = True,
                         maxiter: int = 400):
    """The rigid placement of polyline xy (given from (0, 0) heading +x) on the target that
    minimises the max distance between the curves (`deviation`): ((x0, y0), angle) in m, rad.
    Starts from `start`, `angle` and from the least-squares fit of arc-length-matched points
    (Kabsch; unless kabsch is False), then Nelder-Mead (at most maxiter iterations) on the max
    distance of n + n samples."""
    from scipy.optimize import minimize
    from scipy.spatial import cKDTree

    # For the search only: distances to densely resampled curves (nearest sample; off by at
    # most half a sample spacing, 1/4000 of the length) through k-d trees built once, the
    # target's in its frame and the polyline's in its own. The result is measured exactly.
    length = arc_length(target)
    dense = 2000
    tree_t = cKDTree(resample(target, dense))
    tree_p = cKDTree(resample(xy, dense))
    ps, ts = resample(xy, n), resample(target, n)

    def cost(v):
        c, s = math.cos(v[2]), math.sin(v[2])
        rot = np.array([[c, s], [-s, c]])
        d1, _ = tree_t.query(ps @ rot + v[:2] * length)
        d2, _ = tree_p.query((ts - v[:2] * length) @ rot.T)
        return max(float(d1.max()), float(d2.max())) / length

    starts = [np.array([start[0] / length, start[1] / length, angle])]
    a, b = resample(xy, 200), resample(target, 200)
    ca, cb = a.mean(0), b.mean(0)
    H = (a - ca).T @ (b - cb)
    rot = math.atan2(H[0, 1] - H[1, 0], H[0, 0] + H[1, 1])
    c, s = math.cos(rot), math.sin(rot)
    x0 = cb - np.array([[c, -s], [s, c]]) @ ca
    if kabsch:
        starts.append(np.array([x0[0] / length, x0[1] / length, rot]))
    best = None
    for v0 in starts:
        res = minimize(cost, v0, method="Nelder-Mead",
                       options={"xatol": 1e-7, "fatol": 1e-8, "maxiter": maxiter,
                                "initial_simplex": v0 + np.vstack([np.zeros(3), 0.003 * np.eye(3)])})
        if best is None or res.fun < best.fun:
            best = res
    return (best.x[0] * length, best.x[1] * length), float(best.x[2])


# --------------------------------------------------------------------------- a family of targets
def example_targets() -> dict:
    """{name: (N, 2) points in m}: the family of targets the inverse-design tests and the
    benchmark use (issue 10). Sizes chosen so that units of 50-200 mm can follow them."""
    out = {}
    for turn, R in ((30, 0.30), (90, 0.20), (180, 0.15), (300, 0.12)):
        a = np.radians(np.linspace(0, turn, 121))
        out[f"arc {turn}°"] = np.stack([R * np.sin(a), R * (1 - np.cos(a))], axis=-1)
    # clothoid: curvature rising linearly from 0, turning 180° over 0.6 m
    length, turn = 0.6, math.pi
    s = np.linspace(0, length, 601)
    ang = turn * (s / length) ** 2
    ds = np.diff(s)
    mid = 0.5 * (ang[1:] + ang[:-1])
    out["clothoid 180°"] = np.vstack([[0, 0], np.cumsum(np.stack([np.cos(mid) * ds,
                                                                  np.sin(mid) * ds], -1), 0)])
    x = np.linspace(0, 0.5, 101)
    out["half-sine bump"] = np.stack([x, 0.1 * np.sin(np.pi * x / 0.5)], axis=-1)
    x = np.linspace(0, 0.8, 161)
    out["full sine wave"] = np.stack([x, 0.08 * np.sin(2 * np.pi * x / 0.8)], axis=-1)
    x = np.linspace(0, 0.6, 121)
    out["shallow parabola"] = np.stack([x, 0.045 * (1 - ((x - 0.3) / 0.3) ** 2)], axis=-1)
    R = 0.12
    a = np.linspace(0, np.pi, 121)
    first = np.stack([R * np.sin(a), R * (1 - np.cos(a))], axis=-1)  # left turn, ends at (0, 2R)
    second = np.stack([-R * np.sin(a), 2 * R + R * (1 - np.cos(a))], axis=-1)  # turns right
    out["S of two half-circles"] = np.vstack([first, second[1:]])
    phi = np.linspace(0, np.radians(400), 401)
    r = 0.10 + 0.15 * phi / phi[-1]
    out["spiral 400°"] = np.stack([r * np.cos(phi), r * np.sin(phi)], axis=-1)
    out["paper M (5 points)"] = np.array([[0.0, 0.0], [100.0, 40.0], [200.0, 15.0], [300.0, 50.0],
                                          [400.0, 0.0]]) * 1e-3
    return out
