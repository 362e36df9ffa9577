"""A fast analytic stand-in for `pipeline.kinds.unit.solve_point`, used to test the pipeline machinery.

Behaviour (all dimensionless):
- h/L < h_b(t) = 0.12 + 6 t/L: monostable (F_cr, d_cr present);
- the point (h/L, t/L, w/L) = (0.30, 0.0075, 0.06) of the CI grid: not converged;
- the point (0.40, 0.01, 0.04): raises (the pipeline must record status 2);
- else bistable with smooth analytic fields.
Environment: FAKE_SOLVER_LOG=path appends "h t w" per call (one line, flushed);
FAKE_SOLVER_DELAY=seconds sleeps per call; FAKE_SOLVER_CRASH="h t w" kills the process
(os._exit) at that point, like a segfaulting solver; FAKE_SOLVER_HANG="h t w" never returns at
that point (ignores its time limit); FAKE_SOLVER_SLOW="h t w" works until its time limit at that
point and then reports status 4 (timeout), as a solver that honours `time_limit` does.
"""

import math
import os
import time

import numpy as np

NOT_CONVERGED_POINT = (0.30, 0.0075, 0.06)
RAISING_POINT = (0.40, 0.01, 0.04)


def boundary(t):
    return 0.12 + 6.0 * t


def fields(h, t, w):
    """The analytic values the fake reports at a bistable point."""
    theta = 200.0 * (h - boundary(t)) + 10.0 + 50.0 * w
    S = 1.0 - 0.8 * h * h - 0.01 * t
    F_cr = 30.0 * h / t * (1.0 + w)
    return {"F_cr": F_cr, "d_cr": 0.4 * h, "d_unstable": 1.0 * h, "d_second": 1.8 * h,
            "S": S, "theta": theta, "energy_barrier": 0.2 * F_cr * h, "energy_stored": 0.1 * F_cr * h}


def shape(h, t, w, samples):
    """A circular arc of unit length turning by theta (degrees)."""
    th = math.radians(fields(h, t, w)["theta"])
    s = np.linspace(0.0, 1.0, samples)
    if abs(th) < 1e-12:
        return np.column_stack([s, 0.0 * s])
    r = 1.0 / th
    return np.column_stack([r * np.sin(th * s), r * (1.0 - np.cos(th * s))])


def _near(a, b):
    return all(abs(x - y) < 1e-12 for x, y in zip(a, b))


def solve(h, t, w, b, resolution, samples, time_limit=None):
    log = os.environ.get("FAKE_SOLVER_LOG")
    if log:
        with open(log, "a") as f:
            f.write(f"{h!r} {t!r} {w!r}\n")
            f.flush()
    delay = float(os.environ.get("FAKE_SOLVER_DELAY", "0") or 0)
    if delay:
        time.sleep(delay)
    crash = os.environ.get("FAKE_SOLVER_CRASH")
    if crash and _near((h, t, w), tuple(map(float, crash.split()))):
        os._exit(13)
    hang = os.environ.get("FAKE_SOLVER_HANG")
    if hang and _near((h, t, w), tuple(map(float, hang.split()))):
        while True:  # a solver stuck in a loop that never looks at the clock
            time.sleep(0.05)
    slow = os.environ.get("FAKE_SOLVER_SLOW")
    if slow and _near((h, t, w), tuple(map(float, slow.split()))):
        time.sleep(time_limit if time_limit is not None else 3600.0)
        rec = {k: math.nan for k in fields(h, t, w)}
        rec.update(status=4, bistable=0, self_standing=-1, bifurcation=-1,
                   base_shape=np.full((samples, 2), math.nan), message=f"time limit {time_limit!r} s reached")
        return rec
    if _near((h, t, w), RAISING_POINT):
        raise RuntimeError("fake solver exploded")
    nan = math.nan
    rec = {k: nan for k in fields(h, t, w)}
    rec.update(bistable=0, self_standing=-1, bifurcation=-1, base_shape=np.full((samples, 2), nan),
               message="")
    if _near((h, t, w), NOT_CONVERGED_POINT):
        rec.update(status=2, message="not converged (fake)")
        return rec
    f = fields(h, t, w)
    if h < boundary(t):
        rec.update(status=1, F_cr=f["F_cr"], d_cr=f["d_cr"], bifurcation=0, message="monostable")
        return rec
    rec.update(f)
    rec.update(status=0, bistable=1, self_standing=1 if h > 0.25 else 0, bifurcation=0,
               base_shape=shape(h, t, w, samples), message="ok")
    return rec


def refuse_map(path):
    """A map reader that refuses every file (tests that nothing is deleted before the check)."""
    raise ValueError(f"map {path} refused by the reader")
