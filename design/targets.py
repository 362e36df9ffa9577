"""Target shapes for inverse design: reading, validating, and measuring deviations.

Targets are polylines in m. A CSV target has columns x, y in mm (an optional third column,
the tangent direction in degrees, makes its rows control points with tangents); a header line
is optional.
"""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np


def read_target_csv(path):
    """(points (N, 2) in m, tangent angles (N,) in degrees or None) from a CSV in mm."""
    path = Path(path)
    if not path.is_file():
        raise ValueError(f"target file not found: {path}")
    rows = []
    with path.open(newline="") as fh:
        for n, row in enumerate(csv.reader(fh), start=1):
            cells = [c.strip() for c in row if c.strip() != ""]
            if not cells or cells[0].startswith("#"):
                continue
            try:
                rows.append([float(c) for c in cells])
            except ValueError:
                if not rows and n == 1:
                    continue  # header
                raise ValueError(f"{path}, line {n}: not a number in {row}") from None
    if not rows:
        raise ValueError(f"{path}: no points (expected lines 'x_mm, y_mm[, tangent_deg]')")
    widths = {len(r) for r in rows}
    if len(widths) != 1 or widths.pop() not in (2, 3):
        raise ValueError(f"{path}: every line needs 2 values (x, y in mm) or 3 (x, y, tangent "
                         "angle in degrees)")
    data = np.array(rows, dtype=float)
    points = data[:, :2] * 1e-3
    tangents = data[:, 2] if data.shape[1] == 3 else None
    return points, tangents


def check_points(points, minimum: int, what: str = "target points") -> np.ndarray:
    """Points as a finite (N, 2) float array with at least `minimum` distinct rows."""
    try:
        p = np.asarray(points, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{what} must be an (N, 2) array of numbers (m)") from None
    if p.ndim != 2 or p.shape[1] != 2:
        raise ValueError(f"{what} must be an (N, 2) array (x, y in m), got shape {p.shape}")
    if not np.all(np.isfinite(p)):
        bad = int(np.flatnonzero(~np.all(np.isfinite(p), axis=1))[0])
        raise ValueError(f"{what}: point {bad + 1} is not finite (NaN or inf): {p[bad].tolist()}")
    if len(p) < minimum:
        raise ValueError(f"{what}: need at least {minimum} points, got {len(p)}")
    step = np.hypot(*np.diff(p, axis=0).T)
    if np.any(step <= 1e-9 * max(np.ptp(p[:, 0]), np.ptp(p[:, 1]), 1e-12)):
        i = int(np.flatnonzero(step <= 1e-9 * max(np.ptp(p[:, 0]), np.ptp(p[:, 1]), 1e-12))[0])
        raise ValueError(f"{what}: points {i + 1} and {i + 2} coincide")
    return p


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
