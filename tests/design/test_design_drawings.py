"""Fabrication drawings: clean DXF, closed outlines, dimensions matching the unit table."""

import math
import xml.etree.ElementTree as ET

import ezdxf
import numpy as np
import pytest
from scipy.integrate import quad

from snapmorph.design.drawings import developed_length, split_pieces, write_drawings

from five_units import FIVE as UNITS, T, W


@pytest.fixture(scope="module")
def drawings(tmp_path_factory):
    out = tmp_path_factory.mktemp("drawings")
    paths = write_drawings(UNITS, out, bed_length_mm=300.0, colours={"CUT": 2})
    return {p.name: p for p in paths}


def _polylines(doc, layer):
    return [e for e in doc.modelspace().query("LWPOLYLINE") if e.dxf.layer == layer]


def _texts(doc, layer=None):
    return [e.dxf.text for e in doc.modelspace().query("TEXT")
            if layer is None or e.dxf.layer == layer]


def _bbox(points):
    p = np.asarray(points)
    return p.min(axis=0), p.max(axis=0)


@pytest.mark.parametrize("name", ["base.dxf", "arches.dxf", "molds.dxf"])
def test_dxf_clean(drawings, name):
    doc = ezdxf.readfile(drawings[name])
    auditor = doc.audit()
    assert not auditor.errors and not auditor.fixes
    assert doc.dxfversion >= "AC1015"
    assert doc.header["$INSUNITS"] == 4  # millimetres
    assert {"CUT", "ENGRAVE", "MARKS"} <= {layer.dxf.name for layer in doc.layers}
    assert doc.layers.get("CUT").color == 2  # configured
    assert doc.layers.get("ENGRAVE").color == 5  # default
    cuts = _polylines(doc, "CUT")
    assert cuts
    for pl in cuts:
        assert pl.closed
        pts = np.array([p[:2] for p in pl.get_points()])
        closed = np.vstack([pts, pts[:1]])
        seg = np.hypot(*np.diff(closed, axis=0).T)
        assert seg.min() > 1e-6, "zero-length segment or duplicate vertex"
        assert len({tuple(np.round(p, 9)) for p in pts}) == len(pts), "duplicate vertex"


def test_base_dimensions(drawings):
    doc = ezdxf.readfile(drawings["base.dxf"])
    cuts = [np.array([p[:2] for p in pl.get_points()]) for pl in _polylines(doc, "CUT")]
    sizes = sorted((np.ptp(c[:, 0]), np.ptp(c[:, 1])) for c in cuts)
    outer = [s for s in sizes if s[1] == pytest.approx(4 * W * 1e3)]
    holes = [s for s in sizes if s[1] == pytest.approx(2 * W * 1e3)]
    assert len(outer) == 2  # split in two pieces for a 300 mm bed
    assert sum(s[0] for s in outer) == pytest.approx(sum(u.L for u in UNITS) * 1e3, abs=1e-6)
    assert all(s[0] <= 300.0 for s in outer)
    want = sorted((u.L - 2 * (u.b + u.w)) * 1e3 for u in UNITS if not u.is_spacer)
    assert sorted(s[0] for s in holes) == pytest.approx(want, abs=1e-6)
    texts = _texts(doc, "ENGRAVE")
    for label in ("1+", "2+", "3", "4+", "5-"):
        assert label in texts
    assert texts.count("J1") == 2  # the joint is marked on both pieces
    boundaries = [pl for pl in _polylines(doc, "ENGRAVE")]
    assert len(boundaries) == len(UNITS) - 2  # interior boundaries, minus the one at the joint


def test_split_pieces():
    assert split_pieces(UNITS, None) == [(0, 5)]
    assert split_pieces(UNITS, 300.0) == [(0, 3), (3, 5)]
    assert split_pieces(UNITS, 150.0) == [(0, 2), (2, 3), (3, 4), (4, 5)]
    with pytest.raises(ValueError, match="longer than the bed"):
        split_pieces(UNITS, 100.0)


def test_arch_blanks(drawings):
    doc = ezdxf.readfile(drawings["arches.dxf"])
    cuts = [np.array([p[:2] for p in pl.get_points()]) for pl in _polylines(doc, "CUT")]
    arched = [u for u in UNITS if not u.is_spacer]
    assert len(cuts) == len(arched)
    for u, c in zip(arched, cuts):
        la = u.L - 2 * (u.b + u.w)
        slope = lambda x: math.sqrt(1 + (math.pi * u.h / la * math.sin(2 * math.pi * x / la)) ** 2)  # noqa: E731
        want = 2 * (u.b + u.w) + quad(slope, 0, la, epsabs=1e-13)[0]
        assert developed_length(u) == pytest.approx(want, rel=1e-9)
        assert np.ptp(c[:, 0]) == pytest.approx(want * 1e3, abs=1e-6)
        assert np.ptp(c[:, 1]) == pytest.approx(u.w * 1e3, abs=1e-9)
    texts = _texts(doc, "ENGRAVE")
    assert texts == ["1+", "2+", "4+", "5-"]


def test_molds(drawings):
    doc = ezdxf.readfile(drawings["molds.dxf"])
    cuts = [np.array([p[:2] for p in pl.get_points()]) for pl in _polylines(doc, "CUT")]
    arched = [u for u in UNITS if not u.is_spacer]
    assert len(cuts) == len(arched)
    boxes = []
    for u, c in zip(arched, cuts):
        lo, hi = _bbox(c)
        assert hi[0] - lo[0] == pytest.approx(u.L * 1e3, abs=1e-6)
        # apex of the lower face at h - t/2 above the flat ends' centreline, block 5 mm below
        assert hi[1] - lo[1] == pytest.approx(u.h * 1e3 + 5.0, abs=1e-3)
        boxes.append((lo, hi))
    for (lo1, hi1), (lo2, hi2) in zip(boxes, boxes[1:]):
        assert hi2[1] < lo1[1]  # parts do not overlap


def test_svg(drawings):
    for name in ("base.svg", "arches.svg", "molds.svg"):
        root = ET.parse(drawings[name]).getroot()
        assert root.get("width").endswith("mm")
        ids = {g.get("id") for g in root.iter("{http://www.w3.org/2000/svg}g")}
        assert ids == {"CUT", "ENGRAVE", "MARKS"}
    root = ET.parse(drawings["base.svg"]).getroot()
    polys = list(root.iter("{http://www.w3.org/2000/svg}polygon"))
    assert len(polys) == 2 + 4  # two pieces, four holes
