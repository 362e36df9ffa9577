"""How far a design's all-snapped base is from its target, measured the same way for both
procedures: clamped on the target's start and tangent, and after the best rigid placement;
`assess` for the predicted base, `verify_design` for the whole array simulated."""

from __future__ import annotations

import math

import numpy as np

from snapmorph.design.inverse_result import Design
from snapmorph.design.map_model import chain_fast
from snapmorph.design.targets import best_rigid_placement, deviation, place_rigid, resample


def assess(design: Design, target_xy: np.ndarray, dm, state_kw: dict, placement: str,
           tol: float, start=None, angle=None, quick: int | None = None) -> Design:
    """Fill in the deviations of a design's predicted all-snapped base, both ways: start
    clamped on the target's start point and tangent, and best rigid placement; select the one
    `placement` names for `predicted`, `max_deviation`, `rms_deviation` and `placement`.
    quick: search the best placement from (start, angle) only, in at most `quick` iterations
    (while comparing candidates; the chosen design is assessed in full)."""
    t_angle = (float(design.control_angles[0]) if len(design.control_angles)
               else start_tangent(target_xy))
    local = chain_fast(design.units, dm, state_kw).xy
    s0 = start if start is not None else target_xy[0]
    a0 = angle if angle is not None else t_angle
    design.deviations, design.placements = placed_both_ways(
        local, target_xy, t_angle, s0, a0, kabsch=quick is None, maxiter=quick or 400)
    design.placement_mode = placement
    design.placement = design.placements[placement]
    x0, y0, a = design.placement
    ch = chain_fast(design.units, dm, state_kw, start=(x0, y0), angle=a)
    design.predicted = ch.xy
    design._chain = ch
    design.max_deviation, design.rms_deviation = design.deviations[placement]
    design.tol = tol
    design.met = bool(design.max_deviation <= tol)
    return design


def verify_design(design: Design, nodes: int | None = None) -> dict:
    """Simulate the designed array as a whole (`design.arrays.simulate_array`, every arched unit
    snapped in order, actuators removed) and measure its base against the target both ways.
    Returns (and stores as `design.verification`) {"status", "time", "xy" (placed as the design
    says), "deviations": {"best": (max, rms), "clamped": (max, rms)}, "placements": ...,
    "failure", "result" (the `ArrayResult`), "interference" (its overlapping parts,
    `design.interference`)}. A failed verification (`verification_failure`: the simulation
    did not end ok, or its deviation misses the design's tol; or parts of the array overlap
    in a state it went through) is never met: `design.met` becomes False and
    `design.verification_failure` says why."""
    import time

    from snapmorph.design.arrays import simulate_array

    t0 = time.perf_counter()
    r = simulate_array(design.units, None, nodes=nodes)
    target_xy = design.target
    local = r.base
    out = {"status": r.status, "time": time.perf_counter() - t0}
    t_angle = start_tangent(target_xy)
    x0, y0, a0 = design.placement if design.placement is not None else (*target_xy[0], t_angle)
    out["deviations"], out["placements"] = placed_both_ways(local, target_xy, t_angle, (x0, y0), a0)
    out["xy"] = place_rigid(local, (x0, y0), a0)
    bx, by, ba = out["placements"]["best"]
    out["xy_best"] = place_rigid(local, (bx, by), ba)
    out["max_deviation"], out["rms_deviation"] = out["deviations"][design.placement_mode]
    out["failure"] = verification_failure(r.status, out["max_deviation"], design.tol,
                                          design.placement_mode, design.target_length)
    overlaps = list(getattr(r, "interference", ()))
    out["result"], out["interference"] = r, overlaps
    if out["failure"] is None and overlaps:  # no contact modelled: a clash is a failure
        out["failure"] = (f"{len(overlaps)} overlap(s) of parts in the simulated states, "
                          f"first: {overlaps[0]}")
    design.verification = out
    design.verification_failure = out["failure"]
    if design.tol is not None:
        design.met = bool(design.max_deviation <= design.tol) and not out["failure"]
    return out


def verification_failure(status: str, max_deviation: float, tol: float | None,
                         placement: str, length: float) -> str | None:
    """Why a whole-array simulation does not confirm a design (None when it does): it did not
    end "ok" (not converged, snapped back, ...), or its deviation (a fraction of the target's
    `length`, m) with the `placement` the tolerance applies to is above `tol`."""
    if status != "ok":
        return f"the whole-array simulation ended {status!r}, not ok"
    if not math.isfinite(max_deviation):
        return "the simulated array's deviation is not finite"
    if tol is not None and max_deviation > tol:
        return (f"the simulated array deviates {100 * max_deviation:.2f} % "
                f"({max_deviation * length * 1e3:.2f} mm) > tol {100 * tol:.2f} % "
                f"({placement} placement)")
    return None


def start_tangent(target_xy: np.ndarray) -> float:
    """Direction (rad) of the target's start tangent: its first step at 2001 samples."""
    seg = np.diff(resample(target_xy, 2001)[:2], axis=0)[0]
    return math.atan2(seg[1], seg[0])


def placed_both_ways(local: np.ndarray, target_xy: np.ndarray, t_angle: float, start, angle,
                     **search) -> tuple[dict, dict]:
    """An all-snapped base given from (0, 0) heading +x, placed on the target two ways:
    "clamped" (its start on the target's start point, heading `t_angle`, rad) and "best" (the
    rigid placement searched from `start` (m) and `angle`; `search`: options of
    `best_rigid_placement`), never worse than clamped. Returns ({way: (max, rms) deviation as
    fractions of the target's length}, {way: (x0 m, y0 m, angle rad)})."""
    t_start = target_xy[0]
    clamped = place_rigid(local, t_start, t_angle)
    bs, ba = best_rigid_placement(local, target_xy, start=start, angle=angle, **search)
    deviations = {"clamped": deviation(clamped, target_xy),
                  "best": deviation(place_rigid(local, bs, ba), target_xy)}
    if deviations["best"][0] > deviations["clamped"][0]:
        deviations["best"] = deviations["clamped"]  # never worse
        bs, ba = tuple(t_start), t_angle
    return deviations, {"clamped": (float(t_start[0]), float(t_start[1]), float(t_angle)),
                        "best": (float(bs[0]), float(bs[1]), float(ba))}
