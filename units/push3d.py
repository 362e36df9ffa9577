"""The push experiment on a 3-D rod structure: F–d path to past the second zero of F, the
force maximum (i), and the zero-force states (ii) and (iii) solved as equilibria.

Shared by the 3-D unit (`units.unit3d`) and the 2-D unit (`units.unit2d`); the same
definitions as the planar unit (`solver.unit`): F > 0 pushing down, d the downward
displacement of the pushed node, F_cr the first force maximum, d_unstable the first zero of F
with negative slope after it, d_second the next zero with positive slope. SI units.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

NAN = float("nan")
DOWN = (0.0, 0.0, -1.0)


@dataclass
class PushOutcome:
    status: str  # "ok", "monostable", or "not converged: ..."
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


def _stop_after_second_crossing(rows):
    F = rows["F"]
    if len(F) < 3 or F[-1] <= 0.0:
        return False
    return bool(np.any(np.asarray(F[:-1]) < 0.0))


def first_peak(F):
    """Index of the first local maximum of F with F > 0, or None."""
    for i in range(1, len(F) - 1):
        if F[i] > 0 and F[i] >= F[i - 1] and F[i] > F[i + 1]:
            return i
    return None


def first_crossing(F, start, downward):
    """First index i > start where F crosses zero (downward: from >= 0 to < 0)."""
    for i in range(max(start, 0) + 1, len(F)):
        if downward and F[i - 1] >= 0.0 > F[i]:
            return i
        if not downward and F[i - 1] <= 0.0 < F[i]:
            return i
    return None


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
        from solver.states import DisplacementProbe

        return DisplacementProbe(st, node, DOWN)
    except Exception:  # noqa: BLE001 - the path samples then stand for the states
        return None


def refine_peak(probe, d, F, Q, i, tol=2e-2):
    """F_cr, d_cr: the force maximum near path sample i by displacement-controlled solves
    (a limit point under load control is regular under displacement control); the vertex of
    the parabola through three samples when that fails. ``tol``: the search stops when the
    bracket is below this fraction of the samples' spacing (F is flat at its maximum: an
    error e in d costs ~ F'' e^2 / 2 in F_cr)."""
    if probe is not None and d[i - 1] < d[i] < d[i + 1]:
        try:
            from solver.states import refine_maximum

            F_max, d_max = refine_maximum(probe, d, F, Q, i, tol_d=tol * (d[i + 1] - d[i - 1]))
            if F_max >= F[i]:
                return float(F_max), float(d_max), True
        except Exception:  # noqa: BLE001
            pass
    return (*parabola_peak(d, F, i), False)


def _zero_state(st, path, Q, i, node, probe):
    """The equilibrium at F = 0 between path samples i-1 and i (which bracket a zero of F):
    Newton under no load from the interpolated state; if it leaves the bracket, regula falsi
    on displacement-controlled solves first. Returns (positions, solved?); the interpolated
    state (solved = False) only when every solve failed."""
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
            return st.solve_equilibrium(q, node=None)
        from solver.continuation import equilibrium

        return equilibrium(st, q, None, DOWN, 0.0)

    try:
        pos, _ = solve(guess)
        pos = np.asarray(pos)
        if inside(pos):
            return pos, True
    except Exception:  # noqa: BLE001
        pass
    if probe is not None:
        try:
            from solver.states import zero_force_displacement

            tol_F = 1e-9 * max(abs(F[i - 1]), abs(F[i]))
            _, p = zero_force_displacement(probe, d[i - 1], d[i], Q[i - 1], Q[i], F[i - 1],
                                           F[i], tol_F)
            pos, _ = solve(p)
            pos = np.asarray(pos)
            if inside(pos):
                return pos, True
        except Exception:  # noqa: BLE001
            pass
    return (1 - s) * P[i - 1] + s * P[i], False


def push_through(st, node, distance, steps=60, critical=False, method="mgdc") -> PushOutcome:
    """Push ``node`` of ``st`` down (-z) by up to ``distance`` (m), stopping after the force
    has crossed zero twice; extract F_cr, d's and the states (i)-(iii)."""
    try:
        path = st.push(node, DOWN, distance, method=method, stop=_stop_after_second_crossing,
                       steps=steps, critical=critical)
    except Exception as exc:  # noqa: BLE001 - the caller gets the reason in status
        name = type(exc).__name__
        if name == "ValueError":
            raise
        return PushOutcome(status=f"not converged: {name}: {exc}")
    d, F = np.asarray(path.displacement), np.asarray(path.force)
    out = PushOutcome(status="ok", path_status=str(path.status), curve=(d.copy(), F.copy()),
                      path=path)
    Q = path_states(st, path)
    probe = _probe(st, node)
    i_pk = first_peak(F)
    if i_pk is not None:
        out.F_cr, out.d_cr, _ = refine_peak(probe, d, F, Q, i_pk)
        out.states["i"] = np.asarray(path.positions[i_pk]).copy()
    j = first_crossing(F, start=(i_pk or 0), downward=True)
    k = first_crossing(F, start=j, downward=False) if j is not None else None
    if k is None:
        if path.status == "ok" or (j is None and str(path.status).startswith("stopped")):
            out.status = "monostable"
        else:
            out.status = f"not converged: {path.status}"
        return out
    pos_ii, ok_ii = _zero_state(st, path, Q, j, node, probe)
    pos_iii, ok_iii = _zero_state(st, path, Q, k, node, probe)
    out.exact_states = ok_ii and ok_iii
    X = np.asarray(path.positions[0])
    out.d_unstable = float(X[node, 2] - pos_ii[node, 2])
    out.d_second = float(X[node, 2] - pos_iii[node, 2])
    out.states["ii"], out.states["iii"] = pos_ii, pos_iii
    out.bistable = True
    return out
