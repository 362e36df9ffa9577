"""The tolerance-driven design of any open planar curve (the default of `inverse_design`).

The target is a curve parametrised by arc length (`design.targets.Target`). Initial layouts cut
it where its turning changes direction and give each run units by an equal share of its
turning; then least squares over every unit's (L, h/L), every spacer's L and the placement at
once, through the map's interpolants (`FastModel`, vectorised), until the predicted all-snapped
base is within tol × the target's length; fewest units first; otherwise the best design found.
design/README.md, "Inverse design", has the steps.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from snapmorph.design.inverse_result import Design, Piece
from snapmorph.design.map_model import FastModel, b_length_min, chain_fast
from snapmorph.design.targets import Target, deviation
from snapmorph.design.units import Unit
from snapmorph.design.verification import assess

#: correspondence points of the least-squares residual (each gives an x and a y residual)
N_FIT = 160
#: spacers shorter than this (m) are dropped from an initial layout (they are glue joints)
_MIN_SPACER = 1e-3
#: relative margin kept from the fabrication limits (see `_Fit.bounds`)
EDGE = 1e-5


def resample_batch(z: np.ndarray, u: np.ndarray) -> np.ndarray:
    """(B, K) complex polylines sampled at arc-length fractions u: (B, len(u)) complex."""
    seg = np.abs(np.diff(z, axis=1))
    s = np.concatenate([np.zeros((z.shape[0], 1)), np.cumsum(seg, axis=1)], axis=1)
    out = np.empty((z.shape[0], len(u)), dtype=complex)
    for b in range(z.shape[0]):
        q = u * s[b, -1]
        out[b] = np.interp(q, s[b], z[b].real) + 1j * np.interp(q, s[b], z[b].imag)
    return out


@dataclass
class Limits:
    """Fabrication bounds of a design (SI): unit length range, h/L range (bistable with the
    energy-barrier margin), the θ (deg) those units reach, and the shortest spacer."""

    L_min: float
    L_max: float
    hL_min: float
    hL_max: float
    theta_min: float
    theta_max: float
    spacer_min: float = _MIN_SPACER


def fabrication_limits(dm, t, w, L_range, hL_range, min_barrier, state_kw) -> Limits:
    """Fabrication bounds from the user's ranges, intersected with what the map covers: t/L and
    w/L inside the map, h/L where every unit of the L range is bistable with an energy barrier
    of at least `min_barrier` (E I_arch / L units)."""
    rng = getattr(dm, "ranges", None) or {}
    lo, hi = b_length_min(dm, w), math.inf  # units of flat ends b: b/L inside the map too
    for name, v in (("t_over_L", t), ("w_over_L", w)):
        if name in rng:
            a, b = rng[name]
            lo, hi = max(lo, v / b), min(hi, v / a)
    map_L = (lo, hi)
    if L_range is not None:
        a, b = _increasing_pair("L_range", L_range, "(L_min, L_max) in m",
                                "(L_min, L_max) in m with 0 < L_min < L_max")
        lo, hi = max(lo, a), min(hi, b)
    if not lo < hi:
        raise ValueError(
            f"no valid unit: the map covers unit lengths {map_L[0] * 1e3:.1f} to "
            f"{map_L[1] * 1e3:.1f} mm at t = {t * 1e3:g} mm, w = {w * 1e3:g} mm"
            + _b_words(dm, w)
            + (f", L_range is {L_range[0] * 1e3:g} to {L_range[1] * 1e3:g} mm"
               if L_range is not None else "") + "; they do not overlap")
    hs = np.asarray(dm.h_over_L, dtype=float)
    Ls = np.linspace(lo, hi, 5)
    ok = np.ones(hs.size, dtype=bool)
    for L in Ls:
        r = dm.at(hs, np.full_like(hs, t / L), np.full_like(hs, w / L), allow_nan=True, **state_kw)
        th = np.asarray(r["theta"], float)
        barrier = np.asarray(r["energy_barrier"], float)
        ok &= np.isfinite(th) & (th > 0) & np.isfinite(barrier) & (barrier >= min_barrier)
    if hL_range is not None:
        a, b = _increasing_pair("hL_range", hL_range, "(h/L min, h/L max)",
                                "(min, max) with 0 < min < max")
        ok &= (hs >= a - 1e-12) & (hs <= b + 1e-12)
    # the longest run of consecutive valid grid nodes: interpolation inside it is defined
    best, i = None, 0
    while i < hs.size:
        if ok[i]:
            j = i
            while j + 1 < hs.size and ok[j + 1]:
                j += 1
            if best is None or j - i > best[1] - best[0]:
                best = (i, j)
            i = j + 1
        else:
            i += 1
    if best is None or best[1] == best[0]:
        raise ValueError(
            f"no valid unit: no h/L of the map is bistable with an energy barrier >= "
            f"{min_barrier:g} (E I/L) for every unit length {lo * 1e3:.1f} to {hi * 1e3:.1f} mm"
            + (f" within hL_range {tuple(hL_range)}" if hL_range is not None else "")
            + "; widen hL_range or L_range, or lower min_barrier")
    hL_min, hL_max = float(hs[best[0]]), float(hs[best[1]])
    if hL_range is not None:
        hL_min, hL_max = max(hL_min, float(hL_range[0])), min(hL_max, float(hL_range[1]))
    Lmid = math.sqrt(lo * hi)
    th = np.asarray(dm.at(np.array([hL_min, hL_max]), np.full(2, t / Lmid), np.full(2, w / Lmid),
                          allow_nan=True, **state_kw)["theta"], float)
    return Limits(lo, hi, hL_min, hL_max, float(np.min(th)), float(np.max(th)))


def _b_words(dm, w) -> str:
    """", b = 5 mm" for a map seen at flat ends b (`map_at_b`), else ""."""
    b_over_w = getattr(dm, "b_over_w", None)
    return f", b = {b_over_w * w * 1e3:g} mm" if b_over_w else ""


def _increasing_pair(name, value, what, order) -> tuple[float, float]:
    """(a, b) from a pair of numbers with 0 < a < b; else a ValueError naming `name`, saying
    `what` it is (not two numbers) or the `order` it needs."""
    try:
        a, b = (float(v) for v in value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be {what}, got {value!r}") from None
    if not (math.isfinite(a) and math.isfinite(b) and 0 < a < b):
        raise ValueError(f"{name} must be {order}, got {value!r}")
    return a, b


def hL_for_turn(dm, turn_deg, L, t, w, lim: Limits, state_kw, scale=1.0) -> float:
    """h/L of the unit of length L turning by |turn_deg| × scale (deg), clamped to the limits."""
    want = float(np.clip(abs(turn_deg) * scale, lim.theta_min, lim.theta_max))
    hs = np.linspace(lim.hL_min, lim.hL_max, 200)
    th = np.asarray(dm.at(hs, np.full_like(hs, t / L), np.full_like(hs, w / L), allow_nan=True,
                          **state_kw)["theta"], float)
    good = np.isfinite(th)
    if not np.any(good):
        return 0.5 * (lim.hL_min + lim.hL_max)
    hs, th = hs[good], th[good]
    order = np.argsort(th)
    return float(np.interp(want, th[order], hs[order]))


def _turn_runs(target: Target, hysteresis: float) -> list:
    """Sample intervals [(i0, i1)] of the target on which its tangent turns one way: split at
    the extrema of the tangent angle, ignoring wiggles smaller than `hysteresis` (rad)."""
    phi = target.angle
    breaks, direction, ext = [0], 0, 0
    for i in range(1, len(phi)):
        if direction == 0:
            if abs(phi[i] - phi[0]) > hysteresis:
                direction, ext = (1 if phi[i] > phi[0] else -1), i
        elif direction > 0:
            if phi[i] >= phi[ext]:
                ext = i
            elif phi[ext] - phi[i] > hysteresis:
                breaks.append(ext)
                direction, ext = -1, i
        else:
            if phi[i] <= phi[ext]:
                ext = i
            elif phi[i] - phi[ext] > hysteresis:
                breaks.append(ext)
                direction, ext = 1, i
    breaks.append(len(phi) - 1)
    breaks = sorted(set(breaks))
    return [(a, b) for a, b in zip(breaks[:-1], breaks[1:]) if b > a]


def _initial_layout(target: Target, quantum_deg: float, lim: Limits, dm, t, w, state_kw,
                    theta_scale: float = 1.0, share: float = 1.0):
    """A first guess: (sides, L, h/L). The target is cut where its turning changes direction;
    each run turning Φ gets round(|Φ| / quantum) units (at least enough not to exceed θ_max, none
    when it turns less than half the smallest θ: a spacer), each covering an equal share of the
    turning; a unit whose share of the curve is longer than L_max (or than `share` times it)
    sits at its middle (in turning) between two spacers."""
    s, phi = target.s, target.angle
    runs = _turn_runs(target, math.radians(0.25 * lim.theta_min))
    items = []  # (side, L, hL)

    def spacer(length):
        if length > 0:
            items.append((0, float(length), 0.0))

    for i0, i1 in runs:
        Phi = math.degrees(phi[i1] - phi[i0])
        ell = s[i1] - s[i0]
        if abs(Phi) < 0.5 * lim.theta_min:
            spacer(ell)
            continue
        n = max(1, int(round(abs(Phi) / quantum_deg)), math.ceil(abs(Phi) / lim.theta_max - 1e-9))
        side = 1 if Phi > 0 else -1
        levels = phi[i0] + (phi[i1] - phi[i0]) * np.arange(n + 1) / n
        seg_phi = phi[i0:i1 + 1] * side
        cuts = np.interp(levels * side, np.maximum.accumulate(seg_phi), s[i0:i1 + 1])
        cuts[0], cuts[-1] = s[i0], s[i1]
        for k in range(n):
            a, b = cuts[k], cuts[k + 1]
            length = b - a
            L = float(np.clip(share * length, lim.L_min, lim.L_max))
            mid_level = 0.5 * (levels[k] + levels[k + 1]) * side
            centre = float(np.interp(mid_level, np.maximum.accumulate(seg_phi), s[i0:i1 + 1]))
            left = max(0.0, min(centre - L / 2 - a, length - L))
            right = max(0.0, length - L - left)
            spacer(left)
            hL = hL_for_turn(dm, abs(Phi) / n, L, t, w, lim, state_kw, theta_scale)
            items.append((side, L, hL))
            spacer(right)
    # merge neighbouring spacers; drop slivers
    merged = []
    for it in items:
        if it[0] == 0 and merged and merged[-1][0] == 0:
            merged[-1] = (0, merged[-1][1] + it[1], 0.0)
        else:
            merged.append(it)
    merged = [it for it in merged if it[0] != 0 or it[1] >= lim.spacer_min]
    if not merged:
        merged = [(0, target.length, 0.0)]
    sides = [it[0] for it in merged]
    return sides, np.array([it[1] for it in merged]), np.array([it[2] for it in merged])


class _Fit:
    """Least squares over every unit's (L, h/L), every spacer's L and, for the best placement,
    the start point and direction: residuals are the distances between arc-length-matched points
    of the predicted all-snapped base and the target (over its length). Jacobians by forward
    differences, all perturbed arrays evaluated in one vectorised map lookup."""

    def __init__(self, model: FastModel, target: Target, lim: Limits, placement: str):
        self.m, self.target, self.lim, self.placement = model, target, lim, placement
        self.u = np.linspace(0.0, 1.0, N_FIT)
        self.ref = target.at_fraction(self.u)
        self.ref_c = self.ref[:, 0] + 1j * self.ref[:, 1]
        self.n = len(model.sides)
        self.Lref = target.length

    def pack(self, L, hL, start, angle):
        v = []
        for i in range(self.n):
            v.append(L[i] / self.Lref)
            if self.m.sides[i] != 0:
                v.append(hL[i])
        if self.placement == "best":
            v += [start[0] / self.Lref, start[1] / self.Lref, angle]
        return np.array(v)

    def bounds(self):
        lo, hi = [], []
        for i in range(self.n):
            if self.m.sides[i] != 0:
                # a hair inside the limits: a unit on the map's edge must stay inside it after
                # units.csv rounds it to mm
                lo += [self.lim.L_min * (1 + EDGE) / self.Lref, self.lim.hL_min * (1 + EDGE)]
                hi += [self.lim.L_max * (1 - EDGE) / self.Lref, self.lim.hL_max * (1 - EDGE)]
            else:
                lo.append(self.lim.spacer_min / self.Lref)
                hi.append(2.0)
        if self.placement == "best":
            lo += [-np.inf] * 3
            hi += [np.inf] * 3
        return np.array(lo), np.array(hi)

    def unpack(self, V):
        """(B, p) → L (B, n), hL (B, n), start (B,) complex, angle (B,)."""
        V = np.atleast_2d(V)
        B = V.shape[0]
        L, hL = np.zeros((B, self.n)), np.zeros((B, self.n))
        k = 0
        for i in range(self.n):
            L[:, i] = V[:, k] * self.Lref
            k += 1
            if self.m.sides[i] != 0:
                hL[:, i] = V[:, k]
                k += 1
        if self.placement == "best":
            start = (V[:, k] + 1j * V[:, k + 1]) * self.Lref
            angle = V[:, k + 2]
        else:
            start = np.full(B, complex(*self.target.start))
            angle = np.full(B, self.target.start_angle)
        return L, hL, start, angle

    def _index(self):
        """For each parameter: (unit index or -1 for placement, what)."""
        out = []
        for i in range(self.n):
            out.append((i, "L"))
            if self.m.sides[i] != 0:
                out.append((i, "hL"))
        if self.placement == "best":
            out += [(-1, "x"), (-1, "y"), (-1, "a")]
        return out

    def _residual(self, z):
        p = resample_batch(z, self.u)
        d = (p - self.ref_c[None]) / self.Lref
        r = np.stack([d.real, d.imag], axis=-1).reshape(len(z), -1)
        return np.where(np.isfinite(r), r, 1.0)

    def residuals(self, v):
        L, hL, start, angle = self.unpack(v[None])
        z, turn = self.m.unit_frames(np.arange(self.n), L[0], hL[0])
        return self._residual(self.m.assemble(z[None], turn[None], start, angle))[0]

    def jac(self, v):
        """Forward differences; only the perturbed unit is looked up again (one vectorised
        lookup for all of them), the others reuse the unperturbed shapes."""
        lo, hi = self.bounds()
        step = 1e-6 * np.maximum(1.0, np.abs(v))
        sgn = np.where(v + step > hi, -1.0, 1.0)
        h = sgn * step
        L, hL, start, angle = self.unpack(v[None])
        L, hL, start, angle = L[0], hL[0], start[0], angle[0]
        z0, t0 = self.m.unit_frames(np.arange(self.n), L, hL)
        index = self._index()
        P = len(v)
        Z = np.repeat(z0[None], P + 1, axis=0)
        T = np.repeat(t0[None], P + 1, axis=0)
        S = np.full(P + 1, start, dtype=complex)
        A = np.full(P + 1, angle)
        units, Ls, hLs, rows = [], [], [], []
        for k, (i, what) in enumerate(index):
            if i < 0:
                if what == "x":
                    S[k + 1] += h[k] * self.Lref
                elif what == "y":
                    S[k + 1] += 1j * h[k] * self.Lref
                else:
                    A[k + 1] += h[k]
                continue
            Li, hLi = L[i], hL[i]
            if what == "L":
                Li = Li + h[k] * self.Lref
            else:
                hLi = hLi + h[k]
            units.append(i)
            Ls.append(Li)
            hLs.append(hLi)
            rows.append(k + 1)
        if units:
            zp, tp = self.m.unit_frames(np.array(units), np.array(Ls), np.array(hLs))
            Z[rows, units] = zp
            T[rows, units] = tp
        R = self._residual(self.m.assemble(Z, T, S, A))
        return ((R[1:] - R[0]) / h[:, None]).T

    def solve(self, v0, weights=None, max_nfev=25):
        return bounded_least_squares(self, v0, weights, max_nfev)


def bounded_least_squares(fit, v0, weights=None, max_nfev=25):
    """Minimise ``fit.residuals`` (optionally times ``weights``) inside ``fit.bounds()`` with
    its analytic ``fit.jac``, from v0 moved just inside the bounds; (x, evaluations). The one
    solver of the single- and the multi-shape fit."""
    from scipy.optimize import least_squares

    lo, hi = fit.bounds()
    v0 = np.clip(v0, lo + 1e-12, hi - 1e-12)
    if weights is None:
        fun, jac = fit.residuals, fit.jac
    else:
        fun = lambda v: weights * fit.residuals(v)  # noqa: E731
        jac = lambda v: weights[:, None] * fit.jac(v)  # noqa: E731
    # the residuals are distances of ~1e-3 of the length: 1e-6 relative is plenty
    sol = least_squares(fun, v0, jac=jac, bounds=(lo, hi), x_scale="jac", xtol=1e-7,
                        ftol=1e-6, gtol=1e-8, max_nfev=max_nfev, method="trf")
    return sol.x, int(sol.nfev)


def _units_from(sides, L, hL, t, w, b_over_L) -> list:
    out = []
    for sd, Li, hi in zip(sides, L, hL):
        if sd == 0:
            out.append(Unit(L=float(Li), h=0.0, t=t, w=w, side=0))
        else:
            out.append(Unit(L=float(Li), h=float(hi * Li), t=t, w=w, side=int(sd),
                            b=b_over_L * float(Li)))
    return out


def _pieces_for(units, target: Target) -> list:
    """Each unit's share of the target (by arc length, scaled to the target's length): the
    turning (deg) and chord (m) of that stretch of the target."""
    total = sum(u.L for u in units)
    edges = np.concatenate([[0.0], np.cumsum([u.L for u in units])]) / total * target.length
    ang = np.interp(edges, target.s, target.angle)
    pts = np.stack([np.interp(edges, target.s, target.xy[:, 0]),
                    np.interp(edges, target.s, target.xy[:, 1])], axis=-1)
    return [Piece([], math.degrees(ang[i + 1] - ang[i]), float(np.hypot(*(pts[i + 1] - pts[i]))))
            for i in range(len(units))]


def curve_design(target: Target, t, w, dm, tol, placement, L_range, hL_range, min_barrier,
                 state, max_units, lookup, progress=None) -> Design:
    """Tolerance-driven design of any planar curve (see `inverse_design`); progress("layouts")
    is called once per layout tried."""
    import time

    t0 = time.perf_counter()
    state_kw, state_used = {}, state  # dm is a StateMap: it adds the state itself
    lim = fabrication_limits(dm, t, w, L_range, hL_range, min_barrier, state_kw)
    b_over_L = lookup.b_over_L
    fractions = (0.95, 0.8, 0.65, 0.5, 0.4, 0.3, 0.22)
    quanta = sorted({round(max(lim.theta_min, f * lim.theta_max), 6) for f in fractions}
                    | {round(lim.theta_min, 6)}, reverse=True)
    best, tried, seen = None, [], set()
    # fewest units first; for each count, units covering their whole share of the curve, then
    # units of 60 % of it between spacers (curvature concentrated, as a unit's is)
    for q, share in ((q, s) for q in quanta for s in (1.0, 0.6)):
        sides, L, hL = _initial_layout(target, q, lim, dm, t, w, state_kw, share=share)
        key = (tuple(sides), share if any(s == 0 for s in sides) else 1.0)
        if key in seen:
            continue
        seen.add(key)
        if progress is not None:
            progress("layouts")
        if sum(1 for s in sides if s) > max_units:
            tried.append((q, len(sides), f"the layout needs {sum(1 for s in sides if s)} arched "
                                         f"units > max_units = {max_units}"))
            break
        model = FastModel(dm, t, w, sides, state_kw)
        fit = _Fit(model, target, lim, placement)
        v0 = fit.pack(L, hL, target.start, target.start_angle)
        r0 = fit.residuals(v0)
        v, nfev = fit.solve(v0)
        # minimax polish (Lawson): reweight towards the largest distances, unless the
        # arc-length-matched distances (an upper bound of the deviation, nearly) are already
        # well inside tol
        weights = np.ones_like(r0)
        for _ in range(3):
            r = fit.residuals(v)
            d = np.hypot(r[0::2], r[1::2])
            if not np.all(np.isfinite(d)) or d.max() <= 0.5 * tol:
                break
            weights = weights * np.repeat(np.maximum(d / d.max(), 0.05), 2)
            weights = weights / np.sqrt(np.mean(weights ** 2))
            v2, n2 = fit.solve(v, weights=np.sqrt(weights), max_nfev=20)
            nfev += n2
            if np.max(np.hypot(*fit.residuals(v2).reshape(-1, 2).T)) < d.max():
                v = v2
        Lf, hLf, start_c, angle = (a[0] for a in fit.unpack(v))
        start = (float(start_c.real), float(start_c.imag))
        units = _units_from(sides, Lf, hLf, t, w, b_over_L)
        try:
            d = Design(units=units, predicted=None, target=target.xy, target_length=target.length,
                       max_deviation=math.inf, rms_deviation=math.inf,
                       control_points=np.empty((0, 2)), control_angles=np.array([target.start_angle]),
                       arcs=[], pieces=_pieces_for(units, target), t=t, w=w)
            d = assess(d, target.xy, dm, state_kw, placement, tol, start=start, angle=angle,
                        quick=80)
        except ValueError as exc:
            tried.append((q, len(sides), str(exc)))
            continue
        # the initial layout's deviation, as placed on the target's start and tangent
        try:
            units0 = _units_from(sides, L, hL, t, w, b_over_L)
            before = deviation(chain_fast(units0, dm, state_kw, tuple(target.start),
                                           target.start_angle).xy, target.xy)
        except ValueError:
            before = (math.inf, math.inf)
        d.refinement = {"max_before": before[0], "rms_before": before[1],
                        "max_after": d.max_deviation, "rms_after": d.rms_deviation,
                        "nfev": nfev, "accepted": True, "quantum_deg": q, "share": share}
        tried.append((q, len(sides), d.max_deviation))
        if best is None or d.max_deviation < best.max_deviation:
            best = d
        if best.max_deviation <= tol:
            break
    if best is None:
        raise ValueError("no design: " + "; ".join(str(e) for _, _, e in tried if isinstance(e, str))
                         + "; raise max_units or L_range")
    x0, y0, a0 = best.placements["best"]
    best = assess(best, target.xy, dm, state_kw, placement, tol, start=(x0, y0), angle=a0)
    best.history = tried
    best.state = state_used
    best.limits = lim
    best.time = time.perf_counter() - t0
    return best
