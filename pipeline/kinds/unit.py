"""The planar arch-on-base unit as a kind of map: its grid, its point solver and its schema
section (the map of docs/design-map-schema.md, names from `maps.schema`).

    from snapmorph.pipeline.kinds.unit import SPEC, preset, solve_point
    rec = solve_point(0.2, 0.005, 0.05)       # one point: a dimensionless schema record

`Grid` is a `MapGrid` over (h/L, t/L, w/L, b/L), or over (h/L, t/L, w/L) at one fixed b/L
(the three-axis layout of the maps before schema 3), with the model options resolution and samples,
checked against the unit's domain; points are numbered in C order over the axes: index =
((i_h * n_t + i_t) * n_w + i_w) * n_b + i_b (without the last factor at a fixed b/L). `solve_point` simulates one unit with `snapmorph.units.planar`
and returns its record; it never raises, so that one odd point cannot break a build.
"""

from __future__ import annotations

import importlib
import math

import numpy as np

from snapmorph.maps.schema import (
    B_DIM, BISTABLE_ONLY, COORD_ATTRS, DEFAULT_SAMPLES, FLAG_VARS, FLOAT_VARS,
    GRID_DIMS, GRID_DIMS_B, METRIC_SOURCES, NORMALISATION_3, OPTIONAL_VARS, PATH_METRICS,
    RELEASED_METRICS, RELEASED_VARS, SCHEMA_VERSION, SHAPE_ATTRS, SHAPE_DIMS, SHAPE_VARS, TEXT_VARS,
    XZ,
)
from snapmorph.pipeline.solvers import MapGrid, SolverSpec, failure_statuses, status_codes
from snapmorph.units import status as unit_status
from snapmorph.units.status import FAILED, INVALID_GEOMETRY, NOT_BISTABLE, NOT_CONVERGED

#: reference base length (m) and Young's modulus (Pa) used to build the SI geometry; the
#: normalised outputs do not depend on them
L_REF = 0.1
E_REF = 2.2e9
#: the actuator joint of the maps, over L: the paper's 1/8 in stem at its L = 100 mm
JOINT_LENGTH_OVER_L = 0.03175
#: the maps bond the whole flat part b + w of each end (`UnitGeometry.bond_length` = None)
BOND_LENGTH = "b+w"
TITLE = "snapmorph design map of the bistable arch-on-base unit"

# -- the grid ---------------------------------------------------------------------------------

# Valid ranges: (low, high, low inclusive, high inclusive). The arch needs room between its
# flat ends, 2 (b + w) < L, which is checked jointly below.
_RANGES = {
    "h_over_L": (0.0, 1.0, False, True),
    "t_over_L": (0.0, 0.05, False, True),
    "w_over_L": (0.0, 0.5, False, False),
    "b_over_L": (0.0, 0.5, True, False),
}

#: solver resolution (`nodes` of `snapmorph.units.planar.simulate_unit`) of a Grid unless
#: given; None = the solver's converged default, resolved and recorded when a build starts
PRESET_RESOLUTION = None
#: resolution of the `default` preset: the solver's converged default (None). An earlier
#: solver had F_cr dips of ~3 % between w/L = 0.02 and 0.03 (a roller moved by half an edge
#: where 0.03 L met b + w) and a parabola-fitted F_cr, which pinned this to 161 nodes; both
#: are fixed, see the accuracy figures in the issue notes (`make maps-accuracy`).
DEFAULT_MAP_RESOLUTION = None
MIN_RESOLUTION = 5


def _range_text(name: str) -> str:
    lo, hi, lo_in, hi_in = _RANGES[name]
    return f"{lo} {'<=' if lo_in else '<'} {name} {'<=' if hi_in else '<'} {hi}"


def _axis(name: str, values) -> tuple[float, ...]:
    """Validate one axis: finite, strictly increasing, at least 2 values, inside its range."""
    try:
        arr = np.asarray(values, dtype=float).ravel()
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a sequence of numbers, got {values!r}") from None
    if arr.size < 2:
        raise ValueError(f"{name} needs at least 2 values (got {arr.size}): a map interpolates")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} values must be finite, got {arr.tolist()}")
    if np.any(np.diff(arr) <= 0):
        raise ValueError(f"{name} values must be strictly increasing, got {arr.tolist()}")
    lo, hi, lo_in, hi_in = _RANGES[name]
    bad = arr[(arr < lo) | (arr > hi) | ((arr == lo) & (not lo_in)) | ((arr == hi) & (not hi_in))]
    if bad.size:
        raise ValueError(f"{name} = {float(bad[0])!r} is outside the valid range {_range_text(name)}")
    return tuple(float(v) for v in arr)


def _fixed_b(b) -> float:
    """One b/L for a whole map, validated."""
    if isinstance(b, bool) or not isinstance(b, (int, float, np.floating, np.integer)) \
            or not np.isfinite(b) or b < 0:
        raise ValueError(f"b_over_L must be a finite number >= 0, got {b!r}")
    return float(b)


def _options(resolution, samples) -> dict:
    """The grid's model options, validated."""
    r = resolution
    if r is not None and (isinstance(r, bool) or not isinstance(r, (int, np.integer)) or r < MIN_RESOLUTION):
        raise ValueError(f"resolution must be None or an integer >= {MIN_RESOLUTION}, got {r!r}")
    s = samples
    if isinstance(s, bool) or not isinstance(s, (int, np.integer)) or s < 2:
        raise ValueError(f"samples must be an integer >= 2, got {s!r}")
    return {"resolution": None if r is None else int(r), "samples": int(s)}


class Grid(MapGrid):
    """A design-map grid of the planar unit.

    h_over_L, t_over_L, w_over_L: axis values (dimensionless, strictly increasing, >= 2 each);
    b_over_L: extra flat length of the arch ends / L: a sequence (>= 2 values) is the fourth
      axis; one number fixes it for the whole map (the three-axis layout; default 0, the b/L
      of the maps before schema 3);
    resolution: solver `nodes` parameter (None = the solver's converged default);
    samples: number M of base-shape samples; name: preset name or "custom".
    """

    def __init__(self, h_over_L, t_over_L, w_over_L, b_over_L: float = 0.0,
                 resolution: int | None = PRESET_RESOLUTION, samples: int = DEFAULT_SAMPLES,
                 name: str = "custom"):
        axes = {d: _axis(d, v) for d, v in zip(GRID_DIMS, (h_over_L, t_over_L, w_over_L))}
        options = _options(resolution, samples)
        if np.ndim(b_over_L) == 0 and not isinstance(b_over_L, (list, tuple)):
            b_max = _fixed_b(b_over_L)
            options = {B_DIM: b_max, **options}
        else:
            axes[B_DIM] = _axis(B_DIM, b_over_L)
            b_max = axes[B_DIM][-1]
        w_max, h_max = axes["w_over_L"][-1], axes["h_over_L"][-1]
        if b_max + w_max >= 0.5:
            raise ValueError(
                f"b_over_L + w_over_L must be < 0.5 (the sinusoidal part needs L - 2(b + w) > 0); "
                f"got b_over_L = {b_max} with largest w_over_L = {w_max}, "
                f"so b_over_L must be < {0.5 - w_max:g}"
            )
        if h_max > 1.0 - 2.0 * (b_max + w_max) + 1e-12:
            raise ValueError(
                f"h_over_L must be <= the sinusoid's span 1 - 2 (b_over_L + w_over_L) at every grid "
                f"point (a steeper sinusoid folds over itself); got h_over_L = {h_max} with "
                f"b_over_L = {b_max} and w_over_L = {w_max}, so b_over_L must be <= "
                f"{0.5 * (1.0 - h_max) - w_max:g}")
        super().__init__(axes, options, name)

    h_over_L = property(lambda self: self.axes["h_over_L"], doc="Grid values of h/L.")
    t_over_L = property(lambda self: self.axes["t_over_L"], doc="Grid values of t/L.")
    w_over_L = property(lambda self: self.axes["w_over_L"], doc="Grid values of w/L.")
    b_over_L = property(lambda self: self.axes[B_DIM] if B_DIM in self.axes else self.options[B_DIM],
                        doc="Extra flat length / L: the axis values, or the one value of the map.")
    resolution = property(lambda self: self.options["resolution"], doc="Solver nodes (None: default).")
    samples = property(lambda self: self.options["samples"], doc="Base-shape samples M.")

    @classmethod
    def from_dict(cls, d: dict) -> "Grid":
        return cls(**d["axes"], **d["options"], name=d["name"])

    def with_options(self, **options) -> "Grid":
        return Grid(**self.axes, **{**self.options, **options}, name=self.name)


def _lin(lo: float, hi: float, n: int) -> tuple[float, ...]:
    # Rounded so that e.g. 0.05 + 3 * 0.01 is stored as 0.08, not 0.08000000000000002.
    return tuple(float(round(v, 12)) for v in np.linspace(lo, hi, n))


#: the b/L axis of the default map: the maps before schema 3 (0), the paper's b = w (b/L = 0.05
#: at L = 100 mm, w = 5 mm) and 0.10. The declared domain at h/L = 0.5, w/L = 0.1 reaches 0.15
#: (h/L <= 1 - 2 (b + w) / L), but today's unit model fails at 204 of the 3726 points there
#: ("the zero-force state was not located") and a fourth value costs 40 % more build time
#: the default map's b/L axis: 0 (the parametric study's, every old point) and 0.05 (the
#: paper's b = w at L = 100 mm, w = 5 mm). 0.10 is left out: there F_cr jumps 3-9 % between
#: neighbouring h at w/L = 0.1, h/L ~ 0.43 where the path switches branch (issue 26 (d) is
#: not solved), and at 0.15 the zero-force state is not located at 204 points.
DEFAULT_B_OVER_L = (0.0, 0.05)


def _preset_default() -> Grid:
    # 46 x 9 x 9 x 2 = 7452 points; steps 0.01, 0.00125, 0.01 put the paper's t/L = 0.005,
    # 0.0075 and w/L = 0.05 exactly on the grid, and its h, t, w axes are those of the
    # three-axis map (schema 2, b/L = 0) it replaces, so that every old point is a new one.
    return Grid(
        h_over_L=_lin(0.05, 0.50, 46),
        t_over_L=_lin(0.0025, 0.0125, 9),
        w_over_L=_lin(0.02, 0.10, 9),
        b_over_L=DEFAULT_B_OVER_L,
        resolution=DEFAULT_MAP_RESOLUTION,
        name="default",
    )


def _preset_ci() -> Grid:
    # 4 x 3 x 2 x 2 = 48 points; h/L = 0.10 is monostable in the paper's model (Table 1,
    # h = 10 mm); b/L = 0.05 is the paper's b = w.
    return Grid(
        h_over_L=(0.10, 0.20, 0.30, 0.40),
        t_over_L=(0.005, 0.0075, 0.01),
        w_over_L=(0.04, 0.06),
        b_over_L=(0.0, 0.05),
        name="ci",
    )


PRESETS = {"default": _preset_default, "ci": _preset_ci}


def preset(name: str) -> Grid:
    """The named preset grid ("default" or "ci")."""
    try:
        return PRESETS[name]()
    except KeyError:
        raise ValueError(f"grid must be one of {sorted(PRESETS)}, got {name!r}") from None


def _check_domain(grid) -> None:
    """ValueError unless `grid` (a Grid, or any MapGrid over h/L, t/L, w/L) lies in the unit's
    domain."""
    if isinstance(grid, Grid):
        return
    unknown = sorted(set(grid.options) - set(SPEC.options) - set(SPEC.fixed_dims))
    if unknown:
        raise ValueError(f"the planar unit has no model options {unknown} (it takes {list(SPEC.options)})")
    Grid(**grid.axes, **grid.options, name=grid.name)


# -- one point ----------------------------------------------------------------------------------

def _joint_length(L: float) -> float:
    """The maps' joint (m) for base length L: exactly `UnitGeometry`'s default 1/8 in at the
    reference L = 0.1 m (so that a map point and a default `simulate_unit` are identical)."""
    from snapmorph.units.geometry import JOINT_LENGTH_DEFAULT

    return JOINT_LENGTH_DEFAULT if L == L_REF else JOINT_LENGTH_OVER_L * L


def model_options() -> dict:
    """The unit-model options a map is built with (recorded as global attributes, and part of
    a build's fingerprint)."""
    return {"joint_length_over_L": JOINT_LENGTH_OVER_L, "bond_length_over_L": BOND_LENGTH}


def empty_record(samples: int = DEFAULT_SAMPLES, status: int = NOT_CONVERGED, message: str = "") -> dict:
    """A record with every field absent: NaN floats, flags 0 (bistable) / -1, NaN base shapes."""
    return SPEC.empty_record({"samples": samples}, status, message)


def finalise_record(rec, samples: int = DEFAULT_SAMPLES) -> dict:
    """Check and clean any solver's record so it obeys the schema (`SolverSpec.finalise_record`
    with the unit's `_record_rules`).

    Missing keys or wrong types turn the point into status 2 (the schema-2 additions,
    `OPTIONAL_VARS` and base_shape_released, may be left out: they are then NaN); fields that
    do not exist for the point's status are set to NaN; an "ok" record with non-finite fields
    becomes status 2; released-state fields exist exactly where self_standing = 1.
    """
    return SPEC.finalise_record(rec, {"samples": samples})


def _record_rules(out: dict, rec: dict) -> list:
    """The unit's own rules on a checked record (see `finalise_record`): a point solved but
    not bistable keeps only its force peak (F_cr, d_cr) and bifurcation flag; the released
    state exists exactly where self_standing = 1, and all of it when the solver gave any of
    it; an ok point is bistable. Returns the values missing at an ok point."""
    if out["status"] in NOT_BISTABLE:
        for name in (*BISTABLE_ONLY, *RELEASED_VARS, *RELEASED_METRICS):
            out[name] = math.nan
        for name in SHAPE_VARS:
            out[name][:] = np.nan
        out["bistable"] = 0
        out["self_standing"] = -1
        return []
    missing = []
    if out["self_standing"] != 1:
        for name in (*RELEASED_VARS, *RELEASED_METRICS):
            out[name] = math.nan
        out["base_shape_released"][:] = np.nan
    elif any(n in rec for n in RELEASED_VARS):
        missing += [n for n in RELEASED_VARS if not math.isfinite(out[n])]
        if not np.all(np.isfinite(out["base_shape_released"])):
            missing.append("base_shape_released")
    if out["bistable"] != 1:
        missing.append("bistable")
    return missing


def resample_shape(xz, samples: int) -> np.ndarray:
    """Resample a polyline (m, 2) to `samples` points uniform in arc length, translated to start
    at (0, 0) and rotated so that its start tangent (first segment) points along +x."""
    xz = np.asarray(xz, dtype=float)
    if xz.ndim != 2 or xz.shape[1] != 2 or xz.shape[0] < 2:
        raise ValueError(f"base shape must be an (m >= 2, 2) array, got shape {xz.shape}")
    if not np.all(np.isfinite(xz)):
        raise ValueError("base shape holds non-finite values")
    seg = np.diff(xz, axis=0)
    ds = np.hypot(seg[:, 0], seg[:, 1])
    if not np.any(ds > 0):
        raise ValueError("base shape has zero length")
    s = np.concatenate([[0.0], np.cumsum(ds)])
    su = np.linspace(0.0, s[-1], samples)
    pts = np.column_stack([np.interp(su, s, xz[:, 0]), np.interp(su, s, xz[:, 1])]) - xz[0]
    tx, tz = seg[np.argmax(ds > 0)]
    c, sn = tx / math.hypot(tx, tz), tz / math.hypot(tx, tz)
    rot = np.array([[c, sn], [-sn, c]])  # rotation by -angle of the start tangent
    out = pts @ rot.T
    out[0] = 0.0
    return out


def _flag(value) -> int:
    if value is None:
        return -1
    return 1 if bool(value) else 0


def normalise_result(r, samples: int = DEFAULT_SAMPLES) -> dict:
    """Turn a `snapmorph.units.UnitResult` (SI) into a schema record (dimensionless)."""
    g = r.geometry
    L = g.L
    EI = g.E * g.w * g.t**3 / 12.0  # E I_arch (N m^2)
    f_scale = L**2 / EI
    u_scale = L / EI
    status = int(r.status_code)
    if status not in unit_status.NAME or status < 0:
        return empty_record(samples, NOT_CONVERGED, f"solver returned unknown status_code {status}")
    rec = empty_record(samples, status, str(getattr(r, "status", "")))
    if status in FAILED:
        return rec
    rec["F_cr"] = float(r.F_cr) * f_scale
    rec["d_cr"] = float(r.d_cr) / L
    rec["bifurcation"] = _flag(r.bifurcation)
    metrics = unit_metrics(r, f_scale, L)
    rec.update({k: metrics[k] for k in (*PATH_METRICS, *TEXT_VARS)})
    if status in NOT_BISTABLE:
        return rec
    rec["bistable"] = 1 if r.bistable else 0
    rec["self_standing"] = _flag(r.self_standing)
    rec["d_unstable"] = float(r.d_unstable) / L
    rec["d_second"] = float(r.d_second) / L
    rec["S"] = float(r.S) / L
    rec["theta"] = float(r.theta_deg)
    rec["theta_end"] = float(getattr(r, "theta_end_deg", math.nan))
    rec["energy_barrier"] = float(r.energy_barrier) * u_scale
    rec["energy_stored"] = float(r.energy_stored) * u_scale
    rec["base_shape"] = resample_shape(np.asarray(r.base_shape, dtype=float) / L, samples)
    rel = getattr(r, "released", None) or {}
    if rec["self_standing"] == 1 and "base_shape" in rel:
        rec["S_released"] = float(rel["S"]) / L
        rec["theta_released"] = float(rel["theta_deg"])
        rec["theta_end_released"] = float(rel.get("theta_end_deg", math.nan))
        rec["base_shape_released"] = resample_shape(np.asarray(rel["base_shape"], float) / L, samples)
    if rec["self_standing"] == 1:
        rec.update({k: metrics[k] for k in RELEASED_METRICS})
    return rec


def unit_metrics(r, f_scale: float, L: float) -> dict:
    """The schema-3 unit metrics of a unit result, normalised (`maps.schema.METRIC_SOURCES`):
    forces x f_scale = L^2 / (E I_arch), lengths / L, the stiffness x f_scale L, strains as
    they are. The one place that reads them: a result without a field gives NaN ("" for text),
    so maps build before the unit model reports them."""
    scale = {"force": f_scale, "length": 1.0 / L, "stiffness": f_scale * L, "1": 1.0}
    out = {}
    for name, (field, kind) in METRIC_SOURCES.items():
        value = getattr(r, field, math.nan)
        if kind == "text":
            out[name] = value if isinstance(value, str) else ""
            continue
        try:
            out[name] = float(value) * scale[kind]
        except (TypeError, ValueError):
            out[name] = math.nan
    return out


def unit_model():
    """The planar unit model (`snapmorph.units.planar`: UnitGeometry, simulate_unit,
    DEFAULT_NODES), looked up in ``sys.modules`` at call time so that tests can stand in."""
    return importlib.import_module("snapmorph.units.planar")


def solve_point(h_over_L, t_over_L, w_over_L, b_over_L=0.0, resolution=None,
                samples: int = DEFAULT_SAMPLES, time_limit=None) -> dict:
    """Simulate one unit (L = 0.1 m, E = 2.2 GPa, the maps' joint and bond) and return its
    dimensionless schema record.

    ``time_limit``: wall time (s) for the point (None: none); past it the point gets status 4
    (timeout). Never raises: a geometry ValueError gives status 3 (invalid_geometry), any other
    exception or a failed solve gives status 2 (not_converged) with NaN fields; `message` says
    why.
    """
    try:
        model = unit_model()
        UnitGeometry, simulate_unit = model.UnitGeometry, model.simulate_unit
    except Exception as exc:  # the solver itself is broken: record, do not stop
        return empty_record(samples, NOT_CONVERGED, f"cannot import the unit model: {exc!r}")
    L = L_REF
    try:
        g = UnitGeometry(L=L, h=h_over_L * L, t=t_over_L * L, w=w_over_L * L, b=b_over_L * L,
                         E=E_REF, joint_length=_joint_length(L))
    except ValueError as exc:
        return empty_record(samples, INVALID_GEOMETRY, f"invalid geometry: {exc}")
    except Exception as exc:
        return empty_record(samples, NOT_CONVERGED, f"geometry failed: {exc!r}")
    try:
        if time_limit is None:
            r = simulate_unit(g, nodes=resolution)
        else:
            r = simulate_unit(g, nodes=resolution, time_limit=time_limit)
        return finalise_record(normalise_result(r, samples), samples)
    except Exception as exc:
        return empty_record(samples, NOT_CONVERGED, f"solver raised {exc!r}")


def default_resolution():
    """The solver's converged default resolution (`snapmorph.units.planar.DEFAULT_NODES`), or
    None if the solver does not say (or cannot be imported)."""
    try:
        unit = unit_model()
    except Exception:
        return None
    n = getattr(unit, "DEFAULT_NODES", None)
    return int(n) if isinstance(n, (int, np.integer)) and not isinstance(n, bool) else None


def warm_up(resolution=None) -> float:
    """Compile (or load from the numba cache) the solver kernels by solving one small point.
    Returns the seconds it took."""
    import time

    unit = unit_model()
    t0 = time.perf_counter()
    hook = getattr(unit, "warm_up", None)
    if callable(hook):
        hook()
    else:
        g = unit.UnitGeometry(L=L_REF, h=0.02, t=0.5e-3, w=5e-3, b=0.0, E=E_REF)
        unit.simulate_unit(g, nodes=resolution)
    return time.perf_counter() - t0


# -- the kind's hooks ---------------------------------------------------------------------------

def _resolve_options(options: dict) -> dict:
    """The options with resolution None replaced by the solver's default, a given one checked."""
    from snapmorph.units.geometry import check_nodes

    opts = dict(options)
    if opts.get("resolution") is None:
        opts["resolution"] = default_resolution()
    else:
        try:
            opts["resolution"] = check_nodes(opts["resolution"])
        except ValueError as exc:
            raise ValueError(f"resolution: {exc}") from None
    return opts


def _warm(options: dict) -> float:
    return warm_up(options.get("resolution"))


def _check_file(path) -> None:
    """Read the written map back with `maps.DesignMap` (raises when it is not a valid map)."""
    from snapmorph.maps.designmap import DesignMap

    DesignMap.load(path)


def _global_attrs(grid, options: dict, provenance: dict) -> dict:
    """The schema's global attributes of a map of `grid` built with the resolved `options`."""
    resolution = options.get("resolution")
    fixed_b = {} if B_DIM in grid.axes else {"b_over_L": float(options[B_DIM])}
    return {
        "title": f"{TITLE} (grid {grid.name})",
        "schema_version": np.int32(SCHEMA_VERSION),
        "grid": grid.name,
        **fixed_b,
        # the resolution used (the solver default resolved at the start); netCDF has no None:
        # -1 means "the solver's default, which it did not state"
        "resolution": np.int32(-1 if resolution is None else resolution),
        "package_version": provenance["package_version"],
        "git_commit": provenance["git_commit"],
        "created": provenance["created"],
        "normalisation": NORMALISATION_3,
        "E_reference": float(E_REF),
        "L_reference": float(L_REF),
        **model_options(),
    }


SPEC = SolverSpec(
    name="unit",
    solve=solve_point,
    dims=GRID_DIMS_B,
    fixed_dims={B_DIM: 0.0},
    float_vars=dict(FLOAT_VARS),
    text_vars=dict(TEXT_VARS),
    flag_vars=dict(FLAG_VARS),
    array_vars={name: (SHAPE_DIMS, ("samples", len(XZ)), *SHAPE_ATTRS[name].values())
                for name in SHAPE_VARS},
    dim_attrs={d: tuple(a.values()) for d, a in COORD_ATTRS.items()},
    dim_labels={"xz": XZ},
    status_codes=status_codes(),
    failure_statuses=failure_statuses(),
    required_when_ok=(*(n for n in FLOAT_VARS if n not in OPTIONAL_VARS), "base_shape"),
    required_keys=(*(n for n in FLOAT_VARS if n not in OPTIONAL_VARS), *FLAG_VARS, "base_shape"),
    flag_defaults={"bistable": 0},
    options={"resolution": None, "samples": DEFAULT_SAMPLES},
    presets=dict(PRESETS),
    # the unit model, its normalisation and schema (the modules this one imports are hashed
    # with it: units.planar, the solver, maps.schema, ...)
    sources=(__name__,),
    schema_version=SCHEMA_VERSION,
    title=TITLE,
    call="positional",
    warm=_warm,
    resolve_options=_resolve_options,
    domain=_check_domain,
    rules=_record_rules,
    global_attrs=_global_attrs,
    validate_file=_check_file,
)
