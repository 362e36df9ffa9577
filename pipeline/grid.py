"""The (h/L, t/L, w/L) grid of a design map, its validation and the named presets.

All values are dimensionless (lengths over the base length L). Points are numbered in C order
over (h, t, w): index = (i_h * n_t + i_t) * n_w + i_w.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from snapmorph.pipeline.schema import DEFAULT_SAMPLES

# Valid ranges: (low, high, low inclusive, high inclusive). The arch needs room between its
# flat ends, 2 (b + w) < L, which is checked jointly below.
_RANGES = {
    "h_over_L": (0.0, 1.0, False, True),
    "t_over_L": (0.0, 0.05, False, True),
    "w_over_L": (0.0, 0.5, False, False),
}

#: solver resolution (`nodes` of `solver.unit.simulate_unit`) of a Grid unless given;
#: None = the solver's converged default, resolved and recorded when a build starts
PRESET_RESOLUTION = None
#: resolution of the `default` preset: the solver's converged default (None). An earlier
#: solver had F_cr dips of ~3 % between w/L = 0.02 and 0.03 (a roller moved by half an edge
#: where 0.03 L met b + w) and a parabola-fitted F_cr, which pinned this to 161 nodes; both
#: are fixed, see the accuracy figures in the issue notes (`make maps-accuracy`).
DEFAULT_MAP_RESOLUTION = None
MIN_RESOLUTION = 5


def _range_text(name: str) -> str:
    lo, hi, lo_in, hi_in = _RANGES[name]
    return f"{lo} {'<=' if lo_in else '<'} {name} {'<=' if hi_in else '<'} {hi}"


def _axis(name: str, values) -> tuple[float, ...]:
    """Validate one axis: finite, strictly increasing, at least 2 values, inside its range."""
    try:
        arr = np.asarray(values, dtype=float).ravel()
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a sequence of numbers, got {values!r}") from None
    if arr.size < 2:
        raise ValueError(f"{name} needs at least 2 values (got {arr.size}): a map interpolates")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} values must be finite, got {arr.tolist()}")
    if np.any(np.diff(arr) <= 0):
        raise ValueError(f"{name} values must be strictly increasing, got {arr.tolist()}")
    lo, hi, lo_in, hi_in = _RANGES[name]
    bad = arr[(arr < lo) | (arr > hi) | ((arr == lo) & (not lo_in)) | ((arr == hi) & (not hi_in))]
    if bad.size:
        raise ValueError(f"{name} = {float(bad[0])!r} is outside the valid range {_range_text(name)}")
    return tuple(float(v) for v in arr)


@dataclass(frozen=True)
class Grid:
    """A design-map grid.

    h_over_L, t_over_L, w_over_L: axis values (dimensionless, strictly increasing, >= 2 each);
    b_over_L: extra flat length of the arch ends / L (0 in the paper's study);
    resolution: solver `nodes` parameter (None = the solver's converged default);
    samples: number M of base-shape samples; name: preset name or "custom".
    """

    h_over_L: tuple
    t_over_L: tuple
    w_over_L: tuple
    b_over_L: float = 0.0
    resolution: int | None = PRESET_RESOLUTION
    samples: int = DEFAULT_SAMPLES
    name: str = "custom"

    def __post_init__(self):
        for name in ("h_over_L", "t_over_L", "w_over_L"):
            object.__setattr__(self, name, _axis(name, getattr(self, name)))
        b = self.b_over_L
        if not isinstance(b, (int, float, np.floating, np.integer)) or not np.isfinite(b) or b < 0:
            raise ValueError(f"b_over_L must be a finite number >= 0, got {b!r}")
        object.__setattr__(self, "b_over_L", float(b))
        w_max = self.w_over_L[-1]
        if self.b_over_L + w_max >= 0.5:
            raise ValueError(
                f"b_over_L + w_over_L must be < 0.5 (the sinusoidal part needs L - 2(b + w) > 0); "
                f"got b_over_L = {self.b_over_L} with largest w_over_L = {w_max}, "
                f"so b_over_L must be < {0.5 - w_max:g}"
            )
        r = self.resolution
        if r is not None:
            if isinstance(r, bool) or not isinstance(r, (int, np.integer)) or r < MIN_RESOLUTION:
                raise ValueError(f"resolution must be None or an integer >= {MIN_RESOLUTION}, got {r!r}")
            object.__setattr__(self, "resolution", int(r))
        s = self.samples
        if isinstance(s, bool) or not isinstance(s, (int, np.integer)) or s < 2:
            raise ValueError(f"samples must be an integer >= 2, got {s!r}")
        object.__setattr__(self, "samples", int(s))

    @property
    def dims(self) -> tuple[str, str, str]:
        """The map's grid dimensions, in storage order."""
        return ("h_over_L", "t_over_L", "w_over_L")

    @property
    def axes(self) -> dict:
        """{dimension: values}, in storage order (the interface shared with `MapGrid`)."""
        return {d: getattr(self, d) for d in self.dims}

    @property
    def options(self) -> dict:
        """The model options passed to the point solver (resolution None = solver default)."""
        return {"b_over_L": self.b_over_L, "resolution": self.resolution, "samples": self.samples}

    @property
    def shape(self) -> tuple[int, int, int]:
        """(n_h, n_t, n_w)."""
        return (len(self.h_over_L), len(self.t_over_L), len(self.w_over_L))

    @property
    def size(self) -> int:
        """Number of points."""
        n_h, n_t, n_w = self.shape
        return n_h * n_t * n_w

    def points(self) -> np.ndarray:
        """(size, 3) array of (h/L, t/L, w/L), in C order over (h, t, w)."""
        h, t, w = np.meshgrid(self.h_over_L, self.t_over_L, self.w_over_L, indexing="ij")
        return np.column_stack([h.ravel(), t.ravel(), w.ravel()])

    def to_dict(self) -> dict:
        """JSON-ready description (exact floats survive a JSON round trip)."""
        return {
            "name": self.name,
            "h_over_L": list(self.h_over_L),
            "t_over_L": list(self.t_over_L),
            "w_over_L": list(self.w_over_L),
            "b_over_L": self.b_over_L,
            "resolution": self.resolution,
            "samples": self.samples,
        }

    @classmethod
    def from_dict(cls, d: dict) -> "Grid":
        return cls(**d)

    def with_resolution(self, resolution: int | None) -> "Grid":
        """The same grid at another solver resolution."""
        d = self.to_dict()
        d["resolution"] = resolution
        return Grid.from_dict(d)


def _lin(lo: float, hi: float, n: int) -> tuple[float, ...]:
    # Rounded so that e.g. 0.05 + 3 * 0.01 is stored as 0.08, not 0.08000000000000002.
    return tuple(float(round(v, 12)) for v in np.linspace(lo, hi, n))


def _preset_default() -> Grid:
    # 46 x 9 x 9 = 3726 points; steps 0.01, 0.00125, 0.01 put the paper's t/L = 0.005, 0.0075
    # and w/L = 0.05 exactly on the grid.
    return Grid(
        h_over_L=_lin(0.05, 0.50, 46),
        t_over_L=_lin(0.0025, 0.0125, 9),
        w_over_L=_lin(0.02, 0.10, 9),
        resolution=DEFAULT_MAP_RESOLUTION,
        name="default",
    )


def _preset_ci() -> Grid:
    # 4 x 3 x 2 = 24 points; h/L = 0.10 is monostable in the paper's model (Table 1, h = 10 mm).
    return Grid(
        h_over_L=(0.10, 0.20, 0.30, 0.40),
        t_over_L=(0.005, 0.0075, 0.01),
        w_over_L=(0.04, 0.06),
        name="ci",
    )


PRESETS = {"default": _preset_default, "ci": _preset_ci}


def preset(name: str) -> Grid:
    """The named preset grid ("default" or "ci")."""
    try:
        return PRESETS[name]()
    except KeyError:
        raise ValueError(f"grid must be one of {sorted(PRESETS)}, got {name!r}") from None
