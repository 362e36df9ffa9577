"""Sheets of 2-D units snapped cell by cell, and their memory (issue 25).

    >>> from snapmorph.units.sheet import build_sheet, simulate_sheet
    >>> sheet = build_sheet(UnitGeometry(L=0.1, h=0.04, t=0.5e-3, w=5e-3), "square", (3, 3))
    >>> r = simulate_sheet(sheet, order=[4, 0, 8])
    >>> [(s.cell, s.F_cr, s.snapped.sum(), s.stable) for s in r.steps]

A push of cell c is the 2-D unit's experiment on that cell inside the sheet (`units.push3d`,
the one push-through protocol): the nodes of its arches next to its apex move as one, its
apex cannot move in x or y and is pushed down (-z), and z is held at its sides' midpoints
(the rig it stands on), from the state the previous step left (d from there). The
actuator is then released: the rig is removed, only the sheet's boundary condition is
kept, and the sheet relaxes to the stable equilibrium next to the pushed state
(`units.push3d.relax_released`: Newton, and where that equilibrium is unstable — a global
mode of the sheet — the energy descent along its negative mode into the stable shape it
falls into, reported in ``global_mode``).

Boundary conditions: ``"free"`` — the sheet's rigid-body motion held by a statically
determinate set of six components (`units.sheet_mesh.free_holds`: a midpoint of cell 0
in x, y, z, the midpoint farthest from it in the two components across the line between
them, one more midpoint in z), whose reactions vanish under no load; ``"clamped-edge"`` —
the edges of the sheet's bottom boundary (least y) held: every node's position, and a clamp
frame at each edge's first node (its tangent and twist). A cell is snapped when its apex is
below the mean height of its sides' midpoints. SI units.
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass, field

import numpy as np

from snapmorph.units.frame3d import PETG_NU, UnitGeometry
from snapmorph.units.push3d import path_states, push_through, relax_released
from snapmorph.units.sheet_rig import release_descent, rig_push, rig_release_descent
from snapmorph.units.status import answered
from snapmorph.units.sheet_mesh import TILINGS, SheetModel, build_sheet_mesh, check_cells

__all__ = ["BOUNDARIES", "DEFAULT_NODES_SHEET", "SheetStep", "SheetResult", "build_sheet",
           "simulate_sheet", "apex_heights", "sheet_structure", "explore_orders",
           "shape_distance", "PROTOCOLS", "TILINGS", "check_cells", "edge_curvatures",
           "predict_edge_curvatures", "coupling_error"]

BOUNDARIES = ("free", "clamped-edge")
#: how a cell is pushed: "mgdc", the unit's load-controlled push-through protocol
#: (`units.push3d`); "rig", a displacement-controlled rig that settles into the stable held
#: state at every increment and jumps where the held path folds (`units.sheet_rig`)
PROTOCOLS = ("mgdc", "rig")
#: the protocol of `simulate_sheet` and `explore_orders` when none is named: the rig, which
#: answers every push of a curled sheet (the load-controlled path stops at its step cap in
#: some: 4 of the 3 x 3 sheet's 9) and is the faster of the two there (docs/sheets.md)
DEFAULT_PROTOCOL = "rig"
#: the rig's fewest increments over 3 h: with fewer the samples step over the force's peak
#: and its negative part (a 1 x 1 sheet at h = 40 mm: 3 or 5 increments answer "monostable"
#: for a cell that snaps, 10 or 15 give F_cr 6-9 % high; 20, 30 and 60 agree within 0.06 %)
RIG_MIN_STEPS = 20
#: default resolution of a sheet's cells: nodes along a side (the unit's is 41)
DEFAULT_NODES_SHEET = 21
#: the step cap of a cell's push (MGDC path steps): a push that snaps takes 50-100 steps
#: at the default ``steps``; pushes next to snapped cells were seen to wander between
#: branches for thousands of steps (470 s on a 3 x 3 sheet) without reaching a state
#: (iii). A count, not a time: the same inputs give the same bits.
PUSH_MAX_STEPS = 300
#: the iteration cap of a release's energy descent (`relax_released`; a unit's is 400): a
#: free sheet's soft global modes make it long and steady (428 iterations seen on a 3 x 3
#: sheet, where 400 reported a failed release)
RELEASE_MAX_ITER = 4000
NAN = float("nan")


def build_sheet(geometry: UnitGeometry, tiling: str = "square", cells=(3, 3),
                nodes: int = DEFAULT_NODES_SHEET, nu: float = PETG_NU,
                overlaps: str = "elastic") -> SheetModel:
    """A sheet of ``cells`` ((rows, cols) or a count) 2-D units of ``geometry`` tiled by
    ``tiling`` ("square", "triangle", "hexagon"), sharing their edge strips
    (`units.sheet_mesh.build_sheet_mesh`; L is the side of every cell)."""
    if not isinstance(geometry, UnitGeometry):
        raise ValueError(f"geometry must be a UnitGeometry; got {type(geometry).__name__}")
    return build_sheet_mesh(geometry, tiling, cells, nodes=nodes, nu=nu, overlaps=overlaps)


def _clamped_edges(sheet: SheetModel) -> list:
    """The boundary edges at the sheet's least y (both ends there)."""
    X = sheet.mesh.positions
    y0 = float(np.min(X[:, 1]))
    tol = 1e-9 * sheet.geometry.L
    return [e for e in sheet.boundary_edges()
            if abs(X[sheet.edge_nodes[e][0], 1] - y0) <= tol
            and abs(X[sheet.edge_nodes[e][-1], 1] - y0) <= tol]


def sheet_structure(sheet: SheetModel, boundary: str = "free", cell: int | None = None):
    """The `solver.Structure3D` of ``sheet`` under ``boundary`` with the rig of ``cell``
    (actuator and supports, module docstring) or released (None). The node numbering and the
    state layout are the same for every cell and boundary."""
    check_boundary(boundary)
    fixes, rigid = [], []
    if cell is not None:
        rigid.append(list(sheet.ring[cell]))
        fixes.append((int(sheet.apex[cell]), "xy"))
        fixes += [(int(n), "z") for n in sheet.feet[cell]]
    elif boundary == "free":
        fixes += list(sheet.holds)
    clamped = _clamped_edges(sheet) if boundary == "clamped-edge" else []
    held = sorted({int(n) for e in clamped for n in sheet.edge_nodes[e]})
    fixes += [(n, "xyz") for n in held]
    st = dataclasses.replace(sheet.mesh, fixes=fixes, rigid=rigid).to_structure()
    for e in clamped:
        st.clamp(int(sheet.edge_nodes[e][0]), toward=int(sheet.edge_nodes[e][1]))
    return st


def check_boundary(boundary):
    if boundary not in BOUNDARIES:
        raise ValueError(f"boundary must be one of {BOUNDARIES}; got {boundary!r}")


def apex_heights(sheet: SheetModel, positions) -> np.ndarray:
    """(n_cells,) m: every cell's apex above the centroid of its sides' midpoints, along the
    cell's own normal (h as made, < 0 when the cell is snapped). The normal is that of the
    midpoints' polygon (Newell's: the mean plane of a warped cell), oriented as the as-made
    cell's +z by the midpoints' order, so the height is a property of the shape, whatever
    its placement: a curled free sheet turned over or rolled on its side has the same
    heights. (The global z alone called one shape "snapped" in one placement and not in
    another.)"""
    P = np.asarray(positions, dtype=float)
    X = np.asarray(sheet.mesh.positions, dtype=float)
    out = np.empty(len(sheet.apex))
    for k, (a, f) in enumerate(zip(sheet.apex, sheet.feet)):
        f = np.asarray(f)
        sign = 1.0 if _newell_normal(X[f])[2] >= 0.0 else -1.0
        n = sign * _newell_normal(P[f])
        out[k] = float((P[a] - P[f].mean(axis=0)) @ n)
    return out


def _newell_normal(points) -> np.ndarray:
    """The unit normal of the polygon ``points`` (k, 3) in their order, by Newell's method
    (the area vector: exact for a plane polygon, the mean plane's for a warped one)."""
    p, q = points, np.roll(points, -1, axis=0)
    n = np.array([np.sum((p[:, 1] - q[:, 1]) * (p[:, 2] + q[:, 2])),
                  np.sum((p[:, 2] - q[:, 2]) * (p[:, 0] + q[:, 0])),
                  np.sum((p[:, 0] - q[:, 0]) * (p[:, 1] + q[:, 1]))])
    return n / max(float(np.linalg.norm(n)), 1e-300)


@dataclass(repr=False)
class SheetStep:
    """One push of a sheet and its release (SI). ``cell``: the cell pushed; ``d``, ``F``:
    its force path (m, N; d the apex's travel from the state before); ``F_cr`` (N, NaN: no
    peak); ``push_status``: the push-through's outcome for that cell (`units.status`);
    ``snapped`` (n_cells,) bool after the release; ``stable``: the released sheet is a
    stable equilibrium (no negative eigenvalue of its tangent stiffness,
    ``negative_eigenvalues``; None: singular or not found); ``global_mode``: the equilibrium
    next to the pushed state was unstable and the sheet fell along its negative mode into
    the stable shape reported here; ``positions`` (n_nodes, 3) m and ``state`` (full state)
    of the released sheet; ``apex_heights`` (n_cells,) m; ``moved``: largest node
    displacement in the release, m; ``reason``: "" or why the release found no stable
    state; ``pushed``: (n_nodes, 3) m, the state the release started from (the pushed
    cell's state (iii), actuator on at F = 0, or the push's last state when there is
    none)."""

    cell: int
    d: np.ndarray
    F: np.ndarray
    F_cr: float
    push_status: str
    snapped: np.ndarray
    stable: bool
    negative_eigenvalues: int | None
    global_mode: bool
    positions: np.ndarray
    state: np.ndarray
    apex_heights: np.ndarray
    moved: float = NAN
    reason: str = ""
    seconds: float = NAN
    pushed: np.ndarray | None = None
    #: False when the release found no equilibrium and ``state`` is the pushed state it
    #: started from: the orders' later steps are then not run (`_not_run`)
    equilibrium: bool = True

    def __repr__(self):
        return (f"SheetStep(cell={self.cell}, F_cr={self.F_cr:.4g} N, push={self.push_status!r}, "
                f"snapped={np.flatnonzero(self.snapped).tolist()}, stable={self.stable}, "
                f"global_mode={self.global_mode})")


    @property
    def complete(self) -> bool:
        """Did the push answer (ok, monostable, second state unstable: `units.status`) and
        the release find a stable equilibrium? False when the push was cut short (its step
        cap, a failed solve): the released shape is then where the protocol let go, not a
        result of the sheet."""
        return answered(self.push_status) and not self.reason and bool(self.stable)

@dataclass(repr=False)
class SheetResult:
    """The steps of `simulate_sheet` in push order; ``final``: the last step (None: no
    step); ``boundary``; ``order``; ``solve_time`` s; ``protocol``."""

    sheet: SheetModel
    boundary: str
    order: list
    steps: list = field(default_factory=list)
    solve_time: float = NAN
    #: how the cells were pushed (`PROTOCOLS`)
    protocol: str = DEFAULT_PROTOCOL

    @property
    def final(self):
        return self.steps[-1] if self.steps else None

    @property
    def complete(self) -> bool:
        """Every step `SheetStep.complete` (a final reached through a cut-short push is not a
        result of this order)."""
        return bool(self.steps) and all(step.complete for step in self.steps)

    def __repr__(self):
        f = self.final
        return (f"SheetResult({self.sheet.tiling} {self.sheet.shape[0]}x{self.sheet.shape[1]}, "
                f"order={self.order}, boundary={self.boundary!r}, final snapped="
                f"{np.flatnonzero(f.snapped).tolist() if f else []}, stable="
                f"{f.stable if f else None})")


def check_order(sheet: SheetModel, order) -> list:
    """``order`` as a list of cell indices, or a ValueError naming the valid range."""
    try:
        out = [int(c) for c in order]
        ok = all(float(c) == int(c) and not isinstance(c, (bool, np.bool_)) for c in order)
    except (TypeError, ValueError):
        ok, out = False, []
    n = sheet.n_cells
    if not ok or not out or any(not 0 <= c < n for c in out):
        raise ValueError(f"order must be a non-empty list of cell indices in [0, {n - 1}]; "
                         f"got {order!r}")
    return out


def simulate_sheet(sheet: SheetModel, order, boundary: str = "free", steps: int = 60,
                   start=None, protocol: str = DEFAULT_PROTOCOL) -> SheetResult:
    """Push the cells of ``order`` one at a time (actuator on, then released; module
    docstring) from ``start`` (a full state of the released sheet; None: as made), by
    ``protocol`` (`PROTOCOLS`; ``steps``: the MGDC path's first-step count, or the rig's
    increments over 3 h). Returns a `SheetResult`; failures of a push come back in its
    step's ``push_status``."""
    check_boundary(boundary)
    check_protocol(protocol, steps)
    order = check_order(sheet, order)
    t0 = time.perf_counter()
    released = sheet_structure(sheet, boundary)
    q = np.array(released.initial_state() if start is None else start, dtype=float)
    result = SheetResult(sheet, boundary, order, protocol=protocol)
    for c in order:
        result.steps.append(_next_step(sheet, boundary, released, c, result, q,
                                       (steps, protocol)))
        q = result.steps[-1].state
    result.solve_time = time.perf_counter() - t0
    return result


def check_protocol(protocol, steps):
    """``protocol`` one of `PROTOCOLS` and ``steps`` an integer in its range, or ValueError."""
    if protocol not in PROTOCOLS:
        raise ValueError(f"protocol (how a cell is pushed) must be one of {PROTOCOLS}; "
                         f"got {protocol!r}")
    low, what = (RIG_MIN_STEPS, "the rig's increments over 3 h") if protocol == "rig" else \
        (1, "the MGDC path's first step is 3 h / steps")
    if isinstance(steps, (bool, np.bool_)) or not isinstance(steps, (int, np.integer)) \
            or not low <= steps <= 100000:
        raise ValueError(f"steps ({what}) must be an integer in [{low}, 100000] with protocol "
                         f"{protocol!r}; got {steps!r}")


def _next_step(sheet, boundary, released, cell, result, q, push):
    """The step of ``cell`` after the steps of ``result`` so far, from their state ``q``:
    pushed and released (`_step`; ``push``: (steps, protocol)), or not run when the last
    release found no equilibrium (`_not_run`)."""
    prev = result.steps[-1] if result.steps else None
    if prev is not None and not prev.equilibrium:
        return _not_run(cell, prev)
    return _step(sheet, boundary, released, cell, q, *push)


def _not_run(cell, prev):
    """The step of ``cell`` after ``prev``, whose release found no equilibrium: not pushed
    (a push needs an equilibrium to start from; from the pushed state it fails after a long
    descent), a failure that carries ``prev``'s state on."""
    why = (f"not converged: not run: the release of cell {prev.cell} before it found no "
           f"equilibrium")
    return SheetStep(cell, np.zeros(0), np.zeros(0), NAN, why, prev.snapped.copy(), False,
                     None, False, prev.positions, prev.state, prev.apex_heights, 0.0, why,
                     0.0, prev.pushed, equilibrium=False)


def _step(sheet, boundary, released, cell, q, steps, protocol=DEFAULT_PROTOCOL):
    """Push ``cell`` from the released state ``q`` by ``protocol`` and release it: a
    `SheetStep`."""
    t0 = time.perf_counter()
    g = sheet.geometry
    st = sheet_structure(sheet, boundary, cell)
    q0 = released.initial_state()
    fresh = not np.any(q - q0)
    if boundary == "free" and not fresh:
        # the actuator pushes the apex towards its base, along the cell's own normal: a
        # free sheet (placed only by its rigid-body holds) is first moved rigidly so that
        # the cell's sides' midpoints lie where they were made (a curled sheet had tilted
        # the cells by 10-70 degrees from the actuator's z)
        q = placed_for_push(sheet, released, q, cell)
    # the push's distance counts from the stress-free state: 3 h beyond where the apex is
    # now (an earlier step may have carried it down by more than 3 h: a free sheet curls)
    z = int(released.node_dofs(int(sheet.apex[cell]))[2])
    d_now = 0.0 if fresh else float(q0[z] - q[z])
    travel = 3.0 * g.h + d_now
    if protocol == "rig":
        out = rig_push(st, int(sheet.apex[cell]), q, d_now, travel, int(steps))
    else:
        out = push_through(st, int(sheet.apex[cell]), travel, steps=int(steps),
                           start=None if fresh else q, max_steps=PUSH_MAX_STEPS)
    pushed = out.full_states.get("iii")
    if pushed is None and out.path is not None and len(out.path.positions):
        pushed = path_states(st, out.path)[-1]
    if pushed is None:
        pushed = q
    # the unit's Levenberg-Marquardt descent, and where it finds no equilibrium the
    # line-search descent (`units.sheet_rig.release_descent`): on one 1 x 2 sheet LM took
    # its 4000 iterations on one machine and converged on another (round-off)
    qr, neg, moved, why, first = relax_released(
        released, pushed, RELEASE_MAX_ITER,
        descent=rig_release_descent if protocol == "rig" else release_descent)
    equilibrium = qr is not None
    if qr is None:
        qr = np.asarray(pushed, dtype=float)
    pos = np.array(released.positions_of(qr))
    heights = apex_heights(sheet, pos)
    d, F = (np.asarray(a, dtype=float) for a in out.curve)
    if not fresh and d.size:  # the push's d counts from the stress-free state
        d = d - d[0]
    return SheetStep(cell, d, F, float(out.F_cr), out.status, heights < 0.0,
                     neg == 0, neg, first is None or first > 0, pos, np.array(qr), heights,
                     moved, why, time.perf_counter() - t0,
                     np.array(released.positions_of(pushed)), equilibrium)


def placed_for_push(sheet: SheetModel, structure, q, cell: int) -> np.ndarray:
    """The full state ``q`` of ``sheet`` (canonical twists; ``structure``: the sheet's
    structure) moved rigidly so that ``cell``'s sides' midpoints best fit (least squares,
    `rigid_fit`) their as-made positions. The same shape, the same energy: the twists are
    re-read so that every material frame turns with the positions (`rigid_motion`)."""
    X = np.asarray(sheet.mesh.positions, dtype=float)
    feet = np.asarray(sheet.feet[cell])
    P = np.asarray(structure.positions_of(q), dtype=float)
    R, shift = rigid_fit(P[feet], X[feet])
    return rigid_motion(structure.reduced_system(), q, R, shift)


def rigid_fit(A, B):
    """(R, shift): the proper rotation and translation that carry the points ``A`` (k, 3)
    closest to ``B`` (least squares, Kabsch): B ~ A @ R.T + shift."""
    A, B = np.asarray(A, dtype=float), np.asarray(B, dtype=float)
    ca, cb = A.mean(axis=0), B.mean(axis=0)
    U, _, Vt = np.linalg.svd((A - ca).T @ (B - cb))
    D = np.diag([1.0, 1.0, np.sign(np.linalg.det(Vt.T @ U.T))])
    R = Vt.T @ D @ U.T
    return R, cb - ca @ R.T


def rigid_motion(system, q, R, shift) -> np.ndarray:
    """The full state ``q`` (canonical twists) of a 3-D rod ``system`` moved rigidly: every
    node x to R x + shift (m), and every edge's twist re-read about the canonical director
    of its turned tangent (the stress-free director carried to it by one parallel
    transport, `solver.frames3d.canonical_twist_offset`) so that its material frame turns
    with R; each twist changes by less than pi (the chain of twists stays continuous).
    (The positions alone would not do: the canonical director of R t is not R times that
    of t, and the energy of a 3 x 3 sheet rose from 0.09 J to 1000 J.)"""
    from snapmorph.solver.frames3d import material_directors, transport_frames

    n3, ne = 3 * int(system.n_nodes), int(system.n_edges)
    t0, d0 = (np.ascontiguousarray(a[:ne]) for a in system._stress_free)
    t = np.ascontiguousarray(system._unit_tangents(q))
    theta = np.asarray(q[n3:n3 + ne], dtype=float)
    m1 = material_directors(transport_frames(t0, d0, t), t, theta)[0] @ R.T
    out = np.array(q, dtype=float)
    out[:n3] = (out[:n3].reshape(-1, 3) @ R.T + shift).ravel()
    t2 = np.ascontiguousarray(t @ R.T)
    d2 = transport_frames(t0, d0, t2)
    raw = np.arctan2(np.sum(np.cross(d2, m1) * t2, axis=1), np.sum(d2 * m1, axis=1))
    out[n3:n3 + ne] = theta + (raw - theta + np.pi) % (2.0 * np.pi) - np.pi
    return out


# ---------------------------------------------------------------------------- memory


def shape_distance(a, b) -> float:
    """Largest node distance (m) between two sheet shapes (n, 3) after the rigid motion
    that best superposes them (Kabsch, least squares): 0 for the same shape however it is
    placed."""
    A, B = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    R, shift = rigid_fit(B, A)
    return float(np.max(np.linalg.norm(B @ R.T + shift - A, axis=1)))


def _orders(cells, orders, seed):
    """The orders to run: a list of permutations of ``cells`` as given, or (an int n) the
    identity, its reverse and n - 2 more distinct permutations drawn with ``seed``."""
    if not isinstance(orders, (int, np.integer)):
        return [list(map(int, o)) for o in orders]
    n = int(orders)
    out = [list(cells), list(cells)[::-1]][:n]
    rng = np.random.default_rng(seed)
    tries = 0
    while len(out) < n and tries < 100 * n:
        p = [int(c) for c in rng.permutation(cells)]
        tries += 1
        if p not in out:
            out.append(p)
    return out


def explore_orders(sheet: SheetModel, cells, orders=20, boundary: str = "free",
                   tol: float | None = None, seed: int = 0, steps: int = 60,
                   progress=None, protocol: str = DEFAULT_PROTOCOL) -> dict:
    """Snap the same set of ``cells`` in many ``orders`` (a list of permutations, or a
    count: that many distinct ones, `_orders`) and group the final states by
    `shape_distance` (two finals are one shape when within ``tol``, default L / 100).
    ``progress``: None or a callable given (index, order, `SheetResult`) after every order.
    ``steps``, ``protocol``: as for `simulate_sheet`.

    Returns {"orders": the orders run, "results": their `SheetResult`s, "groups": [{"orders":
    indices into "orders", "snapped": cells snapped in the shape, "stable": bool,
    "positions": (n, 3) of the first, "spread": largest distance to it (m), "complete": the
    indices of its orders whose every step is `SheetStep.complete`}], "distinct": the number
    of distinct stable shapes, "distinct_complete": of those, the shapes reached by at least
    one complete order (the others rest on a push cut short or a failed release: not shown
    to be the sheet's), "distances": (n, n) m between the finals, "pushes": the pushes run
    (a prefix several orders share is pushed once)}."""
    check_protocol(protocol, steps)
    cells = check_order(sheet, cells)
    if len(set(cells)) != len(cells):
        raise ValueError(f"cells must be distinct cell indices; got {cells!r}")
    tol = 0.01 * sheet.geometry.L if tol is None else float(tol)
    runs = _orders(cells, orders, seed)
    for o in runs:
        if sorted(o) != sorted(cells):
            raise ValueError(f"every order must be a permutation of cells {cells}; got {o}")
    results, pushes = _run_orders(sheet, runs, boundary, (steps, protocol), progress)
    finals = [r.final.positions for r in results]
    n = len(finals)
    dist = np.zeros((n, n))
    for i in range(n):
        for j in range(i + 1, n):
            dist[i, j] = dist[j, i] = shape_distance(finals[i], finals[j])
    groups = []
    for i, r in enumerate(results):
        for grp in groups:
            if dist[i, grp["orders"][0]] <= tol:
                grp["orders"].append(i)
                grp["spread"] = max(grp["spread"], float(dist[i, grp["orders"][0]]))
                break
        else:
            groups.append({"orders": [i], "snapped": np.flatnonzero(r.final.snapped).tolist(),
                           "stable": bool(r.final.stable), "positions": finals[i],
                           "spread": 0.0})
    for grp in groups:
        grp["complete"] = [i for i in grp["orders"] if results[i].complete]
    distinct = sum(1 for grp in groups if grp["stable"])
    complete = sum(1 for grp in groups if grp["stable"] and grp["complete"])
    return {"orders": runs, "results": results, "groups": groups, "distinct": distinct,
            "distinct_complete": complete, "distances": dist, "pushes": pushes}


def _run_orders(sheet, runs, boundary, push, progress=None):
    """The `SheetResult` of every order of ``runs``, as `simulate_sheet` gives it, with every
    prefix that several orders share pushed once (a step depends only on the state before
    it and the cell pushed: the orders' steps are those objects, shared). Returns (results,
    the number of pushes run); a result's ``solve_time`` counts its own new steps only."""
    released = sheet_structure(sheet, boundary)
    q0 = np.array(released.initial_state(), dtype=float)
    done = {}
    results = []
    for order in runs:
        t0 = time.perf_counter()
        result = SheetResult(sheet, boundary, list(order), protocol=push[1])
        q = q0
        for k, c in enumerate(order):
            key = tuple(order[: k + 1])
            if key not in done:
                done[key] = _next_step(sheet, boundary, released, c, result, q, push)
            result.steps.append(done[key])
            q = done[key].state
        result.solve_time = time.perf_counter() - t0
        results.append(result)
        if progress is not None:
            progress(len(results) - 1, list(order), result)
    return results, len(done)


# ---------------------------------------------------------------------------- prediction


def edge_curvatures(sheet: SheetModel, positions) -> np.ndarray:
    """(n_edges,) mean curvature (1/m) of every edge strip of the sheet in a state
    (`units.unit2d.edge_metrics`: theta / arc length, > 0 when the ends rise)."""
    from snapmorph.units.unit2d import edge_metrics

    P = np.asarray(positions)
    return np.array([edge_metrics(P[n])["curvature"] for n in sheet.edge_nodes])


def predict_edge_curvatures(sheet: SheetModel, snapped, unit_curvatures) -> np.ndarray:
    """The fast prediction of a sheet's edge curvatures from unit data: every snapped cell
    bends each of its sides as the unit alone bends that side (``unit_curvatures``: (sides,)
    1/m, side k of a cell from vertex k to k + 1 counter-clockwise, e.g. the released
    unit's per-side curvatures of `simulate_unit_2d` in its side order), cells as made add
    nothing, and an edge two cells share takes the sum of both. No coupling between cells:
    the difference from the whole-sheet simulation is the coupling error."""
    snapped = np.asarray(snapped, dtype=bool)
    k = np.asarray(unit_curvatures, dtype=float)
    out = np.zeros(len(sheet.edge_nodes))
    for c, edges in enumerate(sheet.edges):
        if snapped[c]:
            for side, e in enumerate(edges):
                out[e] += k[side]
    return out


def coupling_error(sheet: SheetModel, step, unit_curvatures) -> dict:
    """The prediction of `predict_edge_curvatures` for a step's snapped cells against its
    released sheet: {"predicted", "simulated" (n_edges,) 1/m, "rms_error" 1/m, "relative"
    (rms error / rms simulated), "max_error" 1/m}."""
    sim = edge_curvatures(sheet, step.positions)
    pred = predict_edge_curvatures(sheet, step.snapped, unit_curvatures)
    err = pred - sim
    rms = float(np.sqrt(np.mean(err ** 2)))
    scale = float(np.sqrt(np.mean(sim ** 2)))
    return {"predicted": pred, "simulated": sim, "rms_error": rms,
            "relative": rms / scale if scale > 0 else NAN,
            "max_error": float(np.max(np.abs(err)))}
