"""What every unit result holds: the base of `units.planar.UnitResult`,
`units.unit3d.Unit3DResult` and `units.unit2d.Unit2DResult` (docs/unit-result.md).

The push-through metrics (F_cr, the d's, whether the unit is bistable and why not), the path,
the shapes of the special states, their stability and the released state (iii) (actuator
and supports removed), with ``status`` a name of `units.status` (``status_code`` its map
code), a one-line ``repr`` and the scalar ``summary``. SI units: N, m, J, degrees.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from snapmorph.units import status as statuses

NAN = float("nan")


class ReleasedMetrics:
    """S and theta of the released state (iii) (actuator removed), read from a result's
    ``released`` dict."""

    @property
    def S_released(self) -> float:
        """Chord (m) of the released state (iii); NaN when the released unit is not stable."""
        return float(self.released.get("S", NAN))

    @property
    def theta_released_deg(self) -> float:
        """Turning (degrees) of the released state (iii); NaN when it is not stable."""
        return float(self.released.get("theta_deg", NAN))


@dataclass(repr=False)
class UnitResultBase(ReleasedMetrics):
    """The fields every unit result has (NaN where a value does not exist).

    status: "ok", "monostable", "second state unstable: ...", "timeout: ...", "not converged:
    ..." (`units.status`); reason: why the unit is not bistable ("" when it is); bistable:
    state (iii) exists and is stable with the actuator unloaded; F_cr (N), d_cr (m): the first
    force maximum; d_unstable, d_second (m): the zero-force states (ii) and (iii); curve: the
    path (d, F); shapes: the special states' node positions; stability: negative-eigenvalue
    counts; self_standing, released: state (iii) with the actuator and supports removed
    (None / empty when not checked or not stable); solve_time (s); n_nodes."""

    geometry: object
    status: str
    bistable: bool = False
    F_cr: float = NAN
    d_cr: float = NAN
    d_unstable: float = NAN
    d_second: float = NAN
    curve: tuple = (np.zeros(0), np.zeros(0))
    shapes: dict = field(default_factory=dict)
    stability: dict = field(default_factory=dict)
    reason: str = ""
    self_standing: bool | None = None
    released: dict = field(default_factory=dict)
    solve_time: float = NAN
    n_nodes: int = 0

    #: `summary` keys of the model's own state (iii) metrics (after S and theta) and its
    #: own released or other metrics (after the released S and theta)
    STATE_KEYS: ClassVar[tuple] = ()
    MORE_KEYS: ClassVar[tuple] = ()

    @property
    def status_code(self) -> int:
        """The design-map code of ``status``: 0 ok, 1 monostable, 2 not converged,
        3 invalid geometry, 4 timeout, 5 second state unstable."""
        return statuses.status_code(self.status)

    def summary(self) -> dict:
        """The scalar metrics as a plain dict (SI)."""
        keys = ("status", "bistable", "F_cr", "d_cr", "d_unstable", "d_second", "S",
                "theta_deg", *self.STATE_KEYS, "self_standing", "S_released",
                "theta_released_deg", *self.MORE_KEYS, "reason", "solve_time", "n_nodes")
        out = {k: getattr(self, k) for k in keys}
        out.update(self._summary_details())
        return out

    def _summary_details(self) -> dict:
        """The model's per-state or per-part scalars, appended to `summary`."""
        return {}

    def __repr__(self) -> str:
        g = self.geometry
        head = (f"{type(self).__name__}({self.status.split(':')[0]!r}, L={g.L:.4g} m, "
                f"h={g.h:.4g} m, t={g.t:.4g} m, w={g.w:.4g} m, b={g.b:.4g} m")
        if self.bistable:
            rel = self.theta_released_deg
            return (f"{head}: bistable, F_cr={self.F_cr:.4g} N, S={self.S:.4g} m, "
                    f"theta={self.theta_deg:.4g} deg, released theta={rel:.4g} deg, "
                    f"{self.solve_time:.3g} s)")
        return f"{head}: not bistable ({self.reason or self.status}), F_cr={self.F_cr:.4g} N)"
