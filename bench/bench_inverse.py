"""Inverse-design speed and accuracy (issue 10): a 10-unit design with refinement (target
<= 5 s), its whole-array verification (target <= 30 s), and a table of every test target of
`design.targets.example_targets()`: units, spacers, deviation predicted (map) and simulated
(whole array), best placement and start clamped, in % of the target length."""

from __future__ import annotations

import os
import sys
import time
import warnings

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))

T, W = 0.5e-3, 5e-3


def meander(n_half: int = 5, R: float = 0.12):
    """n_half half-circles of radius R turning alternately left and right (m)."""
    import numpy as np

    parts, start, y0 = [], np.zeros(2), 0.0
    a = np.linspace(0, np.pi, 121)
    for k in range(n_half):
        sgn = 1 if k % 2 == 0 else -1
        xs = sgn * R * np.sin(a)
        ys = y0 + R * (1 - np.cos(a))
        seg = np.stack([xs, ys], axis=-1)
        parts.append(seg if k == 0 else seg[1:])
        y0 += 2 * R
    return np.vstack(parts)


def main():
    warnings.simplefilter("ignore")
    from snapmorph.design import inverse_design
    from snapmorph.design.verification import verify_design
    from snapmorph.design.lookup import load_map
    from snapmorph.design.targets import example_targets

    dm = load_map()
    pts = meander()
    inverse_design(pts, t=T, w=W, design_map=dm)  # warm-up (imports, map caches)
    times, cpu = [], []
    for _ in range(3):
        t0, c0 = time.perf_counter(), time.process_time()
        d = inverse_design(pts, t=T, w=W, design_map=dm)
        times.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)
    n = sum(not u.is_spacer for u in d.units)
    print(f"machine load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores (wall times "
          "grow with it; CPU time is this process's own)")
    print(f"inverse design, meander of 5 half-circles R = 120 mm ({d.target_length * 1e3:.0f} mm): "
          f"{n} units + {len(d.units) - n} spacers, least squares over all at once: median "
          f"{sorted(times)[1]:.2f} s wall, {sorted(cpu)[1]:.2f} s CPU (target <= 5 s), deviation "
          f"{100 * d.max_deviation:.2f} % (map state: {d.state})")
    c0 = time.process_time()
    v = verify_design(d)
    print(f"  its whole-array verification ({v['status']}): {v['time']:.1f} s wall, "
          f"{time.process_time() - c0:.1f} s CPU (target <= 30 s), simulated deviation "
          f"{100 * v['deviations']['best'][0]:.2f} % (best placement)")
    print(f"{'target':<24} {'units':>5} {'spacers':>7} {'pred best':>9} {'pred clamp':>10} "
          f"{'sim best':>8} {'sim clamp':>9} {'design s':>8} {'sim s':>6}")
    for name, p in example_targets().items():
        t0 = time.perf_counter()
        d = inverse_design(p, t=T, w=W, design_map=dm)
        td = time.perf_counter() - t0
        v = verify_design(d)
        n = sum(not u.is_spacer for u in d.units)
        print(f"{name:<24} {n:>5} {len(d.units) - n:>7} {100 * d.deviations['best'][0]:8.2f}% "
              f"{100 * d.deviations['clamped'][0]:9.2f}% {100 * v['deviations']['best'][0]:7.2f}% "
              f"{100 * v['deviations']['clamped'][0]:8.2f}% {td:8.1f} {v['time']:6.1f}",
              flush=True)


if __name__ == "__main__":
    main()
