"""The 3-D rod units' side of the push-through experiment (`units.push_through`), and their
released state.

Shared by the 3-D unit (`units.unit3d`) and the 2-D unit (`units.unit2d`): `RodUnitPush`
is a unit on `solver.Structure3D` as the model of the one push-through driver (the planar
unit's, `units.planar`: F > 0 pushing down, d the downward displacement of the pushed node,
F_cr the first force maximum, d_unstable the first zero of F with negative slope dF/dd after
it, d_second the next zero with positive slope, `units.push_through.snap_crossings`); the
unit is bistable only when state (iii) is a stable equilibrium with the actuator unloaded
(no negative eigenvalue of its tangent stiffness, `solver.stability.state_stability`);
otherwise ``status`` is "second state unstable: ..." (as the planar unit). The rods' own
rules (`RULES`): a shallow dip of F the steps strode over is looked for, and state (ii) may
stay interpolated when it is not found as an equilibrium.

The released state (the unit as an array holds it, actuator and supports removed): the units
rebuild their mesh without actuator and supports, copy state (iii) rod by rod
(`transfer_state`), hold the rigid-body motion only, and `relax_released` finds the stable
equilibrium next to it (Newton; if that equilibrium is unstable, an energy descent from it
along a mode of negative curvature, `descend`); `level` places it as the actuated unit
stands. SI units.
"""

from __future__ import annotations

import numpy as np

from snapmorph.units import push_through as experiment
from snapmorph.units.push_through import PushFailed, PushOutcome, Rules
# the one crossing rule and stop test of every unit, under the names the tests check
from snapmorph.units.push_through import (  # noqa: F401
    first_peak as _first_peak,
    second_state_passed as _stop_at_second_state,
    snap_crossings,
    zero_crossings as _zero_crossings,
)

NAN = float("nan")

#: MGDC's step-size target for the pushes of the 3-D units (the driver's default is 4). A
#: step of these frames takes 5-6 iterations whatever its size over most of the push (the
#: stiff stretching terms' round-off floor costs one), so with 4 the steps never grow. The
#: special states are solved exactly afterwards, so the path needs no denser sampling: on
#: the 3-D unit at h = 20 mm, 6 takes 36 steps instead of 64 and moves F_cr by < 0.03 %.
MGDC_TARGET_ITERATIONS = 6
DOWN = (0.0, 0.0, -1.0)
#: the rods' push-through: a shallow dip below zero looked for; only (iii) must be an
#: equilibrium ((ii) may stay interpolated)
RULES = Rules(refine_dips=True, exact=("iii",))


def path_states(st, path):
    """(K, n_state) full state vectors of a 3-D path (positions, then the edge twists)."""
    P = np.asarray(path.positions)
    K, n = P.shape[0], P.shape[1]
    q0 = np.asarray(st.initial_state(), dtype=float)
    Q = np.repeat(q0[None, :], K, axis=0)
    Q[:, : 3 * n] = P.reshape(K, -1)
    fields = getattr(path, "fields", {}) or {}
    if "twist" in fields:
        tw = np.asarray(fields["twist"])
        Q[:, 3 * n: 3 * n + tw.shape[1]] = tw
    return Q


def _probe(st, node):
    try:
        from snapmorph.solver.states import DisplacementProbe

        return DisplacementProbe(st, node, DOWN)
    except Exception:  # noqa: BLE001 - the path samples then stand for the states
        return None


def _state_stability(st, q, node, system):
    """`StateStability` of the equilibrium ``q`` with ``node`` loaded along -z; None when the
    tangent stiffness is singular there (a critical state)."""
    from snapmorph.solver.stability import state_stability

    try:
        return state_stability(st, q, node, DOWN, system=system)
    except ValueError:
        return None


class RodUnitPush:
    """A unit on 3-D rods as the model of `units.push_through.push_through`: ``node`` of
    ``st`` pushed down (-z) by up to ``distance`` (m) with ``method`` ("mgdc" or
    "displacement"); states are full state vectors (positions, then the edges' twists). A
    failed solve of any kind is a failure here (the 3-D solver's errors are reported in the
    status, not raised)."""

    failures = (Exception,)

    def __init__(self, st, node, distance, steps=60, critical=False, method="mgdc",
                 start=None, max_steps=None):
        self.st, self.node, self.distance, self.start = st, node, distance, start
        self.max_steps = max_steps
        self.steps, self.critical, self.method = steps, critical, method
        self.probe = self.X = self.system = self.d0 = None

    def push(self, stop):
        mgdc = self.method == "mgdc"
        options = {"target_iterations": MGDC_TARGET_ITERATIONS} if mgdc else {}
        if self.start is not None:
            options["start"] = self.start
        if self.max_steps is not None:
            options["max_steps"] = self.max_steps
        rule = stop

        def stop(rows):  # MGDC's force-control counts classify the crossings
            return rule({"d": rows["d"], "F": rows["F"],
                         "neg_force": rows.get("neg") if mgdc else None})
        try:
            path = self.st.push(self.node, DOWN, self.distance, method=self.method, stop=stop,
                                steps=self.steps, critical=self.critical, **options)
        except Exception as exc:  # noqa: BLE001 - the caller gets the reason in status
            name = type(exc).__name__
            if name == "ValueError":
                raise
            raise PushFailed(f"not converged: {name}: {exc}") from exc
        self.X = np.asarray(path.positions[0])
        # the path's d counts from the stress-free state (a push from ``start`` begins at
        # the start's displacement): `displacement` measures on the same scale, so that the
        # states found on the path lie inside its samples' brackets
        self.d0 = float(np.asarray(path.displacement)[0]) if self.start is not None else None
        self.probe = _probe(self.st, self.node)
        return path

    def force_counts(self, path):
        """MGDC's negative-eigenvalue counts under force control (None: displacement control,
        or a path without them)."""
        return getattr(path, "negative_eigenvalues", None) if self.method == "mgdc" else None

    def states(self, path):
        return path_states(self.st, path)

    def positions(self, q):
        return self.st.positions_of(q)

    def displacement(self, positions) -> float:
        d = float(self.X[self.node, 2] - positions[self.node, 2])
        return d if self.d0 is None else d + self.d0

    def solve_unloaded(self, q):
        pos, info = self.st.solve_equilibrium(q, node=None)
        return np.array(pos), np.array(info["state"])

    def stability(self, q):
        if self.system is None:  # force control: the actuator unloaded
            self.system = self.st.reduced_system()
        return _state_stability(self.st, q, self.node, self.system)

    def checkpoint(self, stage):
        pass


def push_through(st, node, distance, steps=60, critical=False, method="mgdc",
                 start=None, max_steps=None) -> PushOutcome:
    """Push ``node`` of ``st`` down (-z) by up to ``distance`` (m) until the force has
    crossed zero twice; F_cr, the d's and the states (i)-(iii), and whether (iii) is stable
    with the actuator unloaded (`units.push_through`; else bistable is False and status
    "second state unstable: ..."). ``start``: the equilibrium the push starts from (a full
    state; None: stress free); d counts from the stress-free state (the path's d, which
    begins at the start's displacement). ``max_steps``: the path's step cap
    (None: the driver's own; a deterministic bound where a path may wander)."""
    return experiment.push_through(
        RodUnitPush(st, node, distance, steps, critical, method, start=start,
                    max_steps=max_steps), RULES)


# ---------------------------------------------------------------------------------------------
# The released state: state (iii) with the actuator and the supports removed


def transfer_state(src_mesh, q, dst_mesh, dst_structure) -> np.ndarray:
    """The full state of ``dst_structure`` (built from ``dst_mesh``) that puts every rod of
    ``dst_mesh`` where the rod of the same name is in the full state ``q`` of the structure
    of ``src_mesh`` (positions, and the twists of its edges). The rods must have the same
    stress-free points in both meshes (a model and its copy without actuator or supports)."""
    src = {r.name: r for r in src_mesh.rods}
    q = np.asarray(q, dtype=float)
    n_src = src_mesh.n_nodes

    def edge_starts(mesh):
        out, k = {}, 0
        for r in mesh.rods:
            out[r.name] = k
            k += len(r.xyz) - 1
        return out, k

    e_src, ne_src = edge_starts(src_mesh)
    e_dst, _ = edge_starts(dst_mesh)
    if q.shape != (3 * n_src + ne_src,):
        raise ValueError(f"q must be a full state of shape ({3 * n_src + ne_src},); got {q.shape}")
    pos_src = q[: 3 * n_src].reshape(-1, 3)
    tw_src = q[3 * n_src:]
    pos = np.array(dst_structure.positions_of(dst_structure.initial_state()))
    tw = np.zeros(dst_structure.n_edges)
    for r in dst_mesh.rods:
        s = src.get(r.name)
        if s is None or s.xyz.shape != r.xyz.shape or not np.array_equal(s.xyz, r.xyz):
            raise ValueError(f"rod {r.name!r} differs between the two meshes")
        pos[r.nodes] = pos_src[s.nodes]
        m = len(r.xyz) - 1
        tw[e_dst[r.name]: e_dst[r.name] + m] = tw_src[e_src[r.name]: e_src[r.name] + m]
    return dst_structure.state(pos, tw)


def _negative_eigenvalues(system, q):
    """Negative eigenvalues of the tangent stiffness of ``system`` at ``q``; None when it is
    singular."""
    system.evaluate(q)
    return int(system.negative_eigenvalues) if system.factor() else None


def _band_matvec(band, x):
    """K x for K in lower band storage (band[k, j] = K[j + k, j])."""
    n = x.shape[0]
    y = band[0, :n] * x
    for k in range(1, band.shape[0]):
        b = band[k, : n - k]
        y[k:] += b * x[: n - k]
        y[: n - k] += b * x[k:]
    return y


def _negative_mode(system, q, iterations=60):
    """A direction of negative curvature (reduced DOFs) of the tangent stiffness at ``q``,
    which has a negative eigenvalue: inverse iteration on the LDL^T factors (it converges to
    the eigenvalue nearest zero, usually the negative one next to an instability); where
    that one is positive, inverse iteration on K + mu I with the least mu (within 5 %,
    bisection on the inertia) that makes it positive definite, which converges to the lowest
    eigenvalue (a negative one). Both use the system's own factorisation (sparse or banded):
    LAPACK's dense banded eigensolver took 38 s on a 3 x 3 sheet's 4,280 DOFs."""
    system.evaluate(q)
    n = system.n
    band = np.array(system.band[:, :n])
    if system.factor():
        x, rq = _inverse_iteration(system, band, iterations)
        if rq < 0:
            return _signed(x)

    def definite(mu):
        system.band[:, :n] = band
        system.band[0, :n] += mu
        return system.factor() and system.negative_eigenvalues == 0

    scale = float(np.max(np.abs(band[0])))
    hi = 1e-12 * scale
    while not definite(hi):
        hi *= 4.0
        if not hi <= 1e3 * scale:
            system.band[:, :n] = band
            raise RuntimeError("no shift makes the tangent stiffness positive definite")
    lo = 0.25 * hi
    while hi - lo > 0.05 * hi:
        mid = 0.5 * (lo + hi)
        if definite(mid):
            hi = mid
        else:
            lo = mid
    definite(hi)
    x, rq = _inverse_iteration(system, band, iterations)
    system.band[:, :n] = band
    if not rq < 0:
        raise RuntimeError(f"no direction of negative curvature found (Rayleigh quotient {rq:g})")
    return _signed(x)


def _inverse_iteration(system, band, iterations):
    """(unit vector, Rayleigh quotient on the K of ``band``) of inverse iteration with the
    system's factorisation, from a fixed pseudo-random start."""
    x = np.random.default_rng(0).standard_normal(system.n)  # deterministic
    x /= np.linalg.norm(x)
    rq = np.inf
    for _ in range(iterations):
        y = system.solve(x)
        x = y / np.linalg.norm(y)
        new = float(x @ _band_matvec(band, x))
        if abs(new - rq) <= 1e-8 * abs(new):
            break
        rq = new
    return x, rq


def _signed(v):
    """``v`` with a sign that does not depend on how it was found (inverse iteration flips
    the sign of a negative mode at every step): positive against a fixed pseudo-random
    vector (not the largest component, which symmetric modes have in pairs)."""
    r = np.random.default_rng(1).standard_normal(v.shape[0])
    return v if float(r @ v) >= 0.0 else -v


def descend(st, q, tol=1e-9, max_iter=400):
    """A local minimum of the energy of ``st`` under no load from the state ``q``: Newton
    steps on the tangent stiffness shifted to positive definite (K + mu I, mu raised until
    LDL^T finds no negative pivot and the step lowers the energy, lowered again as the
    steps succeed: Levenberg–Marquardt on the banded K). Leaves the reference frames of a
    fresh system, so that the result is a state as `Structure3D.solve_equilibrium` returns
    it. Raises RuntimeError when it does not converge."""
    from snapmorph.solver.descent import descend as energy_descent

    system = st.reduced_system()
    length, fscale = st.scales()
    q = np.array(q, dtype=float)
    # converged: force residual below tol x force scale, or the last full Newton step
    # moved nothing by more than 1e-11 x the size (the stiff stretching terms leave a
    # round-off residual), as `Structure3D.relax`
    energy_descent(system, q, tol * fscale, 1e-11 * length, max_iter, max_move=0.05 * length)
    return q


def relax_released(st, q, max_iter=400, descent=None):
    """The stable equilibrium of ``st`` (a structure whose supports remove only its
    rigid-body motion) under no load next to the state ``q``: Newton from ``q``; when that
    equilibrium is unstable (or Newton fails), a descent of the energy (`descend`) from it,
    pushed a little (1 % of the size) along a mode of negative curvature, finished by
    Newton. ``max_iter``: the descent's iteration cap (a sheet's soft global modes need
    more than a unit's: a 3 x 3 sheet's descent was seen to take 428 steady iterations).
    ``descent``: the descent, called as ``descent(st, q, max_iter=...)`` (None: `descend`).

    Returns (full state or None, negative eigenvalues of its tangent stiffness (None:
    singular or not found), largest node displacement from ``q`` (m), "" or why there is no
    stable released state, negative eigenvalues of the equilibrium Newton found first from
    ``q`` (None: Newton failed)). Whether the state is still the second state (and not,
    say, the stress-free one the unit snapped back to) is the caller's test."""
    q = np.asarray(q, dtype=float)
    system = st.reduced_system()
    length = st.scales()[0]
    first = None
    try:
        _, info = st.solve_equilibrium(q, node=None)
        qr = np.array(info["state"])
        neg = first = _negative_eigenvalues(system, qr)
    except Exception:  # noqa: BLE001 - the descent next
        qr, neg = q, None
    if neg != 0:
        try:
            start = qr.copy()
            if first is not None:  # an unstable equilibrium: leave it along its lowest mode
                v = _negative_mode(system, qr)
                probe = qr.copy()
                system.increment(probe, v, 1.0)
                amp = float(np.max(np.abs(st.positions_of(probe) - st.positions_of(qr))))
                system.increment(start, v, 1e-2 * length / max(amp, 1e-300))
            qd = (descend if descent is None else descent)(st, start, max_iter=max_iter)
            qr = _equilibrium_at(st, qd)
            neg = _negative_eigenvalues(system, qr)
        except Exception as exc:  # noqa: BLE001
            why = f"no stable equilibrium found without the actuator ({exc})"
            return None, None, NAN, why, first
    moved = float(np.max(np.abs(st.positions_of(qr) - st.positions_of(q))))
    if neg is None:
        return qr, None, moved, "the released state's tangent stiffness is singular", first
    if neg:
        return qr, neg, moved, (f"the released state has {neg} negative eigenvalue(s) of its "
                                "tangent stiffness"), first
    return qr, neg, moved, "", first


def _equilibrium_at(st, q):
    """The equilibrium Newton finds from the descent's end ``q`` (full state, canonical
    twists). Where Newton from a fresh system fails, ``q`` itself when the energy descent
    with the reference frames carried after every step (`Structure3D.relax`) finds it an
    equilibrium, moving no node by more than 1e-9 of the size: a fresh system reads the
    twists about the stress-free directors carried to each tangent in one transport, which
    is singular at an edge turned by nearly 180 degrees (a sheet rolled up: there Newton
    did not converge in 40 iterations, and with the frames carried converged in 2).
    Raises what Newton raised otherwise."""
    try:
        _, info = st.solve_equilibrium(q, node=None)
        return np.array(info["state"])
    except Exception:  # noqa: BLE001 - checked with the frames carried, or re-raised
        try:
            qr, _ = st.relax(q)
        except Exception:  # noqa: BLE001
            qr = None
        length = st.scales()[0]
        if qr is None or float(np.max(np.abs(st.positions_of(qr) - st.positions_of(q)))) \
                > 1e-9 * length:
            raise
        return np.array(q, dtype=float)


def level(positions, nodes, reference):
    """``positions`` (n, 3) moved rigidly so that the best-fit plane through ``nodes`` is
    horizontal (its normal turned, the shortest way, to +z; the normal taken on the +z side)
    and their centroid is where it is in ``reference`` (n, 3): a placement of a released
    state that does not depend on the supports that held its rigid-body motion (the actuated
    states stand on their rollers, all at z = 0)."""
    P = np.asarray(positions, dtype=float)
    pts = P[np.asarray(nodes)]
    c = pts.mean(axis=0)
    n = np.linalg.svd(pts - c)[2][-1]
    if n[2] < 0:
        n = -n
    z = np.array([0.0, 0.0, 1.0])
    axis = np.cross(n, z)
    s, cth = float(np.linalg.norm(axis)), float(n @ z)
    if s > 1e-15:
        k = axis / s
        K = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
        R = np.eye(3) + s * K + (1.0 - cth) * (K @ K)
    else:
        R = np.eye(3)
    target = np.asarray(reference, dtype=float)[np.asarray(nodes)].mean(axis=0)
    return (P - c) @ R.T + target


def record_release(result, release):
    """Put the outcome of ``release()`` -> (self_standing, released dict or None, negative
    eigenvalues, reason) on a unit result (``self_standing``, ``released``,
    ``stability["released"]``, ``stability["released_reason"]``); a release that raises is
    recorded as not self-standing with the exception as the reason, never raised."""
    try:
        ok, rel, neg, why = release()
    except Exception as exc:  # noqa: BLE001 - a failed release is reported, not raised
        ok, rel, neg, why = False, None, None, f"{type(exc).__name__}: {exc}"
    result.self_standing = ok
    result.released = rel or {}
    result.stability["released"] = neg
    if why:
        result.stability["released_reason"] = why
