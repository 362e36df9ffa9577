"""A cell of a sheet pushed as a displacement-controlled rig pushes it (issue 25).

The apex (with its ring of arch nodes) moves down in equal increments of d; at each the
sheet settles into a *stable* equilibrium with the apex held there, by a descent of its
energy from the state extrapolated from the last two (`minimize_energy`). That is what a
quasi-static indenter does: where the held structure's equilibrium path folds (a snap-back
in d, which the load-controlled path of `units.push3d` follows round closed loops inside a
curled sheet, docs/sheets.md), the state at the next increment is simply the stable one the
sheet falls into there: the rig jumps, as the experiment does. The push ends once the force
has peaked, fallen below zero (past state (ii)) and come back to zero or above (state (iii):
the cell holds itself), or at the travel's end; the caller then lets go from the last state
(`units.push3d.relax_released`).

Every state recorded is a stable equilibrium with the apex held (its stiffness, with the
held component removed, has no negative eigenvalue: Sylvester's count of the sparse or
banded LDL^T), so the path is the one a rig records; F_cr is its largest force (the vertex
of the parabola through the three samples round the largest, where the branch is smooth).
SI units; forces in N, d in m counted from the stress-free state.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from snapmorph.solver.states import DisplacementProbe

#: the rig's direction (the apex is pushed down)
DOWN = (0.0, 0.0, -1.0)
#: a step whose largest node displacement exceeds this many increments of d is a jump: the
#: next guess is not extrapolated from it (it would jump as far again)
JUMP_FACTOR = 3.0
#: the rig's stretch limit: a push ends where the centre line of a rod is stretched (or
#: shortened) by more than this (PETG's elastic range ends near 50 MPa / 2.2 GPa = 2.3 %;
#: a cell that snaps stays below 0.03 %)
STRETCH_LIMIT = 0.02
#: the descent kicks along a negative mode only next to a stationary point: where the
#: gradient is below this many times its tolerance, or below `KICK_FRACTION` of the
#: descent's first (the tolerance alone lies below the round-off floor of a large sheet's
#: gradient, ~1e-8 N: a 6 x 6 sheet's release then never kicked off its saddle)
KICK_FORCE = 1e4
KICK_FRACTION = 1e-3
#: the descent's iteration cap per increment (a jump across a snap was seen to take ~400)
MAX_ITER = 2000


def minimize_energy(system, q, tol_force, tol_disp, max_iter=MAX_ITER, max_move=np.inf):
    """Move the full state ``q`` (in place) down the energy of ``system`` to a stable
    equilibrium: Newton steps with a backtracking (Armijo) line search on the energy; where
    K is not positive definite, on K + mu diag|K| with mu raised fourfold from 1e-6 until
    LDL^T finds no negative pivot (the shift is relative to each DOF's own stiffness, so it
    damps neither the soft bending nor the stiff stretching DOFs more than the other).
    Steps are capped at ``max_move`` (m). Converged when the gradient is below
    ``tol_force`` or a full, unshifted Newton step moved nothing by more than ``tol_disp``.
    The system's frames follow every step (`System.accept`). Returns the iterations used;
    raises RuntimeError when no descent is found or ``max_iter`` is reached."""
    n = system.n
    du_last = np.inf
    kicked = False
    energy = system.evaluate(q)
    for it in range(max_iter):
        g = np.array(system.grad[:n])
        if not np.all(np.isfinite(g)):
            raise RuntimeError("the energy's gradient is not finite")
        g_max = float(np.max(np.abs(g)))
        if g_max <= tol_force or du_last <= tol_disp:
            return it
        K = np.array(system.band[:, :n])  # a banded factorisation overwrites it
        shifted = not (system.factor() and system.negative_eigenvalues == 0)
        kick = None
        if it == 0:
            g_start = g_max
        if shifted and not kicked and g_max <= max(KICK_FORCE * tol_force,
                                                   KICK_FRACTION * g_start):
            # the first time K is indefinite next to a stationary point: also step along a
            # mode of negative curvature (at a symmetric saddle the gradient has no
            # component along it, and the shifted steps alone would leave the saddle only
            # exponentially slowly). Not farther from one: there the shifted steps go down
            # anyway, and a guess's passing negative curvature (a rig's increment strains
            # the elements next to the held group) is no mode of the sheet to kick along
            kicked = True
            kick = _kick(system, q, max_move)
            system.evaluate(q)
        mu = _factor_shifted(system, K) if shifted else 0.0
        q0 = q.copy()
        while True:
            du = system.solve(-g)
            if kick is not None:
                du += kick
            big = float(np.max(np.abs(du)))
            t = min(1.0, max_move / big) if big > 0 else 1.0
            # a direction that is not finite (a factorisation at the edge of definiteness)
            # counts as one along which the energy does not decrease
            trial = _line_search(system, q, q0, du, t, energy, float(g @ du)) \
                if np.isfinite(big) else None
            if trial is not None:
                break
            # the line search assembled K at its trials (a banded factor is made in place):
            # K at q again, for the next direction
            system.evaluate(q)
            K = np.array(system.band[:, :n])
            if kick is not None:  # the kick does not lower the energy here: without it
                kick = None
            elif not shifted and np.isfinite(big):
                return it  # K definite, no decrease within round-off: converged
            elif not shifted:  # K's own direction is not finite: shift it
                shifted, mu = True, 1e-6
            else:  # no decrease along the shifted direction: shift more (towards -g)
                mu *= 16.0
                if mu > 1e6:
                    raise RuntimeError("no step along the shifted Newton direction lowers "
                                       "the energy")
            if shifted:
                _factor_shifted(system, K, mu)
            else:
                system.factor()
        energy, t = trial
        system.accept(q)
        # the system now holds the energy, gradient and K at the new q (evaluated last)
        du_last = big * t if (not shifted and t == 1.0) else np.inf
    raise RuntimeError(f"the energy descent did not converge in {max_iter} iterations")


def _kick(system, q, max_move):
    """A step of 0.2 ``max_move`` along a mode of negative curvature of K at ``q``, in the
    reduced DOFs (`units.push3d._negative_mode`; None when none is found)."""
    from snapmorph.units.push3d import _negative_mode

    try:
        v = _negative_mode(system, q)
    except RuntimeError:
        return None
    big = float(np.max(np.abs(v)))
    return None if not big > 0 else v * (0.2 * max_move / big)


def _line_search(system, q, q0, du, t, energy, slope):
    """Backtrack from ``q0`` along ``du`` from step ``t``: (energy, t) of the first step that
    lowers the energy enough (Armijo) or leaves it unchanged within round-off, with ``q``
    there (the system evaluated there); None (``q`` = ``q0``) when none down to 1e-8."""
    while t >= 1e-8:
        q[:] = q0
        system.increment(q, du, t)
        trial = system.evaluate(q)
        if trial <= energy + 1e-4 * t * slope or trial <= energy + 1e-12 * abs(energy):
            return trial, t
        t *= 0.5
    q[:] = q0
    return None


def _factor_shifted(system, K, mu=1e-6):
    """Factorise K + mu diag|K| (``K``: the assembled band, kept by the caller: a banded
    factorisation is made in place) for the smallest mu * 4^k that makes it positive
    definite; returns that mu."""
    n = system.n
    scale = np.abs(K[0])
    while True:
        system.band[:, :n] = K
        system.band[0, :n] += mu * scale
        if system.factor() and system.negative_eigenvalues == 0:
            return mu
        mu *= 4.0
        if mu > 1e6:
            raise RuntimeError("no shift makes the stiffness positive definite")


def canonical(system, q):
    """``q`` with its twists in the canonical convention, which a fresh system (or one after
    `reset_frames`) reads as the same material frames (`System.state_fields`)."""
    fields = system.state_fields(q)
    q = np.array(q, dtype=float)
    if "twist" in fields:
        n3 = 3 * int(system.n_nodes)
        q[n3:n3 + len(fields["twist"])] = fields["twist"]
    return q


@dataclass
class RigPush:
    """A rig's push of one cell: ``curve`` (d, F) of the stable held states (d m from the
    stress-free state, F N on the apex, down positive), ``F_cr`` N and ``d_cr`` m (NaN:
    the force never peaked), ``status`` ("ok": F fell below zero after its peak and came
    back to zero, state (iii); "monostable: ..." F stayed positive to the end of the travel;
    "not converged: ..." a descent failed, or F was still below zero at the travel's end),
    ``jumps`` (d m of the increments where the sheet jumped), ``iterations``,
    ``full_states`` {"iii": the last held state (state (iii), or the travel's end when F
    stayed positive)} for the release; ``path`` None (no load-controlled path)."""

    curve: tuple
    F_cr: float
    d_cr: float
    status: str
    jumps: list = field(default_factory=list)
    iterations: int = 0
    full_states: dict = field(default_factory=dict)
    path: object = None
    stretch: np.ndarray = None


def rig_push(st, apex, q, d_start, d_end, increments) -> RigPush:
    """Push node ``apex`` of the structure ``st`` (the sheet with the cell's rig, whose apex
    group moves as one) down from the equilibrium ``q`` (full state, canonical twists; its d
    is ``d_start`` m) towards ``d_end`` m in steps of (``d_end`` - ``d_start``) /
    ``increments`` (at least one), as the module docstring says."""
    probe = DisplacementProbe(st, apex, DOWN)
    c, system = probe.control, probe.system
    held = c.member_dofs[:, c.axis]
    sign = float(c.direction[c.axis])
    length, fscale = st.scales()
    tols = (1e-9 * fscale, 1e-11 * length, 0.05 * length)  # force N, move m, step cap m
    dd = (d_end - d_start) / max(int(increments), 1)
    q_now = np.array(q, dtype=float)
    ds, Fs, jumps, total = [d_start], [0.0], [], 0
    strains = [stretch(st, q_now)]
    below = False
    status = f"monostable: F > 0 over the whole push (to d = {d_end:.6g} m)"
    for k in range(1, max(int(increments), 1) + 1):
        d = d_start + k * dd
        try:
            F, q_new, its, predicted = _held_state(system, st, c, held, q_now, sign * dd,
                                                   tols)
        except _Unstable:
            status = f"not converged: the state at d = {d:.6g} m is not stable with the apex held"
            break
        except RuntimeError as exc:
            status = f"not converged: the rig's descent at d = {d:.6g} m: {exc}"
            break
        total += its
        # a jump: the state moved much further than the tangent said (a free sheet's far
        # nodes swing by a lever's multiple of the increment on a smooth branch too)
        moved = float(np.max(np.abs(st.positions_of(q_new) - st.positions_of(q_now))))
        jumped = moved > JUMP_FACTOR * max(predicted, abs(dd))
        if jumped:
            jumps.append(d)
        strain = stretch(st, q_new)
        if strain > STRETCH_LIMIT:
            # beyond the material's elastic range the model no longer describes the
            # specimen (a cell held by its neighbours is pulled taut: its arches reached
            # 120 % at 3 h): the push ends at the last state within it
            status = (f"not converged: F < 0 still where a rod's stretch passed "
                      f"{STRETCH_LIMIT:.0%} (d = {d:.6g} m): no zero-force state (iii) "
                      f"within the elastic range" if below else
                      f"monostable: F > 0 over the push to d = {ds[-1]:.6g} m, where a rod's "
                      f"stretch passes {STRETCH_LIMIT:.0%} (the elastic range's end)")
            break
        q_before, q_now = q_now, q_new
        ds.append(d)
        Fs.append(F)
        strains.append(strain)
        if F < 0.0 and 0 < int(np.argmax(Fs)) < len(Fs) - 1:
            below = True  # past the peak and past state (ii): the cell pulls itself on
            status = (f"not converged: F < 0 still at the travel's end (d = {d:.6g} m): no "
                      f"zero-force state (iii) within it")
        elif below:  # F back to zero or above: state (iii), the cell holds itself
            status = "ok"
            if not jumped and Fs[-2] < 0.0:
                # state (iii) is where F = 0, inside this increment: found by regula falsi
                # on the branch (the increment's end overshoots it by up to 2 mm, and the
                # curvatures there by ~4 %)
                lo, hi = (ds[-2], Fs[-2], q_before), (d, F, q_now)
                try:
                    d, F, q_now, its = _zero_force_state(system, st, c, held, sign, lo, hi,
                                                         tols, max(Fs))
                    total += its
                    ds[-1], Fs[-1], strains[-1] = d, F, stretch(st, q_now)
                except RuntimeError:
                    pass  # the increment's end stands as state (iii)
            break
    d_arr, F_arr = np.asarray(ds), np.asarray(Fs)
    F_cr, d_cr = _peak(d_arr, F_arr, jumps)
    return RigPush((d_arr, F_arr), F_cr, d_cr, status, jumps, total,
                   {"iii": q_now} if not status.startswith("not converged") else {},
                   stretch=np.asarray(strains))


class _Unstable(RuntimeError):
    """A held state the descent reached is not stable with the apex held."""


def _held_state(system, st, c, held, q, step, tols):
    """The stable equilibrium with the held DOFs moved by ``step`` (m) from the stable held
    state ``q``: the tangent predictor (`_predict`), then the energy descent
    (`minimize_energy`; ``tols``: its force tolerance N, displacement tolerance m and step
    cap m). Returns (F N, the state with canonical twists, iterations, the predicted
    largest node move m); raises `_Unstable` when the state reached has a negative pivot
    with the apex held, RuntimeError when the descent fails."""
    tol_force, tol_disp, max_move = tols
    system.reset_frames()
    guess, predicted = _predict(system, st, q, held, step, max_move)
    its = minimize_energy(system, guess, tol_force, tol_disp, max_move=max_move)
    system.evaluate(guess)
    if not (system.factor() and system.negative_eigenvalues == 0):
        raise _Unstable("the held state is not stable")
    return float(c.force(system)), canonical(system, guess), its, predicted


def _zero_force_state(system, st, c, held, sign, lo, hi, tols, F_scale, max_iter=8):
    """(d, F, full state, Newton iterations) of the held state with F = 0 between ``lo`` and
    ``hi`` ((d m, F N, full state): F < 0 at lo, >= 0 at hi, the branch smooth between), by
    regula falsi (Illinois) from lo's state (`_held_state`; ``tols`` as there), to
    |F| <= 1e-6 ``F_scale``; the end returned is the bracket's F >= 0 one. Raises
    RuntimeError when a solve fails or is unstable."""
    total, side = 0, 0
    F_lo, F_hi = lo[1], hi[1]
    for _ in range(max_iter):
        if hi[1] <= 1e-6 * F_scale or abs(hi[0] - lo[0]) <= tols[1]:
            break
        d = lo[0] + (hi[0] - lo[0]) * (-F_lo) / (F_hi - F_lo)
        F, q, its, _ = _held_state(system, st, c, held, lo[2], sign * (d - lo[0]), tols)
        total += its
        state = (d, F, q)
        if F >= 0.0:
            hi, F_hi = state, F
            F_lo = lo[1] if side != 1 else 0.5 * F_lo  # Illinois: halve the stale end
            side = 1
        else:
            lo, F_lo = state, F
            F_hi = hi[1] if side != -1 else 0.5 * F_hi
            side = -1
    return hi[0], hi[1], hi[2], total


def stretch(st, q) -> float:
    """The largest axial strain (stretch or shortening) of the centre line of any rod
    edge of the structure ``st`` at the full state ``q`` (dimensionless)."""
    x, X = st.positions_of(q), st.reference_positions
    worst = 0.0
    for rod in st.rods:
        n = np.asarray(rod.nodes)
        ref = np.linalg.norm(np.diff(X[n], axis=0), axis=1)
        now = np.linalg.norm(np.diff(x[n], axis=0), axis=1)
        worst = max(worst, float(np.max(np.abs(now / ref - 1.0))))
    return worst


def _predict(system, st, q, held, step, max_move):
    """The tangent predictor of one increment: the stable held state ``q`` with the held
    DOFs moved by ``step`` (m) and the others by their linear response to it,
    -K^-1 (dg/dh) step (K at ``q``, definite there; dg/dh, the gradient's rate with the
    held move, by central differences of +-1e-6 ``step``), capped at ``max_move`` (m).
    Without it the held group alone moves: the elements next to it are stretched (to second
    order in the move, with the stretching stiffness), K there is indefinite and the
    descent takes tens of shifted steps to come back. Returns (the guess, the largest node
    move it predicts, m)."""
    eps = 1e-6 * step
    rate = []
    for e in (eps, -eps):
        trial = np.array(q, dtype=float)
        trial[held] += e
        system.evaluate(trial)
        rate.append(np.array(system.grad[:system.n]))
    dg = (rate[0] - rate[1]) * (step / (2.0 * eps))
    guess = np.array(q, dtype=float)
    guess[held] += step
    system.evaluate(q)
    if system.factor() and system.negative_eigenvalues == 0:
        du = system.solve(-dg)
        big = float(np.max(np.abs(du))) if du.size else 0.0
        if np.isfinite(big) and big > 0.0:
            system.increment(guess, du, min(1.0, max_move / big))
    moved = float(np.max(np.abs(st.positions_of(guess) - st.positions_of(q))))
    return guess, moved


def _first_peak(F, drop=0.05):
    """Index of the path's first maximum: the first sample at least as large as the one
    before and larger than the one after, from which F falls by ``drop`` of itself before it
    rises above it again (a wiggle is no maximum); None when F never peaks so."""
    F = np.asarray(F, dtype=float)
    for i in range(1, len(F) - 1):
        if not (F[i] >= F[i - 1] and F[i] > F[i + 1]):
            continue
        after = F[i + 1:]
        above = np.flatnonzero(after > F[i])
        stop = int(above[0]) if above.size else len(after)
        if np.min(after[:max(stop, 1)]) <= (1.0 - drop) * F[i]:
            return i
    return None


def _peak(d, F, jumps):
    """(F_cr, d_cr): the path's first maximum (`_first_peak`; where F rises again after it,
    as in a cell that does not snap and is then pushed on, the later force is not F_cr), at
    the vertex of the parabola through the samples either side where the branch is smooth
    there (no jump into or out of it); NaN when the force never peaked."""
    i = _first_peak(F)
    if i is None:
        return float("nan"), float("nan")
    if any(d[i - 1] < x <= d[i + 1] for x in jumps):
        return float(F[i]), float(d[i])
    (d0, d1, d2), (f0, f1, f2) = d[i - 1:i + 2], F[i - 1:i + 2]
    denom = (d0 - d1) * (d0 - d2) * (d1 - d2)
    a = (d2 * (f1 - f0) + d1 * (f0 - f2) + d0 * (f2 - f1)) / denom
    b = (d2 * d2 * (f0 - f1) + d1 * d1 * (f2 - f0) + d0 * d0 * (f1 - f2)) / denom
    if not a < 0.0:
        return float(F[i]), float(d[i])
    x = -b / (2.0 * a)
    return float(f1 + a * (x - d1) ** 2 + (2 * a * d1 + b) * (x - d1)), float(x)


#: the Levenberg-Marquardt iterations a rig's release tries before the line-search descent
#: (on the 3 x 3 sheet LM crept through its 4000 in 38 s where `settle` took 1.7 s)
RIG_RELEASE_LM_ITER = 1000


def release_descent(st, q, max_iter=MAX_ITER, lm_iter=None):
    """The descent of a release (`units.push3d.relax_released`): the unit's own
    Levenberg–Marquardt descent (`units.push3d.descend`: small steps that follow the energy
    down as an overdamped sheet would; at most ``lm_iter`` iterations, None: ``max_iter``),
    and where it finds no equilibrium in them, `settle` from ``q``."""
    from snapmorph.units.push3d import descend

    try:
        return descend(st, q, max_iter=max_iter if lm_iter is None else min(max_iter, lm_iter))
    except Exception:  # noqa: BLE001 - the line-search descent next
        return settle(st, q, max_iter)


def rig_release_descent(st, q, max_iter=MAX_ITER):
    """`release_descent` with the rig's LM budget (`RIG_RELEASE_LM_ITER`)."""
    return release_descent(st, q, max_iter, RIG_RELEASE_LM_ITER)


def settle(st, q, max_iter=MAX_ITER):
    """The stable equilibrium of the structure ``st`` that the energy descent
    (`minimize_energy`) reaches from the full state ``q`` (canonical twists); returned with
    canonical twists. Raises RuntimeError."""
    system = st.reduced_system()
    length, fscale = st.scales()
    q = np.array(q, dtype=float)
    system.reset_frames()
    minimize_energy(system, q, 1e-9 * fscale, 1e-11 * length, max_iter, 0.05 * length)
    return canonical(system, q)
