"""Compile (or load from numba's on-disk cache) every kernel a first command needs: one small
planar unit (push, probes, release, snap-back), one 3-D and one 2-D unit. `make venv` runs it
after installing, so that the first `snapmorph unit ...` of a fresh clone runs at warm speed.

    python -m snapmorph.units.warmup
"""

from __future__ import annotations

import time


def main() -> int:
    from snapmorph.units.geometry import UnitGeometry
    from snapmorph.units.planar import simulate_unit
    from snapmorph.units.unit2d import simulate_unit_2d
    from snapmorph.units.unit3d import simulate_unit_3d

    t0 = time.perf_counter()
    g = UnitGeometry(L=0.1, h=0.02, t=0.5e-3, w=5e-3, b=5e-3)
    simulate_unit(g, nodes=41)
    simulate_unit(g, nodes=41, method="displacement", check_self_standing=False)
    simulate_unit_3d(g, nodes=21, check_self_standing=False)
    simulate_unit_2d(UnitGeometry(L=0.1, h=0.04, t=0.5e-3, w=5e-3), nodes=21,
                     check_self_standing=False)
    print(f"numba kernels compiled or loaded from the cache in {time.perf_counter() - t0:.1f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
