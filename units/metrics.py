"""The load-bearing metrics of a unit (issue 23): the snap path's most negative force, the
snap-back load and stiffness of the released state (iii), and the sheet's surface strain.

Small numeric kernels (`surface_strain`, `largest_strain`, `strain_place`, `apex_stiffness`)
and one driver, `snap_back`, which pushes the released unit's apex back up (+z) from state
(iii) with its base on the rig's rollers and returns the force peak. SI units: N, m, N/m;
strains dimensionless.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from snapmorph.solver.energies import edge_turning, turning_curvature
from snapmorph.solver.problem import ConvergenceError, load_unit, load_vector, make_control, state_from

NAN = float("nan")
UP = (0.0, 1.0)  # the snap-back push: from the other side, away from the base


# ---------------------------------------------------------------------------- strain
def surface_strain(P, X, t):
    """(..., n) the largest surface strain of a planar rod at each node: |eps| + |kappa -
    kappa_bar| t / 2, with eps the axial strain (the mean of the node's edges'), kappa the
    DER curvature 2 tan(phi / 2) / l (phi the turning angle at the node, l its Voronoi
    length in the stress-free rod) and kappa_bar its stress-free value. ``P``: (..., n, 2)
    deformed node positions along the rod (several states at once), ``X``: (n, 2)
    stress-free ones (m); ``t``: thickness (m), one number or one per half edge (n - 1, 2)
    (a node's is the mean of its two half edges'). The two faces carry eps +- dkappa t / 2;
    the larger magnitude is this sum. End nodes: eps only. (A compiled loop: the unit's
    strain searches evaluate it once per solve.)"""
    P, X = np.asarray(P, float), np.ascontiguousarray(X, dtype=float)
    n = X.shape[0]
    flat = np.ascontiguousarray(P.reshape(-1, n, 2))
    out = np.empty(flat.shape[:2])
    _surface_strain(flat, X, _node_thickness(t, n), out)
    return out.reshape(P.shape[:-1])


def _node_thickness(t, n):
    """(n,) the thickness (m) at each node of a rod of n nodes: ``t`` one number, or per half
    edge (n - 1, 2) (an interior node's is the mean of its two half edges'; the ends' 0,
    unused)."""
    t = np.asarray(t, float)
    if t.ndim == 0:
        return np.full(n, float(t))
    t = np.broadcast_to(t, (n - 1, 2))
    t_node = np.zeros(n)
    t_node[1:-1] = 0.5 * (t[:-1, 1] + t[1:, 0])
    return t_node


@njit(cache=True)
def _surface_strain(P, X, t_node, out):
    """`surface_strain` of K states ``P`` (K, n, 2) into ``out`` (K, n); ``t_node`` (n,) m.
    The stress-free lengths and curvatures are computed once for all the states."""
    n = X.shape[0]
    rest = np.empty(max(n - 1, 0))
    for i in range(n - 1):
        rest[i] = _length(X, i)
    here = np.empty(6)  # a node's three positions (the curvature kernel's)
    made = np.empty(n)  # kappa_bar t / 2 / voronoi length at each interior node
    scale = np.empty(n)
    for i in range(1, n - 1):
        for a in range(3):
            for c in range(2):
                here[2 * a + c] = X[i - 1 + a, c]
        made[i] = turning_curvature(here)
        scale[i] = 0.5 * t_node[i] / (0.5 * (rest[i - 1] + rest[i]))
    for k in range(P.shape[0]):
        eps_prev = 0.0
        a0 = b0 = r0 = 0.0
        for i in range(n - 1):
            a1, b1 = P[k, i + 1, 0] - P[k, i, 0], P[k, i + 1, 1] - P[k, i, 1]
            r1 = np.sqrt(a1 * a1 + b1 * b1)
            eps = r1 / rest[i] - 1.0
            if i == 0:
                out[k, 0] = abs(eps)
            else:
                # `turning_curvature` of nodes i-1, i, i+1 from the edges' lengths taken
                # once (its bits, a third of its square roots)
                dkappa = edge_turning(a0, b0, r0, a1, b1, r1) - made[i]
                out[k, i] = abs(0.5 * (eps_prev + eps)) + abs(dkappa) * scale[i]
            eps_prev = eps
            a0, b0, r0 = a1, b1, r1
        out[k, n - 1] = abs(eps_prev)


@njit(cache=True, inline="always")
def _length(Y, i):
    return np.sqrt((Y[i + 1, 0] - Y[i, 0]) ** 2 + (Y[i + 1, 1] - Y[i, 1]) ** 2)


def largest_strain(positions, X, rods, t):
    """(strain, rod name, node index into the rod, state index, per-state maxima (K,)) of
    the largest surface strain (`surface_strain`) of the states ``positions`` ((K, n_nodes,
    2), or one state (n_nodes, 2)); ``rods``: {name: node indices along the rod}. Of nodes
    within 1e-9 of the largest (mirror images in a symmetric state) the one with the
    smallest stress-free x is named, so that round-off does not pick the side."""
    P = np.asarray(positions, float)
    P = P[None] if P.ndim == 2 else P
    per_rod = {name: surface_strain(P[:, nodes], X[nodes], t) for name, nodes in rods.items()}
    series = np.max([s.max(axis=1) for s in per_rod.values()], axis=0)
    state = int(np.argmax(series))
    top = float(series[state])
    best = None
    for name, s in per_rod.items():
        for k in np.flatnonzero(s[state] >= top * (1.0 - 1e-9)):
            x = float(X[rods[name][k], 0])
            if best is None or x < best[0]:
                best = (x, name, int(k))
    return top, best[1], best[2], state, series


class _StateStrain:
    """The largest surface strain of one state (`largest_strain`'s value alone), with each
    rod's stress-free positions and node thicknesses taken once: the strain search
    (`strain_on_path`) reads it at every solve."""

    def __init__(self, X, rods, t):
        self.parts = []
        for nodes in rods.values():
            Xr = np.ascontiguousarray(np.asarray(X, float)[nodes])
            self.parts.append((np.asarray(nodes), Xr, _node_thickness(t, Xr.shape[0])))

    def __call__(self, positions):
        P = np.asarray(positions, float)
        top = -np.inf
        for nodes, Xr, t_node in self.parts:
            out = np.empty((1, Xr.shape[0]))
            _surface_strain(np.ascontiguousarray(P[nodes])[None], Xr, t_node, out)
            m = float(out.max())
            if m != m:  # NaN: as np.max, it wins
                return m
            top = m if m > top else top
        return top


class _Reading:
    """A displacement probe whose solves report ``read(positions, F)`` instead of the force
    F (the largest strain of the state, or -F: a minimum of F is a maximum of -F), for the
    maximum searches (`push_through.refine_peak`)."""

    def __init__(self, probe, read):
        self.probe, self.read = probe, read

    def solve(self, guess, d):
        pos, F, neg = self.probe.solve(guess, d)
        return pos, self.read(pos, F), neg

    @property
    def last_state(self):
        return self.probe.last_state

    @last_state.setter
    def last_state(self, q):
        self.probe.last_state = q


def strain_on_path(probe, d, series, positions, k, X, rods, t, failures, tol=2e-3,
                   rates=None):
    """The largest surface strain along a path whose sample ``k`` has the largest of the
    samples' ``series`` (`largest_strain`): between the samples, by displacement-controlled
    solves where the path is monotone in d around k (`push_through.refine_peak` on the
    strain; ``tol`` its bracket as a fraction of the samples' spacing; ``rates``: the
    samples' dq/dd, the solves' guesses), else the vertex of the parabola through the three
    samples. Never below the sample itself. The samples of a
    path stepped for its force metrics can stride over the strain's peak: read off them,
    the specimen-class units' strain came out up to 1.7 % low."""
    from snapmorph.units.push_through import refine_peak

    strain = _StateStrain(X, rods, t)
    strained = None if probe is None else _Reading(probe, lambda pos, F: strain(pos))
    value = refine_peak(strained, d, series, positions, k, failures, tol, rates)[0]
    return max(float(series[k]), float(value))


def strain_place(rod, x, L) -> str:
    """Where a point at stress-free abscissa ``x`` (m) of rod ``rod`` ("arch" or "base")
    sits, in words: its rod and "apex" ("middle" on the base), "left end", "right end",
    "left flank" or "right flank" (thirds of L, the apex within L / 10), with x / L."""
    f = x / L
    if abs(f - 0.5) <= 0.1:
        part = "apex" if rod == "arch" else "middle"
    elif f < 1.0 / 3.0 or f > 2.0 / 3.0:
        part = "left end" if f < 0.5 else "right end"
    else:
        part = "left flank" if f < 0.5 else "right flank"
    return f"{rod}, {part} (x = {f:.3f} L)"


# ---------------------------------------------------------------------------- F_min
def most_negative_force(probe, d, F, Q, i_pk, end, failures, tol=2e-3, rates=None):
    """(F_min N, d_Fmin m) of the snap path: the most negative F of the samples after the
    peak ``i_pk`` up to sample ``end`` (inclusive), refined by displacement-controlled
    solves where the path is monotone in d around it (`push_through.refine_peak` on -F,
    ``tol`` its bracket as a fraction of the samples' spacing, ``rates`` the samples' dq/dd);
    (NaN, NaN) when F does not fall below zero there."""
    from snapmorph.units.push_through import refine_peak

    if i_pk is None:
        return NAN, NAN
    seg = np.asarray(F[i_pk:end + 1], float)
    m = i_pk + int(np.argmin(seg))
    if not F[m] < 0.0:
        return NAN, NAN
    if 0 < m < len(F) - 1:
        neg_F = -np.asarray(F, float)
        F_max, d_max, _ = refine_peak(None if probe is None else _Reading(probe, lambda pos, F: -F), d, neg_F,
                                      Q, m, failures, tol, rates)
        return -F_max, d_max
    return float(F[m]), float(d[m])


# ---------------------------------------------------------------------------- stiffness
def apex_stiffness(structure, state, node, direction=UP, system=None) -> float:
    """Tangent stiffness (N/m) of ``structure`` at equilibrium ``state`` against a force on
    ``node`` along ``direction``: 1 / (e^T K^-1 e), e the unit load. NaN when K is
    singular."""
    length, fscale = structure.scales()
    control = make_control(structure, node, direction, 1e-3 * length, "mgdc")
    system = structure.reduced_system() if system is None else system
    system.evaluate(state_from(structure, state))
    if not system.factor():
        return NAN
    unit = load_unit(fscale)  # the load scaled as the drivers do: no underflow
    P = load_vector(system, control) * unit
    flexibility = float(P @ system.solve(P))
    return unit * unit / flexibility if flexibility != 0.0 else NAN


# ---------------------------------------------------------------------------- snap-back
def snap_back(model, released, distance, steps=60, push_options=None, failures=(),
              tol=2e-3):
    """The snap-back load of a released unit: its base on the rollers (``model``: the unit
    built without the actuator, rollers on, its base middle held in x), state (iii)
    ``released`` (positions, actuator and supports removed) placed on the rollers, the apex
    pushed up (+z) by MGDC over ``distance`` (m) until F has passed its first maximum.
    ``push_options``: more options of the push (`solver.mgdc.follow_mgdc`: the predictor,
    the path's tolerance, a time limit); ``tol``: the peak search's bracket, a fraction of
    the samples' spacing (`push_through.refine_peak`). Returns (F_back N, d at it m, stiffness N/m at the
    start, the path); F_back NaN when F has no maximum on the push (a failure of the path
    included)."""
    from snapmorph.units.push_through import first_peak, refine_peak
    from snapmorph.solver.states import DisplacementProbe

    st = model.structure
    # (an equilibrium already: the released state is one, moved rigidly onto rollers that
    # carry nothing; the push polishes it by Newton, and its first state's dF/dd is the
    # stiffness there)
    start = on_rollers(released, model.supports, st.reference_positions)

    def past_peak(rows):
        return first_peak(rows["F"]) is not None

    options = dict(push_options or {})
    path = st.push(model.apex, UP, _reach(st, start, model.apex, distance), start=start,
                   steps=steps, stop=past_peak, critical=False, **options)
    stiffness = float(path.stiffness[0]) if path.stiffness is not None and len(path) \
        and np.isfinite(path.stiffness[0]) else apex_stiffness(st, path.positions[0],
                                                               model.apex, UP)
    d, F = np.asarray(path.displacement), np.asarray(path.force)
    i = first_peak(F)
    if i is None:
        return NAN, NAN, stiffness, path
    probe = DisplacementProbe(st, model.apex, UP)
    F_back, d_back, _ = refine_peak(probe, d, F, np.asarray(path.positions), i,
                                    (ConvergenceError, *failures), tol, path.rates)
    return F_back, d_back, stiffness, path


def _reach(st, start, node, distance):
    """The push's distance, counted as the drivers count it: from the stress-free state."""
    X = st.reference_positions
    return float(np.asarray(start)[node, 1] - X[node, 1]) + distance


def on_rollers(positions, rollers, X):
    """``positions`` moved rigidly so that both roller nodes lie on z = 0 and their midpoint
    at its stress-free x (the released state, which is free of the rig, put back on it)."""
    P = np.asarray(positions, float)
    a, b = P[rollers[0]], P[rollers[1]]
    angle = -np.arctan2(b[1] - a[1], b[0] - a[0])
    c, s = np.cos(angle), np.sin(angle)
    R = np.array([[c, -s], [s, c]])
    out = (P - a) @ R.T
    mid = 0.5 * (X[rollers[0], 0] + X[rollers[1], 0])
    out[:, 0] += mid - 0.5 * (out[rollers[0], 0] + out[rollers[1], 0])
    out[:, 1] -= out[rollers[0], 1]
    return out
