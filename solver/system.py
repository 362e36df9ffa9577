"""A constrained, assembled problem: the element arrays, one DOF map and its band storage.

`ReducedSystem` is what the path followers work on: evaluate the energy, gradient and
tangent stiffness at positions ``q``, factorise, and solve. It owns no physics of its own.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg

from snapmorph.solver.assembly import apply_increment, assemble_system, element_dofs
from snapmorph.solver.banded import (band_to_dense, envelope_heights, ldlt_factor_envelope,
                           ldlt_solve_envelope)
from snapmorph.solver.iteration import mgdc_iteration, newton_iteration

# A pivot smaller than this times the largest diagonal entry means K is numerically singular
# for LDL^T without pivoting; the dense pivoting fallback then takes over.
PIVOT_TOL = 1e-13


class ReducedSystem:
    """K_red = W^T K W and the reduced gradient for one set of constraints.

    ``dof_map`` (2 n_nodes,) maps full DOFs to reduced DOFs (-1 = fixed/prescribed).
    """

    def __init__(self, elements, dof_map, n_reduced, bandwidth):
        self.elements = elements
        self.dof_map = np.ascontiguousarray(dof_map, dtype=np.int64)
        self.dofs = element_dofs(elements, self.dof_map)
        # one full DOF per reduced DOF, to read reduced values off full positions
        free = np.flatnonzero(self.dof_map >= 0)
        self.representative = np.empty(int(n_reduced), dtype=np.int64)
        self.representative[self.dof_map[free]] = free
        self.n = int(n_reduced)
        self.bandwidth = int(bandwidth)
        self.band = np.zeros((self.bandwidth + 1, max(self.n, 1)))
        self._band_copy = np.empty_like(self.band)
        # the factor's envelope: its columns' extents, fill included (no scans per solve)
        self.heights = envelope_heights(self.band.shape[1], *self.dofs)
        self.grad = np.zeros(max(self.n, 1))
        self.grad_full = np.zeros(self.dof_map.shape[0])
        self._work = np.zeros((max(self.n, 1), 3))
        self.energy = 0.0
        self.negative_eigenvalues = 0
        self.factor_ok = False
        self._dense_lu = None
        # N per unit of this system's forces (Pa when its elements are per unit modulus,
        # see `Structure.reduced_system(normalized=True)`); energies J per unit likewise
        self.force_unit = 1.0

    def evaluate(self, q):
        """Assemble energy (J), gradients (N) and K (N/m) at positions ``q`` (m)."""
        self.energy = assemble_system(
            q, self.elements, self.dofs, self.band, self.grad, self.grad_full
        )
        return self.energy

    def factor(self):
        """Factorise the assembled K; records the number of negative eigenvalues.

        Returns False when K is singular even for a pivoting solver.
        """
        self._band_copy[:, :] = self.band
        status, negative, _ = ldlt_factor_envelope(self.band, self.heights, PIVOT_TOL)
        self._dense_lu = None
        if status == 0:
            self.negative_eigenvalues = int(negative)
            self.factor_ok = True
            return True
        # Near a critical point LDL^T without pivoting may meet a tiny pivot: fall back to a
        # dense symmetric-indefinite factorisation (rare; n is a few hundred).
        dense = band_to_dense(self._band_copy)
        if not np.all(np.isfinite(dense)):
            self.factor_ok = False
            return False
        eig = np.linalg.eigvalsh(dense)
        self.negative_eigenvalues = int(np.sum(eig < 0.0))
        if np.min(np.abs(eig)) <= 1e-15 * np.max(np.abs(eig)):
            self.factor_ok = False
            return False
        self._dense_lu = scipy.linalg.lu_factor(dense, check_finite=False)
        self.factor_ok = True
        return True

    def solve(self, rhs):
        """Solve K X = rhs for rhs (n,) or (n, m); returns a new array."""
        b = np.array(rhs, dtype=float, copy=True)
        one = b.ndim == 1
        b2 = b.reshape(self.n, -1)
        if self._dense_lu is not None:
            out = scipy.linalg.lu_solve(self._dense_lu, b2, check_finite=False)
        else:
            out = ldlt_solve_envelope(self.band, self.heights, np.ascontiguousarray(b2))
        return out.ravel() if one else out

    def fused_newton(self, q, lam, P, tol_force):
        """One fused Newton iteration at load lam P (see `solver.iteration`); updates q.

        Returns (status, residual_max, du_max): status 0 converged (K at q factorised),
        1 LDL^T failed (nothing done: use evaluate/factor/solve), 2 q updated."""
        status, neg, r_max, du_max, energy = newton_iteration(
            q, lam, P, self.elements, self.dofs, self.dof_map, self.band, self.heights,
            self.grad, self.grad_full, self._work, PIVOT_TOL, tol_force)
        self._after_fused(status, neg, energy)
        return status, r_max, du_max

    def fused_mgdc(self, q, lam, P, uP1, tol_force):
        """One fused MGDC corrector iteration; updates q. Returns (status, residual_max,
        du_max, dlam) with the statuses of `fused_newton`."""
        status, neg, r_max, du_max, dl, energy = mgdc_iteration(
            q, lam, P, uP1, self.elements, self.dofs, self.dof_map, self.band, self.heights,
            self.grad, self.grad_full, self._work, PIVOT_TOL, tol_force)
        self._after_fused(status, neg, energy)
        return status, r_max, du_max, dl

    @property
    def last_correction(self):
        """The reduced increment applied by the last `fused_newton` call that updated q."""
        return self._work[:, 1]

    def _after_fused(self, status, neg, energy):
        self.energy = energy
        self._dense_lu = None
        self.factor_ok = status != 1
        if status != 1:
            self.negative_eigenvalues = int(neg)

    def accept(self, q):
        """Hook called by the path followers after every accepted state (and after a
        reroute): nothing to carry along for planar rods (3-D rods update their frames)."""

    def step_norm(self, q_new, q_old):
        """Size of a step between two full states (m), as the path followers measure it."""
        return float(np.linalg.norm(q_new - q_old))

    def reduced(self, q):
        """Reduced DOF values of the full vector ``q``."""
        return q[self.representative]

    def increment(self, q, du, scale=1.0):
        """Apply a reduced increment to the full positions in place."""
        apply_increment(q, self.dof_map, du, scale)

    def dense_stiffness(self, q):
        """Dense reduced K at ``q`` (for tests and eigen-analysis)."""
        self.evaluate(q)
        return band_to_dense(self.band)
