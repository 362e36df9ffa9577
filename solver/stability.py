"""Stability of equilibria: inertia under force or displacement control, critical modes,
and imperfections seeded in a chosen shape.

An equilibrium is stable under a control when the reduced tangent stiffness K (N/m) of the
degrees of freedom left free by that control is positive definite. Two controls matter for a
push (load vector P along the pushed node's direction):

- force control: the pushed node is free, K as assembled — its number of negative
  eigenvalues ``n_F`` is the count of negative pivots of LDL^T (Sylvester's law of inertia);
- displacement control: the pushed displacement ``P^T u`` is held, i.e. K restricted to
  ``P^T u = 0``. Bordering K with P (Haynsworth inertia additivity) gives
  ``n_d = n_F - 1`` when the flexibility ``P^T K^-1 P`` (m/N, the compliance dd/dF) is
  negative, else ``n_d = n_F``: no second factorisation is needed.

A critical point is where an eigenvalue of one of these stiffnesses is zero. Its mode is the
eigenvector, found here with LAPACK's banded symmetric eigensolver on the few eigenvalues next
to zero (``scipy.linalg.eig_banded``; K is stored in band form already).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg

from snapmorph.solver.problem import load_unit, load_vector, make_control, state_from

__all__ = [
    "StateStability",
    "CriticalPoint",
    "held_count",
    "state_stability",
    "critical_modes",
    "expand_mode",
    "expand_full",
    "eigenmodes",
    "seed_imperfection",
]


@dataclass(frozen=True)
class StateStability:
    """Negative-eigenvalue counts of one equilibrium under force and displacement control."""

    negative_force: int
    negative_displacement: int

    @property
    def stable_force(self) -> bool:
        """Stable with the force on the pushed node held (a dead load)."""
        return self.negative_force == 0

    @property
    def stable_displacement(self) -> bool:
        """Stable with the pushed node's displacement held (a displacement-controlled rig)."""
        return self.negative_displacement == 0


@dataclass
class CriticalPoint:
    """A point of a path where the tangent stiffness under some control is singular.

    kind: "limit" (the control parameter turns there) or "bifurcation" (an eigenvalue
      crosses zero while the parameters keep going: another branch passes through);
    control: the stiffness that is singular at a limit point: "force" (F turns: a force
      maximum or minimum) or "displacement" (d turns: snap-back); "both" for a bifurcation;
    index: path row just before the point (the point lies between rows index and index + 1,
      or is row index + 1 when the path was rerouted through it);
    d (m), F (N): the pushed node's displacement and force at the point;
    positions: (n_nodes, dim) m, or None when the point was not solved for;
    mode: (n_nodes, dim) critical eigenvector (unit 2-norm over the free DOFs; its position
      components), or None;
    eigenvalue: of the reduced K at the located point, N/m (close to zero);
    multiplicity: how many eigenvalues cross; located: solved to tolerance (not read off a
      step); switched: the path left along another branch here.
    """

    kind: str
    control: str
    index: int
    d: float
    F: float
    positions: np.ndarray | None = None
    mode: np.ndarray | None = None
    eigenvalue: float = float("nan")
    multiplicity: int = 1
    located: bool = False
    switched: bool = False


def held_count(negative_force: int, flexibility: float) -> int:
    """Negative eigenvalues with the pushed displacement held, from the force-control count
    and the flexibility ``P^T K^-1 P`` (m/N) of the pushed node."""
    return max(int(negative_force) - (1 if flexibility < 0.0 else 0), 0)


def state_stability(structure, positions, node, direction=(0.0, -1.0),
                    system=None, factorised=False) -> StateStability:
    """Stability of the equilibrium ``positions`` (n_nodes, dim) m or full state vector of
    ``structure`` with a
    load on ``node`` along ``direction``: counts under force and displacement control.

    The state need not be solved here; it should be an equilibrium for the counts to mean
    stability. ``system``: the structure's `reduced_system()` to reuse (several states);
    ``factorised``: it holds K assembled and factorised at this very state already (the
    system of the Newton that converged there, `solver.equilibrium`'s info["system"]): the
    same counts without a second assembly. Raises ValueError when K is singular (a
    critical state)."""
    length, fscale = structure.scales()
    control = make_control(structure, node, direction, 1e-3 * length, "mgdc")
    if system is None:
        system, factorised = structure.reduced_system(), False
    if not factorised:
        system.evaluate(state_from(structure, positions))
        if not system.factor():
            raise ValueError("the tangent stiffness is singular at this state (a critical "
                             "point)")
    P = load_vector(system, control) * load_unit(fscale)  # exact scaling: no underflow
    flexibility = float(P @ system.solve(P))
    neg = system.negative_eigenvalues
    return StateStability(neg, held_count(neg, flexibility))


def critical_modes(band, count, around, P=None):
    """The ``count`` eigenpairs of a banded symmetric K nearest to zero.

    ``band``: (bw + 1, n) lower band storage of K (N/m), not factorised; ``around``: the
    number of negative eigenvalues on one side of the critical point (the crossing
    eigenvalues sit at indices near it); ``P``: when given, modes must be orthogonal to it
    (a bifurcation mode does not move the load), which decides between candidates.
    Returns (eigenvalues (count,), vectors (n, count)) with unit-norm columns, the largest
    component of each positive.
    """
    n = band.shape[1]
    lo = max(0, around - count - 1)
    hi = min(n - 1, around + count + 1)
    w, v = scipy.linalg.eig_banded(band, lower=True, select="i", select_range=(lo, hi),
                                   check_finite=False)
    score = np.abs(w) / max(np.max(np.abs(w)), 1e-300)
    if P is not None:
        p = P / np.max(np.abs(P))  # no overflow for a scaled load
        p = p / np.linalg.norm(p)
        score = score + np.abs(p @ v)  # a load-moving mode only wins when nothing else fits
    pick = np.sort(np.argsort(score)[:count])
    w, v = w[pick], v[:, pick]
    for j in range(v.shape[1]):
        if v[np.argmax(np.abs(v[:, j])), j] < 0:
            v[:, j] = -v[:, j]
    return w, v


def expand_full(system, vector) -> np.ndarray:
    """Reduced DOF vector -> full state-sized vector (fixed DOFs zero, shared DOFs equal)."""
    return np.where(system.dof_map >= 0, vector[np.maximum(system.dof_map, 0)], 0.0)


def expand_mode(system, vector, structure=None) -> np.ndarray:
    """Reduced DOF vector -> (n_nodes, dim) nodal vector (fixed DOFs zero, shared DOFs
    equal); the position components of `expand_full` (planar when ``structure`` is None)."""
    full = expand_full(system, vector)
    if structure is None:
        return full.reshape(-1, 2)
    return np.array(structure.positions_of(full), copy=True)


def eigenmodes(structure, count=6, positions=None, hold=()):
    """The ``count`` lowest eigenpairs of the reduced tangent stiffness at ``positions``
    (default: the stress-free shape), with the (node, component) pairs in ``hold`` held too
    (e.g. ``[(apex, 1)]`` for the pushed DOF under displacement control).

    Returns (eigenvalues (count,) N/m, modes (count, n_nodes, dim)); each mode has unit 2-norm
    over the free DOFs and its largest component positive. Use a mode as an imperfection
    shape with `seed_imperfection`."""
    system = structure.reduced_system(extra_fixed=list(hold) or None)
    system.evaluate(state_from(structure, positions))
    count = int(min(max(count, 1), system.n))
    w, v = scipy.linalg.eig_banded(system.band, lower=True, select="i",
                                   select_range=(0, count - 1), check_finite=False)
    modes = np.empty((count, structure.n_nodes, int(structure.dim)))
    for j in range(count):
        col = v[:, j]
        if col[np.argmax(np.abs(col))] < 0:
            col = -col
        modes[j] = expand_mode(system, col, structure)
    return w, modes


def seed_imperfection(structure, shape, *, amplitude=None, thickness_fraction=None):
    """A copy of ``structure`` whose stress-free shape is the reference plus an imperfection.

    ``shape``: (n_nodes, dim) nodal displacement pattern (e.g. a mode from `eigenmodes` or a
    path's critical mode), scaled so that its largest nodal displacement is ``amplitude``
    (m) — or ``thickness_fraction`` times the smallest rod thickness. Sections, supports,
    ties, rigid groups and springs are copied; the new shape is stress free (reference
    lengths and curvatures are taken from it). Nodes that share displacements should get
    equal displacements in ``shape`` (modes from this module do).
    """
    shape = np.asarray(shape, dtype=float)
    dim = int(structure.dim)
    if shape.shape != (structure.n_nodes, dim) or not np.all(np.isfinite(shape)):
        raise ValueError(f"shape must be a finite ({structure.n_nodes}, {dim}) array; "
                         f"got shape {shape.shape}")
    if (amplitude is None) == (thickness_fraction is None):
        raise ValueError("give exactly one of amplitude (m) or thickness_fraction")
    if amplitude is None:
        t_min = structure.min_thickness()
        amplitude = float(thickness_fraction) * t_min
    amplitude = float(amplitude)
    peak = float(np.max(np.linalg.norm(shape, axis=1)))
    if not np.isfinite(amplitude) or peak == 0.0:
        raise ValueError("the imperfection needs a finite amplitude and a non-zero shape")
    X = structure.positions_of(structure.initial_state()) + (amplitude / peak) * shape
    return structure.with_reference_positions(X)
