"""Compare two design maps variable by variable (what `snapmorph maps check` reports)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from snapmorph.pipeline.schema import COMPARED_VARS, GRID_DIMS, STATUS_CODES

#: global attributes that must agree (the others record when/where a map was built)
COMPARED_ATTRS = ("schema_version", "b_over_L", "resolution")


@dataclass
class Difference:
    """The points where one variable differs: (h/L, t/L, w/L, expected, actual) examples."""

    variable: str
    count: int
    total: int
    max_abs: float = float("nan")
    examples: list = field(default_factory=list)

    def describe(self, limit: int = 10) -> str:
        head = f"{self.variable}: {self.count} of {self.total} points differ"
        if np.isfinite(self.max_abs):
            head += f" (max |difference| {self.max_abs:.3g})"
        lines = [head]
        for h, t, w, exp, act in self.examples[:limit]:
            lines.append(f"    h/L={h:g} t/L={t:g} w/L={w:g}: expected {exp}, got {act}")
        if self.count > limit:
            lines.append(f"    ... and {self.count - limit} more")
        return "\n".join(lines)


def _fmt(name, v):
    if name == "status":
        return f"{int(v)} ({STATUS_CODES.get(int(v), '?')})"
    return f"{v:.10g}" if isinstance(v, float) else str(v)


def compare_maps(expected, actual, rtol: float = 1e-6, atol: float = 1e-9) -> list:
    """Differences between two map Datasets: a list of strings (grid/attribute problems) and
    `Difference`s (variables). Empty when they agree: integers exactly, floats within
    |a - e| <= atol + rtol |e| with NaN where the other is NaN. solve_time is not compared."""
    for name, v in (("rtol", rtol), ("atol", atol)):
        if not (np.isfinite(v) and v >= 0):
            raise ValueError(f"{name} must be a finite number >= 0, got {v!r}")
    problems = []
    for dim in (*GRID_DIMS, "sample"):
        e, a = np.asarray(expected[dim].values), np.asarray(actual[dim].values)
        if e.shape != a.shape or not np.allclose(e, a, rtol=1e-12, atol=0):
            problems.append(f"coordinate {dim} differs: expected {e.tolist()}, got {a.tolist()}")
    for key in COMPARED_ATTRS:
        e, a = expected.attrs.get(key), actual.attrs.get(key)
        if e is None or a is None or not np.array_equal(np.asarray(e), np.asarray(a)):
            problems.append(f"attribute {key} differs: expected {e!r}, got {a!r}")
    if problems:
        return problems
    grids = np.meshgrid(*(expected[d].values for d in GRID_DIMS), indexing="ij")
    for name in COMPARED_VARS:
        if name not in expected.variables or name not in actual.variables:
            problems.append(f"variable {name} missing from the {'expected' if name not in expected else 'actual'} map")
            continue
        e, a = np.asarray(expected[name].values), np.asarray(actual[name].values)
        if np.issubdtype(e.dtype, np.integer) and np.issubdtype(a.dtype, np.integer):
            bad = e != a
            err = np.where(bad, np.abs(e.astype(float) - a), 0.0)
        else:
            e, a = e.astype(float), a.astype(float)
            both_nan = np.isnan(e) & np.isnan(a)
            with np.errstate(invalid="ignore"):
                err = np.abs(a - e)
                bad = ~both_nan & ~(err <= atol + rtol * np.abs(e))
            err = np.where(np.isfinite(err), err, 0.0)
        if bad.ndim > 3:  # base_shape: a point differs if any sample differs
            bad = bad.reshape(*bad.shape[:3], -1).any(axis=-1)
            err = err.reshape(*err.shape[:3], -1).max(axis=-1)
            e = e.reshape(*e.shape[:3], -1)
            a = a.reshape(*a.shape[:3], -1)
        if not np.any(bad):
            continue
        idx = np.argwhere(bad)
        examples = []
        for i in idx[:20]:
            i = tuple(i)
            ev, av = e[i], a[i]
            if np.ndim(ev):
                j = int(np.nanargmax(np.abs(av - ev))) if np.any(np.isfinite(av - ev)) else 0
                ev, av = ev[j], av[j]
            examples.append((*(float(g[i]) for g in grids), _fmt(name, ev.item()), _fmt(name, av.item())))
        problems.append(Difference(name, int(bad.sum()), int(bad.size), float(err.max()), examples))
    return problems
