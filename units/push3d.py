"""The push experiment on a 3-D rod structure: F–d path to past the second zero of F, the
force maximum (i), and the zero-force states (ii) and (iii) solved as equilibria, with the
stability of (ii) and (iii).

Shared by the 3-D unit (`units.unit3d`) and the 2-D unit (`units.unit2d`); the same
definitions and the same code as the planar unit (`units.planar`, issue 16): F > 0 pushing
down, d the downward displacement of the pushed node, F_cr the first force maximum,
d_unstable the first zero of F with negative slope dF/dd after it, d_second the next zero with
positive slope (`snap_crossings`, on `units.planar`'s `_first_peak` and `_zero_crossings`).
The unit is bistable only when state (iii) is a stable equilibrium with the actuator unloaded
(no negative eigenvalue of its tangent stiffness, `solver.stability.state_stability`);
otherwise ``status`` is "second state unstable: ..." (as the planar unit).

The released state (the unit as an array holds it, actuator and supports removed): the units
rebuild their mesh without actuator and supports, copy state (iii) rod by rod
(`transfer_state`), hold the rigid-body motion only, and `relax_released` finds the stable
equilibrium next to it (Newton; if that equilibrium is unstable, an energy descent from it
along a mode of negative curvature, `descend`); `level` places it as the actuated unit
stands. SI units.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

# one implementation of the crossing rule for every unit (issue 16)
from snapmorph.units.planar import _first_peak, _zero_crossings

NAN = float("nan")

#: MGDC's step-size target for the pushes of the 3-D units (the driver's default is 4). A
#: step of these frames takes 5-6 iterations whatever its size over most of the push (the
#: stiff stretching terms' round-off floor costs one), so with 4 the steps never grow. The
#: special states are solved exactly afterwards, so the path needs no denser sampling: on
#: the 3-D unit at h = 20 mm, 6 takes 36 steps instead of 64 and moves F_cr by < 0.03 %.
MGDC_TARGET_ITERATIONS = 6
DOWN = (0.0, 0.0, -1.0)


@dataclass
class PushOutcome:
    status: str  # "ok", "monostable", "second state unstable: ...", or "not converged: ..."
    path_status: str = ""
    curve: tuple = (np.zeros(0), np.zeros(0))
    F_cr: float = NAN
    d_cr: float = NAN
    d_unstable: float = NAN
    d_second: float = NAN
    bistable: bool = False
    states: dict = field(default_factory=dict)  # "i", "ii", "iii" -> (n_nodes, 3) positions
    exact_states: bool = False  # (ii), (iii) solved as equilibria (not interpolated)
    path: object = None
    #: why the unit is not bistable ("" when it is), as `units.planar.UnitResult.reason`
    reason: str = ""
    #: "i", "ii", "iii" -> full state vectors (positions, then edge twists) of the states
    full_states: dict = field(default_factory=dict)
    #: "ii", "iii" -> `solver.stability.StateStability` (negative eigenvalues with the pushed
    #: node unloaded and held), None where the tangent stiffness is singular
    stability: dict = field(default_factory=dict)


def snap_crossings(d, F):
    """(i_pk, j, k) of a push's F–d samples by the planar unit's rule (issue 16,
    `units.planar`): i_pk the first force maximum (None if none), j the first zero crossing
    of F after it with dF/dd < 0 (the unstable state (ii)), k the next one with dF/dd > 0
    (the candidate second stable state (iii)); a crossing is between samples i-1 and i.
    The slope between the bracketing samples classifies a crossing, not the direction in
    which F changes sign: on a path that snaps back (d decreasing) the two differ."""
    i_pk = _first_peak(F)
    crossings = _zero_crossings(np.asarray(d, float), np.asarray(F, float), start=(i_pk or 0))
    j = next((i for i, slope in crossings if slope < 0), None)
    k = next((i for i, slope in crossings if slope > 0 and j is not None and i > j), None)
    return i_pk, j, k


def _stop_at_second_state(rows):
    """Stop test of the push: the path has passed a candidate (iii) by `snap_crossings`'s
    rule (on an ordinary path the planar unit's stop, F back above zero after a negative F;
    on a path that snaps back it does not stop at a zero of F that is unstable)."""
    F = rows["F"]
    if len(F) < 3:
        return False
    return snap_crossings(rows["d"], F)[2] is not None


def parabola_peak(d, F, i):
    """Vertex of the parabola through samples i-1, i, i+1 (F_max, d_max), or sample i."""
    x, y = np.asarray(d[i - 1: i + 2], float), np.asarray(F[i - 1: i + 2], float)
    if x[0] < x[1] < x[2]:
        a, b, c = np.polyfit(x - x[1], y, 2)
        if a < 0:
            xv = -b / (2 * a)
            if x[0] - x[1] <= xv <= x[2] - x[1]:
                return float(c - b * b / (4 * a)), float(x[1] + xv)
    return float(F[i]), float(d[i])


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


def refine_peak(probe, d, F, Q, i, tol=2e-3):
    """F_cr, d_cr: the force maximum near path sample i by displacement-controlled solves
    (a limit point under load control is regular under displacement control); the vertex of
    the parabola through three samples when that fails. ``tol``: the search stops when the
    bracket is below this fraction of the samples' spacing (F is flat at its maximum: an
    error e in d costs ~ F'' e^2 / 2 in F_cr)."""
    if probe is not None and d[i - 1] < d[i] < d[i + 1]:
        try:
            from snapmorph.solver.states import refine_maximum

            F_max, d_max = refine_maximum(probe, d, F, Q, i, tol_d=tol * (d[i + 1] - d[i - 1]))
            if F_max >= F[i]:
                return float(F_max), float(d_max), True
        except Exception:  # noqa: BLE001
            pass
    return (*parabola_peak(d, F, i), False)


#: a sampled local minimum of F after the peak below this fraction of F_cr (and above 0)
#: is refined: the path's steps may stride over a shallow dip below zero (a marginally
#: bistable unit) that decides whether there is a state (iii)
DIP_FRACTION = 0.2


class _Samples:
    """The path's samples (d, F, positions), with refined states inserted."""

    def __init__(self, displacement, force, positions):
        self.displacement, self.force, self.positions = displacement, force, positions


def refine_dips(probe, d, F, P, Q, i_pk, tol=2e-3):
    """Samples with the minimum of every shallow dip of F (a local minimum after the peak
    with 0 < F < DIP_FRACTION F_cr between two path samples) inserted, located by Brent's
    search on displacement-controlled solves from the nearest sample; returns (d, F, P, Q)
    (the inputs when nothing was inserted). Only a dip the search takes below zero is
    inserted: it makes the zero crossings of a marginally bistable unit visible."""
    if probe is None or i_pk is None or len(F) < 3:
        return d, F, P, Q
    F_cr = F[i_pk]
    inserts = []
    for m in range(i_pk + 1, len(F) - 1):
        if not (0.0 < F[m] < DIP_FRACTION * F_cr and F[m] <= F[m - 1] and F[m] < F[m + 1]):
            continue
        if not d[m - 1] < d[m] < d[m + 1]:
            continue
        cache = {}

        def f(x, m=m, cache=cache):
            x = float(x)
            if x not in cache:
                near = m - 1 + int(np.argmin(np.abs(d[m - 1:m + 2] - x)))
                pos, Fx, _ = probe.solve(Q[near], x)
                cache[x] = (Fx, np.asarray(pos).copy(), probe.last_state.copy())
            return cache[x][0]

        try:
            import scipy.optimize

            res = scipy.optimize.minimize_scalar(
                f, bounds=(float(d[m - 1]), float(d[m + 1])), method="bounded",
                options={"xatol": 0.5 * tol * (d[m + 1] - d[m - 1]), "maxiter": 60})
            x = float(res.x)
            Fx, pos, q = cache[x] if x in cache else (f(x), *cache[x][1:])
        except Exception:  # noqa: BLE001 - the samples stand
            continue
        if Fx < 0.0:
            inserts.append((m + 1 if x > d[m] else m, x, Fx, pos, q))
    if not inserts:
        return d, F, P, Q
    d, F, P, Q = list(d), list(F), list(P), list(Q)
    for at, x, Fx, pos, q in sorted(inserts, key=lambda t: -t[0]):
        d.insert(at, x)
        F.insert(at, Fx)
        P.insert(at, pos)
        Q.insert(at, q)
    return np.asarray(d), np.asarray(F), np.asarray(P), np.asarray(Q)


def _zero_state(st, path, Q, i, node, probe):
    """The equilibrium at F = 0 between path samples i-1 and i (which bracket a zero of F):
    Newton under no load from the interpolated state; if it leaves the bracket, regula falsi
    on displacement-controlled solves first. Returns (positions, full state, solved?); the
    interpolated state (solved = False) only when every solve failed."""
    F, d = path.force, path.displacement
    s = F[i - 1] / (F[i - 1] - F[i])
    P = np.asarray(path.positions)
    guess = (1 - s) * Q[i - 1] + s * Q[i]
    z0 = P[0, node, 2]
    lo, hi = sorted((d[i - 1], d[i]))
    pad = 1e-6 * (hi - lo) + 1e-12

    def inside(pos):
        return lo - pad <= z0 - pos[node, 2] <= hi + pad

    def solve(q):
        if hasattr(st, "solve_equilibrium"):
            pos, info = st.solve_equilibrium(q, node=None)
        else:
            from snapmorph.solver.equilibrium import equilibrium

            pos, info = equilibrium(st, q, None, DOWN, 0.0)
        return np.array(pos), np.array(info["state"])

    try:
        pos, q = solve(guess)
        if inside(pos):
            return pos, q, True
    except Exception:  # noqa: BLE001
        pass
    if probe is not None:
        try:
            from snapmorph.solver.states import zero_force_displacement

            tol_F = 1e-9 * max(abs(F[i - 1]), abs(F[i]))
            zero_force_displacement(probe, d[i - 1], d[i], Q[i - 1], Q[i], F[i - 1], F[i],
                                    tol_F)
            # the full state of the last solve (its twists: positions alone would restart
            # every twist from the stress-free frames)
            pos, q = solve(probe.last_state.copy())
            if inside(pos):
                return pos, q, True
        except Exception:  # noqa: BLE001
            pass
    return (1 - s) * P[i - 1] + s * P[i], guess, False


def _state_stability(st, q, node, system):
    """`StateStability` of the equilibrium ``q`` with ``node`` loaded along -z; None when the
    tangent stiffness is singular there (a critical state)."""
    from snapmorph.solver.stability import state_stability

    try:
        return state_stability(st, q, node, DOWN, system=system)
    except ValueError:
        return None


def unstable_reason(stab, d_second) -> str:
    """The status of a second state (iii) that is not stable, as the planar unit words it."""
    why = ("its tangent stiffness is singular (a critical state)" if stab is None else
           f"{stab.negative_force} negative eigenvalue(s) of the tangent stiffness with the "
           f"actuator unloaded")
    return f"second state unstable: state (iii) at d = {d_second:.4g} m has {why}"


def push_through(st, node, distance, steps=60, critical=False, method="mgdc") -> PushOutcome:
    """Push ``node`` of ``st`` down (-z) by up to ``distance`` (m), stopping after the force
    has crossed zero twice; extract F_cr, d's and the states (i)-(iii) (`snap_crossings`),
    and check that (iii) is stable with the actuator unloaded (else bistable is False and
    status "second state unstable: ...")."""
    try:
        options = {"target_iterations": MGDC_TARGET_ITERATIONS} if method == "mgdc" else {}
        path = st.push(node, DOWN, distance, method=method, stop=_stop_at_second_state,
                       steps=steps, critical=critical, **options)
    except Exception as exc:  # noqa: BLE001 - the caller gets the reason in status
        name = type(exc).__name__
        if name == "ValueError":
            raise
        status = f"not converged: {name}: {exc}"
        return PushOutcome(status=status, reason=status)
    d, F = np.asarray(path.displacement), np.asarray(path.force)
    out = PushOutcome(status="ok", path_status=str(path.status), curve=(d.copy(), F.copy()),
                      path=path)
    Q = path_states(st, path)
    probe = _probe(st, node)
    i_pk, j, k = snap_crossings(d, F)
    samples = path
    if k is None:  # a shallow dip the steps strode over may still go below zero
        d2, F2, P2, Q2 = refine_dips(probe, d, F, np.asarray(path.positions), Q, i_pk)
        if len(d2) > len(d):
            d, F, Q = d2, F2, Q2
            samples = _Samples(d2, F2, P2)
            out.curve = (d.copy(), F.copy())
            i_pk, j, k = snap_crossings(d, F)
    if i_pk is not None:
        out.F_cr, out.d_cr, exact = refine_peak(probe, d, F, Q, i_pk)
        out.states["i"] = np.asarray(path.positions[i_pk]).copy()
        out.full_states["i"] = Q[i_pk].copy()
        if exact:  # state (i) at the maximum itself (solved by the search), whatever the
            # path's sampling
            out.full_states["i"] = probe.last_state.copy()
            out.states["i"] = np.asarray(st.positions_of(out.full_states["i"])).copy()
    if k is None:
        status = str(path.status)
        if status != "ok" and not (j is None and status.startswith("stopped")):
            out.status = f"not converged: {status}"
            out.reason = out.status
        else:
            out.status = "monostable"
            out.reason = ("no snap-through: F does not fall below zero" if j is None else
                          "F crosses zero downwards but does not rise through zero again "
                          f"before d = {d[-1]:.4g} m")
        return out
    pos_ii, q_ii, ok_ii = _zero_state(st, samples, Q, j, node, probe)
    pos_iii, q_iii, ok_iii = _zero_state(st, samples, Q, k, node, probe)
    out.exact_states = ok_ii and ok_iii
    X = np.asarray(path.positions[0])
    out.d_unstable = float(X[node, 2] - pos_ii[node, 2])
    out.d_second = float(X[node, 2] - pos_iii[node, 2])
    out.states["ii"], out.states["iii"] = pos_ii, pos_iii
    out.full_states["ii"], out.full_states["iii"] = q_ii, q_iii
    if not ok_iii:
        out.status = ("not converged: the second state (iii) was not found as an equilibrium "
                      f"near d = {out.d_second:.4g} m")
        out.reason = out.status
        return out
    system = st.reduced_system()
    if ok_ii:
        out.stability["ii"] = _state_stability(st, q_ii, node, system)
    stab = out.stability["iii"] = _state_stability(st, q_iii, node, system)
    if stab is None or not stab.stable_force:
        out.status = unstable_reason(stab, out.d_second)
        out.reason = out.status
        return out
    out.bistable = True
    return out


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
    which has a negative eigenvalue: inverse iteration (on the LDL^T factors; it converges
    to the eigenvalue nearest zero, usually the negative one next to an instability), else
    the eigenvector of the lowest eigenvalue from LAPACK's banded eigensolver (slower)."""
    system.evaluate(q)
    band = np.array(system.band[:, : system.n])
    if system.factor():
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
        if rq < 0:
            return _signed(x)
    import scipy.linalg

    _, v = scipy.linalg.eig_banded(band, lower=True, select="i", select_range=(0, 0),
                                   check_finite=False)
    return _signed(v[:, 0])


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


def relax_released(st, q):
    """The stable equilibrium of ``st`` (a structure whose supports remove only its
    rigid-body motion) under no load next to the state ``q``: Newton from ``q``; when that
    equilibrium is unstable (or Newton fails), a descent of the energy (`descend`) from it,
    pushed a little (1 % of the size) along a mode of negative curvature, finished by
    Newton.

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
            qd = descend(st, start)
            _, info = st.solve_equilibrium(qd, node=None)
            qr = np.array(info["state"])
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
