"""`RodSystem3D`: the constrained, assembled 3-D rod problem the path followers work on.

It has the members of the planar `solver.system.ReducedSystem` (docs/problem-interface.md)
and reuses its banded LDL^T factorisation (inertia count), solves and increments; it owns the
reference frames, carried from accepted state to accepted state by ``accept(q)``.
"""

from __future__ import annotations

import numpy as np

from snapmorph.solver.assembly3d import apply_scaled_increment, assemble_system3d_ws, element_dofs3d
from snapmorph.solver.banded import envelope_heights
from snapmorph.solver.frames3d import canonical_twist_offset, reference_twist, transport_frames
from snapmorph.solver.iteration3d import mgdc_iteration3d, newton_iteration3d
from snapmorph.solver.system import PIVOT_TOL, ReducedSystem


class RodSystem3D(ReducedSystem):
    """K_red = W^T K W and the reduced gradient of 3-D rods for one set of constraints.

    ``model``: dict of the model arrays of `solver.assembly3d` (copied: the reference frames
    of a fresh system always start at the structure's stress-free frames); ``dof_map``
    (3 n_nodes + n_edges,) full -> reduced DOF (-1 held). ``twist_length`` (n_edges,) m:
    a reduced twist DOF is twist_length * theta, a length like the positions, so that the
    path followers' step norms and tolerances weigh rotations and displacements alike
    (default 1: reduced twists in rad).
    """

    def __init__(self, model, dof_map, n_reduced, bandwidth, twist_length=None):
        self.n_nodes = int(model["n_nodes"])
        self.n_edges = int(model["stretch_params"].shape[0])
        self.edge_nodes = model["edge_nodes"]
        self.src_t = np.array(model["src_t"], dtype=float, copy=True)
        self.src_d = np.array(model["src_d"], dtype=float, copy=True)
        self._stress_free = (self.src_t.copy(), self.src_d.copy())
        self.stretch_params = model["stretch_params"]
        self.pair_edges = model["pair_edges"]
        self.pair_signs = model["pair_signs"]
        self.pair_params = model["pair_params"]
        self.dof_map = np.ascontiguousarray(dof_map, dtype=np.int64)
        self.element_dofs = element_dofs3d(self.n_nodes, self.edge_nodes, self.n_edges,
                                           self.pair_edges, self.dof_map)
        self.dof_scale = np.ones(self.dof_map.shape[0])
        if twist_length is not None:
            self.dof_scale[3 * self.n_nodes:] = 1.0 / np.asarray(twist_length, dtype=float)
        free = np.flatnonzero(self.dof_map >= 0)
        self.representative = np.empty(int(n_reduced), dtype=np.int64)
        self.representative[self.dof_map[free]] = free
        self.n = int(n_reduced)
        self.bandwidth = int(bandwidth)
        self.band = np.zeros((self.bandwidth + 1, max(self.n, 1)), order="F")
        self._band_copy = np.empty_like(self.band)
        # the factor's envelope (fill included): assembly clears, the factor and the solves
        # walk only that part of the band (the rest stays zero)
        self.heights = envelope_heights(self.band.shape[1], self.element_dofs[1],
                                        self.element_dofs[3])
        self.grad = np.zeros(max(self.n, 1))
        self.grad_full = np.zeros(self.dof_map.shape[0])
        self._work = np.zeros((max(self.n, 1), 3))
        # the arrays the compiled kernels read (src_t, src_d are updated in place by accept)
        # and the frames' jets, written at every assembly
        n_frames = self.edge_nodes.shape[0]
        sf, sr, pf, pr = self.element_dofs
        self.model_arrays = (self.n_nodes, self.edge_nodes, self.src_t, self.src_d,
                             self.stretch_params, self.pair_edges, self.pair_signs,
                             self.pair_params, sf, sr, pf, pr, np.empty((n_frames, 9)),
                             np.empty((n_frames, 9, 4)), np.empty((n_frames, 9, 4, 4)))
        self.energy = 0.0
        self.negative_eigenvalues = 0
        self.factor_ok = False
        self._dense_lu = None
        self._reference_twist = None

    def evaluate(self, q):
        """Assemble energy (J), gradients (N, N m) and K at the state ``q``."""
        m = self.model_arrays
        self.energy = assemble_system3d_ws(
            np.ascontiguousarray(q, dtype=float), m[0], m[1], m[2], m[3], m[4], m[5], m[6],
            m[7], m[8], m[9], m[10], m[11], self.dof_scale, self.band, self.grad,
            self.grad_full, m[12], m[13], m[14], self.heights)
        return self.energy

    def reduced(self, q):
        """Reduced DOF values of the full state ``q`` (twists times their length)."""
        rep = self.representative
        return np.asarray(q)[rep] / self.dof_scale[rep]

    def step_norm(self, q_new, q_old):
        """Size of a step between two full states in the reduced DOFs' units (m: twists
        times their length), as the path followers measure it."""
        return float(np.linalg.norm((np.asarray(q_new) - q_old) / self.dof_scale))

    def increment(self, q, du, scale=1.0):
        """Apply a reduced increment to the full state in place."""
        apply_scaled_increment(q, self.dof_map, self.dof_scale, np.asarray(du, dtype=float),
                               float(scale))

    def fused_newton(self, q, lam, P, tol_force):
        """One fused Newton iteration at load lam P (see `solver.iteration3d`); updates q.

        Returns (status, residual_max, du_max): status 0 converged (K at q factorised),
        1 LDL^T failed (nothing done: use evaluate/factor/solve), 2 q updated."""
        status, neg, r_max, du_max, energy = newton_iteration3d(
            q, lam, P, self.model_arrays, self.dof_map, self.dof_scale, self.band, self.heights,
            self.grad, self.grad_full, self._work, PIVOT_TOL, tol_force)
        self._after_fused(status, neg, energy)
        return status, r_max, du_max

    def fused_mgdc(self, q, lam, P, uP1, tol_force):
        """One fused MGDC corrector iteration; updates q. Returns (status, residual_max,
        du_max, dlam) with the statuses of `fused_newton`."""
        status, neg, r_max, du_max, dl, energy = mgdc_iteration3d(
            q, lam, P, uP1, self.model_arrays, self.dof_map, self.dof_scale, self.band,
            self.heights, self.grad, self.grad_full, self._work, PIVOT_TOL, tol_force)
        self._after_fused(status, neg, energy)
        return status, r_max, du_max, dl

    def accept(self, q):
        """Carry the reference frames to the state ``q`` by time-parallel transport (the
        material frames at q are unchanged: only the source of the transport moves) and
        record the reference twist of every bending pair of rod edges (rad)."""
        n3 = 3 * self.n_nodes
        X = np.asarray(q[:n3]).reshape(-1, 3)
        en = self.edge_nodes[: self.n_edges]
        e = X[en[:, 1]] - X[en[:, 0]]
        t_new = e / np.linalg.norm(e, axis=1)[:, None]
        self.src_d[: self.n_edges] = transport_frames(np.ascontiguousarray(self.src_t[: self.n_edges]),
                                                      self.src_d[: self.n_edges], t_new)
        self.src_t[: self.n_edges] = t_new
        self._reference_twist = None

    def reset_frames(self):
        """Back to the stress-free reference frames (as a fresh system): a state handed in
        from outside (its twists canonical, see `state_fields`) then means what it says."""
        t0, d0 = self._stress_free
        self.src_t[:] = t0
        self.src_d[:] = d0
        self._reference_twist = None

    def state_fields(self, q):
        """{"twist": (n_edges,) rad}: the twists of the state ``q`` in the canonical
        convention (`solver.frames3d.canonical_twist_offset`), which any fresh system (or one
        after `reset_frames`) reads as the same material frames. Recorded on paths, so that a
        path's states can be restarted from by another system."""
        n3 = 3 * self.n_nodes
        ne = self.n_edges
        X = np.asarray(q[:n3]).reshape(-1, 3)
        en = self.edge_nodes[:ne]
        e = X[en[:, 1]] - X[en[:, 0]]
        t = e / np.linalg.norm(e, axis=1)[:, None]
        d_ref = transport_frames(np.ascontiguousarray(self.src_t[:ne]),
                                 np.ascontiguousarray(self.src_d[:ne]), t)
        t0, d0 = self._stress_free
        off = canonical_twist_offset(t0[:ne], d0[:ne], t, d_ref)
        return {"twist": np.asarray(q[n3:n3 + ne]) - off}

    @property
    def reference_twist(self):
        """(n_pairs,) rad: the reference twist of every pair of consecutive rod edges at the
        last accepted state (NaN for pairs with a clamp frame or across a joint)."""
        if self._reference_twist is None:
            out = np.full(self.pair_edges.shape[0], np.nan)
            rods = ((self.pair_edges[:, 0] < self.n_edges) & (self.pair_edges[:, 1] < self.n_edges)
                    & (self.pair_signs[:, 0] > 0) & (self.pair_signs[:, 1] > 0))
            out[rods] = reference_twist(self.src_t, self.src_d, self.pair_edges[rods])
            self._reference_twist = out
        return self._reference_twist
