"""`DesignMap`: load a design map (schema 3 or 2, or 1 read-only) and look values up by
interpolation.

Interpolation is piecewise linear on the grid cell around the query (scipy
`RegularGridInterpolator`), in the coordinates (h/L, log t/L, log w/L, b/L) of a schema-3 map
((h/L, log t/L, log w/L) of a map at one fixed b/L: every lookup takes ``b_over_L=``, which
must then be left out or equal that value), and of log(F_cr) for the force (F_cr varies like a power of t and w, so that is nearly linear). Every variable has a
validity mask: S, theta, d_unstable, d_second, the energies and the base shape exist only at
bistable points (status ok); F_cr and d_cr also at monostable ones. A query whose cell gives
weight to an invalid grid point raises `MapDomainError` (or returns NaN with allow_nan=True):
NaN holes never leak into valid neighbours.

States: every lookup of S, theta, theta_end and the base shape takes ``state=``: "released"
(default: state (iii) with the actuator and rollers removed, the unit as used in an array;
defined where the released unit is still bistable, self_standing = 1) or "actuated" (state
(iii) with the actuator still glued, the paper's definition). A schema-1 map has no released
state: it loads with a warning and answers only ``state="actuated"``.

The unit metrics of schema 3 (F_min, d_Fmin, strain_max, F_back, stiffness_released,
strain_max_released, `maps.schema.METRIC_VARS`) each have their own validity (finite at a
point with a force peak, or at a self-standing one for the released ones); `at` returns them
NaN where undefined (never an error: the shape lookups do not depend on them), `value` raises
like for any other variable. ``strain_where`` comes back as the common text of the cell's grid
points ("" when they differ).
"""

from __future__ import annotations

import itertools
import math
import warnings
from pathlib import Path

import numpy as np

from snapmorph.maps.schema import (
    B_DIM, BISTABLE_ONLY, FLAG_VARS, FORCE_STATUSES, GRID_DIMS, GRID_DIMS_B, METRIC_VARS,
    OK_STATUS, PATH_METRICS, PENDING_STATUS, READABLE_VERSIONS, RELEASED_VARS, REQUIRED_ATTRS,
    REQUIRED_ATTRS_V3, REQUIRED_VARS, REQUIRED_VARS_V1, REQUIRED_VARS_V3, SCHEMA_VERSION, STATES,
    TEXT_VARS, status_names,
)

DATA_DIR = Path(__file__).resolve().parent / "data"
DEFAULT_MAP = DATA_DIR / "default.nc"
CI_MAP = DATA_DIR / "ci.nc"
#: the three-axis default map (schema 2, b/L = 0) that the map with a b/L axis replaced, kept
#: to say how much every value moved at its points (tests/maps/test_maps_reference.py)
REFERENCE_MAP = DATA_DIR / "reference" / "default-schema2.nc"

_F_VARS = ("F_cr", "d_cr")  # exist at bistable and monostable points
_LOG_VARS = ("F_cr",)  # interpolated as log(value)
_W_TOL = 1e-9  # a grid point with interpolation weight below this is not "touched"
_R_TOL = 1e-12  # relative tolerance on the grid bounds
_B_TOL = 1e-12  # a b/L this close to a fixed-b map's own is that b/L
#: the b/L of a lookup on a schema-3 map that gives none: that of the maps before schema 3
DEFAULT_B_OVER_L = 0.0


class MapFileError(ValueError):
    """A map file that cannot be used: corrupt, not a design map, wrong schema version."""


class MapDomainError(ValueError):
    """A query outside the grid, or touching monostable/failed grid points."""


class OldSchemaWarning(UserWarning):
    """A schema-1 map was loaded: it has no released state."""


STATE_NAMES = tuple(STATES)  # ("released", "actuated")
#: per-state names of `at`'s outputs -> the map variables they come from
_STATE_VARS = {state: dict(zip(("S", "theta", "theta_end"), names[:3]))
               for state, names in STATES.items()}


def check_state(state) -> str:
    """``state`` if it is "released" or "actuated", else ValueError."""
    if not isinstance(state, str) or state not in STATES:
        raise ValueError(f"state must be one of {', '.join(map(repr, STATES))} (the released unit, "
                         f"default, or state (iii) with the actuator still glued); got {state!r}")
    return state


#: what each query parameter is (for error messages)
_MEANING = {"h_over_L": "arch apex height over base length, dimensionless",
            "t_over_L": "sheet thickness over base length, dimensionless",
            "w_over_L": "strip width over base length, dimensionless",
            "b_over_L": "extra flat length of the arch ends over base length, dimensionless",
            "theta_deg": "signed turning angle theta, degrees",
            "theta_end_deg": "end angle theta_end (end tangent to chord), degrees"}


def _real_array(name: str, value) -> np.ndarray:
    """``value`` (a number or an array of numbers) as a float array, or ValueError naming
    ``name``, what it is and its unit. Strings, None, booleans and complex numbers are refused;
    NaN passes (the range checks name it)."""
    what = f"{name} ({_MEANING.get(name, name)})"
    if value is None or isinstance(value, (str, bytes, bool, np.bool_)):
        raise ValueError(f"{what} must be a real number or an array of real numbers; "
                         f"got {value!r}")
    try:
        raw = np.asarray(value)
    except (TypeError, ValueError) as exc:  # ragged lists
        raise ValueError(f"{what} must be a real number or an array of real numbers; "
                         f"got {value!r} ({exc})") from None
    if raw.dtype.kind == "c":
        raise ValueError(f"{what} must be real, not complex; got {value!r}")
    if raw.dtype.kind not in "iufO":
        raise ValueError(f"{what} must be a real number or an array of real numbers; "
                         f"got {value!r}")
    try:
        return np.asarray(value, dtype=float)
    except (TypeError, ValueError):  # an object array holding text, complex numbers, ...
        raise ValueError(f"{what} must be a real number or an array of real numbers; "
                         f"got {value!r}") from None


def _broadcast(**named):
    """Broadcast the named query arrays, or ValueError naming them and their shapes."""
    arrays = [_real_array(name, v) for name, v in named.items()]
    try:
        return np.broadcast_arrays(*arrays)
    except ValueError:
        shapes = ", ".join(f"{name} {a.shape}" for name, a in zip(named, arrays))
        raise ValueError(f"{', '.join(named)} must broadcast to one shape (scalars, or arrays of "
                         f"equal or broadcastable shapes); got shapes {shapes}") from None


def _fail(path, problem):
    raise MapFileError(f"design map {path}: {problem}")


def _open(path: Path):
    import xarray as xr

    try:
        with xr.open_dataset(path, engine="netcdf4") as ds:
            return ds.load()
    except FileNotFoundError:
        raise
    except Exception as exc:
        _fail(path, f"not a readable netCDF file ({type(exc).__name__}: {exc})")


def _validate(ds, path) -> None:
    version = ds.attrs.get("schema_version")
    if version is None:
        _fail(path, "no 'schema_version' attribute: not a snapmorph design map")
    try:
        version = int(version)
    except (TypeError, ValueError):
        _fail(path, f"schema_version {version!r} is not an integer")
    if version > SCHEMA_VERSION:
        _fail(path, f"schema version {version} is newer than this snapmorph reads "
                    f"({SCHEMA_VERSION}); upgrade snapmorph or rebuild the map")
    if version not in READABLE_VERSIONS:
        _fail(path, f"schema version {version} is not supported (this snapmorph reads "
                    f"{', '.join(map(str, READABLE_VERSIONS))})")
    required = {1: REQUIRED_VARS_V1, 2: REQUIRED_VARS}.get(version, REQUIRED_VARS_V3)
    missing = [v for v in required if v not in ds.variables]
    if missing:
        _fail(path, f"missing variables {missing}")
    dims = GRID_DIMS_B if version >= 3 and B_DIM in ds.dims else GRID_DIMS
    missing = [a for a in (REQUIRED_ATTRS_V3 if B_DIM in dims else REQUIRED_ATTRS) if a not in ds.attrs]
    if missing:
        _fail(path, f"missing global attributes {missing}")
    present = (*required, *(v for v in (*METRIC_VARS, *TEXT_VARS) if v in ds.variables))
    for name in present:
        want = dims + (("sample", "xz") if name.startswith("base_shape") else ())
        if ds[name].dims != want:
            _fail(path, f"variable {name} has dimensions {ds[name].dims}, expected {want}")
    for dim in dims:
        c = np.asarray(ds[dim].values, dtype=float)
        low_ok = c[0] >= 0 if dim == B_DIM else c[0] > 0
        if c.size < 2 or not np.all(np.isfinite(c)) or np.any(np.diff(c) <= 0) or not low_ok:
            _fail(path, f"coordinate {dim} must hold >= 2 " + ("non-negative" if dim == B_DIM else
                        "positive") + ", strictly increasing values")
    if ds.sizes["xz"] != 2:
        _fail(path, f"dimension xz has size {ds.sizes['xz']}, expected 2")
    if not np.issubdtype(ds["status"].dtype, np.integer):
        _fail(path, f"status has dtype {ds['status'].dtype}, expected an integer (no _FillValue)")
    try:
        names = status_names(ds["status"].attrs)
    except ValueError as exc:
        _fail(path, str(exc))
    status = ds["status"].values
    unknown = set(np.unique(status).tolist()) - set(names)
    if unknown:
        _fail(path, f"status holds unknown codes {sorted(unknown)}")
    pending = int(np.count_nonzero(np.isin(status, _codes(names, (PENDING_STATUS,)))))
    if pending:
        _fail(path, f"{pending} points are still pending: a partial build, not a finished map")
    return version, names


def _codes(names: dict, wanted) -> list:
    """The codes of the statuses named ``wanted`` in a file's {code: name}."""
    return [code for code, name in names.items() if name in wanted]


class DesignMap:
    """An interpolated design map. Use `DesignMap.load(path=None)`.

    Every length is over the base length L; `F_cr` is F_cr L^2 / (E I_arch) with
    I_arch = w t^3 / 12; `theta` and `theta_end` are in degrees. Every lookup takes
    ``b_over_L=`` (keyword): on a map with a b/L axis (`dims` ends with "b_over_L") None means
    `DEFAULT_B_OVER_L` (0); on a map at one b/L (`fixed_b_over_L`) it must be None or that value. S, theta, theta_end and the
    base shape come from the released state (iii) unless ``state="actuated"``.
    `status_names` is {code: name} of the statuses the file declares (its ``status``
    ``flag_values`` / ``flag_meanings``).
    """

    #: variables returned by `at` (S, theta, theta_end of the state asked for)
    SCALARS = ("F_cr", "d_cr", *BISTABLE_ONLY, *FLAG_VARS)

    def __init__(self, ds, path=None):
        from scipy.interpolate import RegularGridInterpolator as RGI

        self.schema_version, self.status_names = _validate(ds, path)
        if self.schema_version < 2:
            warnings.warn(f"design map {path or '<in memory>'} has schema version "
                          f"{self.schema_version}: it holds no released state (only "
                          f"state='actuated' lookups work) and no theta_end; rebuild it with "
                          f"`make maps` / `snapmorph maps build`", OldSchemaWarning, stacklevel=3)
        self.dataset = ds
        self.path = Path(path) if path is not None else None
        self.dims = GRID_DIMS_B if self.schema_version >= 3 and B_DIM in ds.dims else GRID_DIMS
        self._axes = tuple(np.asarray(ds[d].values, dtype=float) for d in self.dims)
        # interpolation coordinates: (h, log t, log w[, b]); b/L starts at 0, so it stays linear
        self._icoords = (self._axes[0], np.log(self._axes[1]), np.log(self._axes[2]),
                         *self._axes[3:])
        #: the b/L of a map at one fixed b/L (None for a map with a b/L axis)
        self.fixed_b_over_L = (None if B_DIM in self.dims
                               else float(ds.attrs.get("b_over_L", DEFAULT_B_OVER_L)))
        self._status = np.asarray(ds["status"].values)
        ok = np.isin(self._status, _codes(self.status_names, (OK_STATUS,)))
        standing = ok & (np.asarray(ds["self_standing"].values) == 1)
        bistable_vars = [v for v in BISTABLE_ONLY if v in ds.variables]
        force = np.isin(self._status, _codes(self.status_names, FORCE_STATUSES))
        groups = {"F": (list(_F_VARS), force), "bi": (bistable_vars, ok.copy())}
        if self.schema_version >= 2:
            groups["rel"] = (list(RELEASED_VARS), standing.copy())
        # each unit metric on its own: one that the unit model does not report yet (NaN
        # everywhere) leaves the others and the shapes alone
        self.metrics = tuple(v for v in METRIC_VARS if v in ds.variables)
        for name in self.metrics:
            groups[name] = ([name], (force if name in PATH_METRICS else standing).copy())
        self._interp = {}
        self._group_of = {}
        for group, (names, valid) in groups.items():
            vals = []
            for name in names:
                v = np.asarray(ds[name].values, dtype=float)
                if name in _LOG_VARS:
                    with np.errstate(divide="ignore", invalid="ignore"):
                        v = np.log(v)
                valid &= np.isfinite(v)
                vals.append(v)
                self._group_of[name] = group
            shape_var = {"bi": "base_shape", "rel": "base_shape_released"}.get(group)
            if shape_var is not None:
                shape = np.asarray(ds[shape_var].values, dtype=float)
                valid &= np.all(np.isfinite(shape), axis=(-2, -1))
            values = np.where(valid[..., None], np.stack(vals, axis=-1), 0.0)
            self._interp[group] = (
                names,
                RGI(self._icoords, values, method="linear", bounds_error=False, fill_value=np.nan),
                RGI(self._icoords, (~valid).astype(float), method="linear", bounds_error=False,
                    fill_value=np.nan),
                valid,
            )
        self._shape_rgi = {}
        for state, group in (("actuated", "bi"), ("released", "rel")):
            if group not in self._interp:
                continue
            valid = self._interp[group][3]
            var = STATES[state][3]
            shape = np.where(valid[..., None, None], np.asarray(ds[var].values, float), 0.0)
            self._shape_rgi[state] = (group, RGI(self._icoords, shape, method="linear",
                                                 bounds_error=False, fill_value=np.nan))
        # flag consensus: the fraction of stencil weight on each value -1, 0, 1
        ind = [(np.asarray(ds[f].values) == v) for f in FLAG_VARS for v in (-1, 0, 1)]
        self._flag_rgi = RGI(self._icoords, np.stack(ind, axis=-1).astype(float), method="linear",
                             bounds_error=False, fill_value=np.nan)
        # text consensus: the fraction of stencil weight on each text a variable holds
        self._text_rgi = {}
        for name in (v for v in TEXT_VARS if v in ds.variables):
            text = np.asarray(ds[name].values).astype(str)
            words = sorted(set(text.ravel().tolist()))
            ind = np.stack([text == word for word in words], axis=-1).astype(float)
            self._text_rgi[name] = (words, RGI(self._icoords, ind, method="linear",
                                               bounds_error=False, fill_value=np.nan))

    @property
    def states(self) -> tuple:
        """The states this map can answer: ("released", "actuated"), or ("actuated",) for a
        schema-1 map."""
        return STATE_NAMES if self.schema_version >= 2 else ("actuated",)

    def _state(self, state) -> str:
        state = check_state(state)
        if state not in self.states:
            raise MapDomainError(
                f"design map {self.path or '<in memory>'} (schema {self.schema_version}) has no "
                f"{state} state; rebuild it (`make maps`) or pass state='actuated'")
        return state

    # ---------------------------------------------------------------- loading
    @classmethod
    def load(cls, path=None) -> "DesignMap":
        """Load a map file; None = the committed default map `maps/data/default.nc`.

        If the default map has not been built yet, the small CI map `maps/data/ci.nc` is loaded
        instead, with a warning (it is far too coarse for design accuracy). Raises
        MapFileError (a ValueError) naming the file for corrupt files, missing variables or a
        wrong/newer schema version, FileNotFoundError when there is no file.
        """
        if path is None:
            if DEFAULT_MAP.exists():
                path = DEFAULT_MAP
            elif CI_MAP.exists():
                warnings.warn(f"{DEFAULT_MAP} does not exist (run `make maps`); using the coarse "
                              f"CI map {CI_MAP}", stacklevel=2)
                path = CI_MAP
            else:
                raise FileNotFoundError(f"no design map at {DEFAULT_MAP} (run `make maps`)")
        path = Path(path)
        if not path.is_file():
            raise FileNotFoundError(f"design map {path} does not exist")
        return cls(_open(path), path)

    # ---------------------------------------------------------------- grid
    @property
    def h_over_L(self) -> np.ndarray:
        """Grid values of h/L."""
        return self._axes[0].copy()

    @property
    def t_over_L(self) -> np.ndarray:
        """Grid values of t/L."""
        return self._axes[1].copy()

    @property
    def w_over_L(self) -> np.ndarray:
        """Grid values of w/L."""
        return self._axes[2].copy()

    @property
    def b_over_L(self) -> np.ndarray:
        """Grid values of b/L (one value for a map at a fixed b/L)."""
        if self.fixed_b_over_L is not None:
            return np.array([self.fixed_b_over_L])
        return self._axes[3].copy()

    @property
    def ranges(self) -> dict:
        """{"h_over_L": (min, max), "t_over_L": ..., "w_over_L": ...[, "b_over_L": ...]}: the
        grid's axes (b/L only when it is one)."""
        return {d: (float(a[0]), float(a[-1])) for d, a in zip(self.dims, self._axes)}

    @property
    def samples(self) -> int:
        """Number M of base-shape samples."""
        return int(self.dataset.sizes["sample"])

    @property
    def attrs(self) -> dict:
        return dict(self.dataset.attrs)

    def __repr__(self):
        r = ", ".join(f"{k} {lo:g}..{hi:g} ({a.size})" for (k, (lo, hi)), a
                      in zip(self.ranges.items(), self._axes))
        return f"DesignMap({self.path or '<in memory>'}: {r})"

    # ---------------------------------------------------------------- lookup
    def _b_query(self, b_over_L):
        """The b/L of a query: the map's own when None; on a fixed-b map it must equal it."""
        if b_over_L is None:
            return DEFAULT_B_OVER_L if self.fixed_b_over_L is None else self.fixed_b_over_L
        if self.fixed_b_over_L is None:
            return b_over_L
        b = _real_array(B_DIM, b_over_L)
        fixed = self.fixed_b_over_L
        bad = ~(np.abs(b - fixed) <= _B_TOL * max(1.0, abs(fixed)))
        if np.any(bad):
            raise MapDomainError(
                f"b_over_L = {float(b[bad].ravel()[0])!r} is outside the map's range: it was built "
                f"at the one value b_over_L = {fixed:g} (a map without a b/L axis, schema "
                f"{self.schema_version}); leave b_over_L out or give {fixed:g}, or use a map with a "
                f"b/L axis (`make maps`)" + (f" ({self.path})" if self.path else ""))
        return fixed

    def _points(self, h_over_L, t_over_L, w_over_L, b_over_L=None):
        """Broadcast, range-check and transform queries; returns (shape, (n, ndim) array)."""
        b_query = self._b_query(b_over_L)
        h, t, w, b = _broadcast(h_over_L=h_over_L, t_over_L=t_over_L, w_over_L=w_over_L,
                                b_over_L=b_query)
        for name, v, axis in zip(self.dims, (h, t, w, b), self._axes):
            lo, hi = axis[0], axis[-1]
            tol = _R_TOL * (hi - lo)
            bad = ~((v >= lo - tol) & (v <= hi + tol))  # NaN queries are out of range too
            if np.any(bad):
                raise MapDomainError(
                    f"{name} = {float(v[bad].ravel()[0])!r} is outside the map's range "
                    f"{lo:g} <= {name} <= {hi:g}" + (f" ({self.path})" if self.path else ""))
        q = [np.clip(v, a[0], a[-1]) for v, a in zip((h, t, w, b), self._axes)]
        cols = [q[0].ravel(), np.log(q[1].ravel()), np.log(q[2].ravel()), *(v.ravel() for v in q[3:])]
        return h.shape, np.column_stack(cols)

    def _stencil_status(self, xq) -> str:
        """Status names of the grid points around one query (for error messages)."""
        idx = []
        for c, q in zip(self._icoords, xq):
            i = int(np.clip(np.searchsorted(c, q, side="right") - 1, 0, c.size - 2))
            idx.append((i, i + 1))
        codes = {int(self._status[k]) for k in itertools.product(*idx)}
        return ", ".join(self.status_names[c] for c in sorted(codes))

    def _where_query(self, q) -> str:
        where = f"h/L={q[0]:.6g}, t/L={math.exp(q[1]):.6g}, w/L={math.exp(q[2]):.6g}"
        return where + (f", b/L={q[3]:.6g}" if len(q) > 3 else "")

    def _group(self, group, shape, x, allow_nan):
        names, rgi, bad_rgi, _ = self._interp[group]
        vals = rgi(x)
        wbad = bad_rgi(x)
        bad = wbad > _W_TOL
        with np.errstate(invalid="ignore", divide="ignore"):
            vals = vals / (1.0 - wbad)[:, None]  # renormalise over the valid stencil points
        vals[bad] = np.nan
        if np.any(bad) and not allow_nan:
            k = int(np.flatnonzero(bad)[0])
            q = x[k]
            raise MapDomainError(
                f"{', '.join(names)} not defined at {self._where_query(q)}: the interpolation "
                f"cell touches grid points that are "
                f"{self._stencil_status(q)} (only ok points count"
                + ("; F_cr and d_cr also use monostable ones" if group == "F" else "")
                + ("; the released state also needs self_standing = 1, a released unit that "
                   "is still bistable" if group == "rel" else "")
                + "); pass allow_nan=True to get NaN")
        out = {}
        for j, name in enumerate(names):
            v = np.exp(vals[:, j]) if name in _LOG_VARS else vals[:, j]
            out[name] = v.reshape(shape)
        return out

    @staticmethod
    def _scalar(v):
        return v[()] if isinstance(v, np.ndarray) and v.ndim == 0 else v

    def at(self, h_over_L, t_over_L, w_over_L, allow_nan: bool = False,
           state: str = "released", *, b_over_L=None) -> dict:
        """Interpolated values of every scalar variable at (h/L, t/L, w/L, b/L) (broadcast
        arrays; b_over_L None: 0 on a map with a b/L axis, the map's own on one without).

        Returns {name: value} for F_cr, d_cr, d_unstable, d_second, S, theta, theta_end,
        energy_barrier, energy_stored (floats, dimensionless, angles in degrees) and bistable,
        self_standing, bifurcation (int8: the common value of the grid points around the
        query, -1 if they differ). S, theta and theta_end are those of ``state``: "released"
        (default; defined where the released unit is still bistable) or "actuated". Raises
        MapDomainError outside the grid, or where a value is undefined (monostable/failed/not
        self-standing grid points around the query) unless allow_nan=True. A map with the unit
        metrics adds them (NaN where undefined, see the module docstring) and strain_where.
        """
        state = self._state(state)
        shape, x = self._points(h_over_L, t_over_L, w_over_L, b_over_L)
        out = {**self._group("F", shape, x, allow_nan), **self._group("bi", shape, x, allow_nan)}
        if state == "released":
            rel = self._group("rel", shape, x, allow_nan)
            for key, var in _STATE_VARS["released"].items():
                out[key] = rel[var]
        frac = self._flag_rgi(x)
        for j, name in enumerate(FLAG_VARS):
            f = frac[:, 3 * j:3 * j + 3]
            val = np.full(len(x), -1, dtype=np.int8)
            for k, v in enumerate((-1, 0, 1)):
                val[f[:, k] >= 1.0 - _W_TOL] = v
            out[name] = val.reshape(shape)
        for name in self.metrics:
            out[name] = self._group(name, shape, x, allow_nan=True)[name]
        for name, (words, rgi) in self._text_rgi.items():
            frac = rgi(x)
            text = np.full(len(x), "", dtype=object)
            for k, word in enumerate(words):
                text[frac[:, k] >= 1.0 - _W_TOL] = word
            out[name] = text.reshape(shape)
        names = (*self.SCALARS, *self.metrics, *self._text_rgi)
        return {name: self._scalar(out[name]) for name in names if name in out}

    def value(self, name: str, h_over_L, t_over_L, w_over_L, allow_nan: bool = False,
              state: str = "released", *, b_over_L=None):
        """One interpolated variable (see `at`); S, theta and theta_end of ``state``. The map's
        own names (S_released, theta_released, theta_end_released) are accepted too, and the
        unit metrics (`maps.schema.METRIC_VARS`; MapDomainError where undefined)."""
        names = (*self.SCALARS, *RELEASED_VARS, *METRIC_VARS)
        if name not in names:
            raise ValueError(f"name must be one of {names}, got {name!r}")
        state = self._state(state)
        if name in RELEASED_VARS:
            state = self._state("released")
        shape, x = self._points(h_over_L, t_over_L, w_over_L, b_over_L)
        if name in FLAG_VARS:
            return self.at(h_over_L, t_over_L, w_over_L, allow_nan=True, state="actuated",
                           b_over_L=b_over_L)[name]
        var = _STATE_VARS[state].get(name, name)
        if var not in self._group_of:
            raise MapDomainError(f"design map {self.path or '<in memory>'} (schema "
                                 f"{self.schema_version}) has no variable {var!r}; rebuild it")
        group = self._group_of[var]
        return self._scalar(self._group(group, shape, x, allow_nan)[var])

    def base_shape(self, h_over_L, t_over_L, w_over_L, allow_nan: bool = False,
                   state: str = "released", *, b_over_L=None) -> np.ndarray:
        """Base centreline in state (iii) (released by default, or ``state="actuated"``), per
        unit length: (M, 2) of (x, z) / L (or (..., M, 2) for array queries), starting at
        (0, 0) with the start tangent along +x."""
        state = self._state(state)
        shape, x = self._points(h_over_L, t_over_L, w_over_L, b_over_L)
        group, rgi = self._shape_rgi[state]
        _, _, bad_rgi, _ = self._interp[group]
        wbad = bad_rgi(x)
        bad = wbad > _W_TOL
        if np.any(bad) and not allow_nan:
            self._group(group, shape, x, allow_nan=False)  # raises with the standard message
        with np.errstate(invalid="ignore", divide="ignore"):
            out = rgi(x) / (1.0 - wbad)[:, None, None]
        out[bad] = np.nan
        return out.reshape(*shape, self.samples, 2)

    def force_newtons(self, h_over_L, t_over_L, w_over_L, E: float = 2.2e9, L: float = 0.1,
                      allow_nan: bool = False, *, b_over_L=None):
        """Critical force F_cr in N for Young's modulus E (Pa) and base length L (m):
        F_cr = F_norm E I_arch / L^2 with I_arch = w t^3 / 12."""
        for name, v, what in (("E", E, "Young's modulus, Pa"), ("L", L, "base length, m")):
            if (isinstance(v, (bool, np.bool_))
                    or not (isinstance(v, (int, float, np.floating, np.integer))
                            and np.isfinite(v) and v > 0)):
                raise ValueError(f"{name} must be a finite number > 0 ({what}), got {v!r}")
        f = self.value("F_cr", h_over_L, t_over_L, w_over_L, allow_nan=allow_nan, b_over_L=b_over_L)
        t = np.asarray(t_over_L, float) * L
        w = np.asarray(w_over_L, float) * L
        return self._scalar(np.asarray(f * E * (w * t**3 / 12.0) / L**2))

    # ---------------------------------------------------------------- along h
    def _theta_column(self, t_over_L, w_over_L, state="released", angle="theta", b_over_L=None):
        """``angle`` (theta or theta_end, deg) at every grid h/L for one (t, w, b), NaN where
        undefined."""
        t = float(self._one("t_over_L", t_over_L))
        w = float(self._one("w_over_L", w_over_L))
        b = None if b_over_L is None else float(self._one("b_over_L", b_over_L))
        h = self._axes[0]
        th = self.value(angle, h, np.full_like(h, t), np.full_like(h, w), allow_nan=True,
                        state=state, b_over_L=b)
        return h, np.asarray(th)

    def _runs(self, t_over_L, w_over_L, state="released", angle="theta", b_over_L=None):
        """Contiguous runs of grid h/L where the angle is defined: list of (i0, i1) inclusive."""
        h, th = self._theta_column(t_over_L, w_over_L, state, angle, b_over_L)
        ok = np.isfinite(th)
        runs, i = [], 0
        while i < ok.size:
            if ok[i]:
                j = i
                while j + 1 < ok.size and ok[j + 1]:
                    j += 1
                runs.append((i, j))
                i = j + 1
            else:
                i += 1
        return h, th, runs

    @staticmethod
    def _one(name, value) -> float:
        """One real number (see `_real_array`), or ValueError naming ``name``."""
        v = _real_array(name, value)
        if v.size != 1:
            raise ValueError(f"{name} ({_MEANING[name]}) must be one number here; got an array "
                             f"of shape {v.shape}")
        return float(v.reshape(-1)[0])

    def _where(self, t_over_L, w_over_L, state="released", b_over_L=None):
        b = "" if b_over_L is None else f", b/L={float(b_over_L):g}"
        return f"t/L={float(t_over_L):g}, w/L={float(w_over_L):g}{b} ({state} state)"

    @staticmethod
    def _check_angle(angle):
        if angle not in ("theta", "theta_end"):
            raise ValueError(f"angle must be 'theta' (total turning between the end tangents) or "
                             f"'theta_end' (end tangent to chord); got {angle!r}")
        return angle

    def bistable_boundary(self, t_over_L, w_over_L, state: str = "released", *,
                          b_over_L=None) -> float:
        """Smallest grid h/L from which S, theta, ... of ``state`` are defined at (t/L, w/L,
        b/L); the true boundary lies within one h/L grid step below it."""
        state = self._state(state)
        h, th, runs = self._runs(t_over_L, w_over_L, state, b_over_L=b_over_L)
        if not runs:
            raise MapDomainError(f"no bistable unit in the map at "
                                 f"{self._where(t_over_L, w_over_L, state, b_over_L)}")
        return float(h[runs[0][0]])

    def theta_range(self, t_over_L, w_over_L, state: str = "released",
                    angle: str = "theta", *, b_over_L=None) -> tuple[float, float]:
        """(min, max) of ``angle`` (theta, or theta_end) in degrees over the map's h/L range at
        (t/L, w/L). If failed grid points leave holes, some angles inside are not reachable
        (the inverse lookup says which)."""
        state = self._state(state)
        h, th, runs = self._runs(t_over_L, w_over_L, state, self._check_angle(angle), b_over_L)
        if not runs:
            raise MapDomainError(f"no bistable unit in the map at "
                                 f"{self._where(t_over_L, w_over_L, state, b_over_L)}")
        return float(np.nanmin(th)), float(np.nanmax(th))

    def h_over_L_for_theta_end(self, theta_end_deg, t_over_L, w_over_L, state: str = "released",
                               *, b_over_L=None):
        """h/L giving the end angle theta_end_deg (degrees, end tangent to chord; the paper's
        maps' convention, most likely) at (t/L, w/L, b/L). See `h_over_L_for_theta`."""
        return self.h_over_L_for_theta(theta_end_deg, t_over_L, w_over_L, state=state,
                                       angle="theta_end", b_over_L=b_over_L)

    def h_over_L_for_theta(self, theta_deg, t_over_L, w_over_L, state: str = "released",
                           angle: str = "theta", *, b_over_L=None):
        """h/L giving the signed angle theta_deg (degrees) at (t/L, w/L, b/L): a root of the
        interpolated theta(h/L) of ``state`` (``angle="theta_end"``: of theta_end). If it is not
        monotone, the smallest such h/L. Broadcasts; raises MapDomainError when the angle is
        outside the reachable range (which it states)."""
        from scipy.optimize import brentq

        state = self._state(state)
        angle = self._check_angle(angle)
        name = f"{angle}_deg"
        b_in = self._b_query(b_over_L)
        th_q, t_q, w_q, b_q = _broadcast(**{name: theta_deg, "t_over_L": t_over_L,
                                            "w_over_L": w_over_L, "b_over_L": b_in})
        out = np.empty(th_q.shape)
        for k in np.ndindex(th_q.shape):
            target, t, w, bq = float(th_q[k]), float(t_q[k]), float(w_q[k]), float(b_q[k])
            self._points(self._axes[0][0], t, w, bq)  # range check of t, w and b
            h, th, runs = self._runs(t, w, state, angle, bq)
            where = self._where(t, w, state, None if b_over_L is None else bq)
            if not runs:
                raise MapDomainError(f"no bistable unit in the map at {where}")
            if not np.isfinite(target):
                raise ValueError(f"{name} ({_MEANING[name]}) must be finite, got {target!r}")
            found = None
            for i0, i1 in runs:
                if i0 == i1:
                    if th[i0] == target:
                        found = h[i0]
                        break
                    continue
                for i in range(i0, i1):
                    a, b = th[i] - target, th[i + 1] - target
                    if a == 0:
                        found = h[i]
                    elif b == 0:
                        found = h[i + 1]
                    elif a * b < 0:
                        fn = lambda x: float(self.value(angle, x, t, w, state=state,  # noqa: E731
                                                        b_over_L=bq)) - target
                        found = brentq(fn, h[i], h[i + 1], xtol=1e-12, rtol=1e-12)
                    if found is not None:
                        break
                if found is not None:
                    break
            if found is None:
                spans = "; ".join(f"{np.nanmin(th[i0:i1 + 1]):.4g} to {np.nanmax(th[i0:i1 + 1]):.4g} deg "
                                  f"(h/L {h[i0]:g} to {h[i1]:g})" for i0, i1 in runs)
                raise MapDomainError(f"{name} out of reach: {angle} = {target:g} deg is outside "
                                     f"the range reachable at {where}: {spans}")
            out[k] = found
        return self._scalar(out)
