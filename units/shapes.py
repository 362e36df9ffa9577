"""Geometry helpers every unit model shares: the arch's sinusoid, arc lengths along a
polyline, and the angles measured on a base (its turning between the end tangents, the angle
of its chord). Pure functions of plain arrays; SI units (lengths in any one unit, angles in
degrees where the name says so).

The arch of every unit is z = (h/2) (1 - cos(2 pi (x - x0) / span)) over x0 <= x <= x0 + span,
flat (z = 0) outside (`arch_height`); a drawing's developed blank needs its arc length
(`sinusoid_length`), the meshes the arc length along sampled points (`cumulative_length`)
and abscissae between break points (`segment_points`).
"""

from __future__ import annotations

import math

import numpy as np


def sinusoid(x, x0, span, h):
    """z = (h/2) (1 - cos(2 pi (x - x0) / span)) at ``x`` (no flat ends): the raised arch."""
    return 0.5 * h * (1.0 - np.cos(2 * np.pi * (x - x0) / span))


def arch_height(x, x0, span, h, end=None):
    """The arch's height at ``x``: the `sinusoid` strictly between ``x0`` and ``end`` (default
    x0 + span; a unit of length L passes L - x0, the same end up to rounding), 0 outside."""
    x = np.asarray(x, dtype=float)
    end = x0 + span if end is None else end
    inside = (x > x0) & (x < end)
    return np.where(inside, sinusoid(x, x0, span, h), 0.0)


def cumulative_length(x, z):
    """(n,) arc length from the first point along the polyline through (x, z) (sampled at
    least finely enough to stand for the curve)."""
    return np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(x), np.diff(z)))])


def polyline_length(x, z) -> float:
    """Length of the polyline through the points (x, z)."""
    return float(np.sum(np.hypot(np.diff(x), np.diff(z))))


def sinusoid_length(h: float, la: float, n: int = 4001) -> float:
    """Arc length of z = (h/2)(1 - cos(2 pi x / la)) over 0 <= x <= la (any length unit):
    Simpson's rule on sqrt(1 + z'^2) with ``n`` (odd) samples."""
    x = np.linspace(0.0, la, n)
    f = np.sqrt(1.0 + (math.pi * h / la * np.sin(2 * math.pi * x / la)) ** 2)
    return float((la / (n - 1)) / 3.0 * (f[0] + f[-1] + 4 * f[1:-1:2].sum() + 2 * f[2:-1:2].sum()))


def segment_points(breaks, spacing):
    """Points along sorted ``breaks``, every interval split into equal parts no longer than
    ``spacing`` (every break point kept exactly): the abscissae of a mesh."""
    breaks = np.asarray(breaks, dtype=float)
    a, span = breaks[:-1], breaks[1:] - breaks[:-1]
    n = np.maximum(1, np.ceil(span / spacing - 1e-9).astype(np.int64))  # parts per interval
    # every interval's points a + (b - a) k / n, k = 1..n, in one pass (a Python loop over
    # the intervals cost 20 us a mesh)
    which = np.repeat(np.arange(n.shape[0]), n)
    k = np.arange(1, which.shape[0] + 1) - np.repeat(np.cumsum(n) - n, n)
    return np.concatenate([breaks[:1], a[which] + span[which] * k / n[which]])


def _wrapped_degrees(a: float) -> float:
    """The angle ``a`` (rad) wrapped to [-pi, pi), in degrees."""
    return math.degrees((a + math.pi) % (2 * math.pi) - math.pi)


def end_tangent_angle(points, up=(0.0, 0.0, 1.0)) -> float:
    """Signed angle (degrees) from the first to the last edge of a polyline: theta, > 0 when
    the line curls toward +z (``up`` in 3-D), the side the arch started on.

    Planar points (n, 2) (x, z): the difference of the edges' directions. Points in 3-D (n, 3):
    measured in the vertical plane through the chord (``up`` the vertical), which is the
    plane itself for a planar base."""
    p = np.asarray(points, dtype=float)
    if p.shape[1] == 2:
        e0, e1 = p[1] - p[0], p[-1] - p[-2]
        return _wrapped_degrees(math.atan2(e1[1], e1[0]) - math.atan2(e0[1], e0[0]))
    chord = p[-1] - p[0]
    up = np.asarray(up, dtype=float)
    along = chord - (chord @ up) * up
    n = np.linalg.norm(along)
    along = along / n if n > 0 else np.array([1.0, 0.0, 0.0])

    def angle(e):
        return math.atan2(e @ up, e @ along)

    return _wrapped_degrees(angle(p[-1] - p[-2]) - angle(p[1] - p[0]))


def chord_angle(points) -> float:
    """Signed angle (degrees) from a planar base's start tangent (first edge) to its chord
    (first to last point), points (n, 2): theta_end, theta / 2 for a symmetric base."""
    p = np.asarray(points, dtype=float)
    e0, c = p[1] - p[0], p[-1] - p[0]
    return _wrapped_degrees(math.atan2(c[1], c[0]) - math.atan2(e0[1], e0[0]))
