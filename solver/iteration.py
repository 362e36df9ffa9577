"""Fused Newton and MGDC iterations: assemble, factorise, solve and update in one compiled
call, for planar rods (`newton_iteration`, `mgdc_iteration`) and 3-D rods
(`newton_iteration3d`, `mgdc_iteration3d`).

The path followers spend most of their time in Python overhead between small compiled calls
(about 100 us per iteration for a 100-node rod against some 15 us of arithmetic). These
kernels do one whole iteration per call. They return a status so that the driver can fall
back to the system's general path (`solver.system`: dense pivoting solve) when LDL^T without
pivoting meets a tiny pivot.

Status: 0 converged (nothing updated; K at q is factorised in ``band``), 1 LDL^T failed or
non-finite residual (nothing updated), 2 updated q (and lam).

3-D rods apply the reduced increment ``du`` as ``q[j] += dof_scale[j] du[dof_map[j]]``
(reduced twist DOFs are lengths, see `solver.system.RodSystem3D`); ``du_max`` is in reduced
units, as the general path measures it.

Every iteration assembles the structure's dead loads too (``loads``, the record of
`solver.assembly.assemble_dead_loads`; empty when there are none: then nothing changes).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from snapmorph.solver.assembly import (assemble_banded, assemble_dead_loads, assemble_gradient,
                                       stiff_second_difference)
from snapmorph.solver.assembly3d import apply_scaled_increment, assemble_system3d_ws
from snapmorph.solver.banded import ldlt_factor_envelope, ldlt_solve_envelope


@njit(cache=True, inline="always")
def _larger(a, m):
    """max(a, m) as the sequential scans take it (a NaN ``a`` is passed over)."""
    return a if a > m else m


@njit(cache=True)
def _residual(grad, lam, P, R):
    """R = grad - lam P; returns max |R_i|, or inf if any R_i is not finite. Four running
    maxima (a maximum does not depend on the order it is taken in: the same value as one
    scan, without waiting on each comparison)."""
    n = grad.shape[0]
    m0 = m1 = m2 = m3 = 0.0
    finite = True
    i = 0
    while i + 4 <= n:
        r0 = grad[i] - lam * P[i]
        r1 = grad[i + 1] - lam * P[i + 1]
        r2 = grad[i + 2] - lam * P[i + 2]
        r3 = grad[i + 3] - lam * P[i + 3]
        R[i] = r0
        R[i + 1] = r1
        R[i + 2] = r2
        R[i + 3] = r3
        a0 = abs(r0)
        a1 = abs(r1)
        a2 = abs(r2)
        a3 = abs(r3)
        finite &= a0 < np.inf and a1 < np.inf and a2 < np.inf and a3 < np.inf
        m0 = _larger(a0, m0)
        m1 = _larger(a1, m1)
        m2 = _larger(a2, m2)
        m3 = _larger(a3, m3)
        i += 4
    while i < n:
        R[i] = grad[i] - lam * P[i]
        a0 = abs(R[i])
        finite &= a0 < np.inf
        m0 = _larger(a0, m0)
        i += 1
    if not finite:  # NaN or inf
        return np.inf
    return _larger(m3, _larger(m2, _larger(m1, m0)))


@njit(cache=True)
def max_abs(du):
    """Largest |du[i]| (the size of a correction, as the drivers measure it: a NaN entry is
    passed over). Four running maxima, as `_residual`."""
    n = du.shape[0]
    m0 = m1 = m2 = m3 = 0.0
    i = 0
    while i + 4 <= n:
        m0 = _larger(abs(du[i]), m0)
        m1 = _larger(abs(du[i + 1]), m1)
        m2 = _larger(abs(du[i + 2]), m2)
        m3 = _larger(abs(du[i + 3]), m3)
        i += 4
    while i < n:
        m0 = _larger(abs(du[i]), m0)
        i += 1
    return _larger(m3, _larger(m2, _larger(m1, m0)))


@njit(cache=True)
def _apply(q, dof_map, du):
    du_max = max_abs(du)
    for j in range(q.shape[0]):
        r = dof_map[j]
        if r >= 0:
            q[j] += du[r]
    return du_max


@njit(cache=True)
def newton_correction(lam, P, band, heights, grad, work, pivot_tol, tol_force):
    """The part of a Newton iteration after assembly (shared by planar and 3-D rods):
    residual, LDL^T of ``band`` within its envelope ``heights``
    (`solver.banded.envelope_heights`), and the correction -K^-1 R into ``work[:, 1]``.

    Returns (status, negative_eigenvalues, residual_max) with the statuses above (2: the
    correction is ready, nothing updated yet)."""
    R = work[:, 0]
    r_max = _residual(grad, lam, P, R)
    status, neg, _ = ldlt_factor_envelope(band, heights, pivot_tol)
    if status != 0 or not r_max < np.inf:
        return 1, neg, r_max
    if r_max <= tol_force:
        return 0, neg, r_max
    rhs = work[:, 1:2]
    for i in range(R.shape[0]):
        rhs[i, 0] = -R[i]
    ldlt_solve_envelope(band, heights, rhs)
    return 2, neg, r_max


@njit(cache=True)
def mgdc_correction(lam, P, uP1, band, heights, grad, work, pivot_tol, tol_force):
    """The part of an MGDC corrector iteration after assembly (shared by planar and 3-D
    rods): residual, LDL^T, and the correction whose load increment dl keeps it orthogonal
    to the step's first tangent ``uP1``, into ``work[:, 0]``.

    Returns (status, negative_eigenvalues, residual_max, dl)."""
    R = work[:, 0]
    r_max = _residual(grad, lam, P, R)
    status, neg, _ = ldlt_factor_envelope(band, heights, pivot_tol)
    if status != 0 or not r_max < np.inf:
        return 1, neg, r_max, 0.0
    if r_max <= tol_force:
        return 0, neg, r_max, 0.0
    rhs = work[:, 1:3]
    for i in range(R.shape[0]):
        rhs[i, 0] = P[i]
        rhs[i, 1] = -R[i]
    ldlt_solve_envelope(band, heights, rhs)
    num = 0.0
    den = 0.0
    for i in range(R.shape[0]):
        num += uP1[i] * rhs[i, 1]
        den += uP1[i] * rhs[i, 0]
    if den == 0.0 or not abs(den) < np.inf:
        return 1, neg, r_max, 0.0
    dl = -num / den
    du = work[:, 0]  # R is no longer needed
    for i in range(R.shape[0]):
        du[i] = dl * rhs[i, 0] + rhs[i, 1]
    return 2, neg, r_max, dl


@njit(cache=True)
def with_dead_loads(q, loads, grad, grad_full, energy):
    """``energy`` (J) plus the dead loads' potential, their gradient added (`loads` empty:
    ``energy`` itself, nothing touched)."""
    if loads[0].shape[0] == 0:
        return energy
    return energy + assemble_dead_loads(q, loads, grad, grad_full)


@njit(cache=True)
def newton_iteration(q, lam, P, elements, dofs, slots, loads, dof_map, band, heights, grad,
                     grad_full, work, pivot_tol, tol_force):
    """One Newton iteration at fixed load lam P (N) of planar rods (``band`` Fortran
    order, ``slots``: `solver.assembly.band_slots`). ``work`` is (n, 3) scratch.

    Returns (status, negative_eigenvalues, residual_max, du_max, energy)."""
    energy = with_dead_loads(q, loads, grad, grad_full,
                             assemble_banded(q, elements, dofs, slots, dof_map, band, heights,
                                             grad, grad_full))
    status, neg, r_max = newton_correction(lam, P, band, heights, grad, work, pivot_tol,
                                           tol_force)
    if status != 2:
        return status, neg, r_max, 0.0, energy
    du_max = _apply(q, dof_map, work[:, 1])
    return 2, neg, r_max, du_max, energy


@njit(cache=True)
def mgdc_iteration(q, lam, P, uP1, elements, dofs, slots, loads, dof_map, band, heights,
                   grad, grad_full, work, pivot_tol, tol_force):
    """One MGDC corrector iteration: the load increment keeps the correction orthogonal to
    the step's first tangent ``uP1``. ``work`` is (n, 3) scratch.

    Returns (status, negative_eigenvalues, residual_max, du_max, dlam, energy)."""
    energy = with_dead_loads(q, loads, grad, grad_full,
                             assemble_banded(q, elements, dofs, slots, dof_map, band, heights,
                                             grad, grad_full))
    status, neg, r_max, dl = mgdc_correction(lam, P, uP1, band, heights, grad, work,
                                             pivot_tol, tol_force)
    if status != 2:
        return status, neg, r_max, 0.0, 0.0, energy
    du_max = _apply(q, dof_map, work[:, 0])
    return 2, neg, r_max, du_max, dl, energy


@njit(cache=True)
def assemble3d(q, model, loads, dof_scale, band, heights, grad, grad_full):
    """Energy (J) of 3-D rods (``model``: the tuple of `RodSystem3D.model_arrays`) and their
    dead loads; writes the band, the reduced and the full gradient."""
    (n_nodes, edge_nodes, src_t, src_d, stretch_params, pair_edges, pair_signs, pair_params,
     sf, sr, pf, pr, vals, jacs, hesss) = model
    energy = assemble_system3d_ws(q, n_nodes, edge_nodes, src_t, src_d, stretch_params,
                                  pair_edges, pair_signs, pair_params, sf, sr, pf, pr,
                                  dof_scale, band, grad, grad_full, vals, jacs, hesss, heights)
    return with_dead_loads(q, loads, grad, grad_full, energy)


@njit(cache=True)
def _apply_scaled(q, dof_map, dof_scale, du):
    apply_scaled_increment(q, dof_map, dof_scale, du, 1.0)
    return max_abs(du)


@njit(cache=True)
def newton_iteration3d(q, lam, P, model, loads, dof_map, dof_scale, band, heights, grad,
                       grad_full, work, pivot_tol, tol_force):
    """One Newton iteration at fixed load lam P (N) of 3-D rods. ``model``: the tuple of
    `RodSystem3D.model_arrays`; ``work`` (n, 3) scratch.

    Returns (status, negative_eigenvalues, residual_max, du_max, energy)."""
    energy = assemble3d(q, model, loads, dof_scale, band, heights, grad, grad_full)
    status, neg, r_max = newton_correction(lam, P, band, heights, grad, work, pivot_tol,
                                           tol_force)
    if status != 2:
        return status, neg, r_max, 0.0, energy
    du_max = _apply_scaled(q, dof_map, dof_scale, work[:, 1])
    return 2, neg, r_max, du_max, energy


@njit(cache=True)
def mgdc_iteration3d(q, lam, P, uP1, model, loads, dof_map, dof_scale, band, heights, grad,
                     grad_full, work, pivot_tol, tol_force):
    """One MGDC corrector iteration of 3-D rods (see `mgdc_correction`).
    ``work`` (n, 3) scratch.

    Returns (status, negative_eigenvalues, residual_max, du_max, dlam, energy)."""
    energy = assemble3d(q, model, loads, dof_scale, band, heights, grad, grad_full)
    status, neg, r_max, dl = mgdc_correction(lam, P, uP1, band, heights, grad, work,
                                             pivot_tol, tol_force)
    if status != 2:
        return status, neg, r_max, 0.0, 0.0, energy
    du_max = _apply_scaled(q, dof_map, dof_scale, work[:, 0])
    return 2, neg, r_max, du_max, dl, energy


@njit(cache=True)
def settle_state(q, lam, P, elements, dof_map, loads, grad, grad_full, work):
    """The energy (J) and gradients (N) at a state ``q`` Newton has converged to on the
    displacements, without the stiffness (`solver.assembly.assemble_gradient`): K stays
    factorised at the iterate before. ``work`` (n, 3) scratch.

    Returns (residual_max, energy)."""
    energy = with_dead_loads(q, loads, grad, grad_full,
                             assemble_gradient(q, elements, dof_map, grad, grad_full))
    return _residual(grad, lam, P, work[:, 0]), energy


@njit(cache=True)
def second_order_term(q, step, uP, elements, dofs, dof_map, band, heights, bend_fraction,
                      out):
    """The MGDC predictor's second-order term at the converged state ``q`` (planar rods, K
    factorised there in ``band``): for the tangent step ``step`` = dlam u_P (reduced),
    w = K^-1 (g(q + step) + g(q - step) - 2 g(q)) of the stiff terms
    (`solver.assembly.stiff_second_difference`), and the term mu u_P - w / 2 into ``out``,
    mu keeping it orthogonal to the step (`solver.mgdc._Mgdc._bend`). Returns (mu, True),
    or (0, False) where the term is longer than ``bend_fraction`` of the step (the path
    bends too sharply for it) or the step is degenerate. One call for what took eight
    array operations a step."""
    n = step.shape[0]
    plus = q.copy()
    minus = q.copy()
    for j in range(q.shape[0]):
        r = dof_map[j]
        if r >= 0:
            plus[j] += step[r]
            minus[j] -= step[r]
    w = np.empty((n, 1))
    stiff_second_difference(q, plus, minus, elements, dofs, w[:, 0])
    ldlt_solve_envelope(band, heights, w)
    along = 0.0
    sw = 0.0
    for i in range(n):
        along += step[i] * uP[i]
        sw += step[i] * w[i, 0]
    if along == 0.0:
        return 0.0, False
    mu = sw / (2.0 * along)
    size = 0.0
    length = 0.0
    for i in range(n):
        out[i] = mu * uP[i] - 0.5 * w[i, 0]
        size += out[i] * out[i]
        length += step[i] * step[i]
    if not np.sqrt(size) <= bend_fraction * np.sqrt(length):
        return 0.0, False
    return mu, True


# ---------------------------------------------------------------------------- corrector loops
# The drivers' loops over the fused iterations above (`solver.newton.newton`,
# `solver.mgdc._Mgdc._correct`), compiled for planar rods: the same iterations and tests in
# the same order (same bits), without the Python between them. They stop where the Python
# loop has work of its own: convergence, or an iteration the fused kernel cannot do (status
# 1: the general path with its dense fallback takes over at that iteration).

@njit(cache=True, inline="always")
def settled_rule(du_max, du_prev, tol_disp, settle_factor):
    """`solver.newton.settled` (compiled)."""
    return du_max <= tol_disp or (du_max <= settle_factor * tol_disp
                                  and du_max * du_max <= tol_disp * du_prev)


@njit(cache=True)
def newton_loop(q, lam, P, tol_force, tol_disp, max_iter, max_move, settle, elements, dofs,
                slots, loads, dof_map, band, heights, grad, grad_full, work, pivot_tol):
    """`newton_iteration` from iteration 0 while it succeeds. Returns (status, it,
    du_max, negative_eigenvalues, energy): 0 converged at ``it`` (K factorised at q, or one
    iterate back when settled: ``settle`` and the last correction below ``tol_disp``,
    gradients and energy at q by `settle_state`); 1 iteration ``it`` is the general path's
    (the fused one failed and changed nothing, or its correction was longer than
    ``max_move`` and is undone, or ``it`` is the last, which the general path checks)."""
    du_max = np.inf
    neg = 0
    energy = 0.0
    for it in range(max_iter):
        if settle and du_max <= tol_disp:
            _, energy = settle_state(q, lam, P, elements, dof_map, loads, grad, grad_full,
                                     work)
            return 0, it, du_max, neg, energy
        status, neg, r_max, du_step, energy = newton_iteration(
            q, lam, P, elements, dofs, slots, loads, dof_map, band, heights, grad, grad_full,
            work, pivot_tol, tol_force if du_max > tol_disp else np.inf)
        if status == 0:
            return 0, it, du_max, neg, energy
        if status == 2 and du_step <= max_move:
            du_max = du_step
            continue
        if status == 2:  # undo the too-long step: the general path damps it
            for j in range(q.shape[0]):
                r = dof_map[j]
                if r >= 0:
                    q[j] -= work[r, 1]
        return 1, it, du_max, neg, energy
    return 1, max_iter, du_max, neg, energy


@njit(cache=True)
def mgdc_loop(q, lam, P, uP1, tol_force, tol_disp, max_iter, settle_factor, elements, dofs,
              slots, loads, dof_map, band, heights, grad, grad_full, work, pivot_tol):
    """`mgdc_iteration` from iteration 1 while it succeeds. Returns (status, it, lam,
    du_max, du_prev, r_max, done, iterations, negative_eigenvalues, energy): 0 converged at
    ``it`` (``done``: on the displacements, `settled_rule`); 1 the fused iteration ``it``
    failed (nothing changed: the general path's); 3 no convergence in ``max_iter``;
    ``iterations``: the corrections applied."""
    du_max = np.inf
    du_prev = np.inf
    iterations = 0
    neg = 0
    energy = 0.0
    for it in range(1, max_iter + 1):
        done = settled_rule(du_max, du_prev, tol_disp, settle_factor)
        status, neg, r_max, du_step, dl, energy = mgdc_iteration(
            q, lam, P, uP1, elements, dofs, slots, loads, dof_map, band, heights, grad,
            grad_full, work, pivot_tol, np.inf if done else tol_force)
        if status == 0:
            return 0, it, lam, du_max, du_prev, r_max, done, iterations, neg, energy
        if status != 2:
            return 1, it, lam, du_max, du_prev, r_max, done, iterations, neg, energy
        du_prev = du_max
        du_max = du_step
        lam += dl
        iterations += 1
    return 3, max_iter, lam, du_max, du_prev, 0.0, False, iterations, neg, energy


@njit(cache=True)
def mgdc_step(q, lam, dlam, P, uP1, settings, weights, q_try, uP_try, step, elements, dofs,
              slots, loads, dof_map, band, heights, grad, grad_full, work, pivot_tol):
    """One MGDC step of planar rods in one call: the predictor from the converged state
    ``q`` (K factorised there in ``band``) along ``uP1`` by the load increment ``dlam``,
    with the second-order term (`second_order_term`) when asked, then `mgdc_loop` at the
    load ``P``; on convergence also the tangent and the step of the new state. The driver's
    Python path (`solver.mgdc._Mgdc._correct`, `_crosses`) in one call a step.

    ``settings`` = (tol, force scale, load unit, tol_disp, max_iter, settle_factor,
    bend_fraction, second_order (0/1)); ``weights`` = (n_free, r_idx, representative): the
    pushed node's component of a reduced vector u is sum n_free u[r_idx], the reduced values
    of a full state q are q[representative]. Writes the trial state into ``q_try``; on
    convergence ``uP_try`` = K^-1 P there and ``step`` its reduced change from q.
    Returns (status, it, lam, du_max, du_prev, r_max, done, iterations, negative_eigenvalues,
    energy, tol_force, flex, step_norm) with the statuses of `mgdc_loop`; flex (uP_try's
    pushed component) and step_norm (|q_try - q|) NaN unless converged."""
    tol, fscale, unit, tol_disp, max_iter, settle_factor, bend_fraction, second_order = settings
    n_free, r_idx, representative = weights
    n = uP1.shape[0]
    for j in range(q.shape[0]):
        q_try[j] = q[j]
    for j in range(q.shape[0]):
        r = dof_map[j]
        if r >= 0:
            q_try[j] += dlam * uP1[r]
    lam_try = lam + dlam
    if second_order:
        tangent = np.empty(n)
        for i in range(n):
            tangent[i] = dlam * uP1[i]
        bend = np.empty(n)
        mu, ok = second_order_term(q, tangent, uP1, elements, dofs, dof_map, band, heights,
                                   bend_fraction, bend)
        if ok:
            for j in range(q.shape[0]):
                r = dof_map[j]
                if r >= 0:
                    q_try[j] += bend[r]
            lam_try += mu
    tol_force = tol * max(fscale, abs(lam_try) * unit)
    (status, it, lam_try, du_max, du_prev, r_max, done, iterations, neg,
     energy) = mgdc_loop(q_try, lam_try, P, uP1, tol_force, tol_disp, max_iter,
                         settle_factor, elements, dofs, slots, loads, dof_map, band, heights,
                         grad, grad_full, work, pivot_tol)
    flex = np.nan
    size = np.nan
    if status == 0:
        rhs = np.empty((n, 1))
        for i in range(n):
            rhs[i, 0] = P[i]
        ldlt_solve_envelope(band, heights, rhs)
        for i in range(n):
            uP_try[i] = rhs[i, 0]
        flex = 0.0
        for k in range(r_idx.shape[0]):
            flex += n_free[k] * uP_try[r_idx[k]]
        for i in range(n):
            step[i] = q_try[representative[i]] - q[representative[i]]
        size = 0.0
        for j in range(q.shape[0]):
            size += (q_try[j] - q[j]) ** 2
        size = np.sqrt(size)
    return (status, it, lam_try, du_max, du_prev, r_max, done, iterations, neg, energy,
            tol_force, flex, size)
