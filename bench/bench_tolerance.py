"""Speed of `design.tolerance`: 1,000 Monte Carlo samples of the paper's S design (eight
units of Table 3, L = 106.7 mm, h = 25.8 mm, four per arm) through the default map.
Target: <= 2 s (issue 11)."""

from __future__ import annotations

import os
import statistics
import sys
import time
import warnings

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def s_units():
    from snapmorph.design import Unit

    return [Unit(L=0.1067, h=0.0258, t=0.5e-3, w=5e-3, side=s) for s in (1,) * 4 + (-1,) * 4]


def main():
    from snapmorph.design.fabrication_tolerance import tolerance
    from snapmorph.maps import DesignMap

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        dm = DesignMap.load()
    units = s_units()
    state = "released" if "released" in dm.states else "actuated"
    tolerance(units, n=50, design_map=dm, state=state, held_out=False)  # imports, caches
    times = []
    for _ in range(5):
        t0 = time.perf_counter()
        r = tolerance(units, n=1000, seed=0, design_map=dm, state=state, held_out=False)
        times.append(time.perf_counter() - t0)
    f = r.free_end_summary()
    print(f"tolerance, S design (8 units), 1000 samples, {state} state: median "
          f"{statistics.median(times):.3f} s (best {min(times):.3f} s; target <= 2 s); "
          f"free end 95 % within {f['r95_mm']:.3g} mm, end angle std {f['std_angle_deg']:.3g} deg")


if __name__ == "__main__":
    main()
