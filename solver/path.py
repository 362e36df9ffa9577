"""Path recording: the `Path` a push returns, and the `Recorder` the drivers fill.

The recorder sees the structure only through the problem interface (`positions_of`,
`state_fields`; docs/problem-interface.md) and keeps forces and energies in N and J.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numba import njit


@dataclass(repr=False)
class Path:
    """An equilibrium path of a push. Arrays have one entry per converged step.

    displacement: (K,) m, of the node along the direction, from 0;
    force: (K,) N, applied to the node along the direction;
    positions: (K, n_nodes, dim) m; status: "ok" or why the path stopped early
    ("not converged: ...", "stopped: ...", "timeout: ...");
    negative_eigenvalues: (K,) of the tangent stiffness under the path's own control
    (force control for "mgdc", the node's displacement held for "displacement");
    negative_eigenvalues_displacement: (K,) the same with the pushed displacement held;
    critical_points: `solver.stability.CriticalPoint` records (limit points and
    bifurcations met, in path order; empty when the push ran with ``critical=False``);
    fields: the structure's other per-state arrays, name -> (K, ...) (3-D rods: "twist");
    load_factor: (K,) the factor on every dead load (`solver.loading.follow_load` paths;
    None for a push, whose dead loads act at full value throughout);
    limit_load_factor: the load factor at the first limit point of the load factor (the
    dead load at which the structure snaps), None when the path passed none;
    rates: (K, n_nodes, dim) m/m, dq/dd: how the positions change with the pushed node's
    displacement at each state (NaN rows where it is not known, e.g. at a critical point),
    or None when the driver gives none (displacement control; 3-D rods). The probes'
    searches between states take their first guesses from them (`solver.states.between`);
    stiffness: (K,) N/m, dF/dd, the pushed node's tangent stiffness along the path at each
    state (NaN where not known), where ``rates`` are given.
    """

    displacement: np.ndarray
    force: np.ndarray
    positions: np.ndarray
    status: str
    method: str
    energy: np.ndarray
    iterations: np.ndarray
    negative_eigenvalues: np.ndarray
    negative_eigenvalues_displacement: np.ndarray
    info: dict = field(default_factory=dict)
    critical_points: list = field(default_factory=list)
    fields: dict = field(default_factory=dict)
    load_factor: np.ndarray | None = None
    limit_load_factor: float | None = None
    rates: np.ndarray | None = None
    stiffness: np.ndarray | None = None

    @property
    def twist(self) -> np.ndarray:
        """(K, n_edges) rad: the edges' twist angles (3-D rods only)."""
        if "twist" not in self.fields:
            raise AttributeError("this path has no twist (a planar structure)")
        return self.fields["twist"]

    @property
    def stable(self) -> np.ndarray:
        """(K,) bool: stable under the path's own control (no negative eigenvalue)."""
        return self.negative_eigenvalues == 0

    @property
    def stable_displacement(self) -> np.ndarray:
        """(K,) bool: stable with the pushed displacement held."""
        return self.negative_eigenvalues_displacement == 0

    @property
    def bifurcations(self) -> list:
        """The critical points where another branch crosses the path."""
        return [c for c in self.critical_points if c.kind == "bifurcation"]

    @property
    def limit_points(self) -> list:
        """The critical points where F (control "force") or d ("displacement") turns."""
        return [c for c in self.critical_points if c.kind == "limit"]

    def __len__(self):
        return len(self.displacement)

    def __repr__(self):
        n = len(self)
        if n == 0:
            return f"Path(method={self.method!r}, 0 states, status={self.status!r})"
        kinds = {}
        for c in self.critical_points:
            kinds[c.kind] = kinds.get(c.kind, 0) + 1
        crit = ", ".join(f"{v} {k}" for k, v in kinds.items()) or "none"
        return (
            f"Path(method={self.method!r}, {n} states, status={self.status!r},\n"
            f"     d = {self.displacement[0]:.6g} .. {self.displacement[-1]:.6g} m, "
            f"F = {np.min(self.force):.6g} .. {np.max(self.force):.6g} N,\n"
            f"     critical points: {crit}, nodes x dim: "
            f"{self.positions.shape[1]} x {self.positions.shape[2]})"
        )


class Recorder:
    """Collects the converged states of a path (through the structure's interface only).
    Forces and energies come in the driver system's units and are kept in N and J
    (``force_unit``: see `solver.problem.driver_system`). ``rates``: keep each state's
    dq/dd as the path's ``rates`` (the ``rate`` of `add`: (u, c, k), dq/dd = c W u for a
    reduced vector u of the system, k = dF/dd N/m, the path's ``stiffness``; None where
    unknown; mapped to positions once, when the path is made)."""

    def __init__(self, structure, force_unit, system, rates=False):
        self.structure = structure
        self.force_unit = float(force_unit)
        # a system that carries reference frames (3-D rods) records the twists in the
        # canonical convention, so that any other system can restart from a path's states
        self.system = system
        self.rows = {k: [] for k in ("d", "F", "q", "E", "it", "neg", "negd")}
        self.fields = {}
        self.rates = [] if rates else None
        # whether the states carry more than positions (asked once: planar rods do not)
        q0 = structure.initial_state()
        self._fielded = bool(structure.state_fields(q0) or system.state_fields(q0))

    def add(self, d, F, q, E, it, neg, negd, rate=None):
        st, rows = self.structure, self.rows
        rows["d"].append(d)
        rows["F"].append(F * self.force_unit)
        rows["q"].append(np.asarray(st.positions_of(q), dtype=float).copy())
        rows["E"].append(E * self.force_unit)
        rows["it"].append(it)
        rows["neg"].append(neg)
        rows["negd"].append(negd)
        if self.rates is not None:
            self.rates.append(rate)
        if not self._fielded:
            return
        fields = dict(st.state_fields(q))
        fields.update(self.system.state_fields(q))
        for k, v in fields.items():
            self.fields.setdefault(k, []).append(np.array(v, dtype=float, copy=True))

    def rewind(self, rows):
        """Drop the rows from ``rows`` on (a branch abandoned)."""
        for v in self.rows.values():
            del v[rows:]
        for v in self.fields.values():
            del v[rows:]
        if self.rates is not None:
            del self.rates[rows:]

    def path(self, status, method, info, critical_points=()):
        r = self.rows
        st = self.structure
        return Path(
            displacement=np.array(r["d"], dtype=float),
            force=np.array(r["F"], dtype=float),
            positions=np.array(r["q"], dtype=float).reshape(-1, st.n_nodes, int(st.dim)),
            status=status,
            method=method,
            energy=np.array(r["E"], dtype=float),
            iterations=np.array(r["it"], dtype=np.int64),
            negative_eigenvalues=np.array(r["neg"], dtype=np.int64),
            negative_eigenvalues_displacement=np.array(r["negd"], dtype=np.int64),
            info=info,
            critical_points=list(critical_points),
            fields={k: np.array(v) for k, v in self.fields.items()},
            rates=self._rates(),
            stiffness=None if self.rates is None else np.array(
                [np.nan if r is None else r[2] for r in self.rates], dtype=float),
        )

    def _rates(self):
        """(K, n_nodes, dim) dq/dd of the states kept by `add` (NaN rows where unknown)."""
        if self.rates is None:
            return None
        st, system = self.structure, self.system
        dim = int(st.dim)
        out = np.full((len(self.rates), dim * st.n_nodes), np.nan)
        for k, rate in enumerate(self.rates):
            if rate is not None:
                _expand(rate[0], rate[1], system.dof_map, system.dof_scale, out[k])
        return out.reshape(-1, st.n_nodes, dim)


@njit(cache=True)
def _expand(u, scale, dof_map, dof_scale, out):
    """out[j] = scale dof_scale[j] u[dof_map[j]] (0 where held) for the first len(out) full
    DOFs: a reduced vector as node components (W u)."""
    for j in range(out.shape[0]):
        r = dof_map[j]
        out[j] = scale * dof_scale[j] * u[r] if r >= 0 else 0.0
