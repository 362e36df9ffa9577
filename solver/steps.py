"""Step control shared by the path followers (`solver.displacement`, `solver.mgdc`): their
options, the time limit, the rig's rescue of a stuck driver, and the path's info record."""

from __future__ import annotations

import time

from snapmorph.solver.problem import check_options

# A step across which the stability count changes while the path keeps its direction is
# retried smaller down to this fraction of the first step: a bifurcation persists however
# small the step, a fold of the path that a long step jumped over does not.
CROSSING_REFINE = 1.0 / 256.0


def driver_options(steps, tol, max_iter, max_steps, min_step_ratio, max_step, switch_size,
                   max_switches, time_limit, branch):
    """The options every driver takes, validated (ValueError naming the bad one)."""
    if branch not in ("follow", "primary"):
        raise ValueError(f"branch must be 'follow' or 'primary'; got {branch!r}")
    return check_options(
        steps=(steps, "int", 1, 10**7, ""),
        tol=(tol, "pos", 0.0, 1e-1, "(relative)"),
        max_iter=(max_iter, "int", 1, 10**4, ""),
        max_steps=(max_steps, "int", 1, 10**8, ""),
        min_step_ratio=(min_step_ratio, "pos", 0.0, 1.0, "(relative)"),
        max_step=(max_step, "pos?", 0.0, 1e300, "m"),
        switch_size=(switch_size, "pos", 0.0, 1e3, "(fraction of the first step)"),
        max_switches=(max_switches, "int", 0, 10**4, ""),
        time_limit=(time_limit, "pos?", 0.0, 1e9, "s"),
    )


def timed_out(t0, time_limit):
    """Has the wall time since ``t0`` (`time.perf_counter`) passed ``time_limit`` s?"""
    return time_limit is not None and time.perf_counter() - t0 > time_limit


def rig_rescue(monitor, rec, unit=1.0, held=False):
    """When a driver's steps underflow: let the monitor move the push on as a
    displacement-controlled rig would (`BranchMonitor.rig_onwards`), if it may. A
    bifurcation found just ahead is added as a path row here (``unit``: N per unit of the
    states' load factor, in the system's force units; ``held``: the path's own count is
    the one with the displacement held, as under displacement control)."""
    if monitor is None or monitor.branch != "follow" or monitor.switches >= monitor.max_switches:
        return None
    reroute = monitor.rig_onwards(len(rec.rows["d"]) - 1)
    if reroute is not None and reroute.new_point:
        c = reroute.critical  # counted by the monitor's own switch
        if monitor.excursion is not None and "row" not in monitor.excursion:
            monitor.excursion["row"] = len(rec.rows["d"])
        rec.add(c.d, c.lam * unit, c.q, c.energy, 0, c.neg_disp if held else c.neg_force,
                c.neg_disp)
    elif reroute is not None:
        monitor.switches += 1
    return reroute


def path_info(info, monitor):
    """A path's info dict, with the critical-point bookkeeping of ``monitor`` (if any)."""
    if monitor is not None:
        info["branch"] = monitor.branch
        info["branch_switches"] = monitor.switches
        info["critical_seconds"] = monitor.seconds
        info["rig_jumps"] = list(monitor.rig_jumps)
        # d (m) of bifurcations whose backward branch MGDC tried and left (it did not
        # restabilise where d turned); the path jumped on from there as a rig does
        info["abandoned_branches"] = list(monitor.abandoned)
    return info
