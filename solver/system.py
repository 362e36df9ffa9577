"""Constrained, assembled problems: what the path followers work on (`solver.problem.System`).

`BandedSystem` holds what every rod model shares: a DOF map (full -> reduced, -1 held), the
reduced gradient and tangent stiffness in band storage, the factorisation of K with its
inertia count — the banded LDL^T (and a dense pivoting fallback), or for structures whose
envelope makes it slow (sheets) the sparse LDL^T of `solver.sparse`, chosen once per system
by `solver.sparse.system_factorisation` (``factorisation``) — solves and increments. `ReducedSystem`
(planar rods) and `RodSystem3D` (3-D rods with twist, carrying reference frames from state
to state) add the assembly and the fused compiled iterations of their model (`solver.iteration`).
They own no physics of their own. A system may carry dead loads (``loads``: full DOFs,
forces N, stress-free coordinates m): their potential -f (x - X) is part of its energy and
gradient wherever they are assembled, so every driver sees them (docs/loads.md).
"""

from __future__ import annotations

import numpy as np
import scipy.linalg

from snapmorph.solver.assembly import (assemble_banded, assemble_dead_loads, band_slots,
                                       element_dofs, load_record, no_loads,
                                       stiff_second_difference)
from snapmorph.solver.assembly3d import apply_scaled_increment, assemble_system3d_ws, element_dofs3d
from snapmorph.solver.banded import (band_to_dense, envelope_heights, ldlt_factor_envelope,
                                     ldlt_solve_envelope)
from snapmorph.solver.frames3d import canonical_twist_offset, reference_twist, transport_frames
from snapmorph.solver.iteration import (mgdc_iteration, mgdc_iteration3d, newton_iteration,
                                        newton_iteration3d, newton_loop, second_order_term,
                                        settle_state, mgdc_loop, mgdc_step)
from snapmorph.solver.sparse import SparseLDLT, system_factorisation

# A pivot smaller than this times the largest diagonal entry means K is numerically singular
# for LDL^T without pivoting; the dense pivoting fallback then takes over.
PIVOT_TOL = 1e-13
# Above this many DOFs a sparse system's fallback is a sparse pivoting LU (SuperLU) instead
# of the dense one (an eigvalsh of 4000 DOFs takes a minute); its inertia is then the
# sparse LDL^T count of K + SHIFT_FALLBACK max|diag K| I.
DENSE_FALLBACK_MAX = 2000
SHIFT_FALLBACK = 1e-10


class BandedSystem:
    """K_red = W^T K W and the reduced gradient for one set of constraints, in band storage.

    ``dof_map`` (n_full,) int: full -> reduced DOF (-1 held); ``element_dofs``: the reduced
    DOFs of every element's local coordinates (arrays (n_elements, k), -1 held), which fix
    the factor's envelope; ``dof_scale`` (n_full,): dq_full = dof_scale * du_reduced (None:
    all 1, reduced DOFs are the full ones); ``order``: the band's memory order; ``loads``:
    dead loads (full position DOFs (m,), forces (m,) N, stress-free coordinates (m,) m) or
    None."""

    def __init__(self, dof_map, n_reduced, bandwidth, element_dofs, dof_scale=None, order="C",
                 loads=None, heights=None, representative=None):
        self.dof_map = np.ascontiguousarray(dof_map, dtype=np.int64)
        # the dead-load record of `solver.assembly.assemble_dead_loads` (empty: none)
        self.loads = no_loads() if loads is None else load_record(*loads, self.dof_map)
        self._loaded = self.loads[0].shape[0] > 0
        # (no scaling: reduced DOFs are full ones, and the per-step conversions skip it)
        self._scaled = dof_scale is not None
        self.dof_scale = (np.asarray(dof_scale, dtype=float) if self._scaled
                          else np.ones(self.dof_map.shape[0]))
        # one full DOF per reduced DOF, to read reduced values off full states (given: the
        # same, computed before for this DOF map)
        self.representative = representative
        if representative is None:
            free = np.flatnonzero(self.dof_map >= 0)
            self.representative = np.empty(int(n_reduced), dtype=np.int64)
            self.representative[self.dof_map[free]] = free
        self.n = int(n_reduced)
        self.bandwidth = int(bandwidth)
        self.band = np.zeros((self.bandwidth + 1, max(self.n, 1)), order=order)
        self._band_copy = np.empty_like(self.band)
        # the factor's envelope (fill included): assembly clears, the factor and the solves
        # walk only that part of the band (the rest stays zero; no scans per solve)
        # (``heights``: the same, computed before for these element DOFs)
        self.heights = envelope_heights(self.band.shape[1], *element_dofs) \
            if heights is None else heights
        # the one choice of factorisation ("banded" or "sparse"); the sparse pattern and its
        # analysis are built at the first sparse factor()
        self.factorisation = system_factorisation(self.n, self.heights, *element_dofs)
        self._element_dofs = element_dofs
        self._sparse = None
        self._sparse_solves = False  # solve() uses the sparse factor
        self._splu = None  # solve() uses this SuperLU factor (`_factor_sparse_pivoting`)
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
        """Assemble energy (J), gradients (N) and K (N/m) at the full state ``q``."""
        raise NotImplementedError

    def _with_loads(self, q, energy):
        """``energy`` plus the dead loads' potential (their gradient added), when loaded."""
        if not self._loaded:
            return energy
        return energy + assemble_dead_loads(q, self.loads, self.grad, self.grad_full)

    def factor(self):
        """Factorise the assembled K; records the number of negative eigenvalues.

        Returns False when K is singular even for a pivoting solver. The sparse path (when
        chosen) falls back to the banded one below when its pivots are too small.
        """
        self._sparse_solves = False
        self._splu = None
        if self.factorisation == "sparse":
            if self._factor_sparse():
                return True
            if self.n > DENSE_FALLBACK_MAX:
                return self._factor_sparse_pivoting()
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

    def _factor_sparse(self):
        """The sparse LDL^T of the assembled K (band values copied onto its pattern); True
        when it succeeded (inertia recorded, `solve` uses it)."""
        if self._sparse is None:
            self._sparse = SparseLDLT(self.n, *self._element_dofs)
        self._sparse.from_band(self.band)
        status, negative, _ = self._sparse.factor(PIVOT_TOL)
        return status == 0 and self._factored(negative)

    def _factored(self, negative, splu=None):
        """Record a sparse factorisation (``splu``: the pivoting fallback's) for `solve`."""
        self._dense_lu = None
        self._sparse_solves = splu is None
        self._splu = splu
        self.negative_eigenvalues = int(negative)
        self.factor_ok = True
        return True

    def _factor_sparse_pivoting(self):
        """The fallback of a large sparse system where LDL^T without pivoting met a tiny
        pivot: SuperLU with pivoting for the solves, the inertia of K slightly shifted
        (a count exact away from the critical point the tiny pivot signals)."""
        import scipy.sparse.linalg  # noqa: PLC0415 - the rare path only

        f = self._sparse
        self.factor_ok = False
        if not np.all(np.isfinite(f.data)):
            return False
        try:
            lu = scipy.sparse.linalg.splu(f.matrix().tocsc())
        except RuntimeError:  # exactly singular
            return False
        values = f.data.copy()
        f.data[f.diagonal] += SHIFT_FALLBACK * float(np.max(np.abs(values[f.diagonal])))
        status, negative, _ = f.factor(0.0)
        f.data[:] = values
        f.factor_ok = False
        return status == 0 and self._factored(negative, lu)

    def use_band_factor(self):
        """`solve` with the LDL^T factor the caller has made in ``band`` itself."""
        self._dense_lu = None
        self._sparse_solves = False
        self._splu = None

    def solve(self, rhs):
        """Solve K X = rhs for rhs (n,) or (n, m); returns a new array."""
        b = np.array(rhs, dtype=float, copy=True)
        one = b.ndim == 1
        b2 = b.reshape(self.n, -1)
        if self._sparse_solves:
            out = self._sparse.solve(b2)
        elif self._splu is not None:
            out = self._splu.solve(np.ascontiguousarray(b2))
        elif self._dense_lu is not None:
            out = scipy.linalg.lu_solve(self._dense_lu, b2, check_finite=False)
        else:
            out = ldlt_solve_envelope(self.band, self.heights, np.ascontiguousarray(b2))
        return out.ravel() if one else out

    def fused_newton(self, q, lam, P, tol_force):
        """One fused Newton iteration at load lam P (see `solver.iteration`); updates q.

        Returns (status, residual_max, du_max): status 0 converged (K at q factorised),
        1 LDL^T failed or the system factorises sparse (nothing done: use
        evaluate/factor/solve), 2 q updated."""
        if self.factorisation == "sparse":
            return 1, np.nan, np.nan
        status, neg, r_max, du_max, energy = self._newton_iteration(
            q, lam, P, *self._kernel_args, tol_force)
        self._after_fused(status, neg, energy)
        return status, r_max, du_max

    def fused_mgdc(self, q, lam, P, uP1, tol_force):
        """One fused MGDC corrector iteration; updates q. Returns (status, residual_max,
        du_max, dlam) with the statuses of `fused_newton`."""
        if self.factorisation == "sparse":
            return 1, np.nan, np.nan, 0.0
        status, neg, r_max, du_max, dl, energy = self._mgdc_iteration(
            q, lam, P, uP1, *self._kernel_args, tol_force)
        self._after_fused(status, neg, energy)
        return status, r_max, du_max, dl

    def settle(self, q, lam, P):
        """The energy (J) and gradients (N) at ``q``, a state the last correction converged
        to on the displacements, without assembling or factorising K again: K stays
        factorised at the iterate before, within the displacement tolerance of q (its
        inertia and solves hold there to that tolerance). Returns the residual's largest
        entry, or None where this system cannot (then a full iteration confirms q)."""
        return None

    def newton_loop(self, q, lam, P, tol_force, tol_disp, max_iter, max_move, settle):
        """The fused Newton iterations of `solver.newton.newton` in one compiled call, or
        None where the system has none (the caller loops over `fused_newton`). Returns
        (status, it, du_max): 0 converged at iteration ``it``; 1 iteration ``it`` is the
        general path's (see `solver.iteration.newton_loop`)."""
        return None

    def mgdc_loop(self, q, lam, P, uP1, tol_force, tol_disp, max_iter, settle_factor):
        """The fused corrector iterations of `solver.mgdc` in one compiled call, or None
        (the caller loops over `fused_mgdc`). Returns (status, it, lam, du_max, du_prev,
        r_max, done, iterations) (`solver.iteration.mgdc_loop`)."""
        return None

    def mgdc_step(self, q, lam, dlam, P, uP1, settings, weights):
        """A whole MGDC step (predictor, corrector, the new state's tangent) in one
        compiled call, or None (the driver does it in Python). Returns (q_try, uP_try,
        reduced step, the tuple of `solver.iteration.mgdc_step`)."""
        return None

    @property
    def last_correction(self):
        """The reduced increment applied by the last `fused_newton` call that updated q."""
        return self._work[:, 1]

    def _after_fused(self, status, neg, energy):
        self.energy = energy
        self._dense_lu = None
        self._sparse_solves = False
        self._splu = None
        self.factor_ok = status != 1
        if status != 1:
            self.negative_eigenvalues = int(neg)

    def stiff_second_difference(self, q, du):
        """g(q + du) + g(q - du) - 2 g(q) of the stiff terms of the reduced gradient (N), du a
        reduced increment, the assembled K and its factorisation left as they are (the
        second-order predictor of `solver.mgdc`); None where the system does not give it."""
        return None

    def second_order_term(self, q, step, uP, bend_fraction):
        """(du (reduced), dlam) of the MGDC predictor's second-order term at the state ``q``
        (K factorised there) for the tangent step ``step`` along ``uP``
        (`solver.mgdc._Mgdc._bend`), None where the term is not small or the system does not
        give it (then the predictor is the tangent alone)."""
        second = self.stiff_second_difference(q, step)
        if second is None:
            return None
        w = self.solve(second)
        along = float(step @ uP)
        if along == 0.0:
            return None
        mu = float(step @ w) / (2.0 * along)
        bend = mu * uP - 0.5 * w
        if not float(np.linalg.norm(bend)) <= bend_fraction * float(np.linalg.norm(step)):
            return None
        return bend, mu

    def accept(self, q):
        """Hook called by the path followers after every accepted state (and after a
        reroute): nothing to carry along here (3-D rods update their frames)."""

    def reset_frames(self):
        """Back to the frames of a fresh system: nothing to do here (3-D rods)."""

    def state_fields(self, q) -> dict:
        """Per-state arrays the system records on a path instead of the structure's: none
        here (3-D rods: the twists in the canonical convention)."""
        return {}

    def reduced(self, q):
        """Reduced DOF values of the full state ``q``."""
        rep = self.representative
        if self._scaled:
            return np.asarray(q)[rep] / self.dof_scale[rep]
        return np.asarray(q)[rep]

    def step_norm(self, q_new, q_old):
        """Size of a step between two full states in the reduced DOFs' units (m), as the
        path followers measure it."""
        step = np.asarray(q_new) - q_old
        return float(np.linalg.norm(step / self.dof_scale if self._scaled else step))

    def increment(self, q, du, scale=1.0):
        """Apply a reduced increment to the full state in place (tied DOFs move together)."""
        apply_scaled_increment(q, self.dof_map, self.dof_scale, np.asarray(du, dtype=float),
                               float(scale))

    def dense_stiffness(self, q):
        """Dense reduced K at ``q`` (for tests and eigen-analysis)."""
        self.evaluate(q)
        return band_to_dense(self.band)


class ReducedSystem(BandedSystem):
    """The system of planar rods: ``elements`` of `solver.assembly`, ``dof_map``
    (2 n_nodes + 2 n_ghosts,) full -> reduced DOF, ``loads`` dead loads (`BandedSystem`)."""

    def __init__(self, elements, dof_map, n_reduced, bandwidth, loads=None, layout=None):
        """``layout``: (element DOFs, envelope heights, band slots, representatives) of these
        elements and ``dof_map`` when already known (`Structure.reduced_system` keeps them
        with the DOF ordering)."""
        dof_map = np.ascontiguousarray(dof_map, dtype=np.int64)
        self.elements = elements
        self.dofs, heights, slots, representative = layout if layout is not None else \
            (element_dofs(elements, dof_map), None, None, None)
        # Fortran order: the factor and the solves walk the band's columns (1.5x faster)
        super().__init__(dof_map, n_reduced, bandwidth, self.dofs, order="F", loads=loads,
                         heights=heights, representative=representative)
        # where every element's Hessian goes in the band (`solver.assembly.band_slots`)
        self.slots = band_slots(self.dofs, self.band.shape[0]) if slots is None else slots
        # the fused kernels, and their arguments after (q, lam, P[, uP1]) but the last
        self._newton_iteration, self._mgdc_iteration = newton_iteration, mgdc_iteration
        self._kernel_args = (self.elements, self.dofs, self.slots, self.loads, self.dof_map,
                             self.band, self.heights, self.grad, self.grad_full, self._work,
                             PIVOT_TOL)

    def evaluate(self, q):
        """Assemble energy (J), gradients (N) and K (N/m) at positions ``q`` (m)."""
        energy = assemble_banded(q, self.elements, self.dofs, self.slots, self.dof_map,
                                 self.band, self.heights, self.grad, self.grad_full)
        self.energy = self._with_loads(q, energy)
        return self.energy

    def newton_loop(self, q, lam, P, tol_force, tol_disp, max_iter, max_move, settle):
        """`BandedSystem.newton_loop` compiled (`solver.iteration.newton_loop`)."""
        if self.factorisation == "sparse":
            return None
        status, it, du_max, neg, energy = newton_loop(
            q, lam, P, tol_force, tol_disp, max_iter, max_move, settle, *self._kernel_args)
        if it > 0 or status == 0:  # a fused iteration ran: its factor and counts stand
            self._after_fused(0, neg, energy)
        return status, it, du_max

    def mgdc_step(self, q, lam, dlam, P, uP1, settings, weights):
        """`BandedSystem.mgdc_step` compiled (`solver.iteration.mgdc_step`) where K's
        factor at q is the band's own."""
        if self.factorisation == "sparse" or self._dense_lu is not None \
                or self._sparse_solves or self._splu is not None:
            return None
        q_try, uP_try, step = np.empty_like(q), np.empty(self.n), np.empty(self.n)
        out = mgdc_step(q, lam, dlam, P, uP1, settings, weights, q_try, uP_try, step,
                        *self._kernel_args)
        status, it, neg, energy = out[0], out[1], out[8], out[9]
        if status != 1 or it > 1:
            self._after_fused(0 if status != 1 else 2, neg, energy)
        return q_try, uP_try, step, out

    def mgdc_loop(self, q, lam, P, uP1, tol_force, tol_disp, max_iter, settle_factor):
        """`BandedSystem.mgdc_loop` compiled (`solver.iteration.mgdc_loop`)."""
        if self.factorisation == "sparse":
            return None
        (status, it, lam, du_max, du_prev, r_max, done, iterations, neg,
         energy) = mgdc_loop(q, lam, P, uP1, tol_force, tol_disp, max_iter, settle_factor,
                             *self._kernel_args)
        if status != 1 or it > 1:
            self._after_fused(0 if status != 1 else 2, neg, energy)
        return status, it, lam, du_max, du_prev, r_max, done, iterations

    def settle(self, q, lam, P):
        """`BandedSystem.settle` by the compiled gradient-only assembly."""
        if not self.factor_ok:
            return None
        r_max, self.energy = settle_state(q, lam, P, self.elements, self.dof_map, self.loads,
                                          self.grad, self.grad_full, self._work)
        return r_max

    def second_order_term(self, q, step, uP, bend_fraction):
        """`BandedSystem.second_order_term` in one compiled call
        (`solver.iteration.second_order_term`) where K's factor is the band's own."""
        if self._dense_lu is not None or self._sparse_solves or self._splu is not None:
            return super().second_order_term(q, step, uP, bend_fraction)
        out = np.empty(self.n)
        mu, ok = second_order_term(q, np.ascontiguousarray(step, dtype=float),
                                   np.ascontiguousarray(uP, dtype=float), self.elements,
                                   self.dofs, self.dof_map, self.band, self.heights,
                                   float(bend_fraction), out)
        return (out, mu) if ok else None

    def stiff_second_difference(self, q, du):
        """g(q + du) + g(q - du) - 2 g(q) of the stretching and bond-spring terms of the
        reduced gradient (N) (`solver.assembly.stiff_second_difference`); K and its
        factorisation are left as they are. Returns a new array."""
        plus, minus = np.array(q, dtype=float), np.array(q, dtype=float)
        self.increment(plus, du)
        self.increment(minus, du, -1.0)
        out = np.empty(self.n)
        stiff_second_difference(q, plus, minus, self.elements, self.dofs, out)
        return out


class RodSystem3D(BandedSystem):
    """The system of 3-D rods: positions and edge twists, with reference frames.

    ``model``: dict of the model arrays of `solver.assembly3d` (copied: the reference frames
    of a fresh system always start at the structure's stress-free frames); ``dof_map``
    (3 n_nodes + n_edges,) full -> reduced DOF (-1 held). ``twist_length`` (n_edges,) m:
    a reduced twist DOF is twist_length * theta, a length like the positions, so that the
    path followers' step norms and tolerances weigh rotations and displacements alike
    (default 1: reduced twists in rad). The reference frames are carried from accepted state
    to accepted state by ``accept(q)``. ``loads``: dead loads (`BandedSystem`).
    """

    def __init__(self, model, dof_map, n_reduced, bandwidth, twist_length=None, loads=None):
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
        dof_map = np.ascontiguousarray(dof_map, dtype=np.int64)
        self.element_dofs = element_dofs3d(self.n_nodes, self.edge_nodes, self.n_edges,
                                           self.pair_edges, dof_map)
        dof_scale = np.ones(dof_map.shape[0])
        if twist_length is not None:
            dof_scale[3 * self.n_nodes:] = 1.0 / np.asarray(twist_length, dtype=float)
        sf, sr, pf, pr = self.element_dofs
        super().__init__(dof_map, n_reduced, bandwidth, (sr, pr), dof_scale, order="F",
                         loads=loads)
        # the arrays the compiled kernels read (src_t, src_d are updated in place by accept)
        # and the frames' jets, written at every assembly
        n_frames = self.edge_nodes.shape[0]
        self.model_arrays = (self.n_nodes, self.edge_nodes, self.src_t, self.src_d,
                             self.stretch_params, self.pair_edges, self.pair_signs,
                             self.pair_params, sf, sr, pf, pr, np.empty((n_frames, 9)),
                             np.empty((n_frames, 9, 4)), np.empty((n_frames, 9, 4, 4)))
        self._reference_twist = None
        # the fused kernels, and their arguments after (q, lam, P[, uP1]) but the last
        self._newton_iteration, self._mgdc_iteration = newton_iteration3d, mgdc_iteration3d
        self._kernel_args = (self.model_arrays, self.loads, self.dof_map, self.dof_scale,
                             self.band, self.heights, self.grad, self.grad_full, self._work,
                             PIVOT_TOL)

    def evaluate(self, q):
        """Assemble energy (J), gradients (N, N m) and K at the state ``q``."""
        m = self.model_arrays
        q = np.ascontiguousarray(q, dtype=float)
        energy = assemble_system3d_ws(
            q, m[0], m[1], m[2], m[3], m[4], m[5], m[6], m[7], m[8], m[9], m[10], m[11],
            self.dof_scale, self.band, self.grad, self.grad_full, m[12], m[13], m[14],
            self.heights)
        self.energy = self._with_loads(q, energy)
        return self.energy

    def _unit_tangents(self, q):
        """(n_edges, 3) unit tangents of the rods' edges at the state ``q``."""
        X = np.asarray(q[: 3 * self.n_nodes]).reshape(-1, 3)
        en = self.edge_nodes[: self.n_edges]
        e = X[en[:, 1]] - X[en[:, 0]]
        return e / np.linalg.norm(e, axis=1)[:, None]

    def accept(self, q):
        """Carry the reference frames to the state ``q`` by time-parallel transport (the
        material frames at q are unchanged: only the source of the transport moves) and
        record the reference twist of every bending pair of rod edges (rad)."""
        ne = self.n_edges
        t_new = self._unit_tangents(q)
        self.src_d[:ne] = transport_frames(np.ascontiguousarray(self.src_t[:ne]),
                                           self.src_d[:ne], t_new)
        self.src_t[:ne] = t_new
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
        n3, ne = 3 * self.n_nodes, self.n_edges
        t = self._unit_tangents(q)
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
