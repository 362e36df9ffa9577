"""Circular arcs and biarcs (paper, Section 4, Fig. "inverse_steps" d).

A biarc joins two points with given tangents by two circular arcs that meet with a common
tangent (G1). Among the one-parameter family of biarcs we take the usual "equal tangent
lengths" one: with d the common distance from each end point to its arc's tangent intersection,
the junction is the midpoint of q0 = p0 + d t0 and q1 = p1 - d t1, and |q1 - q0| = 2d gives

    d² (t·t - 4) - 2 d (v·t) + v·v = 0,   v = p1 - p0,   t = t0 + t1,

whose positive root is d = (sqrt((v·t)² + (4 - t·t) v·v) - v·t) / (4 - t·t) (d = v·v / (2 v·t)
when t0 = t1, the limit). When the two end points and tangents lie on one circle, both arcs have
the curvature of that circle. Lengths in m, angles in rad, curvature signed (> 0 turns left).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Arc:
    """A circular arc (or a straight segment, k = 0): start point p (2,), start direction
    angle a (rad), signed curvature k (1/m), length s (m)."""

    p: tuple
    a: float
    k: float
    s: float

    @property
    def turn(self) -> float:
        """Signed turning angle k s (rad), > 0 to the left."""
        return self.k * self.s

    @property
    def end(self) -> np.ndarray:
        return self.point(self.s)

    @property
    def end_angle(self) -> float:
        return self.a + self.turn

    @property
    def chord(self) -> float:
        """Distance between the end points (m)."""
        return float(np.hypot(*(self.end - np.asarray(self.p))))

    def point(self, u) -> np.ndarray:
        """Point(s) at arc length u (scalar or array) from the start."""
        u = np.asarray(u, dtype=float)
        p = np.asarray(self.p, dtype=float)
        # chord u sinc(k u / 2) along the mean direction: exact, and stable as k -> 0
        chord = u * np.sinc(self.k * u / (2.0 * math.pi))
        mid = self.a + 0.5 * self.k * u
        return p + np.stack([chord * np.cos(mid), chord * np.sin(mid)], axis=-1)

    def sample(self, n: int = 33) -> np.ndarray:
        """(n, 2) points uniformly in arc length, end points included."""
        return self.point(np.linspace(0.0, self.s, n))

    def split(self, n: int) -> list["Arc"]:
        """n equal arcs covering this one."""
        ds = self.s / n
        return [Arc(_tup(self.point(i * ds)), self.a + self.k * i * ds, self.k, ds)
                for i in range(n)]


def arc_from_tangent(p0, a0: float, p1) -> Arc:
    """The arc leaving p0 in direction a0 (rad) that ends at p1."""
    p0 = np.asarray(p0, dtype=float)
    c = np.asarray(p1, dtype=float) - p0
    length = float(np.hypot(*c))
    if length == 0.0:
        raise ValueError("an arc needs two distinct end points")
    t = np.array([math.cos(a0), math.sin(a0)])
    # Turning = twice the angle from the start tangent to the chord.
    phi = 2.0 * math.atan2(t[0] * c[1] - t[1] * c[0], float(t @ c))
    s = length if abs(phi) < 1e-12 else length * (phi / 2.0) / math.sin(phi / 2.0)
    return Arc(_tup(p0), float(a0), phi / s, s)


def biarc(p0, a0: float, p1, a1: float) -> tuple[Arc, Arc]:
    """Two arcs from p0 heading a0 to p1 heading a1 (rad), G1 at their junction."""
    p0, p1 = np.asarray(p0, dtype=float), np.asarray(p1, dtype=float)
    v = p1 - p0
    vv = float(v @ v)
    if vv == 0.0:
        raise ValueError("biarc end points coincide")
    t0 = np.array([math.cos(a0), math.sin(a0)])
    t1 = np.array([math.cos(a1), math.sin(a1)])
    t = t0 + t1
    vt, tt = float(v @ t), float(t @ t)
    denom = 4.0 - tt
    if denom < 1e-12:  # parallel tangents
        if vt <= 1e-12 * math.sqrt(vv):
            raise ValueError("the tangents at two consecutive control points make a U-turn or "
                             "point backwards; add a control point between them")
        d = vv / (2.0 * vt)
    else:
        d = (math.sqrt(vt * vt + denom * vv) - vt) / denom
    q0, q1 = p0 + d * t0, p1 - d * t1
    pm = 0.5 * (q0 + q1)
    tiny = 1e-15 * math.sqrt(vv)
    if np.allclose(pm, p0, atol=tiny) or np.allclose(pm, p1, atol=tiny):
        raise ValueError("degenerate biarc (junction at an end point)")
    first = arc_from_tangent(p0, a0, pm)
    second = arc_from_tangent(pm, first.end_angle, p1)
    return first, second


def biarcs(points, angles, merge_deg: float = 1e-6) -> list[Arc]:
    """Biarcs through control points (n, 2) with tangent directions (n,) rad: 2(n - 1) arcs.

    Where two consecutive control points and their tangents lie on one circle (the chord makes
    equal angles with both tangents, within `merge_deg` degrees), the biarc is that single arc:
    it turns by the difference of the tangent directions and ends exactly at the next point.
    """
    points = np.asarray(points, dtype=float)
    angles = np.asarray(angles, dtype=float)
    out = []
    for i in range(len(points) - 1):
        single = _circular(points[i], angles[i], points[i + 1], angles[i + 1], merge_deg)
        out.extend([single] if single is not None else
                   biarc(points[i], angles[i], points[i + 1], angles[i + 1]))
    return out


def _circular(p0, a0, p1, a1, merge_deg):
    """The single arc p0 -> p1 turning a1 - a0, if the data are co-circular within merge_deg."""
    v = np.asarray(p1, dtype=float) - np.asarray(p0, dtype=float)
    chord = float(np.hypot(*v))
    phi = float(a1 - a0)
    if chord == 0.0 or abs(phi) >= 2 * math.pi:
        return None
    beta = math.atan2(v[1], v[0])
    # asymmetry: the chord's direction against the mean tangent direction, wrapped to (-pi, pi]
    delta = math.remainder(beta - 0.5 * (a0 + a1), 2 * math.pi)
    if abs(delta) > math.radians(merge_deg):
        return None
    s = chord if abs(phi) < 1e-12 else chord * (phi / 2.0) / math.sin(phi / 2.0)
    return Arc(_tup(p0), beta - phi / 2.0, phi / s, s)


def sample_arcs(arcs, per_arc: int = 33) -> np.ndarray:
    """One polyline through all arcs (shared end points once)."""
    parts = [arc.sample(per_arc) for arc in arcs]
    return np.vstack([parts[0]] + [p[1:] for p in parts[1:]])




def _tup(p) -> tuple:
    return (float(p[0]), float(p[1]))
