"""Compare two maps of one kind variable by variable (what `snapmorph maps check` reports)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from snapmorph.maps.schema import status_names

#: global attributes that must agree where a map has them (the others record when and where it
#: was built): the schema version and the model options
COMPARED_ATTRS = ("schema_version", "b_over_L", "resolution", "model_options")
#: variables not compared: wall-clock measurements
NOT_COMPARED = ("solve_time",)


@dataclass
class Difference:
    """The points where one variable differs: (*grid coordinates, expected, actual) examples
    over the grid dimensions `dims`."""

    variable: str
    count: int
    total: int
    max_abs: float = float("nan")
    examples: list = field(default_factory=list)
    dims: tuple = ("h_over_L", "t_over_L", "w_over_L")

    def describe(self, limit: int = 10) -> str:
        head = f"{self.variable}: {self.count} of {self.total} points differ"
        if np.isfinite(self.max_abs):
            head += f" (max |difference| {self.max_abs:.3g})"
        lines = [head]
        for *where, exp, act in self.examples[:limit]:
            at = " ".join(f"{d.replace('_over_', '/')}={c:g}" for d, c in zip(self.dims, where))
            lines.append(f"    {at}: expected {exp}, got {act}")
        if self.count > limit:
            lines.append(f"    ... and {self.count - limit} more")
        return "\n".join(lines)


def _fmt(v, names=None):
    if names is not None:
        return f"{int(v)} ({names.get(int(v), '?')})"
    return f"{v:.10g}" if isinstance(v, float) else str(v)


def compare_maps(expected, actual, rtol: float = 1e-6, atol: float = 1e-9) -> list:
    """Differences between two map Datasets: a list of strings (grid/attribute problems) and
    `Difference`s (variables). Empty when they agree: integers exactly, floats within
    |a - e| <= atol + rtol |e| with NaN where the other is NaN. solve_time is not compared.
    The grid is the dimensions of the expected map's status."""
    for name, v in (("rtol", rtol), ("atol", atol)):
        if not (np.isfinite(v) and v >= 0):
            raise ValueError(f"{name} must be a finite number >= 0, got {v!r}")
    problems = []
    dims = tuple(expected["status"].dims)
    for dim in expected.coords:
        if dim not in actual.coords:
            problems.append(f"coordinate {dim} missing from the actual map")
            continue
        e, a = np.asarray(expected[dim].values), np.asarray(actual[dim].values)
        same = e.shape == a.shape and (np.allclose(e, a, rtol=1e-12, atol=0) if e.dtype.kind in "iuf"
                                       else np.array_equal(e, a))
        if not same:
            problems.append(f"coordinate {dim} differs: expected {e.tolist()}, got {a.tolist()}")
    for key in COMPARED_ATTRS:
        e, a = expected.attrs.get(key), actual.attrs.get(key)
        if (e is not None or a is not None) and (e is None or a is None or not np.array_equal(np.asarray(e), np.asarray(a))):
            problems.append(f"attribute {key} differs: expected {e!r}, got {a!r}")
    if problems:
        return problems
    grids = np.meshgrid(*(expected[d].values for d in dims), indexing="ij")
    try:
        names = status_names(expected["status"].attrs)
    except ValueError:
        names = {}
    for name in (v for v in expected.data_vars if v not in NOT_COMPARED):
        if name not in actual.variables:
            problems.append(f"variable {name} missing from the actual map")
            continue
        e, a = np.asarray(expected[name].values), np.asarray(actual[name].values)
        if np.issubdtype(e.dtype, np.integer) and np.issubdtype(a.dtype, np.integer):
            bad = e != a
            err = np.where(bad, np.abs(e.astype(float) - a), 0.0)
        elif e.dtype.kind in "OUS" or a.dtype.kind in "OUS":  # text: equal or not
            e, a = e.astype(str), a.astype(str)
            bad = e != a
            err = bad.astype(float)
        else:
            e, a = e.astype(float), a.astype(float)
            both_nan = np.isnan(e) & np.isnan(a)
            with np.errstate(invalid="ignore"):
                err = np.abs(a - e)
                bad = ~both_nan & ~(err <= atol + rtol * np.abs(e))
            err = np.where(np.isfinite(err), err, 0.0)
        n = len(dims)
        if bad.ndim > n:  # an array variable (base_shape): a point differs if any entry differs
            bad = bad.reshape(*bad.shape[:n], -1).any(axis=-1)
            err = err.reshape(*err.shape[:n], -1).max(axis=-1)
            e = e.reshape(*e.shape[:n], -1)
            a = a.reshape(*a.shape[:n], -1)
        if not np.any(bad):
            continue
        examples = []
        for i in np.argwhere(bad)[:20]:
            i = tuple(i)
            ev, av = e[i], a[i]
            if np.ndim(ev):
                j = int(np.nanargmax(np.abs(av - ev))) if np.any(np.isfinite(av - ev)) else 0
                ev, av = ev[j], av[j]
            status = names if name == "status" else None
            examples.append((*(float(g[i]) for g in grids), _fmt(ev.item(), status), _fmt(av.item(), status)))
        problems.append(Difference(name, int(bad.sum()), int(bad.size), float(err.max()), examples, dims))
    for name in (v for v in actual.data_vars if v not in NOT_COMPARED and v not in expected.variables):
        problems.append(f"variable {name} missing from the expected map")
    return problems
