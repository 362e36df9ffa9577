"""Fabrication tolerance: Monte Carlo of hand-made units through the design map.

    from snapmorph.design import tolerance   # this module's `tolerance`
    r = tolerance(units, sigma={"h": 0.5e-3, "L": 0.3e-3, "t": 0.02e-3}, n=1000, seed=0)
    r.envelope_contains(xy), r.free_end_summary(), r.p_bistable

Every arched unit's L, h, t (and w when given in ``sigma``) are drawn independently from
normal distributions about their nominal values (standard deviations in m); b follows L (each
unit keeps its nominal b/L). On a map with a b/L axis every unit is looked up at its own b/L
(units.csv's b_mm); a map at one b/L takes only units at that b/L. Each sample's all-snapped array is built by forward kinematics from the map with
vectorised lookups (one interpolation call per quantity for all samples and units), in the
released state by default. Spacers change length only (sigma "L").

The envelope: each unit's piece is resampled at ``stations`` points uniform in its own arc
length; at each station the samples' points are expressed in the nominal curve's frame there
(tangential and normal offsets) and the envelope is the range [min, max] of the normal offset
over the samples whose units are all bistable and the nominal itself (a sample without
errors) (`lo`, `hi`), widened where needed to a half-width of at least ``floor``
(`ENVELOPE_FLOOR_MM`, 0.05 mm): a band along the nominal curve (`band`). Near the clamp every sample starts at the same
point, so without the floor the band is a few micrometres wide there and a curve that lies
inside it as drawn, a whole-array simulation agreeing with the map to far better than the
fabrication errors, would be counted outside. A curve lies inside when the normal offset of
each of its station points lies in that range (`envelope_contains`, optionally widened by a
`slack`: the accuracy of the model that computed the curve; the tangential range is kept in
`lo`/`hi` too). Its coverage of fresh samples is measured on a second, independent Monte
Carlo set (`held_out_coverage`).

SI units (m, degrees for angles).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from snapmorph.design.units import Unit

SIGMA_DEFAULT = {"h": 0.5e-3, "L": 0.3e-3, "t": 0.02e-3}
SIGMA_KEYS = ("L", "h", "t", "w")
STATIONS = 33
#: the envelope's half-width is at least this (mm): far below fabrication errors and what a
#: plot of the band shows, far above the whole-array simulation's difference from the map
#: next to the clamp (micrometres)
ENVELOPE_FLOOR_MM = 0.05


@dataclass
class ToleranceResult:
    """A Monte Carlo of fabrication errors (see the module docstring). Lengths in m.

    nominal: (K, 2) all-snapped base of the nominal units (FK from the map);
    stations: (n_units, m, 2) the nominal's station points; frames: (n_units, m, 2, 2) unit
    tangent and normal there; lo, hi: (n_units, m, 2) the range of the (tangential, normal)
    offsets over the samples and the nominal (`band()`: the normal band as tested and drawn); samples: (n_ok, n_units, m, 2) every usable sample's station points;
    free_end: (n_ok, 2) end points; end_angle_deg: (n_ok,) end-tangent directions;
    p_bistable: (n_units,) probability that each unit is bistable (released: still snapped
    without its actuator); n, n_ok: samples drawn and usable (every unit bistable, in the map);
    outside_map: samples with a unit outside the map's range; held_out_coverage: fraction of
    a second, independent set of n samples inside the envelope; time_s: wall time of the
    Monte Carlo (s); floor: the smallest half-width of the normal band (m)."""

    units: list
    sigma: dict
    state: str
    nominal: np.ndarray
    stations: np.ndarray
    frames: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    samples: np.ndarray
    free_end: np.ndarray
    end_angle_deg: np.ndarray
    nominal_end_angle_deg: float
    p_bistable: np.ndarray
    n: int
    n_ok: int
    outside_map: int
    held_out_coverage: float = math.nan
    time_s: float = math.nan
    floor: float = ENVELOPE_FLOOR_MM * 1e-3
    extra: dict = field(default_factory=dict)

    # --------------------------------------------------------------------- queries
    def offsets(self, pts) -> np.ndarray:
        """(..., n_units, m, 2) station points -> (tangential, normal) offsets from the nominal."""
        d = np.asarray(pts, float) - self.stations
        return np.einsum("...uid,uikd->...uik", d, self.frames)

    def envelope_contains(self, curve, slack=0.0) -> bool:
        """Is the base ``curve`` ((K, 2) m, an all-snapped array from (0, 0) heading +x, unit
        ends where forward kinematics puts them) inside the envelope at every station? `slack`
        (m, a number or (n_units, m)): the band widened by that much on both sides."""
        return bool(np.all(self.inside(curve, slack)))

    def inside(self, curve, slack=0.0) -> np.ndarray:
        """(n_units, m) bool: which station points of ``curve`` are inside the envelope
        (widened by `slack`, m, on both sides).

        The curve is cut into units by arc length in proportion to the nominal units' base
        lengths (hand-made units differ; at 0.3 mm in L the cut moves by far less than the
        envelope's width)."""
        lo, hi = self.band()
        off = self.normal_offsets(curve)
        return (off >= lo - slack) & (off <= hi + slack)

    def band(self) -> tuple:
        """(lo, hi), each (n_units, m): the envelope's normal band (m), the samples' range
        (`lo`, `hi`) widened about its middle to a half-width of at least `floor`."""
        mid = (self.lo[..., 1] + self.hi[..., 1]) / 2
        half = np.maximum((self.hi[..., 1] - self.lo[..., 1]) / 2, self.floor)
        return mid - half, mid + half

    def normal_offsets(self, curve) -> np.ndarray:
        """(n_units, m) normal offsets (m) of a base curve's station points from the nominal
        (cut into units as `inside` cuts it)."""
        pts = _stations_of_curve(np.asarray(curve, float), [u.L for u in self.units],
                                 self.stations.shape[1])
        return self.offsets(pts)[..., 1]

    def free_end_summary(self) -> dict:
        """Scatter of the free end: standard deviations (mm, degrees) and the 95th percentile
        distance from the nominal end (mm)."""
        d = self.free_end - self.nominal[-1]
        r = np.hypot(d[:, 0], d[:, 1])
        return {
            "std_x_mm": float(np.std(self.free_end[:, 0]) * 1e3),
            "std_y_mm": float(np.std(self.free_end[:, 1]) * 1e3),
            "r95_mm": float(np.percentile(r, 95) * 1e3),
            "max_mm": float(r.max() * 1e3),
            "std_angle_deg": float(np.std(self.end_angle_deg)),
            "angle_range_deg": (float(self.end_angle_deg.min()), float(self.end_angle_deg.max())),
        }

    def envelope_polygon(self) -> np.ndarray:
        """(P, 2) closed outline of the envelope (m): the normal bounds along the stations."""
        lo, hi = self.band()
        lo_pts = self.stations + lo[..., None] * self.frames[..., 1, :]
        hi_pts = self.stations + hi[..., None] * self.frames[..., 1, :]
        lo_pts = lo_pts.reshape(-1, 2)
        hi_pts = hi_pts.reshape(-1, 2)
        return np.vstack([lo_pts, hi_pts[::-1], lo_pts[:1]])

    def summary(self) -> str:
        """A few lines for the command line."""
        f = self.free_end_summary()
        lo, hi = self.band()
        lines = [f"{self.n} samples ({self.n_ok} usable, {self.outside_map} outside the map), "
                 f"{self.state} state, sigma " + ", ".join(f"{k} {v * 1e3:g} mm"
                                                          for k, v in self.sigma.items()),
                 f"free end: std x {f['std_x_mm']:.3g} mm, y {f['std_y_mm']:.3g} mm, "
                 f"95 % within {f['r95_mm']:.3g} mm of nominal (max {f['max_mm']:.3g} mm); "
                 f"end angle std {f['std_angle_deg']:.3g} deg",
                 "P(bistable) per unit: " + ", ".join(
                     f"{i + 1}: {p:.3f}" for i, p in enumerate(self.p_bistable)),
                 f"envelope half-width: largest {np.max(hi - lo) * 500:.3g} mm, smallest "
                 f"{np.min(hi - lo) * 500:.3g} mm (its floor)"]
        if math.isfinite(self.held_out_coverage):
            lines.append(f"held-out coverage: {self.held_out_coverage * 100:.1f} % of "
                         f"{self.n} independent samples inside the envelope")
        lines.append(f"time {self.time_s:.3g} s")
        return "\n".join(lines)


# ------------------------------------------------------------------------- the Monte Carlo
def check_sigma(sigma) -> dict:
    """``sigma`` as {name: standard deviation (m)} over L, h, t, w; ValueError otherwise."""
    if sigma is None:
        return dict(SIGMA_DEFAULT)
    if not isinstance(sigma, dict):
        raise ValueError(f"sigma must be a dict of standard deviations in m over "
                         f"{', '.join(SIGMA_KEYS)}; got {type(sigma).__name__}")
    out = {}
    for k, v in sigma.items():
        if k not in SIGMA_KEYS:
            raise ValueError(f"sigma keys must be among {', '.join(SIGMA_KEYS)}; got {k!r}")
        if isinstance(v, (bool, str, complex)) or v is None:
            raise ValueError(f"sigma[{k!r}] (standard deviation of {k}, m) must be a real number "
                             f">= 0; got {v!r}")
        try:
            v = float(v)
        except (TypeError, ValueError):
            raise ValueError(f"sigma[{k!r}] (standard deviation of {k}, m) must be a real number "
                             f">= 0; got {v!r}") from None
        if not (math.isfinite(v) and 0 <= v <= 0.01):
            raise ValueError(f"sigma[{k!r}] (standard deviation of {k}, m) must be in [0, 0.01] m; "
                             f"got {v!r}")
        out[k] = v
    return out


def _check_units(units) -> list:
    units = list(units) if not isinstance(units, Unit) else [units]
    if not units:
        raise ValueError("units must list at least one design.Unit")
    for i, u in enumerate(units):
        if not isinstance(u, Unit):
            raise ValueError(f"units[{i}] must be a design.Unit; got {type(u).__name__}")
    if all(u.is_spacer for u in units):
        raise ValueError("units must hold at least one arched unit")
    return units


def _draw(units, sigma, n, rng):
    """(n, n_units) arrays of L, h, t, w: nominal + normal errors (spacers: L only)."""
    nominal = {k: np.array([getattr(u, k) for u in units], float) for k in SIGMA_KEYS}
    out = {}
    arched = np.array([not u.is_spacer for u in units])
    for k in SIGMA_KEYS:  # fixed order: the same seed gives the same draws
        noise = rng.standard_normal((n, len(units))) * sigma.get(k, 0.0)
        if k != "L":
            noise[:, ~arched] = 0.0
        out[k] = nominal[k][None, :] + noise
    return out


def _b_over_L(dm, units):
    """(n_units,) b/L to look each unit up at on a map with a b/L axis (b follows L: the
    nominal b/L of every sample), or None on a map at one b/L, which every arched unit must
    have. ValueError naming b and the map's b range otherwise."""
    if "b_over_L" not in tuple(getattr(dm, "dims", ())):
        fixed = getattr(dm, "fixed_b_over_L", None)
        fixed = float(dm.attrs.get("b_over_L", 0.0) if fixed is None else fixed)
        for i, u in enumerate(units):
            if not u.is_spacer and abs(u.b / u.L - fixed) > 1e-6:
                raise ValueError(
                    f"unit {i + 1} has b = {u.b * 1e3:.4g} mm (b/L = {u.b / u.L:.4g}), but the "
                    f"design map has no b/L axis: it was built at the one b/L = {fixed:.4g} "
                    f"(b = {fixed * u.L * 1e3:.4g} mm for this unit); use a map with a b/L axis "
                    f"(the default map) for other b")
        return None
    lo, hi = dm.ranges["b_over_L"]
    tol = 1e-9 * (hi - lo)
    out = np.zeros(len(units))
    for i, u in enumerate(units):
        if u.is_spacer:
            continue
        bL = u.b / u.L
        if not lo - tol <= bL <= hi + tol:
            raise ValueError(
                f"unit {i + 1} has b = {u.b * 1e3:.4g} mm (b/L = {bL:.4g}), outside the design "
                f"map's b range: b/L in [{lo:g}, {hi:g}], b in [{lo * u.L * 1e3:.4g}, "
                f"{hi * u.L * 1e3:.4g}] mm at its L = {u.L * 1e3:.4g} mm")
        out[i] = min(max(bL, lo), hi)
    return out


def _fk_samples(dm, units, draws, state, stations, b_over_L=None):
    """Forward kinematics of every sample: (station points (n, u, m, 2), ends (n, 2), end
    angles (n,) rad, bistable (n, u) bool, inside map (n,) bool). ``b_over_L``: None (the
    map's one b/L) or (n_units,) each unit's b/L on a map with a b/L axis."""
    from snapmorph.design.shapes import conform  # noqa: F401  (the same similarity, vectorised below)

    L, h, t, w = draws["L"], draws["h"], draws["t"], draws["w"]
    n, nu = L.shape
    arched = np.array([not u.is_spacer for u in units])
    side = np.array([u.side if not u.is_spacer else 0 for u in units], float)
    hL, tL, wL = h / L, t / L, w / L
    inside = np.ones(n, bool)
    lo_hi = dm.ranges
    for name, v in (("h_over_L", hL), ("t_over_L", tL), ("w_over_L", wL)):
        lo, hi = lo_hi[name]
        inside &= np.all(((v >= lo) & (v <= hi)) | ~arched[None, :], axis=1)
    idx = np.flatnonzero(inside)
    m = stations
    pts = np.full((n, nu, m, 2), np.nan)
    theta = np.zeros((n, nu))
    bist = np.zeros((n, nu), bool)
    bist[:, ~arched] = True
    ja = np.flatnonzero(arched)
    if idx.size:
        q = np.ix_(idx, ja)
        kw = {} if b_over_L is None else {
            "b_over_L": np.broadcast_to(np.asarray(b_over_L, float)[ja], hL[q].shape)}
        vals = dm.at(hL[q], tL[q], wL[q], allow_nan=True, state=state, **kw)
        th, S = np.asarray(vals["theta"], float), np.asarray(vals["S"], float)
        shp = np.asarray(dm.base_shape(hL[q], tL[q], wL[q], allow_nan=True, state=state, **kw),
                         float)
        ok = np.isfinite(th) & np.isfinite(S) & np.all(np.isfinite(shp), axis=(-2, -1))
        bist[q] = ok
        # conform each shape to its (S, theta) (as design.shapes.conform), scale by L
        z = shp[..., 0] + 1j * shp[..., 1]
        z = z - z[..., :1]
        want = S * np.exp(0.5j * np.radians(th))
        with np.errstate(invalid="ignore", divide="ignore"):
            z = z * (want / z[..., -1])[..., None] * L[q][..., None]
        z = z.real + 1j * (z.imag * side[ja][None, :, None])
        # resample at m points uniform in arc length
        seg = np.abs(np.diff(z, axis=-1))
        s = np.concatenate([np.zeros(seg.shape[:-1] + (1,)), np.cumsum(seg, axis=-1)], axis=-1)
        frac = np.linspace(0.0, 1.0, m)
        res = np.empty(z.shape[:-1] + (m,), complex)
        for a in range(z.shape[0]):
            for b in range(z.shape[1]):
                if not ok[a, b]:
                    res[a, b] = np.nan
                    continue
                sq = frac * s[a, b, -1]
                res[a, b] = (np.interp(sq, s[a, b], z[a, b].real)
                             + 1j * np.interp(sq, s[a, b], z[a, b].imag))
        local = np.full((n, nu, m), np.nan, complex)
        local[q] = res
        theta[q] = np.where(ok, side[ja][None, :] * np.radians(th), np.nan)
    else:
        local = np.full((n, nu, m), np.nan, complex)
    # straight pieces: unsnapped arched units never occur (all snapped); spacers
    for j in np.flatnonzero(~arched):
        local[:, j] = L[:, j:j + 1] * np.linspace(0.0, 1.0, m)[None, :]
    # place end to end
    pos = np.zeros(n, complex)
    ang = np.zeros(n)
    for j in range(nu):
        piece = local[:, j] * np.exp(1j * ang)[:, None] + pos[:, None]
        pts[:, j, :, 0], pts[:, j, :, 1] = piece.real, piece.imag
        pos = piece[:, -1]
        ang = ang + theta[:, j]
    ends = np.stack([pos.real, pos.imag], axis=-1)
    return pts, ends, ang, bist, inside


def _frames(stations):
    """Unit tangents and normals (n_units, m, 2, 2) of the nominal curve at its stations."""
    flat = stations.reshape(-1, 2)
    tan = np.gradient(flat, axis=0)
    # a station shared by two units (a joint) sits twice in `flat`: the gradient there
    # would be zero, so use the neighbours
    bad = np.hypot(tan[:, 0], tan[:, 1]) < 1e-15
    for i in np.flatnonzero(bad):
        j0, j1 = max(i - 1, 0), min(i + 1, len(flat) - 1)
        tan[i] = flat[j1] - flat[j0]
    tan /= np.hypot(tan[:, 0], tan[:, 1])[:, None]
    nor = np.stack([-tan[:, 1], tan[:, 0]], axis=-1)
    return np.stack([tan, nor], axis=-2).reshape(*stations.shape[:2], 2, 2)


def _stations_of_curve(curve, lengths, m):
    """(n_units, m, 2) points of a polyline cut into pieces by arc length in proportion to
    ``lengths``, each resampled at m points uniform in its arc length."""
    seg = np.hypot(*np.diff(curve, axis=0).T)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    cuts = np.concatenate([[0.0], np.cumsum(lengths)]) / np.sum(lengths) * s[-1]
    out = np.empty((len(lengths), m, 2))
    for j in range(len(lengths)):
        sq = np.linspace(cuts[j], cuts[j + 1], m)
        out[j, :, 0] = np.interp(sq, s, curve[:, 0])
        out[j, :, 1] = np.interp(sq, s, curve[:, 1])
    return out


def tolerance(units, sigma=None, n: int = 1000, seed: int = 0, design_map=None,
              state: str = "released", stations: int = STATIONS,
              held_out: bool = True, floor: float = ENVELOPE_FLOOR_MM * 1e-3
              ) -> ToleranceResult:
    """Monte Carlo of fabrication errors of ``units`` (design.Unit, SI) through the map.

    ``sigma``: standard deviations in m by dimension (keys L, h, t, w; default
    {"h": 0.5e-3, "L": 0.3e-3, "t": 0.02e-3}); ``n``: samples (>= 10); ``seed``: the random
    generator's seed (identical inputs give identical results); ``design_map``: a
    `maps.DesignMap` (default map; each unit is looked up at its own b/L on a map with a b/L
    axis, ValueError naming b and the map's range when a unit's b/L is outside it or, on a map
    at one b/L, is not that one); ``state``: "released" (default) or "actuated";
    ``stations``: envelope points per unit; ``held_out``: also measure the envelope's
    coverage of a second, independent set of n samples (`held_out_coverage`); ``floor``: the
    smallest half-width of the envelope's normal band (m, default `ENVELOPE_FLOOR_MM`)."""
    from snapmorph.design.lookup import check_state, load_map

    units = _check_units(units)
    sigma = check_sigma(sigma)
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or not 10 <= n <= 10**6:
        raise ValueError(f"n (number of samples) must be an integer in [10, 1000000]; got {n!r}")
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ValueError(f"seed must be an integer >= 0; got {seed!r}")
    if isinstance(stations, bool) or not isinstance(stations, (int, np.integer)) or \
            not 3 <= stations <= 1000:
        raise ValueError(f"stations (envelope points per unit) must be an integer in [3, 1000]; "
                         f"got {stations!r}")
    state = check_state(state)
    if isinstance(floor, bool) or not isinstance(floor, (int, float, np.floating)) or \
            not (math.isfinite(floor) and 0 <= floor <= 0.01):
        raise ValueError(f"floor (smallest envelope half-width, m) must be in [0, 0.01] m; "
                         f"got {floor!r}")
    dm = design_map if design_map is not None else load_map(None)
    bL = _b_over_L(dm, units)
    t0 = time.perf_counter()
    rng = np.random.default_rng(int(seed))
    nominal_draw = {k: np.array([[getattr(u, k) for u in units]], float) for k in SIGMA_KEYS}
    nom_pts, nom_end, nom_ang, nom_ok, nom_in = _fk_samples(dm, units, nominal_draw, state,
                                                            stations, bL)
    if not (nom_in[0] and np.all(nom_ok[0])):
        bad = [i + 1 for i in range(len(units)) if not nom_ok[0, i]]
        raise ValueError("the nominal units are not all bistable in the map "
                         f"({state} state)" + (f": units {bad}" if bad else ": outside its range"))
    draws = _draw(units, sigma, int(n), rng)
    pts, ends, ang, bist, inside = _fk_samples(dm, units, draws, state, stations, bL)
    usable = inside & np.all(bist, axis=1)
    p_bistable = np.where(inside[:, None], bist, False).sum(axis=0) / max(int(inside.sum()), 1)
    stations_nom = nom_pts[0]
    frames = _frames(stations_nom)
    res = ToleranceResult(units=units, sigma=sigma, state=state,
                          nominal=_polyline(stations_nom), stations=stations_nom, frames=frames,
                          lo=np.zeros_like(stations_nom), hi=np.zeros_like(stations_nom),
                          samples=pts[usable], free_end=ends[usable],
                          end_angle_deg=np.degrees(ang[usable]),
                          nominal_end_angle_deg=float(np.degrees(nom_ang[0])),
                          p_bistable=p_bistable, n=int(n), n_ok=int(usable.sum()),
                          outside_map=int((~inside).sum()))
    if res.n_ok == 0:
        raise ValueError("no sample has every unit bistable in the map: the tolerances are too "
                         "wide for this design")
    off = res.offsets(res.samples)
    res.lo, res.hi = np.minimum(off.min(axis=0), 0.0), np.maximum(off.max(axis=0), 0.0)
    res.floor = float(floor)
    res.time_s = time.perf_counter() - t0
    if held_out:
        d2 = _draw(units, sigma, int(n), rng)
        p2, _, _, b2, in2 = _fk_samples(dm, units, d2, state, stations, bL)
        ok2 = in2 & np.all(b2, axis=1)
        o2 = res.offsets(p2[ok2])[..., 1]
        lo, hi = res.band()
        within = np.all((o2 >= lo) & (o2 <= hi), axis=(-2, -1))
        res.held_out_coverage = float(np.mean(within)) if within.size else math.nan
    return res


def perturbed_units(units, sigma=None, k: int = 50, seed: int = 1) -> list:
    """``k`` independently perturbed copies of ``units`` (lists of design.Unit), drawn as the
    Monte Carlo draws them (b follows L at the units' b/L), for whole-array checks."""
    import dataclasses

    units = _check_units(units)
    sigma = check_sigma(sigma)
    d = _draw(units, sigma, int(k), np.random.default_rng(int(seed)))
    out = []
    for i in range(int(k)):
        row = []
        for j, u in enumerate(units):
            L = float(d["L"][i, j])
            kw = dict(L=L, b=u.b / u.L * L)
            if not u.is_spacer:
                kw.update(h=float(d["h"][i, j]), t=float(d["t"][i, j]), w=float(d["w"][i, j]))
            row.append(dataclasses.replace(u, **kw))
        out.append(row)
    return out


def _polyline(stations):
    """(K, 2) polyline through the units' station points (shared joints once)."""
    parts = [stations[0]] + [s[1:] for s in stations[1:]]
    return np.vstack(parts)


def plot_tolerance(result: ToleranceResult, path, target=None, simulated=None):
    """Figure: the envelope (shaded), the nominal all-snapped shape, the free-end scatter and
    optionally a ``target`` polyline (m) and ``simulated`` curves (list of (K, 2) m)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Polygon

    fig, ax = plt.subplots(figsize=(7, 5))
    mm = 1e3
    band_lo, band_hi = result.band()
    for j in range(result.stations.shape[0]):
        lo = result.stations[j] + band_lo[j, :, None] * result.frames[j, :, 1, :]
        hi = result.stations[j] + band_hi[j, :, None] * result.frames[j, :, 1, :]
        poly = np.vstack([lo, hi[::-1]]) * mm
        ax.add_patch(Polygon(poly, closed=True, facecolor="tab:blue", alpha=0.25, lw=0,
                             label="envelope" if j == 0 else None))
    if target is not None:
        tg = np.asarray(target, float) * mm
        ax.plot(tg[:, 0], tg[:, 1], "k--", lw=1.2, label="target")
    ax.plot(result.nominal[:, 0] * mm, result.nominal[:, 1] * mm, "tab:blue", lw=1.5,
            label="nominal (map)")
    for k, c in enumerate(simulated or []):
        c = np.asarray(c) * mm
        ax.plot(c[:, 0], c[:, 1], color="tab:red", lw=0.5, alpha=0.6,
                label="simulated arrays" if k == 0 else None)
    ax.plot(result.free_end[:, 0] * mm, result.free_end[:, 1] * mm, ".", ms=1.5,
            color="tab:orange", label="free end")
    ax.set_aspect("equal")
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    f = result.free_end_summary()
    ax.set_title(f"{result.n} samples: free end 95 % within {f['r95_mm']:.2g} mm, "
                 f"angle std {f['std_angle_deg']:.2g}°", fontsize=9)
    ax.legend(fontsize=7, loc="best")
    fig.tight_layout()
    fig.savefig(path, dpi=150)
    plt.close(fig)
    return path


__all__ = ["tolerance", "ToleranceResult", "plot_tolerance", "perturbed_units", "SIGMA_DEFAULT",
           "ENVELOPE_FLOOR_MM", "check_sigma"]
