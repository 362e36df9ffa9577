"""Displacement control: the pushed node's displacement along an axis prescribed step by
step, each state solved by Newton from a secant predictor (a push rig).

A step is retried at half the length when Newton fails, when it breaks the energy balance
(``WORK_TOL``: Newton went to a far state), when the stability count changes across it
(a bifurcation to locate, `solver.branching`) or when F turns or kinks inside it; steps grow
by 1.5 after an easy one. Where the steps underflow the rig moves on (`steps.rig_rescue`) or
snaps forward to the nearest state ahead that releases energy.
"""

from __future__ import annotations

import time

from snapmorph.solver.branching import BranchMonitor, PathState
from snapmorph.solver.newton import TOL_DISP, newton
from snapmorph.solver.path import Recorder
from snapmorph.solver.problem import driver_system, load_unit
from snapmorph.solver.steps import CROSSING_REFINE, driver_options, path_info, rig_rescue, timed_out

# Along a displacement-controlled equilibrium path dE/dd = F, so over a step the energy
# change must match the trapezoidal work 0.5 (F_k + F_k+1) dd to within this fraction of
# |dE| + fscale dd (smooth steps of the arch: <= 0.05, up to 0.09 just after a rig jump;
# a step over the fold where the stable branch ends: 0.15; a jump to a far state: 0.65-1).
# A step that misses it is retried smaller; one that still misses it at the smallest step
# is a real jump (see `_work_mismatch`).
WORK_TOL = 0.1


def follow_displacement(
    structure,
    control,
    steps=100,
    max_step=None,
    min_step_ratio=1e-6,
    tol=1e-9,
    max_iter=25,
    max_steps=20000,
    stop=None,
    branch="follow",
    critical=True,
    switch_size=0.5,
    max_switches=8,
    time_limit=None,
):
    """Prescribe the node's displacement along an axis from its start (0: the stress-free
    state; ``control.d_start`` from a start state) to ``control.distance``.

    ``steps``: initial number of equal steps; steps are halved on failure and grow back
    (up to ``max_step`` m) when Newton converges quickly. ``stop(path_arrays)`` may end
    the path early (it receives the recorder's dict of lists).
    ``critical``: detect, classify and locate critical points (`solver.branching`);
    ``branch``: at a bifurcation, "follow" the branch a push rig follows (leave along
    the critical mode) or stay on the "primary" one; ``switch_size``: the perturbation
    as a fraction of the first step (distance / steps); at most ``max_switches`` switches.
    ``time_limit`` (s): wall time after which the path ends with status "timeout: ...";
    at most ``max_steps`` steps ("stopped: ...").
    """
    t0 = time.perf_counter()
    o = driver_options(steps, tol, max_iter, max_steps, min_step_ratio, max_step,
                       switch_size, max_switches, time_limit, branch)
    return _Rig(structure, control, o, stop, branch, critical, t0).run()


class _Rig:
    """One displacement-controlled push (`follow_displacement`): its state between steps."""

    def __init__(self, structure, control, o, stop, branch, critical, t0):
        self.t0, self.o, self.stop, self.control = t0, o, stop, control
        self.tol, self.max_iter = o["tol"], o["max_iter"]
        axis = control.axis
        self.system, self.fu = driver_system(structure, [(control.node, axis)])
        system, fu = self.system, self.fu
        self.length, fscale = structure.scales()
        self.fscale = fscale = fscale / fu  # forces below are in the system's units (N / fu)
        self.unit = load_unit(fscale)
        self.q0 = structure.initial_state()  # the prescribed displacements count from it
        self.held = control.member_dofs[:, axis]
        self.q = control.first_state(structure)
        self.d = control.d_start
        self.rec = Recorder(structure, fu, system)
        system.evaluate(self.q)
        system.factor()
        neg = system.negative_eigenvalues
        self.rec.add(self.d, 0.0, self.q, system.energy, 0, neg, neg)
        self.dd0 = control.span() / o["steps"]
        self.monitor = None
        if critical:
            self.monitor = BranchMonitor(
                structure, control, branch, self.tol, fscale, self.length,
                nominal_step=self.dd0, switch_size=o["switch_size"],
                max_switches=o["max_switches"], load_unit=self.unit,
                rig_step=o["switch_size"] * control.span() / o["steps"], prefer_rig=True,
                driver_max_iter=self.max_iter, force_unit=fu, driver_system=system)
            self.monitor.start(PathState(self.q.copy(), 0.0, self.d, -1, neg, 0.0, 1.0,
                                         system.energy))
        self.dd_max = self.dd0 if o["max_step"] is None else o["max_step"]
        self.dd = self.dd0
        self.q_prev, self.d_prev = None, self.d
        self.status = "ok"
        self.sign = control.direction[axis]
        self.turn_candidate = None
        self.snap_candidate = None  # first state of a refinement that released energy (a snap)
        self.energy_jumps = []  # d (m) of steps accepted as snaps by the work check

    def run(self):
        """Step until the target displacement (or a stop); returns the `Path`."""
        c = self.control
        while self.d < c.distance * (1 - 1e-12):
            if len(self.rec.rows["d"]) > self.o["max_steps"]:
                self.status = f"stopped: more than {self.o['max_steps']} steps"
                break
            if timed_out(self.t0, self.o["time_limit"]):
                self.status = (f"timeout: time_limit {self.o['time_limit']:g} s reached at "
                               f"d = {self.d:.6g} m")
                break
            step = min(self.dd, c.distance - self.d)
            q_try, target, it, verdict = self._solve_step(step)
            if verdict == "stop":
                break
            if verdict == "retry":
                continue
            self._accept(q_try, target, it)
            if self.stop is not None and self.stop(self.rec.rows):
                break
        s = self.system
        info = {"wall_time": time.perf_counter() - self.t0, "bandwidth": s.bandwidth,
                "n_dofs": s.n, "energy_jumps": self.energy_jumps}
        monitor = self.monitor
        return self.rec.path(self.status, "displacement", path_info(info, monitor),
                             monitor.points if monitor is not None else ())

    def _solve_step(self, step):
        """Newton at d + step from the secant predictor; judge the result. Returns (q_try,
        target, iterations, verdict): verdict "retry" (a smaller step next), "stop" (the
        status says why), "rescued" (the rig moved on; nothing to accept) or "take"."""
        system, rec, fu = self.system, self.rec, self.fu
        q, d, dd0 = self.q, self.d, self.dd0
        q_try = q.copy()
        if self.q_prev is not None and d - self.d_prev > 0:
            q_try += (q - self.q_prev) * (step / (d - self.d_prev))
        target = d + step
        q_try[self.held] = self.q0[self.held] + self.sign * target
        fmax = max(self.fscale, abs(rec.rows["F"][-1]) / fu)
        predicted = system.step_norm(q_try, q)  # m: how far the predictor moved
        it = newton(system, q_try, 0.0, None, self.tol * fmax, TOL_DISP * self.length,
                    self.max_iter, 0.25 * self.length)
        if it >= 0:
            verdict = self._judge(q_try, target, it, step, fmax, predicted)
            if verdict is not None:
                return q_try, target, it, verdict
        if it < 0 and self.turn_candidate is not None:
            q_try, target, it = self.turn_candidate
            system.evaluate(q_try)
            system.factor()
        if it < 0:
            self.dd = step / 2
            if self.dd >= self.o["min_step_ratio"] * dd0:
                return q_try, target, it, "retry"
            return self._underflow()
        return q_try, target, it, "take"

    def _judge(self, q_try, target, it, step, fmax, predicted):
        """None to take a converged step, else "retry" (refined) or "stop"."""
        system, rec, fu, dd0 = self.system, self.rec, self.fu, self.dd0
        E_k, F_k = rec.rows["E"][-1] / fu, rec.rows["F"][-1] / fu
        gap, allowed = _work_mismatch(E_k, system.energy, F_k, self.control.force(system),
                                      step, self.fscale)
        if gap > WORK_TOL:  # Newton went to a far state, not along the path
            if step / 2 >= self.o["min_step_ratio"] * dd0:
                if allowed and self.snap_candidate is None:
                    self.snap_candidate = (q_try.copy(), target, it)
                self.dd = step / 2
                return "retry"
            if not allowed:  # no snap: it would need energy the push did not supply
                self.status = (
                    f"stopped: energy jump: displacement control reached a state at "
                    f"d = {target:.6g} m whose energy exceeds the last one by more than "
                    f"the work of the push however small the step (a jump to a far "
                    f"branch, not a snap; use method='mgdc')"
                )
                return "stop"
            self.energy_jumps.append(target)  # a real snap: it releases energy
        if (self.monitor is not None and step > CROSSING_REFINE * dd0
                and self.monitor.suspicious(system.negative_eigenvalues, 1.0)):
            self.dd = step / 2  # refine a step across which the count changes
            return "retry"
        if step > CROSSING_REFINE * dd0 and _force_turns(
                rec, self.control.force(system) * fu, target, 10 * self.tol * fmax * fu):
            # refine onto a force extremum or a kink (where branches exchange stability);
            # should a shorter step fail (the point may be singular), the longer one is taken
            # (not a state Newton reached only slowly or far from its predictor: that may be
            # a jump to a far branch, which the turn of F then merely reflects; 401-node
            # arch, centre free: F = -6e4 EI h / l^3 with status "ok")
            if (self.turn_candidate is None and it <= self.max_iter // 2
                    and system.step_norm(q_try, self.q) <= 10.0 * predicted):
                self.turn_candidate = (q_try.copy(), target, it)
            self.dd = step / 2
            return "retry"
        return None

    def _underflow(self):
        """The steps underflowed at the last state: the rig moves on, or the push snaps
        forward. Returns (q_try, target, iterations, verdict) as `_solve_step`."""
        system, rec = self.system, self.rec
        reroute = rig_rescue(self.monitor, rec, self.unit, held=True)
        if reroute is not None:  # the rig moved on (a snap): continue from there
            self.q, self.d = reroute.state.q.copy(), reroute.state.d
            self.q_prev, self.d_prev, self.dd = None, self.d, self.dd0
            self.snap_candidate = None
            system.evaluate(self.q)
            system.factor()
            system.accept(self.q)
            neg = system.negative_eigenvalues
            rec.add(self.d, self.control.force(system), self.q, system.energy, 0, neg, neg)
            return None, None, 0, "retry"
        if self.snap_candidate is None:
            self.snap_candidate = self._snap_forward()
        if self.snap_candidate is None:
            self.status = (
                f"not converged: displacement control failed near d = {self.d:.6g} m "
                "(step size underflow; a snap-back? use method='mgdc')"
            )
            return None, None, -1, "stop"
        # no rig to move on (branch="primary"): the path ends in d here (a fold of this
        # branch; arch, centre free, primary branch at d = 1.91 h), so the push snaps
        # forward to a state that releases energy, as a rig does
        q_try, target, it = self.snap_candidate
        self.energy_jumps.append(target)
        system.evaluate(q_try)
        system.factor()
        return q_try, target, it, "take"

    def _snap_forward(self):
        """A displacement-controlled snap past the end of a branch: the nearest state ahead,
        on steps growing from CROSSING_REFINE x the first step up to the first step, that
        Newton reaches from the last state and that releases energy (dE <= work). None if
        there is none; the system is left assembled at the last state then."""
        system, rec, fu, q, d = self.system, self.rec, self.fu, self.q, self.d
        E_k, F_k = rec.rows["E"][-1] / fu, rec.rows["F"][-1] / fu
        fmax = max(self.fscale, abs(F_k))
        step = CROSSING_REFINE * self.dd0
        while step <= self.dd0 * (1 + 1e-12):
            q_try = q.copy()
            q_try[self.held] = self.q0[self.held] + self.sign * (d + step)
            it = newton(system, q_try, 0.0, None, self.tol * fmax, TOL_DISP * self.length,
                        self.max_iter, 0.25 * self.length)
            if it >= 0:
                _, allowed = _work_mismatch(E_k, system.energy, F_k,
                                            self.control.force(system), step, self.fscale)
                if allowed:
                    return q_try, d + step, it
            step *= 2.0
        system.evaluate(q)
        system.factor()
        return None

    def _accept(self, q_try, target, it):
        """Take the converged state (q_try at d = target, ``it`` iterations): record it, and
        follow the monitor's reroute onto another branch if it asks for one."""
        system, rec, monitor = self.system, self.rec, self.monitor
        self.turn_candidate = None
        self.snap_candidate = None
        self.q_prev, self.d_prev = self.q, self.d
        self.q, self.d = q_try, target
        system.accept(self.q)
        F = self.control.force(system)
        neg = system.negative_eigenvalues
        iterations = it
        if monitor is not None:
            new = PathState(self.q.copy(), F / self.unit, self.d, -1, neg, 0.0, 1.0,
                            system.energy)
            reroute = monitor.observe(new, len(rec.rows["d"]) - 1)
            if reroute is not None:
                c = reroute.critical
                rec.add(c.d, c.lam * self.unit, c.q, c.energy, 0, c.neg_disp, c.neg_disp)
                # continue from the first state on the new branch; the next predictor
                # extrapolates along the branch's tangent dq/dd there
                self.q, self.d, iterations = reroute.state.q.copy(), reroute.state.d, 0
                self.dd = max(self.dd, self.dd0)  # steps were refined onto the point: start afresh
                self.q_prev, self.d_prev = None, self.d
                if reroute.rate is not None:
                    self.q_prev, self.d_prev = self.q - reroute.rate * self.dd, self.d - self.dd
                system.evaluate(self.q)
                system.factor()
                system.accept(self.q)
                F = self.control.force(system)
                neg = system.negative_eigenvalues
        rec.add(self.d, F, self.q, system.energy, iterations, neg, neg)
        if it <= 3:
            self.dd = min(1.5 * self.dd, self.dd_max)


def _force_turns(rec, F_new, d_new, noise):
    """Does F(d) turn or bend sharply between the last path rows and a new state (F_new N
    at d_new m)? True when dF changes sign, or when the chord slope of the new step differs
    from the last step's by more than half the larger of the two (a kink, e.g. where a
    secondary branch rejoins and exchanges stability, hides inside one step); changes
    below ``noise`` N are round-off."""
    F, d = rec.rows["F"], rec.rows["d"]
    if len(F) < 2 or not (d[-1] > d[-2] and d_new > d[-1]):
        return False
    before, after = F[-1] - F[-2], F_new - F[-1]
    if abs(before) <= noise or abs(after) <= noise:
        return False
    if before * after < 0.0:
        return True
    s1, s2 = before / (d[-1] - d[-2]), after / (d_new - d[-1])
    return abs(s2 - s1) > 0.5 * max(abs(s1), abs(s2))


def _work_mismatch(E0, E1, F0, F1, dd, fscale):
    """Energy balance of a displacement-controlled step of dd m from energy E0 to E1 (J)
    with forces F0, F1 (N) along the push: along an equilibrium path dE/dd = F, so
    E1 - E0 = 0.5 (F0 + F1) dd up to the trapezoid's error. Returns (gap, allowed): gap is
    |E1 - E0 - work| / (|E1 - E0| + fscale dd) (fscale N: the structure's force scale);
    allowed says whether the energy rose no more than the work supplied (within WORK_TOL
    of that scale): a physical snap releases energy, a jump that gains it is no snap."""
    work = 0.5 * (F0 + F1) * dd
    dE = E1 - E0
    scale = abs(dE) + fscale * dd
    gap = abs(dE - work) / scale if scale > 0.0 else 0.0
    return gap, dE <= work + WORK_TOL * fscale * dd
