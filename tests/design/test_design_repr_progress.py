"""Short reprs (issue 15) and the progress callback of inverse_design (the CLI's tqdm bar)."""

import numpy as np
import pytest

from snapmorph.design import Unit, chain, inverse_design
from snapmorph.design.lookup import MapLookup
from snapmorph.solver import Structure

T, W = 0.5e-3, 5e-3
BARRIER = {"min_barrier": 0.0}  # the synthetic map's barrier is not physical
KNOWN = [Unit(L=0.10, h=0.020, t=T, w=W, side=1), Unit(L=0.12, h=0.030, t=T, w=W, side=-1)]


@pytest.fixture(scope="module")
def pts(design_map):
    return chain(KNOWN, None, lookup=MapLookup(design_map)).xy[::12]


def test_design_repr_short_and_progress_called(design_map, pts):
    stages = []
    d = inverse_design(pts, t=T, w=W, design_map=design_map, **BARRIER, controls=[0.1],
                       refine=True, progress=stages.append)
    text = repr(d)
    assert len(text) < 300 and "arched units" in text and "mm" in text
    assert stages[0] == "design"
    # one call per least-squares evaluation of the refinement (each counted in nfev or r0)
    assert stages.count("refine") >= d.refinement["nfev"]


def test_progress_must_be_callable(design_map, pts):
    with pytest.raises(ValueError, match="progress"):
        inverse_design(pts, t=T, w=W, design_map=design_map, progress=3)


def test_rod_repr_short():
    x = np.linspace(0.0, 0.1, 401)
    rod = Structure().add_rod(np.stack([x, 0.01 * np.sin(np.pi * x / 0.1)], axis=1),
                              width=5e-3, thickness=5e-4, E=2.2e9)
    text = repr(rod)
    assert len(text) < 200 and "401" in text and "E=2.2e+09 Pa" in text
