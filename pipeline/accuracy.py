"""Measure a map's interpolation accuracy against direct simulation at random off-grid points.

    python -m snapmorph.pipeline.accuracy --map maps/data/default.nc --n 50

Points are drawn uniformly in the map's (h/L, t/L, w/L) box and kept when they are "away from
the bistability boundary": every grid point of their interpolation cell, and of the cells one
h/L step below and above, is ok. Each kept point is simulated with `solve_point` at the map's
resolution and b/L. Reports the max |error| in theta (degrees) and the max relative errors in
S/L and F_cr (%), and the point where each occurs.
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import dataclass

import numpy as np


@dataclass
class Accuracy:
    """Errors of the interpolated map at n points (theta in degrees, S and F_cr relative)."""

    points: np.ndarray  # (n, 3) h/L, t/L, w/L
    theta_err: np.ndarray  # deg, interpolated - simulated
    S_rel: np.ndarray  # (interpolated - simulated) / simulated
    F_rel: np.ndarray
    skipped: int  # simulations that did not converge (not counted)

    def summary(self) -> str:
        lines = [f"{len(self.points)} off-grid points ({self.skipped} simulations failed, skipped)"]
        for name, err, unit, scale in (("theta", self.theta_err, "deg", 1.0),
                                       ("S/L", self.S_rel, "%", 100.0),
                                       ("F_cr", self.F_rel, "%", 100.0)):
            k = int(np.argmax(np.abs(err)))
            h, t, w = self.points[k]
            lines.append(f"  {name}: max |error| {abs(err[k]) * scale:.4g} {unit} at h/L={h:.4f}, "
                         f"t/L={t:.5f}, w/L={w:.4f}; mean |error| {np.mean(np.abs(err)) * scale:.3g} {unit}")
        return "\n".join(lines)


def _away_from_boundary(dm, h, t, w, b=None) -> bool:
    # theta defined on the cell and on the cells one h step below and above
    step = np.diff(dm.h_over_L).max()
    hs = np.clip([h - step, h, h + step], dm.h_over_L[0], dm.h_over_L[-1])
    v = dm.value("theta", hs, t, w, allow_nan=True, state="actuated", b_over_L=b)
    return bool(np.all(np.isfinite(v)))


def check_nodes(dm, solve, resolution, b, k: int = 3, seed: int = 1, rtol: float = 1e-6) -> None:
    """Re-simulate k ok grid points; raise if the map does not hold what the solver computes
    there now (the solver changed since the map was built: errors would not be interpolation's)."""
    rng = np.random.default_rng(seed)
    status = dm.dataset["status"].values
    ok = np.argwhere(status == 0)
    for idx in ok[rng.choice(len(ok), size=min(k, len(ok)), replace=False)]:
        i, j, l = idx[:3]
        h, t, w = dm.h_over_L[i], dm.t_over_L[j], dm.w_over_L[l]
        b_point = float(dm.b_over_L[idx[3]]) if len(idx) > 3 else b
        rec = solve(float(h), float(t), float(w), b_point, resolution, dm.samples)
        for name in ("theta", "S", "F_cr"):
            stored = float(dm.dataset[name].values[tuple(idx)])
            if not abs(rec[name] - stored) <= rtol * abs(stored):
                raise ValueError(
                    f"the map does not reproduce the solver at the grid point h/L={h:g}, t/L={t:g}, "
                    f"w/L={w:g}, b/L={b_point:g}: {name} stored {stored!r}, simulated now {rec[name]!r}; the solver "
                    f"changed since the map was built (rebuild it first)")


def measure(dm, n: int = 50, seed: int = 0, solve=None, max_tries: int = 100000) -> Accuracy:
    """Compare `dm` with direct simulations at n random off-grid points away from the boundary
    (after checking that the map still reproduces the solver at a few grid points)."""
    from snapmorph.pipeline.kinds.unit import solve_point

    solve = solve or solve_point
    rng = np.random.default_rng(seed)
    ranges = dm.ranges
    (h0, h1), (t0, t1), (w0, w1) = (ranges[d] for d in ("h_over_L", "t_over_L", "w_over_L"))
    # a map with a b/L axis: b/L drawn over its range too; else the map's one b/L
    b0, b1 = ranges.get("b_over_L", (float(dm.attrs.get("b_over_L", 0.0)),) * 2)
    resolution = int(dm.attrs.get("resolution", -1))
    resolution = None if resolution < 0 else resolution
    check_nodes(dm, solve, resolution, b0)
    pts, th, S, F = [], [], [], []
    skipped = 0
    for _ in range(max_tries):
        if len(pts) >= n:
            break
        h, t, w = rng.uniform(h0, h1), rng.uniform(t0, t1), rng.uniform(w0, w1)
        b = rng.uniform(b0, b1) if b1 > b0 else b0
        if not _away_from_boundary(dm, h, t, w, b):
            continue
        rec = solve(h, t, w, b, resolution, dm.samples)
        if rec["status"] != 0:
            skipped += 1
            continue
        v = dm.at(h, t, w, state="actuated", b_over_L=b)
        pts.append((h, t, w))
        th.append(v["theta"] - rec["theta"])
        S.append((v["S"] - rec["S"]) / rec["S"])
        F.append((v["F_cr"] - rec["F_cr"]) / rec["F_cr"])
    return Accuracy(np.array(pts), np.array(th), np.array(S), np.array(F), skipped)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m snapmorph.pipeline.accuracy", description=__doc__.splitlines()[0])
    p.add_argument("--map", default=None, help="map file (default: the default map)")
    p.add_argument("--n", type=int, default=50, help="number of points (default 50)")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    args = p.parse_args(argv)
    from snapmorph.maps import DesignMap

    dm = DesignMap.load(args.map)
    print(f"{dm}")
    print(measure(dm, n=args.n, seed=args.seed).summary())
    return 0


if __name__ == "__main__":
    sys.exit(main())
