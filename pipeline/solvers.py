"""Point solvers the pipeline can map, each with its own schema section: the registry.

A `SolverSpec` says everything the pipeline needs to fan a point solver out over a grid and
write its map: the grid dimensions, the variables it returns (floats, int8 flags, arrays with
extra dimensions), its status codes and which of them are failures, its model options, its
grid presets, and the source code whose content determines its results (hashed into the
build's fingerprint, see `pipeline.fingerprint`).

    from snapmorph.pipeline.solvers import get_spec
    spec = get_spec("unit")            # the planar unit (the default); "unit2d" once registered
    grid = spec.preset("ci")

Registered kinds: "unit" here; "unit2d" is looked up lazily as `units.unit2d:MAP_SPEC`
(`KNOWN`), so that the module defining it needs no edit here. Any "module:ATTRIBUTE" naming a
SolverSpec also works (tests use it), and `register(spec)` adds one at run time in this process
(dask workers receive the spec itself, pickled, so they do not need the registry).

Point-solver calling convention (call="keywords", the default for new kinds):
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
from dataclasses import dataclass, field

import numpy as np

PENDING = -1

#: built-in kinds looked up lazily: name -> "module:ATTRIBUTE" of a SolverSpec (or a function
#: returning one)
KNOWN = {
    "unit": "snapmorph.pipeline.solvers:unit_spec",
    "unit2d": "snapmorph.units.unit2d:MAP_SPEC",
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
    """A grid over any named axes with model options, for kinds other than the planar unit.

    axes: {dimension name: strictly increasing values (>= 2)}, in the map's dimension order;
    options: model options passed to the point solver as keywords (JSON-able values);
    name: preset name or "custom".
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
        return tuple(self.axes)

    @property
    def shape(self) -> tuple:
        return tuple(len(v) for v in self.axes.values())

    @property
    def size(self) -> int:
        return int(np.prod(self.shape))

    def points(self) -> np.ndarray:
        """(size, ndim) array of the points, C order over the axes."""
        mesh = np.meshgrid(*self.axes.values(), indexing="ij")
        return np.column_stack([m.ravel() for m in mesh])

    def to_dict(self) -> dict:
        return {"name": self.name, "axes": {k: list(v) for k, v in self.axes.items()},
                "options": dict(self.options)}

    def with_options(self, **options) -> "MapGrid":
        return MapGrid(self.axes, {**self.options, **options}, self.name)


@dataclass(frozen=True)
class SolverSpec:
    """A point solver and its schema section (see the module docstring).

    name: kind name; solve: "module:function" of the point solver (importable on workers);
    dims: grid dimensions in storage order; float_vars / flag_vars: name -> (units, long_name);
    array_vars: name -> (extra dims, extra shape, units, long_name), a shape entry that is a
      string is read from the model options (e.g. "samples");
    status_codes: code -> name, must include 0 "ok" (-1 "pending" is implied);
    failure_statuses: names of the codes that mean "no result" (counted by --max-failed);
    required_when_ok: variables that must be finite at status ok (default: all floats, arrays);
    options: model options and their defaults; presets: preset name -> grid or
      "module:function" returning one; warm: "module:function"(options) run once per process
      before the fan-out (compiles kernels); sources: modules / packages whose source
      determines the results (hashed into the fingerprint; the solver's own module is added);
    schema_version, title, attrs: what the map file says about itself;
    call: "keywords" or "positional" (the planar unit's historical call);
    hooks (None = generic): finalise(rec, options) -> record, empty(options, status, message)
      -> record, resolve_options(options) -> options, assemble(grid, total, attrs, spec) ->
      xarray.Dataset, write(ds, path), validate_file(path) (raises when the map is unusable).
    """

    name: str
    solve: str
    dims: tuple
    float_vars: dict
    flag_vars: dict = field(default_factory=dict)
    array_vars: dict = field(default_factory=dict)
    status_codes: dict = field(default_factory=lambda: {0: "ok", 2: "not_converged", 4: "timeout"})
    failure_statuses: tuple = ("not_converged", "timeout")
    required_when_ok: tuple | None = None
    options: dict = field(default_factory=dict)
    presets: dict = field(default_factory=dict)
    warm: str | None = None
    sources: tuple = ()
    schema_version: int = 1
    title: str = ""
    attrs: dict = field(default_factory=dict)
    dim_attrs: dict = field(default_factory=dict)
    call: str = "keywords"
    finalise: str | None = None
    empty: str | None = None
    resolve_options: str | None = None
    assemble: str | None = None
    write: str | None = None
    validate_file: str | None = None

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
                "solve_time", "message")

    # -- grids and options --------------------------------------------------------------------
    def preset(self, name: str):
        if name not in self.presets:
            raise ValueError(f"grid must be one of {sorted(self.presets)} for kind {self.name!r}, got {name!r}")
        p = self.presets[name]
        p = resolve(p) if isinstance(p, str) else p
        return p() if callable(p) else p

    def grid_options(self, grid) -> dict:
        """The model options of `grid` (defaults filled in), resolved (e.g. the default resolution)."""
        opts = {**self.options, **dict(getattr(grid, "options", {}))}
        if self.resolve_options:
            opts = resolve(self.resolve_options)(opts)
        return opts

    def check_grid(self, grid) -> None:
        dims = tuple(getattr(grid, "dims", ()))
        if dims != self.dims:
            raise ValueError(f"grid dimensions {dims} do not match kind {self.name!r} {self.dims}")

    # -- records -------------------------------------------------------------------------------
    def empty_record(self, options: dict, status: int, message: str = "") -> dict:
        if self.empty:
            return resolve(self.empty)(options, status, message)
        rec = {name: math.nan for name in self.float_vars}
        rec.update({name: -1 for name in self.flag_vars})
        for name in self.array_vars:
            rec[name] = np.full(self.array_shape(name, options), np.nan)
        rec["status"] = int(status)
        rec["message"] = str(message)
        return rec

    def finalise_record(self, rec, options: dict) -> dict:
        """Check and clean a solver's record: known status; at "ok" every required variable
        finite; at other statuses absent fields NaN. A malformed record becomes not_converged."""
        if self.finalise:
            return resolve(self.finalise)(rec, options)
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
                v = rec.get(name, math.nan)
                out[name] = math.nan if v is None else float(v)
            for name in self.flag_vars:
                v = int(rec.get(name, -1))
                if v not in (-1, 0, 1):
                    raise ValueError(f"flag {name} = {v} is not -1, 0 or 1")
                out[name] = v
            for name in self.array_vars:
                if name in rec and rec[name] is not None:
                    arr = np.asarray(rec[name], dtype=float)
                    want = self.array_shape(name, options)
                    if arr.shape != want:
                        raise ValueError(f"{name} has shape {arr.shape}, expected {want}")
                    out[name] = arr.copy()
        except Exception as exc:
            return self.empty_record(options, bad, f"malformed solver record: {exc!r}")
        if status == 0:
            missing = [n for n in self.required if not np.all(np.isfinite(out[n]))]
            if missing:
                return self.empty_record(options, bad, f"status ok but missing/invalid: {', '.join(missing)}")
        return out

    def call_solver(self, fn, coords, options: dict, time_limit):
        """Call the point solver `fn` at `coords` per this kind's convention."""
        kwargs = {"time_limit": time_limit} if time_limit is not None and accepts_time_limit(fn) else {}
        if self.call == "positional":
            return fn(*(float(c) for c in coords), *options.values(), **kwargs)
        return fn(*(float(c) for c in coords), **options, **kwargs)


def accepts_time_limit(fn) -> bool:
    """Whether `fn` takes a `time_limit` keyword (explicitly or through **kwargs)."""
    try:
        params = inspect.signature(fn).parameters.values()
    except (TypeError, ValueError):
        return False
    return any(p.name == "time_limit" or p.kind is p.VAR_KEYWORD for p in params)


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


# ---------------------------------------------------------------------------------------------
# The planar unit: the schema-1 design map of pipeline.schema / docs/design-map-schema.md.

_UNIT_REQUIRED = ("F_cr", "d_cr", "d_unstable", "d_second", "S", "theta", "energy_barrier",
                  "energy_stored")


def unit_spec() -> SolverSpec:
    """The planar arch-on-base unit over (h/L, t/L, w/L), written by `pipeline.dataset`."""
    from snapmorph.pipeline import schema
    from snapmorph.pipeline.grid import PRESETS

    codes = {k: v for k, v in schema.STATUS_CODES.items() if k != PENDING}
    return SolverSpec(
        name="unit",
        solve="snapmorph.pipeline.point:solve_point",
        dims=tuple(schema.GRID_DIMS),
        float_vars=dict(schema.FLOAT_VARS),
        flag_vars=dict(schema.FLAG_VARS),
        array_vars={name: (("sample", "xz"), ("samples", 2), *schema.SHAPE_ATTRS[name].values())
                    for name in getattr(schema, "SHAPE_VARS", ("base_shape",))},
        status_codes=codes,
        # the schema-1 fields point.finalise_record guarantees at "ok"
        required_when_ok=tuple(n for n in (*_UNIT_REQUIRED, "base_shape")
                               if n in schema.FLOAT_VARS or n == "base_shape"),
        failure_statuses=tuple(n for n in ("not_converged", "timeout", "invalid_geometry") if n in codes.values()),
        options={"b_over_L": 0.0, "resolution": None, "samples": schema.DEFAULT_SAMPLES},
        presets=dict(PRESETS),
        warm="snapmorph.pipeline.solvers:_unit_warm",
        # the rod solver, the planar unit model (units/ also holds the 2-D and 3-D units, which
        # do not change this map), the normalisation, and the writer (it decides the bytes)
        sources=("snapmorph.solver", "snapmorph.units.__init__", "snapmorph.units.geometry", "snapmorph.units.planar", "snapmorph.pipeline.point",
                 "snapmorph.pipeline.schema", "snapmorph.pipeline.dataset"),
        schema_version=int(schema.SCHEMA_VERSION),
        title="snapmorph design map of the bistable arch-on-base unit",
        call="positional",
        finalise="snapmorph.pipeline.solvers:_unit_finalise",
        empty="snapmorph.pipeline.solvers:_unit_empty",
        resolve_options="snapmorph.pipeline.solvers:_unit_resolve_options",
        assemble="snapmorph.pipeline.solvers:_unit_assemble",
        write="snapmorph.pipeline.dataset:write_netcdf",
        validate_file="snapmorph.pipeline.solvers:_unit_validate_file",
    )


def _unit_finalise(rec, options):
    from snapmorph.pipeline.point import finalise_record

    return finalise_record(rec, options["samples"])


def _unit_empty(options, status, message=""):
    from snapmorph.pipeline.point import empty_record

    return empty_record(options["samples"], status, message)


def _unit_resolve_options(options):
    from snapmorph.pipeline.point import default_resolution

    opts = dict(options)
    if opts.get("resolution") is None:
        opts["resolution"] = default_resolution()
    else:
        try:
            from snapmorph.units.geometry import check_nodes
        except ImportError:  # an older solver without the check: its own errors per point
            return opts
        try:
            opts["resolution"] = check_nodes(opts["resolution"])
        except ValueError as exc:
            raise ValueError(f"resolution: {exc}") from None
    return opts


def _unit_warm(options):
    from snapmorph.pipeline.point import warm_up

    return warm_up(options.get("resolution"))


def _unit_assemble(grid, total, attrs, spec):
    from snapmorph.pipeline.dataset import assemble, global_attrs

    prov = {k: attrs[k] for k in ("created", "package_version", "git_commit")}
    prov["resolution"] = attrs["model_options"]["resolution"]
    ds = assemble(grid, total, global_attrs(grid, prov))
    return ds


def _unit_validate_file(path):
    from snapmorph.maps.designmap import DesignMap

    DesignMap.load(path)
