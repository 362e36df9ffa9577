"""Geometric interference of an array's parts in a state: arches of different units, an arch
and another unit's base, or two units' bases that would overlap (issue 23).

No contact mechanics: the planar model lets rods pass through each other, so a state whose
parts overlap is one the real array cannot reach (the first contact would change it). Two
parts overlap when their centrelines come closer than half the sum of their thicknesses
(the sheets would touch; crossing centrelines are the extreme case). Not checked, as the
model intends them: an arch against its own base (it passes through the base frame's hole
when snapped), the bonded flat ends of an arch (they lie on the base), and the shared node
of two neighbouring bases.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Overlap", "interference", "polyline_gap"]


@dataclass(frozen=True)
class Overlap:
    """Two parts that overlap in a state. state: its '0'/'1' string (" loaded" appended under
    the dead loads); first, second: ("arch" | "base", 0-based unit index); gap: the smallest
    centreline distance less ``clearance``, half the thicknesses' sum (m, < 0; -clearance
    where the centrelines cross); at: (x, z) m, where
    (`polyline_gap`)."""

    state: str
    first: tuple
    second: tuple
    gap: float
    at: tuple
    clearance: float = 0.0

    def __str__(self):
        (a, i), (b, j) = self.first, self.second
        where = f"at ({self.at[0] * 1e3:.1f}, {self.at[1] * 1e3:.1f}) mm"
        if self.gap <= -self.clearance:
            how = "crosses"
        else:
            how = (f"comes within {(self.gap + self.clearance) * 1e3:.3f} mm (less than the "
                   f"sheets' {self.clearance * 1e3:.2f} mm) of")
        return f"state {self.state}: the {a} of unit {i + 1} {how} the {b} of unit {j + 1} {where}"


def _point_segment(p, a, b):
    """Distances (P, S) from points p (P, 2) to segments a-b (S, 2), and the closest points."""
    ab = b - a
    denom = np.maximum(np.sum(ab * ab, axis=1), 1e-300)
    s = np.clip(np.einsum("psk,sk->ps", p[:, None, :] - a[None], ab) / denom, 0.0, 1.0)
    c = a[None] + s[..., None] * ab[None]
    return np.hypot(*(p[:, None, :] - c).transpose(2, 0, 1))


def _crossing(a0, a1, b0, b1):
    """(A, B) True where segment a0-a1 properly crosses segment b0-b1."""
    def cross(o, p, q):
        return (p[..., 0] - o[..., 0]) * (q[..., 1] - o[..., 1]) - \
            (p[..., 1] - o[..., 1]) * (q[..., 0] - o[..., 0])
    A0, A1, B0, B1 = a0[:, None], a1[:, None], b0[None], b1[None]
    d1, d2 = cross(B0, B1, A0), cross(B0, B1, A1)
    d3, d4 = cross(A0, A1, B0), cross(A0, A1, B1)
    return (d1 * d2 < 0) & (d3 * d4 < 0)


def polyline_gap(a, b) -> tuple:
    """(smallest distance m, where: the vertex of either polyline nearest the other) between
    polylines a (n, 2) and b (m, 2); 0 (and the crossing edge's midpoint on a) where they
    cross."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    cross = _crossing(a[:-1], a[1:], b[:-1], b[1:])
    if cross.any():
        i, _ = np.argwhere(cross)[0]
        return 0.0, tuple(0.5 * (a[i] + a[i + 1]))
    d_ab = _point_segment(a, b[:-1], b[1:]).min(axis=1)
    d_ba = _point_segment(b, a[:-1], a[1:]).min(axis=1)
    if d_ab.min() <= d_ba.min():
        return float(d_ab.min()), tuple(a[int(np.argmin(d_ab))])
    return float(d_ba.min()), tuple(b[int(np.argmin(d_ba))])


def _parts(model, P):
    """[(("arch" | "base", unit), polyline (k, 2), thickness m)]: each unit's base and the
    free part of its arch (tied nodes left out)."""
    tied = {a for a, _ in model.ties}
    parts = []
    for i, (u, m) in enumerate(zip(model.units, model.meshes)):
        parts.append((("base", i), P[m.base], u.t))
        if len(m.arch):
            free = [n for n in m.arch if int(n) not in tied]
            if len(free) >= 2:
                parts.append((("arch", i), P[free], u.t))
    return parts


def interference(model, positions, state: str) -> list:
    """[Overlap] of the parts of `design.arrays.ArrayModel` ``model`` at ``positions``
    (n_nodes, 2) m, labelled ``state`` (module doc for what counts)."""
    P = np.asarray(positions, float)
    parts = _parts(model, P)
    boxes = [(xy.min(axis=0), xy.max(axis=0)) for _, xy, _ in parts]
    out = []
    for p in range(len(parts)):
        (ka, i), a, ta = parts[p]
        for q in range(p + 1, len(parts)):
            (kb, j), b, tb = parts[q]
            if i == j:
                continue  # an arch against its own base: by design (module doc)
            if ka == kb == "base" and abs(i - j) == 1:  # the shared node is not an overlap
                a_, b_ = (a[:-1], b[1:]) if j == i + 1 else (a[1:], b[:-1])
            else:
                a_, b_ = a, b
            clearance = 0.5 * (ta + tb)
            lo_a, hi_a = boxes[p]
            lo_b, hi_b = boxes[q]
            if np.any(lo_a - clearance > hi_b) or np.any(lo_b - clearance > hi_a):
                continue
            gap, at = polyline_gap(a_, b_)
            if gap < clearance:
                out.append(Overlap(state, (ka, i), (kb, j), gap - clearance,
                                   (float(at[0]), float(at[1])), clearance))
    return out
