"""From the pieces a drawing is made of to the one open curve that is the target.

A drawing program writes a curve as pieces: an Inkscape path with several subpaths, a LINE and
an ARC that FreeCAD wrote for one wire, the SPLINEs and LWPOLYLINE of Inkscape's DXF export.
The readers (`targets_svg`, `targets_dxf`) turn every drawn element into `Piece`s (points in mm
in the target's frame); here pieces whose ends meet within `JOIN_TOL_MM` are chained into
curves, closed curves are set aside (never targets), and exactly one open curve is chosen:
the only one, or the one `select` names (an element id, a layer or group name, a DXF handle).
Every refusal is a `TargetError` (a ValueError) whose `reason` names the case.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

#: ends of pieces closer than this (mm) are the same point: chained into one curve
JOIN_TOL_MM = 0.05
#: a curve whose z varies by more than this (mm) is not planar
PLANAR_TOL_MM = 0.01
#: at most this many candidates are named in a refusal
LISTED = 12

REASONS = ("unreadable", "no-curve", "closed", "several-candidates", "not-selected", "branched",
           "non-planar", "units", "too-short", "too-long", "probably-metres")


class TargetError(ValueError):
    """A target file that cannot be read as one open curve; `reason` is one of `REASONS`,
    the message (one line, lengths in mm) says why and how to choose."""

    def __init__(self, message: str, reason: str):
        super().__init__(message)
        self.reason = reason


@dataclass
class Piece:
    """One drawn piece: points (k, 3) in mm (x, y in the target's frame, z as drawn).

    `label` names it in messages ("path#curveA", "ARC 2F on layer 0"); `names` are what a
    `select` may call the piece itself (element id, DXF handle); `groups` what it may call a
    set of pieces (layer names, group ids and labels, block names); `order` its place in the
    file (chains keep the direction of their first piece)."""

    points: np.ndarray
    label: str
    closed: bool = False
    names: frozenset = frozenset()
    groups: frozenset = frozenset()
    order: int = 0

    @property
    def length(self) -> float:
        return _length(self.points)


@dataclass
class Curve:
    """Pieces chained end to end: points (n, 3) mm; closed when its ends meet."""

    points: np.ndarray
    pieces: list = field(default_factory=list)
    closed: bool = False
    branched: bool = False

    @property
    def length(self) -> float:
        return _length(self.points)

    @property
    def z_range(self) -> float:
        return float(np.ptp(self.points[:, 2])) if len(self.points) else 0.0

    @property
    def label(self) -> str:
        names = [p.label for p in sorted(self.pieces, key=lambda p: p.order)]
        text = names[0] if len(names) == 1 else f"{names[0]} + {len(names) - 1} more"
        groups = sorted(set().union(*(p.groups for p in self.pieces)) - set().union(
            *(p.names for p in self.pieces)))
        layer = [g for g in groups if g.startswith("layer ")]
        if layer and layer[0] not in text:
            text += f" ({layer[0]})"
        return text

    def describe(self) -> str:
        kind = ("branched" if self.branched else "closed" if self.closed else
                "non-planar" if self.z_range > PLANAR_TOL_MM else "")
        return f"{self.label}, {self.length:.2f} mm" + (f", {kind}" if kind else "")


def _length(p: np.ndarray) -> float:
    return float(np.sum(np.linalg.norm(np.diff(p, axis=0), axis=1))) if len(p) > 1 else 0.0


def chain_pieces(pieces, tol_mm: float = JOIN_TOL_MM) -> list:
    """Curves made of the pieces, in file order of their first piece.

    Open pieces whose end points lie within tol_mm of each other are joined (a point where
    three or more ends meet makes a `branched` curve: no single path through it). A chain
    runs in the direction of its earliest piece in the file; its joints are the pieces' own
    end points (the first piece's where they differ by less than tol_mm)."""
    from scipy.spatial import cKDTree

    curves, open_ = [], []
    for p in pieces:
        if len(p.points) < 2 or p.length <= 0:
            continue
        if p.closed or (len(p.points) > 2 and
                        np.linalg.norm(p.points[-1] - p.points[0]) <= tol_mm):
            curves.append(Curve(p.points, [p], closed=True))
        else:
            open_.append(p)
    if open_:
        ends = np.array([q.points[k] for q in open_ for k in (0, -1)])  # piece i: 2i, 2i+1
        n = len(ends)
        close = np.array(sorted(cKDTree(ends).query_pairs(tol_mm)), dtype=int).reshape(-1, 2)
        node = _components(n, close)  # ends within tol_mm are one node
        same_piece = np.arange(n).reshape(-1, 2)
        piece_set = _components(n, np.vstack([close, same_piece]))
        for c in np.unique(piece_set[::2]):
            idx = [i for i in range(len(open_)) if piece_set[2 * i] == c]
            curves.append(_walk([open_[i] for i in idx], [node[2 * i] for i in idx],
                                [node[2 * i + 1] for i in idx]))
    return sorted(curves, key=lambda cv: min(p.order for p in cv.pieces))


def _components(n: int, pairs: np.ndarray) -> np.ndarray:
    """Connected-component label of each of n nodes joined by the (k, 2) index pairs."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n, n))
    return connected_components(graph, directed=False)[1]


def _walk(pieces, starts, ends) -> Curve:
    """The pieces of one connected set as a path from one free end to the other (or round a
    cycle), oriented like the earliest piece; a node with three or more ends is a branch."""
    from collections import Counter, defaultdict

    degree = Counter(starts) + Counter(ends)
    if max(degree.values()) > 2:
        pts = np.vstack([p.points for p in sorted(pieces, key=lambda p: p.order)])
        return Curve(pts, list(pieces), branched=True)
    at = defaultdict(list)
    for i, (a, b) in enumerate(zip(starts, ends)):
        at[a].append(i)
        at[b].append(i)
    first = min(range(len(pieces)), key=lambda i: pieces[i].order)
    # from the first piece walk forwards, then from its start walk backwards
    forward = _follow(first, ends[first], at, starts, ends)
    used = {first, *(i for i, _ in forward)}
    backward = [] if len(used) == len(pieces) else _follow(first, starts[first], at, starts, ends)
    seq = [(i, not rev) for i, rev in reversed(backward)] + [(first, False)] + forward
    parts = []
    for k, (i, rev) in enumerate(seq):
        p = pieces[i].points[::-1] if rev else pieces[i].points
        parts.append(p if k == 0 else p[1:])
    pts = np.vstack(parts)
    closed = len(seq) > 1 and all(degree[v] == 2 for v in degree)
    return Curve(pts, [pieces[i] for i, _ in seq], closed=closed)


def _follow(i, node, at, starts, ends):
    """[(piece, reversed)] walking on from piece i's end `node` until a free end (or back)."""
    out, seen = [], {i}
    while True:
        nxt = [j for j in at[node] if j not in seen]
        if not nxt:
            return out
        j = nxt[0]
        seen.add(j)
        rev = ends[j] == node and starts[j] != node
        out.append((j, rev))
        node = starts[j] if rev else ends[j]


def choose(curves, select=None, where: str = "target") -> Curve:
    """The one open, planar curve of a drawing, or the one `select` names.

    `select` names a piece (id, handle: its curve is taken) or a group (layer, group: only
    its pieces are chained); without it the drawing must hold exactly one open curve."""
    if select is not None:
        select = str(select)
        pieces = [p for c in curves for p in c.pieces]
        if any(select in p.groups for p in pieces):
            curves = chain_pieces([p for p in pieces if select in p.groups])
        else:
            curves = [c for c in curves if any(select in p.names for p in c.pieces)]
            if not curves:
                known = sorted({n for p in pieces for n in (*p.names, *p.groups)})
                raise TargetError(f"{where}: nothing called {select!r} (ids, layers and handles "
                                  f"in the file: {_some(known)})", "not-selected")
    usable = [c for c in curves if not c.closed and not c.branched]
    if not usable:
        if not curves:
            raise TargetError(f"{where}: no curve in the drawing (draw the target as one open "
                              "path, polyline, line or arc)", "no-curve")
        if all(c.closed for c in curves):
            raise TargetError(f"{where}: only closed curves ({_list(curves)}); a closed curve is "
                              "never a target: draw an open curve (an array's base has two ends)",
                              "closed")
        raise TargetError(f"{where}: the pieces branch (three or more ends meet at one point: "
                          f"{_list(curves)}); delete the extra piece or select one", "branched")
    if len(usable) > 1:
        how = "select one" + ("" if select is None else f" inside {select!r}")
        raise TargetError(f"{where}: {len(usable)} open curves, {how} by id, layer or handle "
                          f"(--select): {_list(usable)}", "several-candidates")
    curve = usable[0]
    if curve.z_range > PLANAR_TOL_MM:
        raise TargetError(f"{where}: {curve.label} is not planar (z varies by "
                          f"{curve.z_range:.2f} mm over {curve.length:.2f} mm); draw the target "
                          "flat in the XY plane", "non-planar")
    return curve


def _list(curves) -> str:
    items = [c.describe() for c in curves[:LISTED]]
    more = len(curves) - len(items)
    return "; ".join(items) + (f"; and {more} more" if more > 0 else "")


def _some(names) -> str:
    return ", ".join(names[:20]) + (f", ... ({len(names)} in all)" if len(names) > 20 else "") \
        if names else "none"
