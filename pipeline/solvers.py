"""The kinds of map the pipeline can build, each a point solver with its own schema section: the
registry, the grid, and the one record finaliser.

A `SolverSpec` says everything the pipeline needs to fan a point solver out over a grid and
write its map: the grid dimensions, the variables it returns (floats, int8 flags, arrays with
extra dimensions), its status codes and which of them are failures, its model options, its
grid presets, and the modules whose source determines its results (hashed into the build's
fingerprint, see `pipeline.fingerprint`). A `MapGrid` is a grid of any kind: named axes and
model options.

    from snapmorph.pipeline.solvers import get_spec
    spec = get_spec("unit")            # the planar unit (the default); "unit2d" the 2-D unit
    grid = spec.preset("ci")

Every kind is a plug-in: a module holding a SolverSpec. The built-in ones are
`pipeline.kinds.unit` and `pipeline.kinds.unit2d`, named in `KNOWN` as "module:ATTRIBUTE" and
imported on first use; any other "module:ATTRIBUTE" naming a SolverSpec works the same way
(tests use it), and `register(spec)` adds one under its name in this process (dask workers
receive the spec itself, pickled, so they do not need the registry). The core modules know no
kind by name.

Point-solver calling convention (call="keywords", the default):
    record = solve(*coords, **model_options, time_limit=seconds)   # time_limit only if accepted
where coords are the point's grid values in `dims` order and the record is a dict with
"status" (int code), the float and flag variables, the array variables and "message". The
planar unit keeps its historical positional call (call="positional"):
    solve_point(h_over_L, t_over_L, w_over_L, b_over_L, resolution, samples[, time_limit=])
"""

from __future__ import annotations

import importlib
import inspect
import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from snapmorph.units import status as unit_status

PENDING = unit_status.PENDING

#: built-in kinds, imported on first use: name -> "module:ATTRIBUTE" of a SolverSpec (or of a
#: function returning one)
KNOWN = {
    "unit": "snapmorph.pipeline.kinds.unit:SPEC",
    "unit2d": "snapmorph.pipeline.kinds.unit2d:SPEC",
    "unit2d_triangle": "snapmorph.pipeline.kinds.unit2d:TRIANGLE",
    "unit2d_hexagon": "snapmorph.pipeline.kinds.unit2d:HEXAGON",
}
_REGISTRY: dict = {}


def resolve(ref):
    """A callable or object given directly, or named by "module:attr.attr"."""
    if not isinstance(ref, str):
        return ref
    if ":" not in ref:
        raise ValueError(f"expected 'module:function', got {ref!r}")
    module, _, attr = ref.partition(":")
    try:
        obj = importlib.import_module(module)
        for part in attr.split("."):
            obj = getattr(obj, part)
    except (ImportError, AttributeError) as exc:
        raise ValueError(f"cannot import {ref!r}: {exc}") from None
    return obj


@dataclass(frozen=True)
class MapGrid:
    """The grid of a map: named axes and the model options of its points.

    axes: {dimension name: strictly increasing values (>= 2)}, in the map's dimension order;
    options: model options passed to the point solver as keywords (JSON-able values);
    name: preset name or "custom". Points are numbered in C order over the axes.
    """

    axes: dict
    options: dict = field(default_factory=dict)
    name: str = "custom"

    def __post_init__(self):
        if not isinstance(self.axes, dict) or not self.axes:
            raise ValueError(f"axes must be a non-empty dict of name -> values, got {self.axes!r}")
        clean = {}
        for dim, values in self.axes.items():
            try:
                arr = np.asarray(values, dtype=float).ravel()
            except (TypeError, ValueError):
                raise ValueError(f"axis {dim} must be a sequence of numbers, got {values!r}") from None
            if arr.size < 2 or not np.all(np.isfinite(arr)) or np.any(np.diff(arr) <= 0):
                raise ValueError(f"axis {dim} needs >= 2 finite, strictly increasing values, got {arr.tolist()}")
            clean[str(dim)] = tuple(float(v) for v in arr)
        object.__setattr__(self, "axes", clean)
        object.__setattr__(self, "options", dict(self.options))

    @property
    def dims(self) -> tuple:
        """The map's grid dimensions, in storage order."""
        return tuple(self.axes)

    @property
    def shape(self) -> tuple:
        return tuple(len(v) for v in self.axes.values())

    @property
    def size(self) -> int:
        """Number of points."""
        return int(np.prod(self.shape))

    def points(self) -> np.ndarray:
        """(size, ndim) array of the points, C order over the axes."""
        mesh = np.meshgrid(*self.axes.values(), indexing="ij")
        return np.column_stack([m.ravel() for m in mesh])

    def to_dict(self) -> dict:
        """JSON-ready description (exact floats survive a JSON round trip)."""
        return {"name": self.name, "axes": {k: list(v) for k, v in self.axes.items()},
                "options": dict(self.options)}

    @classmethod
    def from_dict(cls, d: dict) -> "MapGrid":
        return MapGrid(d["axes"], d.get("options", {}), d.get("name", "custom"))

    def with_options(self, **options) -> "MapGrid":
        """The same axes with some model options replaced."""
        return MapGrid(self.axes, {**self.options, **options}, self.name)

    def with_resolution(self, resolution) -> "MapGrid":
        """The same grid at another solver resolution."""
        return self.with_options(resolution=resolution)


@dataclass(frozen=True)
class SolverSpec:
    """A point solver and its schema section (see the module docstring).

    name: kind name; solve: the point solver (a module-level function, or "module:function";
      importable on the workers); dims: grid dimensions in storage order;
    float_vars / flag_vars: name -> (units, long_name);
    array_vars: name -> (extra dims, extra shape, units, long_name), a shape entry that is a
      string is read from the model options (e.g. "samples");
    text_vars: name -> (units, long_name) of per-point strings ("" where absent);
    fixed_dims: grid dimension -> default value, for the dimensions a grid may fix instead of
      spanning (a model option of the same name): the map then has the other dimensions, and
      the solver gets the fixed value where the coordinate would be;
    dim_attrs: dimension -> (units, long_name) of its coordinate (grid or extra dimension);
    dim_labels: extra dimension -> its fixed coordinate values (default 0, 1, ...);
    status_codes: code -> name, must include 0 "ok" (-1 "pending" is implied);
    failure_statuses: names of the codes that mean "no result" (counted by --max-failed);
    required_when_ok: variables that must be finite at status ok (default: all floats, arrays);
    required_keys: keys a record must hold at a status that is not a failure (else it is
      malformed: not_converged); default none (a missing value is then absent);
    flag_defaults: flag -> its value at a point that has none (default -1, unknown);
    options: model options and their defaults; presets: preset name -> grid, or a function
      (or "module:function") returning one;
    sources: modules / packages whose source determines the results (hashed into the
      fingerprint with the modules they import; the solver's own module is added);
    schema_version, title, attrs: what the map file says about itself;
    call: "keywords" or "positional" (the planar unit's historical call).
    Hooks, functions (or "module:function"); None = none / the generic behaviour:
      warm(options): run once per process before the fan-out (compiles kernels);
      resolve_options(options) -> options: fills in defaults the solver decides;
      domain(grid): raises ValueError when the grid is outside the kind's domain;
      rules(record, raw) -> [names]: the kind's own rules on a checked record of a status
        that is not a failure (may clear what does not exist at that status); returns the
        names of values missing at status ok;
      global_attrs(grid, options, provenance) -> dict: the file's global attributes;
      finalise, empty, assemble, write, validate_file: replace the generic record check,
        empty record, Dataset assembly, netCDF writer, or add a check of the written file.
    """

    name: str
    solve: Callable | str
    dims: tuple
    float_vars: dict
    flag_vars: dict = field(default_factory=dict)
    array_vars: dict = field(default_factory=dict)
    text_vars: dict = field(default_factory=dict)
    fixed_dims: dict = field(default_factory=dict)
    status_codes: dict = field(default_factory=lambda: {0: "ok", 2: "not_converged", 4: "timeout"})
    failure_statuses: tuple = ("not_converged", "timeout")
    required_when_ok: tuple | None = None
    options: dict = field(default_factory=dict)
    presets: dict = field(default_factory=dict)
    warm: Callable | str | None = None
    sources: tuple = ()
    schema_version: int = 1
    title: str = ""
    attrs: dict = field(default_factory=dict)
    dim_attrs: dict = field(default_factory=dict)
    call: str = "keywords"
    finalise: Callable | str | None = None
    empty: Callable | str | None = None
    resolve_options: Callable | str | None = None
    assemble: Callable | str | None = None
    write: Callable | str | None = None
    validate_file: Callable | str | None = None
    required_keys: tuple = ()
    flag_defaults: dict = field(default_factory=dict)
    dim_labels: dict = field(default_factory=dict)
    domain: Callable | str | None = None
    rules: Callable | str | None = None
    global_attrs: Callable | str | None = None

    def __post_init__(self):
        codes = {int(k): str(v) for k, v in self.status_codes.items()}
        if codes.get(0) != "ok" or PENDING in codes:
            raise ValueError(f"status_codes must map 0 to 'ok' and must not use -1 (pending), got {codes}")
        object.__setattr__(self, "status_codes", codes)
        unknown = [s for s in self.failure_statuses if s not in codes.values()]
        if unknown:
            raise ValueError(f"failure_statuses {unknown} are not in status_codes {codes}")
        if self.call not in ("keywords", "positional"):
            raise ValueError(f"call must be 'keywords' or 'positional', got {self.call!r}")
        object.__setattr__(self, "dims", tuple(self.dims))

    def hook(self, name: str):
        """The hook `name` as a function (None if the kind has none)."""
        ref = getattr(self, name)
        return None if ref is None else resolve(ref)

    # -- status codes ---------------------------------------------------------------------
    def code(self, name: str, fallback: str = "not_converged") -> int:
        """The code of status `name` (of `fallback` if this kind has no such status)."""
        for k, v in self.status_codes.items():
            if v == name:
                return k
        if fallback is None:
            raise KeyError(name)
        return self.code(fallback, None)

    @property
    def failed_codes(self) -> tuple:
        return tuple(sorted(k for k, v in self.status_codes.items() if v in self.failure_statuses))

    @property
    def all_codes(self) -> dict:
        """The codes including -1 "pending"."""
        return {PENDING: "pending", **self.status_codes}

    # -- variables --------------------------------------------------------------------------
    @property
    def int_vars(self) -> tuple:
        return (*self.flag_vars, "status")

    def array_shape(self, name: str, options: dict) -> tuple:
        _, shape, *_ = self.array_vars[name]
        return tuple(int(options[s]) if isinstance(s, str) else int(s) for s in shape)

    @property
    def required(self) -> tuple:
        if self.required_when_ok is not None:
            return tuple(self.required_when_ok)
        return (*self.float_vars, *self.array_vars)

    def block_keys(self) -> tuple:
        """The keys of a result block (see pipeline.batch)."""
        return ("index", "coords", *self.float_vars, *self.int_vars, *self.array_vars,
                *self.text_vars, "solve_time", "message")

    @property
    def text_keys(self) -> tuple:
        """The block keys that hold strings."""
        return (*self.text_vars, "message")

    # -- grids and options --------------------------------------------------------------------
    def preset(self, name: str):
        if name not in self.presets:
            raise ValueError(f"grid must be one of {sorted(self.presets)} for kind {self.name!r}, got {name!r}")
        p = self.presets[name]
        p = resolve(p) if isinstance(p, str) else p
        return p() if callable(p) else p

    def grid_options(self, grid) -> dict:
        """The model options of `grid` (defaults filled in), resolved (e.g. the default
        resolution); the dimensions the grid fixes first, in dimension order (a positional
        solver gets them where their coordinates would be)."""
        given = dict(getattr(grid, "options", {}))
        axes = tuple(getattr(grid, "dims", ()))
        fixed = {d: given.pop(d, v) for d, v in self.fixed_dims.items() if d not in axes}
        opts = {**fixed, **self.options, **given}
        fill = self.hook("resolve_options")
        return fill(opts) if fill else opts

    def grid_dims(self, grid) -> tuple:
        """The dimensions of a map of `grid`: this kind's, less those the grid fixes."""
        axes = tuple(getattr(grid, "dims", ()))
        return tuple(d for d in self.dims if d in axes or d not in self.fixed_dims)

    def check_grid(self, grid) -> None:
        """ValueError unless `grid` has this kind's dimensions (less those it may fix) and lies
        in its domain."""
        dims = tuple(getattr(grid, "dims", ()))
        if dims != self.grid_dims(grid):
            raise ValueError(f"grid dimensions {dims} do not match kind {self.name!r} {self.dims}")
        domain = self.hook("domain")
        if domain:
            domain(grid)

    # -- records -------------------------------------------------------------------------------
    def empty_record(self, options: dict, status: int, message: str = "") -> dict:
        """A record of `status` in which every value is absent: NaN floats and arrays, flags at
        their defaults."""
        if self.empty:
            return self.hook("empty")(options, status, message)
        rec = {name: math.nan for name in self.float_vars}
        rec.update({name: self.flag_defaults.get(name, -1) for name in self.flag_vars})
        for name in self.array_vars:
            rec[name] = np.full(self.array_shape(name, options), np.nan)
        rec.update({name: "" for name in self.text_vars})
        rec["status"] = int(status)
        rec["message"] = str(message)
        return rec

    def finalise_record(self, rec, options: dict) -> dict:
        """Check and clean a solver's record: a known status; at a failure status every value
        absent; the values and shapes of the others checked (a missing one absent, unless it is
        in `required_keys`), then the kind's `rules`; at "ok" every required variable finite.
        A malformed record, or an "ok" one with a value missing, becomes not_converged."""
        if self.finalise:
            return self.hook("finalise")(rec, options)
        bad = self.code("not_converged")
        if not isinstance(rec, dict):
            return self.empty_record(options, bad, f"solver returned {type(rec).__name__}, not dict")
        try:
            status = int(rec["status"])
            if status not in self.status_codes:
                raise ValueError(f"unknown status {status}")
            out = self.empty_record(options, status, str(rec.get("message", "")))
            if self.status_codes[status] in self.failure_statuses:
                return out
            for name in self.float_vars:
                v = self._get(rec, name, None)
                out[name] = math.nan if v is None and name not in self.required_keys else float(v)
            for name in self.flag_vars:
                v = int(self._get(rec, name, out[name]))
                if v not in (-1, 0, 1):
                    raise ValueError(f"flag {name} = {v} is not -1, 0 or 1")
                out[name] = v
            for name in self.array_vars:
                v = self._get(rec, name, None)
                if v is not None or name in self.required_keys:
                    arr = np.asarray(v, dtype=float)
                    want = self.array_shape(name, options)
                    if arr.shape != want:
                        raise ValueError(f"{name} has shape {arr.shape}, expected {want}")
                    out[name] = arr.copy()
            for name in self.text_vars:
                out[name] = _text(self._get(rec, name, ""))
        except Exception as exc:
            return self.empty_record(options, bad, f"malformed solver record: {exc!r}")
        rules = self.hook("rules")
        problems = rules(out, rec) if rules else []
        if status == 0:
            missing = [n for n in self.required if not np.all(np.isfinite(out[n]))] + list(problems)
            if missing:
                return self.empty_record(options, bad, f"status ok but missing/invalid: {', '.join(missing)}")
        return out

    def _get(self, rec: dict, name: str, default):
        """rec[name], or `default` when the record leaves it out and the kind allows that."""
        return rec[name] if name in self.required_keys else rec.get(name, default)

    def call_solver(self, fn, coords, options: dict, time_limit):
        """Call the point solver `fn` at `coords` per this kind's convention."""
        kwargs = {"time_limit": time_limit} if time_limit is not None and accepts_time_limit(fn) else {}
        if self.call == "positional":
            return fn(*(float(c) for c in coords), *options.values(), **kwargs)
        return fn(*(float(c) for c in coords), **options, **kwargs)


def _text(value) -> str:
    """A record's text value: "" for None or NaN (absent), else the string."""
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return ""
    if not isinstance(value, str):
        raise ValueError(f"text value {value!r} is not a string")
    return value


def accepts_time_limit(fn) -> bool:
    """Whether `fn` takes a `time_limit` keyword (explicitly or through **kwargs)."""
    try:
        params = inspect.signature(fn).parameters.values()
    except (TypeError, ValueError):
        return False
    return any(p.name == "time_limit" or p.kind is p.VAR_KEYWORD for p in params)


def status_codes() -> dict:
    """code -> name of every status of `units.status` but pending: the built-in kinds' codes."""
    return {code: name for name, code in unit_status.CODE.items() if code != PENDING}


def failure_statuses() -> tuple:
    """The names of the failed computations of `units.status` (no value exists)."""
    return tuple(unit_status.NAME[code] for code in unit_status.FAILED)


def register(spec: SolverSpec) -> SolverSpec:
    """Make `spec` available under `spec.name` in this process."""
    if not isinstance(spec, SolverSpec):
        raise ValueError(f"register expects a SolverSpec, got {type(spec).__name__}")
    _REGISTRY[spec.name] = spec
    return spec


def kinds() -> list:
    """The kind names this process knows (registered ones may fail to import: see get_spec)."""
    return sorted({*KNOWN, *_REGISTRY})


def get_spec(kind="unit") -> SolverSpec:
    """The SolverSpec of a registered kind name, of "module:ATTRIBUTE", or `kind` itself."""
    if isinstance(kind, SolverSpec):
        return kind
    if not isinstance(kind, str) or not kind:
        raise ValueError(f"kind must be a registered name {kinds()} or 'module:ATTRIBUTE', got {kind!r}")
    if kind in _REGISTRY:
        return _REGISTRY[kind]
    if kind not in KNOWN and ":" not in kind:
        raise ValueError(f"kind must be one of {kinds()} or 'module:ATTRIBUTE', got {kind!r}")
    try:
        obj = resolve(KNOWN.get(kind, kind))
    except ValueError as exc:
        raise ValueError(f"kind {kind!r} is not available: {exc}") from None
    spec = obj() if callable(obj) and not isinstance(obj, SolverSpec) else obj
    if not isinstance(spec, SolverSpec):
        raise ValueError(f"kind {kind!r} does not name a SolverSpec (got {type(spec).__name__})")
    if kind in KNOWN:
        _REGISTRY[kind] = spec
    return spec
