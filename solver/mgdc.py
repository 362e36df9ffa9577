"""MGDC load control: the modified generalised displacement control method (Yang & Shieh
1990; modified by Liu & Paulino 2017, the paper's choice).

Each step starts from the tangent ``u_P = K^-1 P`` with a load increment
``dlam = ± s / |u_P|`` — a fixed displacement norm ``s`` per step, which is what GDC's
stiffness parameter achieves. GDC flips the sign when consecutive tangents point apart; here
the predictor is oriented along the previous converged step instead (``sign(u_P . du_prev)``),
which turns at limit points the same way but is not fooled when the tangent rotates fast in
a very compliant structure. Corrector iterations keep the increment orthogonal to the step's
first tangent: ``dlam_j = -(u_P1 . u_R^j) / (u_P1 . u_P^j)``. The step size adapts to the
number of iterations, as in Liu & Paulino's modification.
"""

from __future__ import annotations

import math
import time

import numpy as np

from snapmorph.solver.branching import BranchMonitor, PathState
from snapmorph.solver.newton import SETTLE_FACTOR, TOL_DISP, counted, newton, settled
from snapmorph.solver.path import Recorder
from snapmorph.solver.problem import check_options, driver_system, load_unit, load_vector
from snapmorph.solver.stability import held_count
from snapmorph.solver.steps import CROSSING_REFINE, driver_options, path_info, rig_rescue, timed_out

# A path on which the pushed node travels (sum of |dd|) more than this times the push
# distance goes back and forth between branches instead of on to the target: it is stopped
# with a "stopped: the path wanders" status (a snap-back adds its own return only).
WANDER = 6.0

#: `follow_mgdc`'s predictors
PREDICTORS = ("tangent", "second-order")

# The second-order predictor's curvature term is used only while it is shorter than this
# fraction of the tangent step (longer, the path bends too sharply for a Taylor step: the
# tangent alone, and the step control, take the bend).
BEND_FRACTION = 0.5


def follow_mgdc(
    structure,
    control,
    steps=100,
    max_step=None,
    tol=1e-9,
    max_iter=12,
    max_accept_iter=8,
    target_iterations=4,
    max_steps=20000,
    stop=None,
    min_step_ratio=1e-7,
    branch="follow",
    critical=True,
    switch_size=0.5,
    max_switches=8,
    time_limit=None,
    tol_disp=None,
    predictor="tangent",
):
    """Load-controlled path with MGDC until the node's displacement reaches
    ``control.distance``.

    ``steps``: the first step moves the node by about distance / (4 steps); later steps
    adapt to the iteration count, with a displacement norm per step up to ``max_step`` (m,
    default 8 x the first's); a step that needs more than ``max_accept_iter`` iterations
    is retried at half the size.
    ``stop(path_arrays)`` may end the path early.
    ``critical``, ``branch``, ``switch_size``, ``max_switches``, ``time_limit``,
    ``max_steps``: as for `follow_displacement` (critical points and branch switching).
    ``tol_disp``: the correctors stop when a correction is below it (relative to the
    structure's size; None: `solver.newton.TOL_DISP`) or the residual below ``tol``; a
    looser one saves the last iteration of most steps where the path's samples need not be
    exact (metrics solved again at their own states).
    ``predictor``: "tangent" (the step ``dlam u_P``, the method's own) or "second-order"
    (the tangent step plus the path's curvature term, `_Mgdc._bend`; the tangent alone
    where the system gives no `stiff_second_difference`: 3-D rods).
    """
    t0 = time.perf_counter()
    o = driver_options(steps, tol, max_iter, max_steps, min_step_ratio, max_step,
                       switch_size, max_switches, time_limit, branch)
    o.update(check_options(max_accept_iter=(max_accept_iter, "int", 1, 10**4, ""),
                           target_iterations=(target_iterations, "int", 1, 10**4, ""),
                           tol_disp=(TOL_DISP if tol_disp is None else tol_disp, "pos", 0.0,
                                     1e-2, "(relative to the structure's size)")))
    if predictor not in PREDICTORS:
        raise ValueError(f"predictor must be one of {PREDICTORS}; got {predictor!r}")
    o["predictor"] = predictor
    return _Mgdc(structure, control, o, stop, branch, critical, t0).run()


class _Mgdc:
    """One MGDC push (`follow_mgdc`): its state between steps."""

    def __init__(self, structure, control, o, stop, branch, critical, t0):
        self.t0, self.o, self.stop, self.control = t0, o, stop, control
        self.tol, self.max_iter = o["tol"], o["max_iter"]
        system, fu = driver_system(structure)
        self.system, self.fu = system, fu
        length, fscale = structure.scales()
        self.fscale = fscale = fscale / fu  # forces below are in the system's units (N / fu)
        self.length, self.tol_disp = length, o["tol_disp"] * length
        # the load factor lam is the force in units of `unit` N (see `load_unit`)
        self.unit = load_unit(fscale)
        self.unit_N = self.unit * fu  # N per unit of lam (what the control's targets need)
        self.P = load_vector(system, control) * self.unit
        self._n_free, self._r_idx = control.reduced_weights(system)
        self.q = control.first_state(structure)
        self.lam = 0.0
        self.d = control.d_start
        # dq/dd at each state (`_rate`) where the state is positions alone (planar rods)
        self.rec = Recorder(structure, fu, system, rates=not system.state_fields(self.q))
        system.evaluate(self.q)
        if not system.factor():
            raise ValueError(
                "the structure is not held against rigid-body motion under load control "
                "(singular stiffness); add supports"
            )
        self.uP = system.solve(self.P)
        neg0 = system.negative_eigenvalues
        flex = self.node_component(self.uP)
        self.rec.add(self.d, 0.0, self.q, system.energy, 0, neg0, neg0, self._rate(flex))
        if not flex > 0:
            raise ValueError("the pushed node does not move along the direction under load")
        dd0 = control.span(flex, self.unit_N) / o["steps"]
        # the first step moves the node by a quarter of distance / steps (the path may bend
        # sharply at once); steps then grow up to four times that, i.e. about distance / steps
        self.s0 = s0 = 0.25 * dd0 * np.linalg.norm(self.uP) / flex
        self.monitor = None
        if critical:
            self.monitor = BranchMonitor(structure, control, branch, self.tol, fscale, length,
                                         s0, system=system, switch_size=o["switch_size"],
                                         max_switches=o["max_switches"], load_unit=self.unit,
                                         rig_step=o["switch_size"] * 0.25 * dd0,
                                         driver_max_iter=self.max_iter, force_unit=fu)
            self.monitor.start(PathState(self.q.copy(), 0.0, self.d, neg0, neg0, 1.0, 1.0,
                                         system.energy))
        self.s = s0
        self.s_max = self.s_max0 = 8.0 * s0 if o["max_step"] is None else o["max_step"]
        self.sign = 1.0
        self.step_prev = None
        self.status = "ok"
        self.landed = None  # a control that ends on a load factor: was it landed on exactly?
        self.rejected = 0
        self.total_iterations = 0
        self.travelled = 0.0  # sum of |dd| along the path, m (wandering guard)
        self.arc = 0.0  # the path's length so far in the step norm (reduced DOFs), m
        # (q_try, its reduced step, its flexibility[, held count]) of the trial state, as
        # `_crosses` and `_accept` need them (computed once a step)
        self._trial = None
        self._orient = None  # (u_P, step, sign of u_P . step) last computed, for `run`
        # a whole step in one compiled call where the system has it (`System.mgdc_step`)
        self._settings = (float(self.tol), float(self.fscale), float(self.unit),
                          float(self.tol_disp), int(self.max_iter), float(SETTLE_FACTOR),
                          float(BEND_FRACTION), int(o["predictor"] == "second-order"))
        self._weights = (np.ascontiguousarray(self._n_free, dtype=float),
                         np.ascontiguousarray(self._r_idx, dtype=np.int64),
                         np.ascontiguousarray(system.representative, dtype=np.int64))
        self._fast = None  # (q_try, u_P, reduced step, flexibility, step norm) of that call

    def node_component(self, u):
        """The pushed node's component along the direction of a reduced vector ``u``."""
        return float(self._n_free @ u[self._r_idx])

    def _rate(self, flex):
        """dq/dd and dF/dd at the current state as the recorder keeps them, (u_P, 1 / flex,
        stiffness), from the tangent u_P = K^-1 P whose pushed component is ``flex``: along
        the path u = lam' u_P, d' = lam' flex, so dq/dd = W u_P / flex and dF/dd = (N per
        unit of lam) / flex; None where d does not move with the load (a limit of d)."""
        if not (abs(flex) > 0.0 and np.isfinite(flex)):  # (u_P itself is a finite solve)
            return None
        return self.uP, 1.0 / flex, self.unit_N / flex

    def run(self):
        """Step until the target displacement (or a stop); returns the `Path`."""
        while not self.control.reached(self.d, self.lam, self.unit_N):
            if len(self.rec.rows["d"]) > self.o["max_steps"]:
                self.status = f"stopped: more than {self.o['max_steps']} steps"
                break
            if self.step_prev is not None:
                # orient the predictor along the previous step (passes limit points, where the
                # tangent K^-1 P reverses, without being fooled by fast-rotating tangents)
                self.sign = self._orientation(self.uP, self.step_prev)
            trial = self._step()
            if trial == "rescued":
                continue
            if trial is None or not self._accept(*trial):
                break
        s = self.system
        info = {
            "wall_time": time.perf_counter() - self.t0,
            "bandwidth": s.bandwidth,
            "n_dofs": s.n,
            "final_step_norm": self.s,
            "rejected_steps": self.rejected,
            "total_iterations": self.total_iterations,
        }
        if self.landed is not None:
            info["landed"] = self.landed
        monitor = self.monitor
        return self.rec.path(self.status, "mgdc", path_info(info, monitor),
                             monitor.points if monitor is not None else ())

    def _step(self):
        """Predictor and corrector, halving the step until one is accepted. Returns (q_try,
        lam_try, iterations, u_P at q_try or None), "rescued" (the rig moved the push on)
        or None (the path ends; the status says why)."""
        system, o = self.system, self.o
        uP1 = self.uP
        while True:
            if timed_out(self.t0, o["time_limit"]):
                self.status = (f"timeout: time_limit {o['time_limit']:g} s reached at "
                               f"d = {self.d:.6g} m, F = {self.lam * self.unit * self.fu:.6g} N")
                return None
            q_try, lam_try, it, converged = self._correct(uP1)
            fast, self._fast = self._fast, None
            fast = fast if fast is not None and fast[0] is q_try else None
            # A corrector that wandered far from its predictor may have jumped to another
            # branch: reject the step and retry with half the size.
            # Too many iterations also means the predictor overshot a strongly curved path.
            size = fast[4] if fast is not None else system.step_norm(q_try, self.q)
            if converged and (size > 4.0 * self.s or it > o["max_accept_iter"]):
                converged = False
            uP_try = None
            if converged and fast is not None:  # the step's call solved the tangent
                uP_try = fast[1]
                self._trial = (q_try, fast[2], fast[3])
            if converged and self.monitor is not None and self.s > CROSSING_REFINE * self.s0:
                uP_try = system.solve(self.P) if uP_try is None else uP_try
                converged = not self._crosses(uP_try, q_try)
            if converged:
                return q_try, lam_try, it, uP_try
            self.rejected += 1
            self.s *= 0.5
            if self.s < o["min_step_ratio"] * self.s0:
                self.status = (
                    f"not converged: MGDC step size underflow near d = {self.d:.6g} m, "
                    f"F = {self.lam * self.unit * self.fu:.6g} N"
                )
                return "rescued" if self._rescue() else None
            # restore the factorisation at the last converged state for the next try
            system.evaluate(self.q)
            system.factor()

    def _correct(self, uP1):
        """One predictor along ``uP1`` and the MGDC corrector iterations from it. Returns
        (q_try, lam_try, iterations as step control counts them, converged)."""
        system, P, tol_disp = self.system, self.P, self.tol_disp
        dlam = self.sign * self.s / math.sqrt(float(uP1 @ uP1))
        fast = system.mgdc_step(self.q, self.lam, dlam, P, uP1, self._settings,
                                self._weights)
        if fast is not None:  # the whole step in one call (planar rods)
            q_try, uP_try, step, out = fast
            status, start, lam_try, du_max, du_prev, r_max, done, iterations = out[:8]
            tol_force, flex, size = out[10:]
            self.total_iterations += iterations
            if status == 0:
                self._fast = (q_try, uP_try, step, flex, size)
                return q_try, lam_try, counted(start, done, du_max, tol_disp, r_max,
                                               tol_force), True
            if status == 3:
                return q_try, lam_try, start, False
            return self._general(q_try, lam_try, uP1, tol_force, start, du_max, du_prev)
        q_try = self.q.copy()
        lam_try = self.lam + dlam
        system.increment(q_try, uP1, dlam)
        if self.o["predictor"] == "second-order":
            bend = self._bend(uP1, dlam)
            if bend is not None:
                system.increment(q_try, bend[0])
                lam_try += bend[1]
        tol_force = self.tol * max(self.fscale, abs(lam_try) * self.unit)
        du_max = du_prev = np.inf
        start = 1
        looped = system.mgdc_loop(q_try, lam_try, P, uP1, tol_force, tol_disp, self.max_iter,
                                  SETTLE_FACTOR)
        if looped is not None:  # the fused iterations in one call (planar rods)
            status, start, lam_try, du_max, du_prev, r_max, done, iterations = looped
            self.total_iterations += iterations
            if status == 0:
                return q_try, lam_try, counted(start, done, du_max, tol_disp, r_max,
                                               tol_force), True
            if status == 3:
                return q_try, lam_try, start, False
            return self._general(q_try, lam_try, uP1, tol_force, start, du_max, du_prev)
        return self._general(q_try, lam_try, uP1, tol_force, 1, du_max, du_prev, fused=True)

    def _general(self, q_try, lam_try, uP1, tol_force, start, du_max, du_prev, fused=False):
        """The corrector iterations from iteration ``start`` in Python: the general path
        (assemble, factorise with the dense fallback, solve apart) at ``start`` when a
        compiled iteration failed there (``fused`` False), the fused iterations otherwise.
        Returns what `_correct` returns."""
        system, P, tol_disp = self.system, self.P, self.tol_disp
        it = start
        for it in range(start, self.max_iter + 1):
            done = settled(du_max, du_prev, tol_disp)
            fstat, r_max, du_step, dl = (1, 0.0, 0.0, 0.0) if not fused and it == start \
                else system.fused_mgdc(q_try, lam_try, P, uP1, np.inf if done else tol_force)
            if fstat == 0:
                return q_try, lam_try, counted(it, done, du_max, tol_disp, r_max,
                                               tol_force), True
            if fstat == 2:
                du_max, du_prev = du_step, du_max
                lam_try += dl
                self.total_iterations += 1
                continue
            # LDL^T without pivoting failed: the general path with the dense fallback
            system.evaluate(q_try)
            R = system.grad - lam_try * P
            if not np.all(np.isfinite(R)) or not system.factor():
                break
            r_max = float(np.max(np.abs(R)))
            if r_max <= tol_force or done:
                return q_try, lam_try, counted(it, done, du_max, tol_disp, r_max,
                                               tol_force), True
            both = system.solve(np.stack([P, -R], axis=1))
            uPj, uRj = both[:, 0], both[:, 1]
            denom = float(uP1 @ uPj)
            if denom == 0.0 or not np.isfinite(denom):
                break
            dl = -float(uP1 @ uRj) / denom
            du = dl * uPj + uRj
            if not np.all(np.isfinite(du)):
                break
            du_max, du_prev = float(np.max(np.abs(du))), du_max
            system.increment(q_try, du)
            lam_try += dl
            self.total_iterations += 1
        return q_try, lam_try, it, False

    def _bend(self, uP1, dlam):
        """The second-order term of the predictor at the state q (K factorised there):
        (du (reduced), dlam) of s^2 / 2 times the path's curvature, orthogonal to the
        tangent step du_t = dlam u_P; None where the system gives no second difference or
        the term is not small (BEND_FRACTION).

        On the path g(q) = lam P, so g_qq[du_t, du_t] + K q'' = lam'' P; the second
        difference g(q + du_t) + g(q - du_t) - 2 g(q) is g_qq[du_t, du_t] to fourth order,
        and the term is -w / 2 + mu u_P with w = K^-1 of it and mu the load increment that
        keeps it orthogonal to du_t. Only the stiff terms' difference is taken
        (`stiff_second_difference`: stretching, bond springs): the tangent step stretches
        every rotating edge by the square of its rotation, and the stretching answers with a
        residual some 10^3 times the force scale, which the corrector takes 4-5 iterations
        to remove; with this term, 3."""
        return self.system.second_order_term(self.q, dlam * uP1, uP1, BEND_FRACTION)

    def _crosses(self, uP, q_try):
        """Would the converged trial state q_try (tangent ``uP = K^-1 P`` there) put a
        bifurcation or a jumped fold between itself and q (see CROSSING_REFINE)?"""
        system = self.system
        trial = self._trial
        if trial is not None and trial[0] is q_try:  # (computed by the step's call)
            step, flex = trial[1], trial[2]
        else:
            flex = self.node_component(uP)
            step = system.reduced(q_try) - system.reduced(self.q)
        orient = self._orientation(uP, step)
        negd = held_count(system.negative_eigenvalues, flex)
        self._trial = (q_try, step, flex, negd)  # what `_accept` needs of the same state
        return self.monitor.suspicious(negd, orient * (1.0 if flex >= 0.0 else -1.0))

    def _orientation(self, uP, step):
        """+1 or -1: the sign of u_P . step (the direction of travel along +-u_P), remembered
        for the same pair of arrays (the crossing test, the new state and the next predictor
        ask it of the same tangent and step)."""
        last = self._orient
        if last is not None and last[0] is uP and last[1] is step:
            return last[2]
        orient = 1.0 if float(uP @ step) >= 0.0 else -1.0
        self._orient = (uP, step, orient)
        return orient

    def _rescue(self):
        """The steps underflowed: the rig moves the push on (`steps.rig_rescue`), if it may.
        True when it did (the path goes on from its new state)."""
        reroute = rig_rescue(self.monitor, self.rec, self.unit)
        if reroute is None:
            return False
        self._go_on_from(reroute)
        self.rec.add(self.d, self.lam * self.unit, self.q, reroute.state.energy, 0,
                     reroute.state.neg_force, reroute.state.neg_disp,
                     self._rate(self.node_component(self.uP)))
        self.s, self.status = self.s0, "ok"
        return True

    def _go_on_from(self, reroute):
        """Continue from the first state of the branch a `Reroute` leads onto (the monitor
        left the system factorised there)."""
        s_new = reroute.state
        self.q, self.lam, self.step_prev = s_new.q.copy(), s_new.lam, reroute.step
        self.system.accept(self.q)
        self.uP = self.system.solve(self.P)
        self.d = s_new.d

    def _accept(self, q_try, lam_try, it, uP_try):
        """Take the converged trial state; record it (or the monitor's reroute) and adapt
        the step. False when the path ends here (the status says why, or ``stop``)."""
        system, rec, monitor, unit = self.system, self.rec, self.monitor, self.unit
        target = self.control.landing(self.lam, lam_try, self.unit_N)
        if target is not None:
            q_try, lam_try, it, uP_try = self._land(target, q_try, lam_try, it, uP_try)
        # accepted: the system holds K at q_try
        trial, self._trial = self._trial, None
        seen = trial is not None and trial[0] is q_try and uP_try is not None
        self.step_prev = trial[1] if seen else system.reduced(q_try) - system.reduced(self.q)
        self.q, self.lam = q_try, lam_try
        system.accept(self.q)
        self.uP = system.solve(self.P) if uP_try is None else uP_try
        self.d = self.control.displacement(self.q)
        neg = system.negative_eigenvalues
        # Schur complement: dF/dd of the pushed node is 1 / (n . u_P); a negative one
        # accounts for one negative eigenvalue that holding the displacement removes.
        flex = trial[2] if seen else self.node_component(self.uP)
        known = seen and len(trial) == 4  # (the crossing test's count of this state)
        negd = trial[3] if known else held_count(neg, flex)
        energy, iterations = system.energy, it
        if monitor is not None:
            # direction of travel at the new state: along +-u_P, oriented like the last step
            orient = self._orientation(self.uP, self.step_prev)
            new = PathState(self.q.copy(), self.lam, self.d, neg, negd, orient,
                            orient * (1.0 if flex >= 0.0 else -1.0), energy)
            reroute = self._observe(new)
            if reroute is False:
                return False
            if reroute is not None:
                self._go_on_from(reroute)
                # Restart at a step half the distance from the point: near a bifurcation
                # the other branches are that close, and a longer step could land on one
                # of them (a wrong reversal); steps then grow by 1.5 per step.
                self.s = min(max(self.s, 0.5 * reroute.distance), self.s_max)
                s_new = reroute.state
                neg, negd = s_new.neg_force, s_new.neg_disp
                energy, iterations = s_new.energy, 0
                flex = self.node_component(self.uP)
        rec.add(self.d, self.lam * unit, self.q, energy, iterations, neg, negd,
                self._rate(flex))
        self.travelled += abs(self.d - rec.rows["d"][-2])
        distance = self.control.travel
        if self.travelled > WANDER * distance:
            self.status = _wandering(rec, self.travelled, distance)
            return False
        self.arc += math.sqrt(float(self.step_prev @ self.step_prev))
        if self.o["max_step"] is None:  # the control may let the steps grow with the path
            self.s_max = self.control.max_step(self.s_max0, self.arc)
        target = self.o["target_iterations"]
        if it <= target - 1:
            self.s = min(1.5 * self.s, self.s_max)
        elif it >= target + 3:
            self.s *= 0.6
        if self.stop is not None and self.stop(rec.rows):
            return False
        if abs(self.d - self.control.d_start) > 10 * distance:
            self.status = "stopped: the pushed node moved away from the target distance"
            return False
        return True

    def _land(self, target, q_try, lam_try, it, uP_try):
        """The step from the last state to (q_try, lam_try) passed the control's target load
        factor: Newton at exactly ``target`` from the state interpolated between the two
        (a regular point of a converged step). Returns the state to accept (the landed one,
        or the trial itself when Newton fails there: ``landed`` False); the system holds K
        at it."""
        t = (target - self.lam) / (lam_try - self.lam)
        q = self.q + t * (q_try - self.q)
        tol_force = self.tol * max(self.fscale, abs(target) * self.unit)
        got = newton(self.system, q, target, self.P, tol_force, self.tol_disp, self.max_iter,
                     0.25 * self.length)
        self.landed = got >= 0
        if got >= 0:
            return q, target, got, None
        self.system.evaluate(q_try)
        self.system.factor()
        return q_try, lam_try, it, uP_try

    def _observe(self, new):
        """Show the new state to the monitor. Returns its `Reroute`, None (go on), or False
        (the path ends: a backward branch that does not restabilise, and nothing ahead)."""
        monitor, rec = self.monitor, self.rec
        if monitor.excursion_verdict(new) == "abandon":
            # the backward branch taken at a bifurcation climbs to ever less stable
            # branches instead of restabilising: back to the point, the rig jumps on
            row = monitor.excursion["row"]
            reroute = monitor.abandon_excursion()
            if reroute is None:
                self.status = (f"stopped: the branch left at the bifurcation at d = "
                               f"{rec.rows['d'][row]:.6g} m turns back and does not "
                               f"restabilise, and no stable state lies ahead of the point")
                return False
            rec.rewind(row + 1)
            self.travelled = float(np.sum(np.abs(np.diff(rec.rows["d"]))))
            return reroute
        reroute = monitor.observe(new, len(rec.rows["d"]) - 1)
        if reroute is not None:
            if monitor.excursion is not None and "row" not in monitor.excursion:
                monitor.excursion["row"] = len(rec.rows["d"])
            c = reroute.critical
            rec.add(c.d, c.lam * self.unit, c.q, c.energy, 0, c.neg_force, c.neg_disp)
        return reroute


def _wandering(rec, travelled, distance):
    """The status of a path stopped because d went back and forth (see WANDER)."""
    d = np.asarray(rec.rows["d"])
    dd = np.diff(d)
    dd = dd[dd != 0.0]
    turns = int(np.sum(dd[1:] * dd[:-1] < 0.0))
    return (f"stopped: the path wanders: the pushed node travelled {travelled / distance:.3g} "
            f"x the distance, turning back {turns} times between d = {d.min():.6g} and "
            f"{d.max():.6g} m (branches switched to do not lead to the target); "
            f"try method='displacement'")
