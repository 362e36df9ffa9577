"""One way to time a warm call for every benchmark: median and best of several runs."""

from __future__ import annotations

import statistics
import time


def median_time(fn, runs, warm=False):
    """(median s, best s, last result) of ``runs`` calls of ``fn``; ``warm`` calls it once
    first, untimed (numba kernels compiled or loaded from the cache)."""
    if warm:
        fn()
    times, out = [], None
    for _ in range(runs):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), min(times), out


def best_time(fn, reps):
    """The fastest of ``reps`` calls of ``fn`` (s), after one untimed call: for kernels
    timed per call on a shared machine (the minimum is what the code costs alone)."""
    fn()
    t = float("inf")
    for _ in range(reps):
        t0 = time.perf_counter()
        fn()
        t = min(t, time.perf_counter() - t0)
    return t
