"""The continuous part of multi-shape design (`design.multishape`, steps 2 and 3): least
squares over every unit and every target's placement at once, and the exact re-selection of
each target's pattern for the fitted units by branch and bound.
"""

from __future__ import annotations

import numpy as np

# Private helpers of the single-target design, used as they are (one mechanism for each job):
# the vectorised map model, the fit's residual count and edge margin, batch resampling.
from snapmorph.design.curve_fit import EDGE, N_FIT, Limits, bounded_least_squares, resample_batch
from snapmorph.design.map_model import FastModel
from snapmorph.design.nearest import (_mask_to_pattern, _pattern_to_mask, _reference,
                                      branch_and_bound, matched_costs, pattern_table)

#: fit / re-select rounds per layout
PATTERN_ROUNDS = 3


# =============================================================================================
# 2. Least squares over every unit and every target's placement
# =============================================================================================
class _JointFit:
    """Least squares over every unit's (L, h/L), every spacer's L and, for the best placement,
    one start point and direction per target: residuals are the arc-length-matched distances
    of each target's predicted state (its pattern's units snapped) to the target, all targets
    at once. Jacobians by forward differences; every perturbed unit looked up in one call."""

    def __init__(self, model: FastModel, patterns, targets, lim: Limits, placement: str):
        self.m, self.lim, self.placement = model, lim, placement
        self.patterns = np.asarray(patterns, dtype=bool)
        self.targets = targets
        self.K = len(targets)
        self.n = len(model.sides)
        self.u = np.linspace(0.0, 1.0, N_FIT)
        self.refs = []
        for tg in targets:
            p = tg.at_fraction(self.u)
            self.refs.append(p[:, 0] + 1j * p[:, 1])
        self.Lref = float(np.mean([tg.length for tg in targets]))
        self.lin = np.linspace(0.0, 1.0, model.M)
        self.index = []
        for i in range(self.n):
            self.index.append((i, "L"))
            if model.sides[i] != 0:
                self.index.append((i, "hL"))
        if placement == "best":
            for k in range(self.K):
                self.index += [(-1 - k, "x"), (-1 - k, "y"), (-1 - k, "a")]

    # --- parameters -----------------------------------------------------------------------
    def pack(self, L, hL, frames):
        v = []
        for i, what in self.index:
            if i >= 0:
                v.append(L[i] / self.Lref if what == "L" else hL[i])
            else:
                x0, y0, a0 = frames[-1 - i]
                v.append({"x": x0 / self.Lref, "y": y0 / self.Lref, "a": a0}[what])
        return np.array(v)

    def unpack(self, v):
        L, hL = np.zeros(self.n), np.zeros(self.n)
        frames = [[float(tg.start[0]), float(tg.start[1]), tg.start_angle] for tg in self.targets]
        for (i, what), x in zip(self.index, v):
            if i >= 0:
                if what == "L":
                    L[i] = x * self.Lref
                else:
                    hL[i] = x
            else:
                j = "xya".index(what)
                frames[-1 - i][j] = x * self.Lref if j < 2 else x
        return L, hL, [tuple(f) for f in frames]

    def bounds(self):
        lo, hi, lim = [], [], self.lim
        for i, what in self.index:
            if i < 0:
                lo.append(-np.inf)
                hi.append(np.inf)
            elif what == "hL":
                lo.append(lim.hL_min * (1 + EDGE))
                hi.append(lim.hL_max * (1 - EDGE))
            elif self.m.sides[i] != 0:
                # a hair inside the limits: units.csv rounds to mm (as design.inverse)
                lo.append(lim.L_min * (1 + EDGE) / self.Lref)
                hi.append(lim.L_max * (1 - EDGE) / self.Lref)
            else:
                lo.append(lim.spacer_min / self.Lref)
                hi.append(2.0)
        return np.array(lo), np.array(hi)

    # --- shapes and residuals -------------------------------------------------------------
    def shapes(self, L, hL):
        """(snapped shapes (n, M) complex m, end turns (n,) rad, straight shapes (n, M)); the
        last answer is kept (least squares asks for the residuals and then the Jacobian at the
        same point)."""
        key = (L.tobytes(), hL.tobytes())
        if getattr(self, "_last", (None,))[0] != key:
            zs, ts = self.m.unit_frames(np.arange(self.n), L, hL)
            self._last = (key, (zs, ts, L[:, None] * self.lin[None, :]))
        return self._last[1]

    def chains(self, zs, ts, zf, k, starts, angles):
        """Target k's state placed from starts (B,) complex heading angles (B,): (B, K') complex."""
        pat = self.patterns[k]
        Z = np.where(pat[None, :, None], zs, zf)
        T = np.where(pat[None, :], ts, 0.0)
        return self.m.assemble(Z, T, starts, angles)

    def _res(self, k, poly):
        p = resample_batch(poly, self.u)
        d = (p - self.refs[k][None]) / self.Lref
        r = np.stack([d.real, d.imag], axis=-1).reshape(len(poly), -1)
        return np.where(np.isfinite(r), r, 1.0)

    def residuals(self, v):
        L, hL, frames = self.unpack(v)
        zs, ts, zf = self.shapes(L, hL)
        out = []
        for k, (x0, y0, a0) in enumerate(frames):
            poly = self.chains(zs[None], ts[None], zf[None], k, np.array([x0 + 1j * y0]),
                               np.array([a0]))
            out.append(self._res(k, poly)[0])
        return np.concatenate(out)

    def jac(self, v):
        lo, hi = self.bounds()
        step = 1e-6 * np.maximum(1.0, np.abs(v))
        h = np.where(v + step > hi, -1.0, 1.0) * step
        L, hL, frames = self.unpack(v)
        zs0, ts0, zf0 = self.shapes(L, hL)
        P = len(v)
        Zs = np.repeat(zs0[None], P + 1, axis=0)
        Ts = np.repeat(ts0[None], P + 1, axis=0)
        Zf = np.repeat(zf0[None], P + 1, axis=0)
        S = np.array([[f[0] + 1j * f[1] for f in frames]] * (P + 1))
        A = np.array([[f[2] for f in frames]] * (P + 1))
        units, Ls, hLs, rows = [], [], [], []
        for r, (i, what) in enumerate(self.index, start=1):
            if i < 0:
                k = -1 - i
                if what == "x":
                    S[r, k] += h[r - 1] * self.Lref
                elif what == "y":
                    S[r, k] += 1j * h[r - 1] * self.Lref
                else:
                    A[r, k] += h[r - 1]
                continue
            Li = L[i] + (h[r - 1] * self.Lref if what == "L" else 0.0)
            hLi = hL[i] + (h[r - 1] if what == "hL" else 0.0)
            units.append(i)
            Ls.append(Li)
            hLs.append(hLi)
            rows.append(r)
        if units:
            zp, tp = self.m.unit_frames(np.array(units), np.array(Ls), np.array(hLs))
            Zs[rows, units] = zp
            Ts[rows, units] = tp
            Zf[rows, units] = np.array(Ls)[:, None] * self.lin[None, :]
        blocks = []
        for k in range(self.K):
            R = self._res(k, self.chains(Zs, Ts, Zf, k, S[:, k], A[:, k]))
            blocks.append(((R[1:] - R[0]) / h[:, None]).T)
        return np.vstack(blocks)

    def solve(self, v0, weights=None, max_nfev=25):
        return bounded_least_squares(self, v0, weights, max_nfev)

    def solve_minimax(self, v0, tol):
        """Least squares, then up to three Lawson re-weightings towards the largest distance
        of any target, unless every matched distance is already within tol / 2."""
        v, nfev = self.solve(v0)
        weights = np.ones(len(self.residuals(v)))
        for _ in range(3):
            d = np.hypot(*self.residuals(v).reshape(-1, 2).T)
            if not np.all(np.isfinite(d)) or d.max() <= 0.5 * tol:
                break
            weights = weights * np.repeat(np.maximum(d / d.max(), 0.05), 2)
            weights = weights / np.sqrt(np.mean(weights ** 2))
            v2, n2 = self.solve(v, weights=np.sqrt(weights), max_nfev=20)
            nfev += n2
            if np.max(np.hypot(*self.residuals(v2).reshape(-1, 2).T)) < d.max():
                v = v2
        return v, nfev


# =============================================================================================
# 3. Exact pattern re-selection
# =============================================================================================
def _reselect(fit: _JointFit, v) -> tuple[np.ndarray, list]:
    """Each target's best pattern for the fitted units (branch and bound in the target's
    fitted frame, the current pattern as the incumbent): (patterns (K, n), per target (old c,
    new c, nodes))."""
    L, hL, frames = fit.unpack(v)
    zs, ts, _ = fit.shapes(L, hL)
    arched = fit.m.sides != 0
    table = pattern_table(zs, L, arched, ts)
    new = fit.patterns.copy()
    info = []
    for k, tg in enumerate(fit.targets):
        Q, Qj = _reference(table, tg, frames[k])
        cur = _pattern_to_mask(fit.patterns[k])
        c_cur = float(matched_costs(table, Q, [cur])[0])
        found, nodes, _ = branch_and_bound(table, Q, Qj, top=1, seeds=[cur])
        c_new, mask = found[0]
        if mask != cur and c_new < 0.98 * c_cur:
            new[k] = _mask_to_pattern(mask, fit.n)
        info.append((c_cur, c_new, nodes))
    return new, info


# =============================================================================================
# The design
# =============================================================================================
def _fit_layout(dm, t, w, sides, L, hL, pats, frames, tgts, lim, placement, tol):
    """Fit a layout (step 2), re-select its patterns (step 3) and fit again while they change.
    Returns (fit, v, evaluations, pattern entries changed)."""
    nfev, changes = 0, 0
    model = FastModel(dm, t, w, sides, {})
    fit = _JointFit(model, pats, tgts, lim, placement)
    v = fit.pack(L, hL, frames)
    for _ in range(PATTERN_ROUNDS):
        v, n_ev = fit.solve_minimax(v, tol)
        nfev += n_ev
        new, _info = _reselect(fit, v)
        if np.array_equal(new, fit.patterns):
            break
        changes += int(np.count_nonzero(new != fit.patterns))
        fit = _JointFit(model, new, tgts, lim, placement)
    return fit, v, nfev, changes
