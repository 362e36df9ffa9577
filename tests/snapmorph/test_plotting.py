"""Figures checked as a reader would, automatically: every panel has axis labels with units,
every drawn mark has a legend entry, colours come from the colour-blind-safe palette, shape
plots keep their true aspect ratio (the mm axes are their scale).

Each plotting function is run for real; `Figure.savefig` is wrapped so the figure is inspected
just before it is written.
"""

from __future__ import annotations

import math

import matplotlib

matplotlib.use("Agg")
import matplotlib.colors as mcolors  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

from snapmorph.plotting.arrays import OKABE_ITO  # noqa: E402

SAFE = {mcolors.to_hex(c) for c in OKABE_ITO.values()}


def _is_grey(colour) -> bool:
    r, g, b, _ = mcolors.to_rgba(colour)
    return abs(r - g) < 1e-6 and abs(g - b) < 1e-6


def _style(line):
    return (mcolors.to_hex(line.get_color()), line.get_linestyle(), line.get_marker())


def _covered(style, legend_styles) -> bool:
    """A mark is explained by the legend: the same handle, or (a factored legend) its colour
    in one entry and its line style in another."""
    if style in legend_styles:
        return True
    colour, ls, marker = style
    if marker not in ("None", "", None):
        return False
    return (any(c == colour for c, _, _ in legend_styles)
            and any(l == ls for _, l, m in legend_styles if m in ("None", "", None)))


def problems(fig) -> list:
    """What a reader would miss in `fig` (empty when it is fine)."""
    out = []
    legend_styles, legend_labels = set(), []
    legends = [ax.get_legend() for ax in fig.axes if ax.get_legend()] + list(fig.legends)
    for lg in legends:
        for h, t in zip(lg.legend_handles, lg.get_texts()):
            legend_labels.append(t.get_text())
            if hasattr(h, "get_color") and hasattr(h, "get_linestyle"):
                legend_styles.add(_style(h))
    for k, ax in enumerate(fig.axes):
        if not ax.axison or ax.get_label() == "<colorbar>":
            continue
        data_lines = [ln for ln in ax.lines if ln.get_transform() == ax.transData]
        if not data_lines and not ax.collections:
            continue
        first_col = ax.get_subplotspec() is None or ax.get_subplotspec().is_first_col()
        last_row = ax.get_subplotspec() is None or ax.get_subplotspec().is_last_row()
        if last_row and "(" not in ax.get_xlabel():
            out.append(f"axes {k}: x label without a unit: {ax.get_xlabel()!r}")
        if first_col and "(" not in ax.get_ylabel() and ax.get_yticks().size:
            out.append(f"axes {k}: y label without a unit: {ax.get_ylabel()!r}")
        for ln in data_lines:
            colour = mcolors.to_hex(ln.get_color())
            if colour not in SAFE and not _is_grey(colour):
                out.append(f"axes {k}: colour {colour} is not in the colour-blind-safe palette")
            if not _covered(_style(ln), legend_styles) and not _is_grey(colour):
                out.append(f"axes {k}: a mark {_style(ln)} has no legend entry")
    if not legends:
        out.append("no legend")
    return out


@pytest.fixture
def inspected(monkeypatch):
    """The problems of every figure saved while the test runs: {file name: [problems]}."""
    found = {}
    original = Figure.savefig

    def savefig(self, fname, *a, **kw):
        found[str(fname).rsplit("/", 1)[-1]] = problems(self)
        return original(self, fname, *a, **kw)

    monkeypatch.setattr(Figure, "savefig", savefig)
    return found


def _units():
    from snapmorph.design import Unit

    return [Unit(L=0.1, h=0.02, t=5e-4, w=5e-3, side=1), Unit(L=0.06, h=0.0, t=5e-4, w=5e-3),
            Unit(L=0.1, h=0.02, t=5e-4, w=5e-3, side=-1)]


def test_fk_figures(tmp_path, inspected):
    from snapmorph.design import all_snap_patterns as all_states
    from snapmorph.design import chain
    from snapmorph.design.lookup import MapLookup
    from snapmorph.maps import DesignMap
    from snapmorph.plotting.arrays import plot_fk_state, plot_fk_states
    from tests.design import synthetic_map

    dm = DesignMap.load(synthetic_map.write(tmp_path / "s.nc"))
    units = _units()
    pl = (0.01, 0.02, math.radians(30))
    target = np.array([[0.0, 0.0], [0.1, 0.05], [0.2, 0.0]])
    ch = chain(units, [True, False, True], lookup=MapLookup(dm), start=pl[:2], start_angle=pl[2])
    plot_fk_state(ch.xy, ch.joints, tmp_path / "one.png", title="t", target=target, placement=pl)
    states = all_states(units, design_map=dm)
    plot_fk_states(states, tmp_path / "all.png", title="t", target=target)
    assert set(inspected) == {"one.png", "all.png"}
    for name, p in inspected.items():
        assert not p, (name, p)


def test_array_figures(tmp_path, inspected):
    from snapmorph.design.array_plots import plot_result, plot_study
    from snapmorph.design.array_study import run_study
    from snapmorph.design.arrays import simulate_array

    units = _units()
    r = simulate_array(units, "100", nodes=41)
    plot_result(r, tmp_path / "one.png", fk=r.base, placement=(0.0, 0.0, 0.5),
                target=np.array([[0.0, 0.0], [0.1, 0.1]]))
    s = run_study(units[:1], name="one unit", nodes=41)
    plot_study(s, tmp_path / "study.png", title="one unit")
    for name, p in inspected.items():
        assert not p, (name, p)


def test_unit_figure(tmp_path, inspected):
    from snapmorph.plotting.unit import plot_unit
    from snapmorph.units import UnitGeometry, simulate_unit

    plot_unit(simulate_unit(UnitGeometry(L=0.1, h=0.02, t=5e-4, w=5e-3), nodes=61),
              tmp_path / "unit.png")
    assert not inspected["unit.png"], inspected["unit.png"]


def test_problems_catches_what_a_reader_misses():
    """The checker itself can fail: no labels, a non-palette colour, a mark without legend."""
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots()
    ax.plot([0, 1], [0, 1], color="red")
    found = " | ".join(problems(fig))
    plt.close(fig)
    for text in ("x label without a unit", "y label without a unit", "colour-blind",
                 "no legend entry", "no legend"):
        assert text in found, text


def test_maps_figure(tmp_path, inspected):
    from types import SimpleNamespace

    from snapmorph import figures_maps
    from tests.design import synthetic_map

    path = synthetic_map.write(tmp_path / "s.nc")
    figures_maps.make(str(tmp_path), SimpleNamespace(map=str(path)))
    assert not inspected["design_maps.png"], inspected["design_maps.png"]


def test_specimens_figure(tmp_path, inspected):
    from snapmorph import figures_specimens

    figures_specimens.make(str(tmp_path))
    assert not inspected["specimens_forcedef.png"], inspected["specimens_forcedef.png"]
