"""Result blocks and the batch task that runs on a dask worker.

A *block* is a dict of arrays for a set of points: "index" (int64 flat grid index), "coords"
(n, ndim) the points' grid values, one array per schema variable (floats, int8 flags and
status), the array variables (n, *extra shape; the planar unit's "base_shape" (n, M, 2)),
"solve_time" (s) and "message" (str, why a point failed). Blocks are what tasks return, what
checkpoint files hold, and (for all points) what the driver assembles into the dataset. The keys
of a kind's blocks are `SolverSpec.block_keys()`.
"""

from __future__ import annotations

import time
import warnings

import numpy as np

from snapmorph.pipeline.solvers import PENDING, get_spec, resolve


def new_block(spec, indices, options: dict, coords=None) -> dict:
    """A block of kind `spec` for `indices`, every point pending (status -1), NaN fields."""
    idx = np.asarray(indices, dtype=np.int64)
    n = idx.size
    block = {"index": idx}
    block["coords"] = (np.full((n, len(spec.dims)), np.nan) if coords is None
                       else np.asarray(coords, dtype=float).reshape(n, -1).copy())
    for name in spec.float_vars:
        block[name] = np.full(n, np.nan)
    for name in spec.flag_vars:
        block[name] = np.full(n, spec.flag_defaults.get(name, -1), dtype=np.int8)
    block["status"] = np.full(n, PENDING, dtype=np.int8)
    for name in spec.array_vars:
        block[name] = np.full((n, *spec.array_shape(name, options)), np.nan)
    for name in spec.text_vars:
        block[name] = np.array([""] * n, dtype=object)
    block["solve_time"] = np.full(n, np.nan)
    block["message"] = np.array([""] * n, dtype=object)
    return block


def empty_block(indices, samples: int) -> dict:
    """Deprecated: `new_block(get_spec("unit"), indices, {"samples": samples})`."""
    _deprecated("empty_block", 'new_block(get_spec("unit"), indices, {"samples": samples})')
    return new_block(get_spec("unit"), indices, {"samples": samples})


def put(block: dict, k: int, rec: dict, solve_time: float) -> None:
    """Store the (finalised) record `rec` as row k of `block`."""
    for key, arr in block.items():
        if key in ("index", "coords", "solve_time", "message"):
            continue
        arr[k] = rec[key]
    block["solve_time"][k] = solve_time
    block["message"][k] = rec.get("message", "")


def merge(total: dict, block: dict) -> None:
    """Copy the rows of `block` into `total` (a block over all points, index = arange(N))."""
    idx = block["index"]
    for key, arr in total.items():
        if key != "index" and key in block:
            arr[idx] = block[key]


def check_block(block: dict, spec, options: dict, points: np.ndarray) -> None:
    """Raise ValueError unless `block` is a well-formed, plausible block of kind `spec` for the
    grid whose points are `points` ((N, ndim)): every key with its shape; indices unique and in
    range; coordinates equal to the grid's at those indices (catches shifted indices); known,
    non-pending status codes; flags -1/0/1; at status ok every required variable finite."""
    keys = spec.block_keys()
    missing = [k for k in keys if k not in block]
    if missing:
        raise ValueError(f"missing keys {missing}")
    idx = np.asarray(block["index"])
    n = idx.size
    n_points = len(points)
    if idx.ndim != 1 or n == 0 or not np.issubdtype(idx.dtype, np.integer):
        raise ValueError("bad index array")
    if idx.min() < 0 or idx.max() >= n_points:
        raise ValueError(f"indices {int(idx.min())}..{int(idx.max())} outside the grid's 0..{n_points - 1}")
    if np.unique(idx).size != n:
        raise ValueError("repeated indices")
    for key in keys[1:]:
        if key == "coords":
            expected = (n, points.shape[1])
        elif key in spec.array_vars:
            expected = (n, *spec.array_shape(key, options))
        else:
            expected = (n,)
        if np.shape(block[key]) != expected:
            raise ValueError(f"{key} has shape {np.shape(block[key])}, expected {expected}")
    if not np.array_equal(np.asarray(block["coords"], dtype=float), points[idx]):
        k = int(np.argmax(np.any(np.asarray(block["coords"], dtype=float) != points[idx], axis=1)))
        raise ValueError(f"point {int(idx[k])} has coordinates {np.asarray(block['coords'])[k].tolist()}, "
                         f"the grid's are {points[idx[k]].tolist()} (shifted or foreign indices)")
    status = np.asarray(block["status"])
    unknown = sorted(set(np.unique(status).tolist()) - set(spec.status_codes))
    if unknown:
        raise ValueError(f"unknown status codes {unknown} (known: {spec.all_codes})")
    for name in spec.flag_vars:
        v = np.asarray(block[name])
        if not np.all(np.isin(v, (-1, 0, 1))):
            raise ValueError(f"flag {name} holds values other than -1, 0, 1")
    ok = status == 0
    for name in spec.required:
        v = np.asarray(block[name], dtype=float)[ok]
        if not np.all(np.isfinite(v)):
            raise ValueError(f"{name} is not finite at {int(np.sum(~np.isfinite(v.reshape(v.shape[0], -1)).any(axis=1)))} "
                             f"point(s) with status ok")


def resolve_solver(solve):
    """A callable, or "module:function" naming one (importable on the workers)."""
    if callable(solve):
        return solve
    if isinstance(solve, str) and ":" in solve:
        fn = resolve(solve)  # ValueError naming the solver if it does not import
        if callable(fn):
            return fn
    raise ValueError(f"solver must be a callable or 'module:function', got {solve!r}")


def solver_name(solve) -> str:
    """A stable name for a point solver, recorded in the checkpoint."""
    if isinstance(solve, str):
        return solve
    return f"{getattr(solve, '__module__', '?')}:{getattr(solve, '__qualname__', repr(solve))}"


def solve_points(indices, coords, spec, options: dict, solve, time_limit=None) -> dict:
    """Solve the points `coords` ((n, ndim)) with flat indices `indices` with the point solver
    `solve` of kind `spec`; runs on a worker.

    Never raises because of one point: an exception of the solver is recorded as not_converged
    with its message. `time_limit` (s per point, None = none) is passed to solvers that take it;
    a point that returns after it keeps its result (the driver's watchdog handles one that does
    not return). `solve_time` is the wall time (s) of each point's solve.
    """
    fn = resolve_solver(solve)
    coords = np.asarray(coords, dtype=float).reshape(len(indices), -1)
    block = new_block(spec, indices, options, coords)
    failed = spec.code("not_converged")
    for k, point in enumerate(coords):
        t0 = time.perf_counter()
        try:
            rec = spec.finalise_record(spec.call_solver(fn, point, options, time_limit), options)
        except Exception as exc:
            rec = spec.empty_record(options, failed, f"solver raised {exc!r}")
        put(block, k, rec, time.perf_counter() - t0)
    return block


def solve_batch(indices, coords, b_over_L: float, resolution, samples: int, solve,
                time_limit=None) -> dict:
    """Deprecated: `solve_points` with the planar unit's spec and options."""
    _deprecated("solve_batch", 'solve_points(indices, coords, get_spec("unit"), options, solve)')
    options = {"b_over_L": b_over_L, "resolution": resolution, "samples": samples}
    return solve_points(indices, coords, get_spec("unit"), options, solve, time_limit)


def timeout_record(spec, options: dict, time_limit: float, what: str) -> dict:
    """The record of a point stopped by the watchdog after `time_limit` s."""
    return spec.empty_record(options, spec.code("timeout"),
                             f"exceeded the wall-time limit of {time_limit:g} s per point ({what})")


def _deprecated(old: str, new: str) -> None:
    warnings.warn(f"pipeline.batch.{old} is deprecated (snapmorph 0.2); use {new}",
                  DeprecationWarning, stacklevel=3)


__all__ = ["new_block", "put", "merge", "check_block", "resolve_solver", "solver_name",
           "solve_points", "timeout_record"]
