"""Fused Newton and MGDC iterations for 3-D rods: assemble, factorise, solve and update in
one compiled call, as `solver.iteration` does for planar rods (same statuses: 0 converged,
nothing updated, K at q factorised in ``band``; 1 LDL^T failed or non-finite residual,
nothing updated; 2 updated q (and lam)).

The reduced increment ``du`` is applied as ``q[j] += dof_scale[j] du[dof_map[j]]`` (reduced
twist DOFs are lengths, see `solver.system3d.RodSystem3D`); ``du_max`` is in reduced units,
as the general path measures it.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from solver.assembly3d import assemble_system3d_ws
from solver.banded import ldlt_factor, ldlt_solve
from solver.iteration import _residual


@njit(cache=True)
def _assemble(q, model, dof_scale, band, grad, grad_full):
    (n_nodes, edge_nodes, src_t, src_d, stretch_params, pair_edges, pair_signs, pair_params,
     sf, sr, pf, pr, vals, jacs, hesss) = model
    return assemble_system3d_ws(q, n_nodes, edge_nodes, src_t, src_d, stretch_params,
                                pair_edges, pair_signs, pair_params, sf, sr, pf, pr, dof_scale,
                                band, grad, grad_full, vals, jacs, hesss)


@njit(cache=True)
def _apply_scaled(q, dof_map, dof_scale, du):
    du_max = 0.0
    for i in range(du.shape[0]):
        a = abs(du[i])
        if a > du_max:
            du_max = a
    for j in range(q.shape[0]):
        r = dof_map[j]
        if r >= 0:
            q[j] += dof_scale[j] * du[r]
    return du_max


@njit(cache=True)
def newton_iteration3d(q, lam, P, model, dof_map, dof_scale, band, grad, grad_full, work,
                       pivot_tol, tol_force):
    """One Newton iteration at fixed load lam P (N) of 3-D rods. ``model``: the tuple of
    `RodSystem3D.model_arrays`; ``work`` (n, 3) scratch.

    Returns (status, negative_eigenvalues, residual_max, du_max, energy)."""
    energy = _assemble(q, model, dof_scale, band, grad, grad_full)
    R = work[:, 0]
    r_max = _residual(grad, lam, P, R)
    status, neg, _ = ldlt_factor(band, pivot_tol)
    if status != 0 or not r_max < np.inf:
        return 1, neg, r_max, 0.0, energy
    if r_max <= tol_force:
        return 0, neg, r_max, 0.0, energy
    rhs = work[:, 1:2]
    for i in range(R.shape[0]):
        rhs[i, 0] = -R[i]
    ldlt_solve(band, rhs)
    du_max = _apply_scaled(q, dof_map, dof_scale, rhs[:, 0])
    return 2, neg, r_max, du_max, energy


@njit(cache=True)
def mgdc_iteration3d(q, lam, P, uP1, model, dof_map, dof_scale, band, grad, grad_full, work,
                     pivot_tol, tol_force):
    """One MGDC corrector iteration of 3-D rods: the load increment keeps the correction
    orthogonal to the step's first tangent ``uP1``. ``work`` (n, 3) scratch.

    Returns (status, negative_eigenvalues, residual_max, du_max, dlam, energy)."""
    energy = _assemble(q, model, dof_scale, band, grad, grad_full)
    R = work[:, 0]
    r_max = _residual(grad, lam, P, R)
    status, neg, _ = ldlt_factor(band, pivot_tol)
    if status != 0 or not r_max < np.inf:
        return 1, neg, r_max, 0.0, 0.0, energy
    if r_max <= tol_force:
        return 0, neg, r_max, 0.0, 0.0, energy
    rhs = work[:, 1:3]
    for i in range(R.shape[0]):
        rhs[i, 0] = P[i]
        rhs[i, 1] = -R[i]
    ldlt_solve(band, rhs)
    num = 0.0
    den = 0.0
    for i in range(R.shape[0]):
        num += uP1[i] * rhs[i, 1]
        den += uP1[i] * rhs[i, 0]
    if den == 0.0 or not abs(den) < np.inf:
        return 1, neg, r_max, 0.0, 0.0, energy
    dl = -num / den
    du = work[:, 0]  # R is no longer needed
    for i in range(R.shape[0]):
        du[i] = dl * rhs[i, 0] + rhs[i, 1]
    du_max = _apply_scaled(q, dof_map, dof_scale, du)
    return 2, neg, r_max, du_max, dl, energy
