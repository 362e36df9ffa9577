"""Critical points along a path and branch switching.

`BranchMonitor` watches a path follower step by step. Between two converged states it
compares the stability counts (`solver.stability`) and the direction of travel:

- the force F turns (dF/ds changes sign): a limit point under force control;
- the displacement d turns together with a change of ``n_d`` (the negative eigenvalues with
  the pushed displacement held): a limit point under displacement control (snap-back);
- ``n_d`` changes while d keeps going: a bifurcation — another equilibrium branch crosses
  (its mode does not move the load, so both stiffnesses are singular there). The drivers
  first retry such a step smaller (`solver.steps.CROSSING_REFINE`): a fold of the
  path that a long step jumped over (an imperfect structure) then shows as limit points;
- d turns while ``(-1)^n_d`` does not flip with it: the sign of the determinant of K
  bordered with the path tangent, ``(-1)^n_d sign(dd/ds)``, has flipped, which happens at
  bifurcation points only — the path ran through one along a branch that turns there (a
  secondary branch that rejoins the primary one, say).

A bifurcation is located on the step by regula falsi (Illinois) on a scale-free test
function: ``f = ± (det K_d(tau) / det K_d(0))^(1/m)`` for m crossing eigenvalues (sign read
off the count; ``det K_d ∝ det K · P^T K^-1 P``, so one LDL^T gives both), or the bordered
determinant for a branch through the point. Each evaluation is an equilibrium on the
hyperplane through the linear interpolation of the two step ends.

With ``branch="follow"`` the path then leaves along the other branch through the point:
at the point the equilibrium tangents span ``(phi, 0)`` (the critical mode) and ``(v, 1)``
(``K v = P``, ``v ⟂ phi``); the new direction is the one of that plane orthogonal to the
direction of arrival, and of its two senses the one that increases d is taken (a push rig
advances) — for a symmetric pitchfork both are mirror images and ``+phi`` is taken. The
first state on the new branch is solved on the hyperplane a distance ``eps`` beyond the
point, ``eps = switch_size x`` the driver's first step (a displacement norm).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
import scipy.linalg

from snapmorph.solver.banded import ldlt_factor, ldlt_solve
from snapmorph.solver.descent import descend
from snapmorph.solver.newton import TOL_DISP, newton
from snapmorph.solver.problem import ConvergenceError, driver_system, load_vector
from snapmorph.solver.roots import illinois
from snapmorph.solver.stability import CriticalPoint, critical_modes, expand_full, expand_mode, held_count

BRANCHES = ("follow", "primary")


@dataclass
class PathState:
    """One converged state of a path, as the monitor sees it.

    q: the full state vector (positions, m, and whatever else the structure's state holds);
    lam: load factor, the force on the pushed node along its direction in units of the
    monitor's ``load_unit`` (N);
    d: its displacement along the direction, m; neg_force/neg_disp: negative eigenvalues
    under force / displacement control (-1: unknown); dir_force/dir_disp: +1 or -1 when F / d
    grows along the direction of travel at this state, 0 when unknown.
    """

    q: np.ndarray
    lam: float
    d: float
    neg_force: int
    neg_disp: int
    dir_force: float = 0.0
    dir_disp: float = 1.0
    energy: float = float("nan")


@dataclass
class Reroute:
    """The path leaves its branch: the bifurcation point and the first state beyond it, both
    path rows; ``step``: a reduced vector along the new branch's direction of travel at
    its first state (orients the driver's next predictor);
    ``rate``: dq/dd (flat, 1) along the new branch at its first state, the predictor of a
    displacement-controlled step (None where d turns)."""

    critical: PathState
    state: PathState
    step: np.ndarray
    rate: np.ndarray | None = None
    distance: float = 0.0  # scaled distance (u, omega lam) from the point to the state, m
    new_point: bool = False  # ``critical`` is not a path row yet (see `rig_onwards`)


class BranchMonitor:
    """Detects, classifies and locates critical points; switches branches (see module doc).

    ``structure``/``control``: the push; ``branch``: "follow" or "primary";
    ``fscale`` (N) and ``length`` (m): the structure's scales for the Newton tolerances;
    ``system``: the force-control `ReducedSystem` to share (MGDC), else one is built when
    first needed; ``nominal_step`` (m): the driver's first-step size, displacement norm;
    ``switch_size``: the perturbation as a fraction of it; ``load_unit`` (N): the force of
    a unit load factor (states carry lam = F / load_unit; critical points record F in N).
    ``driver_system``: the system the driver steps with (default ``system``); the monitor's
    own systems that are not it are carried along to every state observed (`accept`), so
    3-D reference frames stay in step with the driver's (planar rods: a no-op).
    """

    def __init__(self, structure, control, branch, tol, fscale, length, nominal_step,
                 system=None, switch_size=0.5, max_switches=8, max_iter=25, load_unit=1.0,
                 rig_step=None, prefer_rig=False, driver_max_iter=25, force_unit=1.0,
                 driver_system=None):
        if branch not in BRANCHES:
            raise ValueError(f"branch must be one of {BRANCHES}; got {branch!r}")
        self.structure = structure
        self.control = control
        self.branch = branch
        self.tol = tol
        self.fscale = fscale
        self.length = length
        self.switch_size = float(switch_size)
        self.nominal_step = float(nominal_step)
        self.max_switches = int(max_switches)
        self.max_iter = int(max_iter)
        self.load_unit = float(load_unit)
        self.rig_step = None if rig_step is None else float(rig_step)
        self._held = None
        self.prefer_rig = bool(prefer_rig)
        self.driver_max_iter = int(driver_max_iter)
        self.force_unit = float(force_unit)  # N per unit of the systems' forces
        self._switched_at: list[np.ndarray] = []  # states of the points switched at
        self.rig_jumps: list[float] = []  # d (m) where the path jumped as a rig snaps
        # A backward branch taken by the tangent plane (where the rig would jump) is on
        # probation until the held count drops back to its value before the point (a true
        # snap-back restabilises at its limit of d); see `excursion_verdict`.
        self.excursion: dict | None = None
        self.abandoned: list[float] = []  # d (m) of points whose backward branch was left
        self._system = system
        self.driver_system = system if driver_system is None else driver_system
        self._P = None
        self.points: list[CriticalPoint] = []
        self.history: list[PathState] = []
        self.switches = 0
        self.seconds = 0.0  # time spent locating and switching

    # ------------------------------------------------------------------ set-up
    @property
    def system(self):
        if self._system is None:
            self._system = driver_system(self.structure)[0]
        return self._system

    @property
    def P(self):
        if self._P is None:
            self._P = load_vector(self.system, self.control) * self.load_unit
        return self._P

    def start(self, state: PathState):
        self.history = [state]

    def _accept(self, q):
        """Carry the monitor's own systems (not the driver's, which the driver carries) to
        the state q, as the driver does with its system after every accepted state."""
        for system in (self._system, self._held):
            if system is not None and system is not self.driver_system:
                system.accept(q)

    # ------------------------------------------------------------------ per step
    def suspicious(self, neg_disp, dir_disp) -> bool:
        """Would a state with these values put a bifurcation (or a fold that a long step
        jumped over) between itself and the last state? See `_classify`."""
        return _classify(self.history[-1], neg_disp, dir_disp)[1] is not None

    def observe(self, new: PathState, index: int) -> Reroute | None:
        """Compare ``new`` with the last state (path row ``index``); record what lies between.

        Returns a `Reroute` when the path should continue on another branch."""
        prev = self.history[-1]
        self._accept(new.q)
        if new.dir_force == 0.0:  # read off the sequence (displacement control)
            new.dir_force = float(np.sign(new.lam - prev.lam))
        if prev.dir_force * new.dir_force < 0.0:
            self._record_limit("force", index, new)
        limit, crossing = _classify(prev, new.neg_disp, new.dir_disp)
        if limit:
            self._record_limit("displacement", index, new)
        reroute = None
        if crossing is not None:
            t0 = time.perf_counter()
            reroute = self._bifurcation(prev, new, crossing, index)
            self.seconds += time.perf_counter() - t0
        if reroute is None:
            self.history = self.history[-1:] + [new]
        else:
            self.history = [reroute.critical, reroute.state]
            self._accept(reroute.state.q)  # the driver goes on from there
        return reroute

    def _record_limit(self, control, index, new):
        """A limit point of F (or of d) near the last states: the vertex of the parabola
        through the last three states (no extra solves)."""
        states = (self.history + [new])[-3:]
        d = np.array([s.d for s in states])
        F = np.array([s.lam for s in states])
        x, y = (d, F) if control == "force" else (F, d)  # y turns as x goes on
        rising = (states[-2].dir_force if control == "force" else states[-2].dir_disp) > 0
        k = int(np.argmax(y) if rising else np.argmin(y))
        xv, yv = x[k], y[k]
        if len(x) == 3 and (x[0] < x[1] < x[2] or x[0] > x[1] > x[2]):
            # the parabola a u^2 + b u + c through the three (u = x - x[1]) in closed form
            # (np.polyfit's least squares cost 0.15 ms a limit point)
            u0, u2 = x[0] - x[1], x[2] - x[1]
            s0, s2 = (y[0] - y[1]) / u0, (y[2] - y[1]) / u2
            a = (s2 - s0) / (u2 - u0)
            b, c = s0 - a * u0, y[1]
            xr = x[1] - b / (2 * a) if a != 0.0 else np.inf
            if x.min() <= xr <= x.max():
                xv, yv = xr, c - b * b / (4 * a)
        d_v, F_v = (xv, yv) if control == "force" else (yv, xv)
        self.points.append(CriticalPoint("limit", control, index, float(d_v),
                                         float(F_v) * self.load_unit * self.force_unit))

    # ------------------------------------------------------------------ bifurcations
    def _bifurcation(self, a, b, m, index):
        """Locate the bifurcation between the states a and b (m crossing eigenvalues; 0: a
        branch through a bifurcation point, see `_classify`), record it, maybe switch.

        When the step is too short to bracket the point (the counts of its two ends,
        recomputed, agree: both ends sit on the singular point within round-off), the end
        state b stands for the point (``located`` False)."""
        located = self._locate(a, b, m)
        if located is None:
            modes = self._modes_at(b.q, max(m, 1))
            if modes is None:
                self._restore(b.q)
                return None
            c = PathState(b.q.copy(), b.lam, b.d, -1, -1, energy=b.energy)
            phi, mu, m = modes[1][:, 0], float(modes[0][0]), max(m, 1)
        else:
            c, phi, mu, m = located
        c.neg_force, c.neg_disp = a.neg_force, a.neg_disp
        st = self.structure
        point = CriticalPoint("bifurcation", "both", index, c.d,
                              c.lam * self.load_unit * self.force_unit,
                              positions=np.array(st.positions_of(c.q), copy=True),
                              mode=expand_mode(self.system, phi, st),
                              eigenvalue=mu * self.force_unit,
                              multiplicity=m, located=located is not None)
        self.points.append(point)
        return self._maybe_switch(point, a, b, c, phi)

    def _maybe_switch(self, point, a, b, c, phi):
        """Switch at ``c`` (reached from ``a``; ``b`` is the driver's last state) when
        following branches; otherwise leave the system at ``b``."""
        reroute = None
        if self.branch == "follow" and self.switches < self.max_switches:
            # Which way on. The rig (`_rig_switch`): the pushed node moves on and the
            # structure settles into a stable state, as under a displacement-controlled
            # rig; it copes with several modes crossing at once (symmetric structures),
            # which the one-mode tangent plane (`_switch`) cannot. When the rig would
            # jump (the branch through the point turns back in d), MGDC takes the tangent
            # plane instead and follows the snap-back (on probation until it restabilises,
            # `excursion_verdict`; a landing onwards in d but less stable than before the
            # point is no snap-back: the rig jumps); displacement control jumps. At a
            # point switched at before, the tangent plane would loop between branches (a
            # wrong reversal): the rig then moves on, jumping if it must.
            eps = self.switch_size * self.nominal_step
            rig_ok = self.rig_step is not None and self.control_axis is not None
            near = 4.0 * max(eps, self.rig_step or 0.0)
            uc = self.system.reduced(c.q)
            repeat = any(float(np.linalg.norm(uc - self.system.reduced(q))) <= near
                         for q in self._switched_at)
            if rig_ok:
                reroute = self._rig_switch(a, c, allow_jump=True if repeat else None)
            if reroute is None and not repeat:
                reroute = self._switch(a, c, phi, eps)
                # (displacement control asked the rig to jump already: it keeps this)
                if reroute is not None and rig_ok and not self.prefer_rig:
                    if reroute.state.dir_disp < 0.0:  # a snap-back, on probation
                        self.excursion = {"a": a, "c": c, "held_before": a.neg_disp,
                                          "points": len(self.points)}
                    elif reroute.state.neg_disp > a.neg_disp:
                        # onwards in d but less stable than before the point: not a
                        # snap-back to follow but (Newton on the plane falling back onto
                        # it) the unstable continuation of the branch just left, or a
                        # branch no rig holds; the rig jumps instead
                        reroute = None
                if reroute is None and rig_ok and not self.prefer_rig:
                    reroute = self._rig_switch(a, c, allow_jump=True)
            if reroute is not None:
                self._switched_at.append(c.q.copy())
        if reroute is None:
            self._restore(b.q)
            return None
        point.switched = True
        self.switches += 1
        return reroute

    def excursion_verdict(self, new: PathState) -> str | None:
        """On a backward branch left by the tangent plane (`_maybe_switch`): "kept" once the
        held count is back to its value before the point (a true snap-back, which
        restabilises where d turns), "abandon" when it exceeds that value by more than one
        (the branch does not restabilise where d turns but climbs to ever less stable
        branches: the wandering of issue 12), else None (still on probation)."""
        if self.excursion is None or new.neg_disp < 0:
            return None
        before = self.excursion["held_before"]
        if new.neg_disp <= before:
            self.excursion = None
            return "kept"
        if new.neg_disp > before + 1:
            return "abandon"
        return None

    def abandon_excursion(self) -> Reroute | None:
        """Leave the backward branch on probation: back at its bifurcation point, do what a
        displacement-controlled rig does there (jump onwards, `_rig_switch`). The critical
        points met on the abandoned branch are dropped. Returns a `Reroute` from the point,
        or None (the path cannot go on)."""
        ex, self.excursion = self.excursion, None
        if ex is None:
            return None
        del self.points[ex["points"]:]
        t0 = time.perf_counter()
        reroute = self._rig_switch(ex["a"], ex["c"], allow_jump=True)
        self.seconds += time.perf_counter() - t0
        if reroute is not None:
            self.abandoned.append(float(ex["c"].d))
            self.history = [reroute.critical, reroute.state]
        return reroute

    def _modes_at(self, q, m):
        """The m eigenpairs of K at q next to zero that do not move the load."""
        self.system.evaluate(q)
        band = self.system.band.copy()
        negative = self._factor_assembled()
        if negative is None:
            return None
        return critical_modes(band, m, negative, self.P)

    # ------------------------------------------------------------------ linear algebra
    # Critical points are where K is singular: the system's own factor() would hand such
    # a K to its dense pivoting fallback (slow: O(n^3), and far slower when BLAS threads
    # compete for the cores). Here any non-zero pivot is accepted: the count and the
    # determinant stay exact, and the Newton corrections below never solve along the
    # singular direction alone (they are combined on a plane that cuts it).
    def _factor(self, q):
        """Assemble and factorise K at q; returns the number of negative eigenvalues of K
        under force control, or None when a pivot is exactly zero (or not finite), or when
        q is degenerate (a trial state of a switch with an edge of zero length: the kernels'
        division by zero is a failed trial, not a failed path)."""
        try:
            self.system.evaluate(q)
        except (ZeroDivisionError, FloatingPointError):
            return None
        return self._factor_assembled()

    def _factor_assembled(self):
        status, negative, _ = ldlt_factor(self.system.band, 0.0)
        return int(negative) if status == 0 else None

    def _solve(self, rhs):
        """Solve with the factor of `_factor`; rhs (n,) or (n, m); returns a new array."""
        b = np.array(rhs, dtype=float).reshape(self.system.n, -1)
        out = ldlt_solve(self.system.band, np.ascontiguousarray(b))
        return out.ravel() if np.ndim(rhs) == 1 else out

    def _restore(self, q):
        """Leave the shared system assembled and factorised (its own way) at q."""
        self.system.evaluate(q)
        self.system.factor()

    # ------------------------------------------------------------------ equilibrium on a plane
    def _solve_on_plane(self, q, lam, normal_u, normal_lam):
        """Newton for grad(q) = lam P with increments kept on the plane
        ``normal_u . du + normal_lam dlam = 0``; q (flat, m) is updated in place.
        Returns (lam, negative count under force control) or None; the factor of K at the
        converged q is left in the system's band (for `_solve`)."""
        sysm, P = self.system, self.P
        fmax = max(self.fscale, abs(lam) * self.load_unit)
        tol_disp = 1e-11 * self.length
        du_max = np.inf
        for it in range(self.max_iter + 1):
            negative = self._factor(q)  # assembles the gradient too
            R = sysm.grad - lam * P
            if negative is None or not np.all(np.isfinite(R)):
                return None
            if np.max(np.abs(R)) <= self.tol * fmax or du_max <= tol_disp:
                return lam, negative
            both = self._solve(np.stack([P, -R], axis=1))
            uP, uR = both[:, 0], both[:, 1]
            denom = float(normal_u @ uP) + normal_lam
            if denom == 0.0 or not np.isfinite(denom):
                return None
            dl = -float(normal_u @ uR) / denom
            du = uR + dl * uP
            du_max = float(np.max(np.abs(du)))
            if not np.isfinite(du_max):
                return None
            sysm.increment(q, du)
            lam += dl
        return None

    def _test_values(self, negative, Du, omega0):
        """At the factorised state: (label, log|g|) of the test function whose sign change
        marks the bifurcation. ``Du`` None: g = det K_d ∝ det K . P^T K^-1 P (bordering K
        with P), label = n_d. Else g = det of K bordered with the path tangent
        ``t ∝ ±(u_P, 1)`` oriented along Du: ``(-1)^n_F sign(t_lam) |det K| (1 +
        |u_P|^2 / omega0^2)^(1/2)``, which changes sign at a bifurcation point on any
        branch through it and stays finite and signed at limit points; label = its sign."""
        sysm, P = self.system, self.P
        uP = self._solve(P)
        flex = float(P @ uP)
        with np.errstate(divide="ignore"):
            logdet = float(np.sum(np.log(np.abs(sysm.band[0, : sysm.n]))))
            if Du is None:
                return held_count(negative, flex), logdet + float(np.log(abs(flex)))
            orient = 1.0 if float(uP @ Du) >= 0.0 else -1.0
            bordered = logdet + 0.5 * float(np.log1p(float(uP @ uP) / omega0**2))
        return (-1.0) ** negative * orient, bordered

    def _locate(self, a, b, m, tol_tau=1e-9, tol_f=1e-7, max_eval=40):
        """The first zero of the test function (`_test_values`) on the step a -> b by
        regula falsi with the Illinois modification; for m > 0 eigenvalues crossing, the
        m-th root of det K_d with m following the count across the shrinking bracket.

        Returns (state, mode (reduced, unit 2-norm), eigenvalue N/m, multiplicity) or None."""
        sysm = self.system
        Du = sysm.reduced(b.q) - sysm.reduced(a.q)
        if not np.any(Du):
            return None
        through = m == 0  # a branch through a bifurcation point: the bordered test
        omega0 = [None]

        def evaluate(tau, lo, hi):
            """Equilibrium on the plane tau (0 at a, 1 at b), from the bracket's states."""
            s = (tau - lo[0]) / (hi[0] - lo[0]) if hi[0] != lo[0] else 0.0
            q = lo[1] + s * (hi[1] - lo[1])
            out = self._solve_on_plane(q, lo[2] + s * (hi[2] - lo[2]), Du, 0.0)
            if out is None:
                return None
            if through and omega0[0] is None:
                omega0[0] = max(float(np.linalg.norm(self._solve(self.P))), 1e-300)
            label, logmag = self._test_values(out[1], Du if through else None, omega0[0])
            return (tau, q, out[0], label, logmag)

        ends = (0.0, a.q, a.lam), (1.0, b.q, b.lam)
        lo, hi = evaluate(0.0, *ends), evaluate(1.0, *ends)
        if lo is None or hi is None or lo[3] == hi[3]:
            return None
        n0, log0 = lo[3], lo[4]

        def root(e):
            return 1 if through else max(int(abs(e[3] - n0)), 1)

        def f_of(e, m):
            sign = 1.0 if e[3] == n0 else -1.0
            return sign * float(np.exp(np.clip((e[4] - log0) / m, -700.0, 700.0)))

        crossing = [root(hi)]  # the multiplicity the current bracket implies

        def restart(e):
            if root(e) == crossing[0]:
                return False
            crossing[0] = root(e)  # fewer eigenvalues cross in the smaller bracket
            return True

        best, _ = illinois(lo, hi, evaluate, lambda e: f_of(e, crossing[0]), tol_tau, tol_f,
                           max_eval, same_side=lambda e: e[3] == n0, restart=restart)
        m = crossing[0]
        _, q, lam, _, _ = best
        modes = self._modes_at(q, m)
        if modes is None:
            return None
        w, v = modes
        state = PathState(q.copy(), lam, _node_displacement(self, q), -1, -1,
                          energy=sysm.energy)
        return state, v[:, 0], float(w[0]), m

    # ------------------------------------------------------------------ switching
    @property
    def control_axis(self):
        """The state component the push moves (an axis-aligned push), else None (no rig:
        an oblique push, or dead loads followed)."""
        return self.control.rig_axis

    @property
    def held_system(self):
        """The system with the pushed displacement held (built when first needed)."""
        if self._held is None:
            self._held = driver_system(
                self.structure, [(self.control.node, self.control_axis)])[0]
        return self._held

    def rig_onwards(self, index=None):
        """See `_rig_onwards`; the monitor's own systems are carried to the new state."""
        reroute = self._rig_onwards(index)
        if reroute is not None:
            self._accept(reroute.state.q)
        return reroute

    def _rig_onwards(self, index=None):
        """The driver is stuck at its last state (its steps shrank to nothing, e.g. at a
        point where several branches meet and a limit point coincides, at a snap-back
        under displacement control, or right at a bifurcation that load control cannot
        step across): do what a displacement-controlled rig does there. First, the rig
        steps on along the current branch (`_critical_ahead`): when the stability count
        changes on the way, the bifurcation is located and recorded (``index``: the path
        row of the last state) and left as at any other (the returned `Reroute` has
        ``new_point`` True: its ``critical`` is not a path row yet). Otherwise the rig
        moves on from the last state (`_rig_switch`); the `Reroute`'s ``critical`` is then
        the last state itself (already a path row). None when neither works."""
        if self.control_axis is None or self.rig_step is None:
            return None
        c = self.history[-1]
        a = self.history[-2] if len(self.history) > 1 else c
        t0 = time.perf_counter()
        reroute = None
        if index is not None:
            reroute = self._critical_ahead(a, c, index)
        if reroute is None:
            # within the driver's own iteration budget: a path stuck because the caller's
            # max_iter is too small stays stuck
            reroute = self._rig_switch(a, c, allow_jump=True,
                                       settle_iter=4 * self.driver_max_iter)
            if reroute is not None:
                self.history = [c, reroute.state]
        else:
            reroute.new_point = True
            self.history = [reroute.critical, reroute.state]
        self.seconds += time.perf_counter() - t0
        return reroute

    def _critical_ahead(self, a, c, index):
        """Does a bifurcation sit just ahead of the stuck state c (reached from a)? The
        rig moves the pushed node on by ``rig_step`` along the arriving chord and Newton
        (no descent: it stays on the current branch, e.g. in a symmetric structure's
        symmetric subspace) solves there; when the held count differs from c's, the point
        between is located and handled by `_bifurcation`. Returns its `Reroute` or None
        (nothing ahead, or not switched; a located point is recorded either way).
        Without it, a load-controlled path stuck at a bifurcation (steps shrinking to
        nothing as the corrector slides off along the mode) was moved on by the rig onto
        the other branch with no critical point recorded (3-D lateral-torsional
        buckling at 201 nodes)."""
        sysd = self.held_system
        q = self._rig_predictor(a, c)
        it = newton(sysd, q, 0.0, None, self.tol * self.fscale, TOL_DISP * self.length,
                    self.max_iter, 0.25 * self.length)
        if it < 0:
            return None
        F = self.control.force(sysd)
        sysm = self.system
        self._restore(q)
        if not sysm.factor_ok:
            self._restore(c.q)
            return None
        flex = float(self.P @ sysm.solve(self.P))
        negative = sysm.negative_eigenvalues
        b = PathState(q, F / self.load_unit, _node_displacement(self, q), negative,
                      held_count(negative, flex), 0.0, 1.0, sysm.energy)
        _, crossing = _classify(c, b.neg_disp, 1.0 if c.dir_disp >= 0.0 else -1.0)
        if not crossing:
            self._restore(c.q)
            return None
        return self._bifurcation(c, b, crossing, index)

    def _rig_switch(self, a, c, allow_jump=None, settle_iter=100):
        """What a displacement-controlled rig does at the bifurcation point c (reached from
        the state a): the pushed node is moved on to d_c + rig_step and the structure settles
        into a stable equilibrium there. Newton from the point (shifted along the arriving
        chord) finds the nearest equilibrium; while it is unstable with the displacement
        held, the state leaves it along all of its unstable modes together and descends the
        energy (`solver.descent.descend`, the least-shift rule). Every branch through the
        point is covered whatever the multiplicity (a symmetric structure may have several
        modes crossing at once), and the new state lies ahead in d. Returns a `Reroute` or None (then `_switch`)."""
        if allow_jump is None:
            allow_jump = self.prefer_rig  # a displacement-controlled path is a rig
        sysd = self.held_system
        q = self._rig_predictor(a, c)
        try:
            descend(sysd, q, self.tol * self.fscale, TOL_DISP * self.length, settle_iter,
                    shift="least", push=0.1 * self.rig_step)
        except ConvergenceError:
            return None
        F = self.control.force(sysd)
        # Did the structure stay on a branch through c, or jump to a far one (a branch
        # through c that turns back in d: the rig snaps)? A quarter of the way back
        # (d_c itself is singular), Newton from the new state lands a quarter (a branch
        # through c straight in d) or half (a pitchfork's branch, sqrt in d) of the way
        # back to c, but stays about as far from c as the new state after a jump.
        gap = float(np.linalg.norm(q - c.q))
        back = q.copy()
        self._hold_at(back, c.d + 0.25 * self.rig_step)
        it = newton(sysd, back, 0.0, None, self.tol * self.fscale, TOL_DISP * self.length,
                    self.max_iter, 0.25 * self.length)
        jump = it < 0 or float(np.linalg.norm(back - c.q)) > 0.75 * gap
        if jump and not allow_jump:
            return None
        if jump:
            self.rig_jumps.append(float(c.d))
        sysd.evaluate(q)
        sysd.factor()
        sysm, P = self.system, self.P
        self._restore(q)
        if not sysm.factor_ok:
            return None
        uP = sysm.solve(P)
        flex = float(P @ uP)
        negative = sysm.negative_eigenvalues
        orient = 1.0 if flex >= 0.0 else -1.0  # onwards in d
        state = PathState(q, F / self.load_unit, _node_displacement(self, q), negative,
                          held_count(negative, flex), orient, 1.0, sysm.energy)
        rate = None
        if abs(flex) > 0.0 and np.isfinite(flex):  # du/dd = u_P / (P^T u_P) on the branch
            rate = expand_full(sysm, uP / flex)
        distance = float(np.linalg.norm(sysm.reduced(q) - sysm.reduced(c.q)))
        return Reroute(c, state, orient * uP, rate, distance)

    def _rig_predictor(self, a, c):
        """The state a rig step of ``rig_step`` beyond the point c predicts: c moved along
        the chord arriving from a, with the pushed node held at d_c + rig_step."""
        delta = self.rig_step
        q = c.q.copy()
        if c.d - a.d > 1e-3 * delta:  # predictor along the arriving chord
            q += (c.q - a.q) * (delta / (c.d - a.d))
        self._hold_at(q, c.d + delta)
        return q

    def _hold_at(self, q, d):
        """Put the pushed node (and the nodes sharing its displacement) of the state q at
        displacement d (m) along the (axis-aligned) push."""
        ctl, axis = self.control, self.control_axis
        held = ctl.member_dofs[:, axis]
        q0 = self.structure.initial_state()
        q[held] = q0[held] + ctl.direction[axis] * d

    def _switch(self, a, c, phi, eps):
        """Leave the point ``c`` along the branch that does not contain the state ``a``
        (the direction of arrival, up to its sense); see the module doc."""
        plane = self._tangent_plane(c, phi)
        if plane is None:
            return None
        e1, e2, omega = plane
        uc = self.system.reduced(c.q)
        arrive = np.append(uc - self.system.reduced(a.q), omega * (c.lam - a.lam))
        a1, a2 = float(e1 @ arrive), float(e2 @ arrive)
        if a1 == 0.0 and a2 == 0.0:
            a1, a2 = 0.0, 1.0
        t = -a2 * e1 + a1 * e2
        t /= np.linalg.norm(t)
        found = []
        for direction in (t, -t):
            state = self._beyond(c, direction, omega, eps)
            if state is not None:
                found.append((state[0], float(direction @ e1), state[1], state[2], direction))
        if not found:
            return None
        _, _, q, lam, direction = _forward(found, c.d, self.length)
        return self._rerouted(c, q, lam, direction, omega)

    def _tangent_plane(self, c, phi):
        """Orthonormal (e1, e2) spanning the equilibrium tangents at the bifurcation point
        c, ``(phi, 0)`` and ``(v, omega)`` with ``K v = P``, ``v ⟂ phi`` (a bordered solve);
        the load is scaled by omega = |v| (m/N). None when K cannot be factorised."""
        if self._factor(c.q) is None:
            return None
        x = self._solve(self.P)
        y = self._solve(phi)
        v = x - (float(phi @ x) / float(phi @ y)) * y
        omega = float(np.linalg.norm(v))
        if not np.isfinite(omega) or omega == 0.0:
            return None
        e1 = np.append(phi, 0.0) / np.linalg.norm(phi)
        e2 = np.append(v, omega) / (np.sqrt(2.0) * omega)
        return e1, e2, omega

    def _beyond(self, c, direction, omega, eps0):
        """The equilibrium on the plane a distance eps beyond c along ``direction`` (scaled
        (u, omega lam)), halving eps from eps0 until Newton lands near the predictor.
        Returns (d, q, lam) or None."""
        sysm = self.system
        uc = sysm.reduced(c.q)
        eps = eps0
        while eps >= 1e-3 * eps0:
            q = c.q.copy()
            sysm.increment(q, direction[:-1], eps)
            out = self._solve_on_plane(q, c.lam + eps * direction[-1] / omega,
                                       direction[:-1], direction[-1] * omega)
            if out is not None:
                dz = np.append(sysm.reduced(q) - uc, omega * (out[0] - c.lam))
                if np.linalg.norm(dz) <= 4.0 * eps:
                    return _node_displacement(self, q), q, out[0]
            eps *= 0.5
        return None

    def _rerouted(self, c, q, lam, direction, omega):
        """The `Reroute` from the point c to the state (q, lam) on the new branch, with the
        shared system left factorised at q. ``direction`` (scaled (u, omega lam), see
        `_switch`) is the branch's direction of departure: the path's direction of travel
        at q is the tangent ±(u_P, 1) that goes on that way. (The chord from c to q is no
        guide: c is located only to a tolerance, off the new branch along the mode, and near
        a pitchfork the chord's component along u_P is round-off.)"""
        sysm, P = self.system, self.P
        self._restore(q)
        uP = sysm.solve(P)
        orient = 1.0 if float(uP @ direction[:-1]) + omega * float(direction[-1]) >= 0.0 else -1.0
        step = orient * uP  # orients the driver's next predictor
        flex = float(P @ uP)
        negative = sysm.negative_eigenvalues
        state = PathState(q, lam, _node_displacement(self, q), negative,
                          held_count(negative, flex), orient,
                          orient * (1.0 if flex >= 0.0 else -1.0), sysm.energy)
        rate = None
        if abs(flex) > 0.0 and np.isfinite(flex):  # du/dd = u_P / (P^T u_P) on the branch
            rate = expand_full(sysm, uP / flex)
        dz = np.append(sysm.reduced(q) - sysm.reduced(c.q), omega * (lam - c.lam))
        return Reroute(c, state, step, rate, float(np.linalg.norm(dz)))


def _classify(prev, neg_disp, dir_disp):
    """What lies between the state ``prev`` and a state with these values.

    Returns (limit, crossing): ``limit`` True for a limit point of d; ``crossing`` None, or
    the number of eigenvalues crossing zero while d keeps its direction (a bifurcation on
    the path), or 0 for a branch that passes through a bifurcation point as it turns in d.
    The latter is read off the invariant ``(-1)^n_d sign(dd/ds)`` — the sign of the
    determinant of K bordered with the tangent — which flips at bifurcation points only.
    """
    crossed = neg_disp - prev.neg_disp
    if prev.dir_disp * dir_disp > 0.0:
        return False, (abs(crossed) if crossed else None)
    if crossed % 2:
        return True, None
    return crossed != 0, 0


def _forward(candidates, d_c, length):
    """Of the candidate states (d, phi-component, q, lam, direction), the one that advances the push
    most; when they advance alike (mirror images), the one along +phi."""
    span = max(abs(f[0] - d_c) for f in candidates)
    tie = 1e-3 * span + 1e-12 * length
    best = max(candidates, key=lambda f: f[0])
    alike = [f for f in candidates if best[0] - f[0] <= tie]
    return max(alike, key=lambda f: f[1])


def _node_displacement(monitor, q):
    """Displacement (m) of the pushed node along the push direction at the state q."""
    return monitor.control.displacement(q)
