"""`DesignMap`: load a schema-1 design map and look values up by interpolation.

Interpolation is piecewise linear on the grid cell around the query (scipy
`RegularGridInterpolator`), in the coordinates (h/L, log t/L, log w/L), and of log(F_cr) for the
force (F_cr varies like a power of t and w, so that is nearly linear). Every variable has a
validity mask: S, theta, d_unstable, d_second, the energies and the base shape exist only at
bistable points (status ok); F_cr and d_cr also at monostable ones. A query whose cell gives
weight to an invalid grid point raises `MapDomainError` (or returns NaN with allow_nan=True):
NaN holes never leak into valid neighbours.
"""

from __future__ import annotations

import math
import warnings
from pathlib import Path

import numpy as np

from pipeline.schema import (
    BISTABLE_ONLY, FLAG_VARS, GRID_DIMS, REQUIRED_ATTRS, REQUIRED_VARS, SCHEMA_VERSION,
    STATUS_CODES,
)

DATA_DIR = Path(__file__).resolve().parent / "data"
DEFAULT_MAP = DATA_DIR / "default.nc"
CI_MAP = DATA_DIR / "ci.nc"

_F_VARS = ("F_cr", "d_cr")  # exist at bistable and monostable points
_LOG_VARS = ("F_cr",)  # interpolated as log(value)
_W_TOL = 1e-9  # a grid point with interpolation weight below this is not "touched"
_R_TOL = 1e-12  # relative tolerance on the grid bounds


class MapFileError(ValueError):
    """A map file that cannot be used: corrupt, not a design map, wrong schema version."""


class MapDomainError(ValueError):
    """A query outside the grid, or touching monostable/failed grid points."""


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
    if version != SCHEMA_VERSION:
        _fail(path, f"schema version {version} is not supported (this snapmorph reads {SCHEMA_VERSION})")
    missing = [v for v in REQUIRED_VARS if v not in ds.variables]
    if missing:
        _fail(path, f"missing variables {missing}")
    missing = [a for a in REQUIRED_ATTRS if a not in ds.attrs]
    if missing:
        _fail(path, f"missing global attributes {missing}")
    for name in REQUIRED_VARS:
        want = GRID_DIMS + (("sample", "xz") if name == "base_shape" else ())
        if ds[name].dims != want:
            _fail(path, f"variable {name} has dimensions {ds[name].dims}, expected {want}")
    for dim in GRID_DIMS:
        c = np.asarray(ds[dim].values, dtype=float)
        if c.size < 2 or not np.all(np.isfinite(c)) or np.any(np.diff(c) <= 0) or c[0] <= 0:
            _fail(path, f"coordinate {dim} must hold >= 2 positive, strictly increasing values")
    if ds.sizes["xz"] != 2:
        _fail(path, f"dimension xz has size {ds.sizes['xz']}, expected 2")
    if not np.issubdtype(ds["status"].dtype, np.integer):
        _fail(path, f"status has dtype {ds['status'].dtype}, expected an integer (no _FillValue)")
    status = ds["status"].values
    unknown = set(np.unique(status).tolist()) - set(STATUS_CODES)
    if unknown:
        _fail(path, f"status holds unknown codes {sorted(unknown)}")
    pending = int(np.count_nonzero(status < 0))
    if pending:
        _fail(path, f"{pending} points are still pending: a partial build, not a finished map")


class DesignMap:
    """An interpolated design map. Use `DesignMap.load(path=None)`.

    Every length is over the base length L; `F_cr` is F_cr L^2 / (E I_arch) with
    I_arch = w t^3 / 12; `theta` is in degrees.
    """

    #: variables returned by `at`
    SCALARS = ("F_cr", "d_cr", *BISTABLE_ONLY, *FLAG_VARS)

    def __init__(self, ds, path=None):
        from scipy.interpolate import RegularGridInterpolator as RGI

        _validate(ds, path)
        self.dataset = ds
        self.path = Path(path) if path is not None else None
        self._axes = tuple(np.asarray(ds[d].values, dtype=float) for d in GRID_DIMS)
        # interpolation coordinates: (h, log t, log w)
        self._icoords = (self._axes[0], np.log(self._axes[1]), np.log(self._axes[2]))
        self._status = np.asarray(ds["status"].values)
        ok = self._status == 0
        groups = {"F": list(_F_VARS), "bi": list(BISTABLE_ONLY)}
        self._interp = {}
        for group, names in groups.items():
            vals = []
            valid = ok | (self._status == 1) if group == "F" else ok.copy()
            for name in names:
                v = np.asarray(ds[name].values, dtype=float)
                if name in _LOG_VARS:
                    with np.errstate(divide="ignore", invalid="ignore"):
                        v = np.log(v)
                valid &= np.isfinite(v)
                vals.append(v)
            if group == "bi":
                shape = np.asarray(ds["base_shape"].values, dtype=float)
                valid &= np.all(np.isfinite(shape), axis=(-2, -1))
            values = np.where(valid[..., None], np.stack(vals, axis=-1), 0.0)
            self._interp[group] = (
                names,
                RGI(self._icoords, values, method="linear", bounds_error=False, fill_value=np.nan),
                RGI(self._icoords, (~valid).astype(float), method="linear", bounds_error=False,
                    fill_value=np.nan),
                valid,
            )
        valid_bi = self._interp["bi"][3]
        shape = np.where(valid_bi[..., None, None], np.asarray(ds["base_shape"].values, float), 0.0)
        self._shape_rgi = RGI(self._icoords, shape, method="linear", bounds_error=False, fill_value=np.nan)
        # flag consensus: the fraction of stencil weight on each value -1, 0, 1
        ind = [(np.asarray(ds[f].values) == v) for f in FLAG_VARS for v in (-1, 0, 1)]
        self._flag_rgi = RGI(self._icoords, np.stack(ind, axis=-1).astype(float), method="linear",
                             bounds_error=False, fill_value=np.nan)

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
    def ranges(self) -> dict:
        """{"h_over_L": (min, max), "t_over_L": ..., "w_over_L": ...}."""
        return {d: (float(a[0]), float(a[-1])) for d, a in zip(GRID_DIMS, self._axes)}

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
    def _points(self, h_over_L, t_over_L, w_over_L):
        """Broadcast, range-check and transform queries; returns (shape, (n, 3) array)."""
        h, t, w = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (h_over_L, t_over_L, w_over_L)))
        for name, v, axis in zip(GRID_DIMS, (h, t, w), self._axes):
            lo, hi = axis[0], axis[-1]
            tol = _R_TOL * (hi - lo)
            bad = ~((v >= lo - tol) & (v <= hi + tol))  # NaN queries are out of range too
            if np.any(bad):
                raise MapDomainError(
                    f"{name} = {float(v[bad].ravel()[0])!r} is outside the map's range "
                    f"{lo:g} <= {name} <= {hi:g}" + (f" ({self.path})" if self.path else ""))
        h = np.clip(h, self._axes[0][0], self._axes[0][-1])
        t = np.clip(t, self._axes[1][0], self._axes[1][-1])
        w = np.clip(w, self._axes[2][0], self._axes[2][-1])
        x = np.column_stack([h.ravel(), np.log(t.ravel()), np.log(w.ravel())])
        return h.shape, x

    def _stencil_status(self, xq) -> str:
        """Status names of the grid points around one query (for error messages)."""
        idx = []
        for c, q in zip(self._icoords, xq):
            i = int(np.clip(np.searchsorted(c, q, side="right") - 1, 0, c.size - 2))
            idx.append((i, i + 1))
        codes = {int(self._status[a, b, c]) for a in idx[0] for b in idx[1] for c in idx[2]}
        return ", ".join(STATUS_CODES[c] for c in sorted(codes))

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
                f"{', '.join(names)} not defined at h/L={q[0]:.6g}, t/L={math.exp(q[1]):.6g}, "
                f"w/L={math.exp(q[2]):.6g}: the interpolation cell touches grid points that are "
                f"{self._stencil_status(q)} (only ok points count"
                + ("; F_cr and d_cr also use monostable ones" if group == "F" else "")
                + "); pass allow_nan=True to get NaN")
        out = {}
        for j, name in enumerate(names):
            v = np.exp(vals[:, j]) if name in _LOG_VARS else vals[:, j]
            out[name] = v.reshape(shape)
        return out

    @staticmethod
    def _scalar(v):
        return v[()] if isinstance(v, np.ndarray) and v.ndim == 0 else v

    def at(self, h_over_L, t_over_L, w_over_L, allow_nan: bool = False) -> dict:
        """Interpolated values of every scalar variable at (h/L, t/L, w/L) (broadcast arrays).

        Returns {name: value} for F_cr, d_cr, d_unstable, d_second, S, theta, energy_barrier,
        energy_stored (floats, dimensionless, theta in degrees) and bistable, self_standing,
        bifurcation (int8: the common value of the grid points around the query, -1 if they
        differ). Raises MapDomainError outside the grid, or where a value is undefined
        (monostable/failed grid points around the query) unless allow_nan=True.
        """
        shape, x = self._points(h_over_L, t_over_L, w_over_L)
        out = {**self._group("F", shape, x, allow_nan), **self._group("bi", shape, x, allow_nan)}
        frac = self._flag_rgi(x)
        for j, name in enumerate(FLAG_VARS):
            f = frac[:, 3 * j:3 * j + 3]
            val = np.full(len(x), -1, dtype=np.int8)
            for k, v in enumerate((-1, 0, 1)):
                val[f[:, k] >= 1.0 - _W_TOL] = v
            out[name] = val.reshape(shape)
        return {name: self._scalar(out[name]) for name in self.SCALARS}

    def value(self, name: str, h_over_L, t_over_L, w_over_L, allow_nan: bool = False):
        """One interpolated variable (see `at`)."""
        if name not in self.SCALARS:
            raise ValueError(f"name must be one of {self.SCALARS}, got {name!r}")
        shape, x = self._points(h_over_L, t_over_L, w_over_L)
        if name in FLAG_VARS:
            return self.at(h_over_L, t_over_L, w_over_L, allow_nan=True)[name]
        group = "F" if name in _F_VARS else "bi"
        return self._scalar(self._group(group, shape, x, allow_nan)[name])

    def base_shape(self, h_over_L, t_over_L, w_over_L, allow_nan: bool = False) -> np.ndarray:
        """Base centreline in state (iii), per unit length: (M, 2) of (x, z) / L (or (..., M, 2)
        for array queries), starting at (0, 0) with the start tangent along +x."""
        shape, x = self._points(h_over_L, t_over_L, w_over_L)
        _, _, bad_rgi, _ = self._interp["bi"]
        wbad = bad_rgi(x)
        bad = wbad > _W_TOL
        if np.any(bad) and not allow_nan:
            self._group("bi", shape, x, allow_nan=False)  # raises with the standard message
        with np.errstate(invalid="ignore", divide="ignore"):
            out = self._shape_rgi(x) / (1.0 - wbad)[:, None, None]
        out[bad] = np.nan
        return out.reshape(*shape, self.samples, 2)

    def force_newtons(self, h_over_L, t_over_L, w_over_L, E: float = 2.2e9, L: float = 0.1,
                      allow_nan: bool = False):
        """Critical force F_cr in N for Young's modulus E (Pa) and base length L (m):
        F_cr = F_norm E I_arch / L^2 with I_arch = w t^3 / 12."""
        for name, v in (("E", E), ("L", L)):
            if not (isinstance(v, (int, float, np.floating, np.integer)) and np.isfinite(v) and v > 0):
                raise ValueError(f"{name} must be a finite number > 0, got {v!r}")
        f = self.value("F_cr", h_over_L, t_over_L, w_over_L, allow_nan=allow_nan)
        t = np.asarray(t_over_L, float) * L
        w = np.asarray(w_over_L, float) * L
        return self._scalar(np.asarray(f * E * (w * t**3 / 12.0) / L**2))

    # ---------------------------------------------------------------- along h
    def _theta_column(self, t_over_L, w_over_L):
        """theta (deg) at every grid h/L for one (t, w), NaN where undefined."""
        t = float(t_over_L)
        w = float(w_over_L)
        h = self._axes[0]
        th = self.value("theta", h, np.full_like(h, t), np.full_like(h, w), allow_nan=True)
        return h, np.asarray(th)

    def _runs(self, t_over_L, w_over_L):
        """Contiguous runs of grid h/L where theta is defined: list of (i0, i1) inclusive."""
        h, th = self._theta_column(t_over_L, w_over_L)
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

    def _where(self, t_over_L, w_over_L):
        return f"t/L={float(t_over_L):g}, w/L={float(w_over_L):g}"

    def bistable_boundary(self, t_over_L, w_over_L) -> float:
        """Smallest grid h/L from which S, theta, ... are defined at (t/L, w/L); the true
        bistability boundary lies within one h/L grid step below it."""
        h, th, runs = self._runs(t_over_L, w_over_L)
        if not runs:
            raise MapDomainError(f"no bistable unit in the map at {self._where(t_over_L, w_over_L)}")
        return float(h[runs[0][0]])

    def theta_range(self, t_over_L, w_over_L) -> tuple[float, float]:
        """(min, max) theta in degrees over the map's h/L range at (t/L, w/L). If failed grid
        points leave holes, some angles inside are not reachable (the inverse lookup says which)."""
        h, th, runs = self._runs(t_over_L, w_over_L)
        if not runs:
            raise MapDomainError(f"no bistable unit in the map at {self._where(t_over_L, w_over_L)}")
        return float(np.nanmin(th)), float(np.nanmax(th))

    def h_over_L_for_theta(self, theta_deg, t_over_L, w_over_L):
        """h/L giving the signed angle theta_deg (degrees) at (t/L, w/L): a root of the
        interpolated theta(h/L). If theta is not monotone, the smallest such h/L. Broadcasts;
        raises MapDomainError when theta is outside the reachable range (which it states)."""
        from scipy.optimize import brentq

        th_q, t_q, w_q = np.broadcast_arrays(*(np.asarray(v, float) for v in (theta_deg, t_over_L, w_over_L)))
        out = np.empty(th_q.shape)
        for k in np.ndindex(th_q.shape):
            target, t, w = float(th_q[k]), float(t_q[k]), float(w_q[k])
            self._points(self._axes[0][0], t, w)  # range check of t and w
            h, th, runs = self._runs(t, w)
            where = self._where(t, w)
            if not runs:
                raise MapDomainError(f"no bistable unit in the map at {where}")
            if not np.isfinite(target):
                raise ValueError(f"theta_deg must be finite, got {target!r}")
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
                        fn = lambda x: float(self.value("theta", x, t, w)) - target  # noqa: E731
                        found = brentq(fn, h[i], h[i + 1], xtol=1e-12, rtol=1e-12)
                    if found is not None:
                        break
                if found is not None:
                    break
            if found is None:
                spans = "; ".join(f"{np.nanmin(th[i0:i1 + 1]):.4g} to {np.nanmax(th[i0:i1 + 1]):.4g} deg "
                                  f"(h/L {h[i0]:g} to {h[i1]:g})" for i0, i1 in runs)
                raise MapDomainError(f"theta_deg = {target:g} is outside the range reachable at {where}: {spans}")
            out[k] = found
        return self._scalar(out)
