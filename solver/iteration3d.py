"""Fused Newton and MGDC iterations for 3-D rods: assemble, factorise, solve and update in
one compiled call, as `solver.iteration` does for planar rods (same statuses: 0 converged,
nothing updated, K at q factorised in ``band``; 1 LDL^T failed or non-finite residual,
nothing updated; 2 updated q (and lam)).

The reduced increment ``du`` is applied as ``q[j] += dof_scale[j] du[dof_map[j]]`` (reduced
twist DOFs are lengths, see `solver.system3d.RodSystem3D`); ``du_max`` is in reduced units,
as the general path measures it.
"""

from __future__ import annotations

from numba import njit

from snapmorph.solver.assembly3d import apply_scaled_increment, assemble_system3d_ws
from snapmorph.solver.iteration import max_abs, mgdc_correction, newton_correction


@njit(cache=True)
def _assemble(q, model, dof_scale, band, heights, grad, grad_full):
    (n_nodes, edge_nodes, src_t, src_d, stretch_params, pair_edges, pair_signs, pair_params,
     sf, sr, pf, pr, vals, jacs, hesss) = model
    return assemble_system3d_ws(q, n_nodes, edge_nodes, src_t, src_d, stretch_params,
                                pair_edges, pair_signs, pair_params, sf, sr, pf, pr, dof_scale,
                                band, grad, grad_full, vals, jacs, hesss, heights)


@njit(cache=True)
def _apply_scaled(q, dof_map, dof_scale, du):
    apply_scaled_increment(q, dof_map, dof_scale, du, 1.0)
    return max_abs(du)


@njit(cache=True)
def newton_iteration3d(q, lam, P, model, dof_map, dof_scale, band, heights, grad, grad_full,
                       work, pivot_tol, tol_force):
    """One Newton iteration at fixed load lam P (N) of 3-D rods. ``model``: the tuple of
    `RodSystem3D.model_arrays`; ``work`` (n, 3) scratch.

    Returns (status, negative_eigenvalues, residual_max, du_max, energy)."""
    energy = _assemble(q, model, dof_scale, band, heights, grad, grad_full)
    status, neg, r_max = newton_correction(lam, P, band, heights, grad, work, pivot_tol,
                                           tol_force)
    if status != 2:
        return status, neg, r_max, 0.0, energy
    du_max = _apply_scaled(q, dof_map, dof_scale, work[:, 1])
    return 2, neg, r_max, du_max, energy


@njit(cache=True)
def mgdc_iteration3d(q, lam, P, uP1, model, dof_map, dof_scale, band, heights, grad,
                     grad_full, work, pivot_tol, tol_force):
    """One MGDC corrector iteration of 3-D rods (see `solver.iteration.mgdc_correction`).
    ``work`` (n, 3) scratch.

    Returns (status, negative_eigenvalues, residual_max, du_max, dlam, energy)."""
    energy = _assemble(q, model, dof_scale, band, heights, grad, grad_full)
    status, neg, r_max, dl = mgdc_correction(lam, P, uP1, band, heights, grad, work,
                                             pivot_tol, tol_force)
    if status != 2:
        return status, neg, r_max, 0.0, 0.0, energy
    du_max = _apply_scaled(q, dof_map, dof_scale, work[:, 0])
    return 2, neg, r_max, du_max, dl, energy
