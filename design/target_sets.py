"""A generated family of target sets for multi-shape design (issue 24): the tests and the
benchmark use it.

Each set is two or three targets of one length. They come from rules, not from a list of
cases known to work: set i turns Φ_i = 30° + 240° i / (count − 1) in total (30° to 270°),
its kinds come from the templates below in turn (mirror images, straight-plus-curved pieces,
S curves against C curves, three-target sets), and a seeded random generator jitters where the
straight pieces end and which way each set turns first. The length follows one sizing rule
from the turning, so that units of the map's range have room for it:
length = 0.25 m + 0.25 m × (Φ⁺ + Φ⁻) / 90°, with Φ± the largest left / right turning any
target of the set asks for.
"""

from __future__ import annotations

import numpy as np

__all__ = ["TEMPLATES", "describe", "target_family", "turning_curve"]


def turning_curve(pieces, length: float, n: int = 801) -> np.ndarray:
    """Points (n, 2) m of a curve of `length` m from (0, 0) heading +x made of pieces
    [(share of the length, turning in degrees)], each turning uniformly (0: straight)."""
    shares = np.array([float(f) for f, _ in pieces])
    if np.any(shares <= 0):
        raise ValueError(f"piece shares must be > 0, got {shares.tolist()}")
    edges = np.concatenate([[0.0], np.cumsum(shares / shares.sum())])
    turns = np.radians([float(t) for _, t in pieces])
    s = np.linspace(0.0, 1.0, n)
    ang = np.zeros(n)
    for e0, e1, a0, turn in zip(edges[:-1], edges[1:], np.concatenate([[0.0], np.cumsum(turns)]),
                                turns):
        inside = s >= e0
        ang[inside] = a0 + turn * np.clip((s[inside] - e0) / (e1 - e0), 0.0, 1.0)
    mid = 0.5 * (ang[1:] + ang[:-1])
    ds = length / (n - 1)
    steps = np.stack([np.cos(mid), np.sin(mid)], axis=-1) * ds
    return np.vstack([[0.0, 0.0], np.cumsum(steps, axis=0)])


# Each template: (name, function (Φ, f, sign) -> [pieces of each target]); f in [0.3, 0.6] is a
# straight piece's share, sign ±1 which way the set turns first.
TEMPLATES = (
    ("arc | mirror image", lambda P, f, s: [[(1, s * P)], [(1, -s * P)]]),
    ("straight+arc | arc+straight", lambda P, f, s: [[(f, 0), (1 - f, s * P)],
                                                     [(1 - f, s * P), (f, 0)]]),
    ("C | S", lambda P, f, s: [[(1, s * P)], [(1, s * P / 2), (1, -s * P / 2)]]),
    ("arc | straight+mirror | S", lambda P, f, s: [[(1, s * P)], [(f, 0), (1 - f, -s * P)],
                                                   [(1, s * P / 2), (1, -s * P / 2)]]),
    ("S | mirror image", lambda P, f, s: [[(1, s * P / 2), (1, -s * P / 2)],
                                          [(1, -s * P / 2), (1, s * P / 2)]]),
    ("arc | arc+straight | mirror image", lambda P, f, s: [[(1, s * P)], [(1 - f, s * P), (f, 0)],
                                                           [(1, -s * P)]]),
)


def _size(piece_sets) -> float:
    """The sizing rule: 0.25 m + 0.25 m (Φ⁺ + Φ⁻) / 90° (Φ±: the set's largest left / right
    turning of any target)."""
    pos = max(sum(t for _, t in p if t > 0) for p in piece_sets)
    neg = max(sum(-t for _, t in p if t < 0) for p in piece_sets)
    return 0.25 + 0.25 * (pos + neg) / 90.0


def target_family(count: int = 12, seed: int = 24) -> list:
    """`count` target sets (see the module docstring): [{"name", "turn_deg", "length" (m),
    "pieces" (per target), "targets" (per target (801, 2) points, m)}]."""
    if isinstance(count, bool) or not isinstance(count, int) or count < 2:
        raise ValueError(f"count must be an integer >= 2, got {count!r}")
    rng = np.random.default_rng(seed)
    out = []
    for i in range(count):
        turn = 30.0 + 240.0 * i / (count - 1)
        name, make = TEMPLATES[i % len(TEMPLATES)]
        f = float(rng.uniform(0.3, 0.6))
        sign = 1 if rng.random() < 0.5 else -1
        pieces = make(turn, f, sign)
        length = _size(pieces)
        out.append({"name": f"{i + 1:02d} {name}, {turn:.0f} deg",
                    "turn_deg": turn, "length": length, "pieces": pieces,
                    "targets": [turning_curve(p, length) for p in pieces]})
    return out


def describe(family) -> str:
    """One line per set (for a bench or a failing test's message)."""
    lines = []
    for s in family:
        parts = "; ".join(" + ".join(f"{100 * f / sum(g for g, _ in p):.0f}%:{t:+.0f}"
                                     for f, t in p) for p in s["pieces"])
        lines.append(f"{s['name']}: {s['length'] * 1e3:.0f} mm, pieces (share:turn deg) {parts}")
    return "\n".join(lines)
