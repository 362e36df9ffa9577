"""Result blocks and the batch task that runs on a dask worker.

A *block* is a dict of arrays for a set of points: "index" (int64 flat grid index), one array
per schema variable (floats, int8 flags and status), "base_shape" (n, M, 2), "solve_time" (s)
and "message" (str, why a point failed). Blocks are what tasks return, what checkpoint files
hold, and (for all points) what the driver assembles into the dataset.
"""

from __future__ import annotations

import importlib
import time

import numpy as np

from pipeline.point import finalise_record, empty_record
from pipeline.schema import FLAG_VARS, FLOAT_VARS, NOT_CONVERGED, PENDING

INT_VARS = (*FLAG_VARS, "status")
BLOCK_KEYS = ("index", *FLOAT_VARS, *INT_VARS, "base_shape", "solve_time", "message")


def empty_block(indices, samples: int) -> dict:
    """A block for `indices` with every point pending (status -1) and NaN fields."""
    idx = np.asarray(indices, dtype=np.int64)
    n = idx.size
    block = {"index": idx}
    for name in FLOAT_VARS:
        block[name] = np.full(n, np.nan)
    for name in INT_VARS:
        block[name] = np.full(n, -1, dtype=np.int8)
    block["bistable"][:] = 0
    block["status"][:] = PENDING
    block["base_shape"] = np.full((n, samples, 2), np.nan)
    block["solve_time"] = np.full(n, np.nan)
    block["message"] = np.array([""] * n, dtype=object)
    return block


def put(block: dict, k: int, rec: dict, solve_time: float) -> None:
    """Store the (finalised) record `rec` as row k of `block`."""
    for name in FLOAT_VARS:
        block[name][k] = rec[name]
    for name in INT_VARS:
        block[name][k] = rec[name]
    block["base_shape"][k] = rec["base_shape"]
    block["solve_time"][k] = solve_time
    block["message"][k] = rec.get("message", "")


def merge(total: dict, block: dict) -> None:
    """Copy the rows of `block` into `total` (a block over all points, index = arange(N))."""
    idx = block["index"]
    for key in BLOCK_KEYS[1:]:
        total[key][idx] = block[key]


def validate_block(block: dict, n_points: int, samples: int) -> None:
    """Raise ValueError if `block` is not a well-formed block for a grid of n_points."""
    missing = [k for k in BLOCK_KEYS if k not in block]
    if missing:
        raise ValueError(f"missing keys {missing}")
    idx = np.asarray(block["index"])
    n = idx.size
    if idx.ndim != 1 or n == 0 or idx.min() < 0 or idx.max() >= n_points:
        raise ValueError(f"bad index array (grid has {n_points} points)")
    for key in BLOCK_KEYS[1:]:
        expected = (n, samples, 2) if key == "base_shape" else (n,)
        if np.shape(block[key]) != expected:
            raise ValueError(f"{key} has shape {np.shape(block[key])}, expected {expected}")
    if np.any(np.asarray(block["status"]) < 0):
        raise ValueError("block holds pending points")


def resolve_solver(solve):
    """A callable, or "module:function" naming one (importable on the workers)."""
    if callable(solve):
        return solve
    if isinstance(solve, str) and ":" in solve:
        module, _, attr = solve.partition(":")
        fn = importlib.import_module(module)
        for part in attr.split("."):
            fn = getattr(fn, part)
        if callable(fn):
            return fn
    raise ValueError(f"solver must be a callable or 'module:function', got {solve!r}")


def solver_name(solve) -> str:
    """A stable name for a point solver, recorded in the checkpoint."""
    if isinstance(solve, str):
        return solve
    return f"{getattr(solve, '__module__', '?')}:{getattr(solve, '__qualname__', repr(solve))}"


def solve_batch(indices, coords, b_over_L: float, resolution, samples: int, solve) -> dict:
    """Solve the points `coords` ((n, 3) of h/L, t/L, w/L) with flat indices `indices`.

    Runs on a worker. Never raises because of one point: an exception of the solver is recorded
    as status 2 with its message. `solve_time` is the wall time (s) of each point's solve.
    """
    fn = resolve_solver(solve)
    block = empty_block(indices, samples)
    for k, (h, t, w) in enumerate(np.asarray(coords, dtype=float)):
        t0 = time.perf_counter()
        try:
            rec = finalise_record(fn(float(h), float(t), float(w), b_over_L, resolution, samples), samples)
        except Exception as exc:
            rec = empty_record(samples, NOT_CONVERGED, f"solver raised {exc!r}")
        put(block, k, rec, time.perf_counter() - t0)
    return block
