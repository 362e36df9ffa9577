"""The corpus of real target files (tests/data/targets, written by Inkscape, FreeCAD, LibreCAD,
LibreOffice and labelled synthetic ones): each is read with its visible length within 0.5 %
and the right orientation (ends, start heading, turn), or refused for the reason the manifest
gives, in one line that says why and how to choose.

Frames (tests/data/targets/README.md): SVG entries are in page mm with y down, read targets
have y up (y = -Y); DXF and CSV entries are in mm as the target is.
"""

import json
import math
import re
from pathlib import Path

import numpy as np
import pytest

from snapmorph.design.target_io import read_target_file
from snapmorph.design.targets_pieces import TargetError
from snapmorph.design.targets_scale import check_scale, unit_length_range

ROOT = Path(__file__).resolve().parents[1] / "data" / "targets"
MANIFEST = json.loads((ROOT / "manifest.json").read_text()) if (ROOT / "manifest.json").is_file() \
    else []
T, W = 0.5e-3, 5e-3  # the paper's sheet and strip: units of 50-200 mm in the default map


def _id(e):
    return e["file"] + (f"[select={e['select']}]" if e.get("select") else "")


@pytest.fixture(scope="module")
def L_range():
    from snapmorph.maps import DesignMap

    return unit_length_range(T, W, DesignMap.load())


def _read(e, L_range):
    tf = read_target_file(ROOT / e["file"], select=e.get("select"))
    check_scale(tf.length_mm * 1e-3, T, W, L_range=L_range)
    return tf


def _headings(p):
    seg = np.diff(p, axis=0)
    ang = np.arctan2(seg[:, 1], seg[:, 0])
    turn = float(np.sum((np.diff(ang) + math.pi) % (2 * math.pi) - math.pi))
    return math.degrees(ang[0]), math.degrees(turn)


def _angle_diff(a, b):
    return abs((a - b + 180.0) % 360.0 - 180.0)


def test_corpus_is_there():
    assert len(MANIFEST) >= 180
    assert sum(e["expect"] == "refuse" for e in MANIFEST) >= 30


@pytest.mark.parametrize("e", [e for e in MANIFEST if e["expect"] == "read"], ids=_id)
def test_read(e, L_range):
    tf = _read(e, L_range)
    p = tf.points * 1e3
    assert tf.length_mm == pytest.approx(e["length_mm"], rel=0.005)
    assert abs(tf.length_mm - e["length_mm"]) <= max(e["tol_mm"], 0.001 * e["length_mm"])
    start, end = np.array(e["start_mm"], float), np.array(e["end_mm"], float)
    if e["frame"] == "svg-page-mm-ydown":
        start[1], end[1] = -start[1], -end[1]
    heading, turn = _headings(p)
    want_heading, want_turn = e["start_heading_deg"], e["turn_deg"]
    forward = max(np.hypot(*(p[0] - start)), np.hypot(*(p[-1] - end)))
    if e["direction"] == "either" and forward > e["tol_mm"]:  # the reverse is allowed
        start, end = end, start
        want_heading, want_turn = want_heading + want_turn + 180.0, -want_turn
    assert np.hypot(*(p[0] - start)) <= e["tol_mm"], f"start {p[0]} vs {start}"
    assert np.hypot(*(p[-1] - end)) <= e["tol_mm"], f"end {p[-1]} vs {end}"
    assert _angle_diff(heading, want_heading) <= e["turn_tol_deg"]
    assert turn == pytest.approx(want_turn, abs=e["turn_tol_deg"])
    if "tangents" in e:
        assert (tf.tangents is not None) == e["tangents"]
        if e["tangents"]:
            assert tf.tangents[0] == pytest.approx(e["tangent_start_deg"], abs=1e-6)
            assert tf.tangents[-1] == pytest.approx(e["tangent_end_deg"], abs=1e-6)
    if e.get("insunits") in (0, None) and e["file"].endswith(".dxf"):
        assert any("taken as mm" in n for n in tf.notes), tf.notes


@pytest.mark.parametrize("e", [e for e in MANIFEST if e["expect"] == "refuse"], ids=_id)
def test_refused_with_reason(e, L_range):
    with pytest.raises(TargetError) as info:
        _read(e, L_range)
    err = info.value
    message = str(err)
    assert err.reason in [e["reason"], *e.get("reason_alt", [])], message
    assert "\n" not in message and len(message) < 600
    if err.reason not in ("no-curve", "units"):
        assert re.search(r"\d mm", message), message  # lengths said in mm
    if err.reason in ("too-short", "probably-metres"):
        assert re.match(r"target [\d.]+ mm long: shorter than the shortest unit", message)
    if err.reason == "probably-metres":
        assert "is the file in metres" in message
    if err.reason == "several-candidates":  # every candidate listed with its length
        assert "select" in message
        for c in e["candidates"]:
            lengths = [float(v) for v in re.findall(r"(\d+\.\d+) mm", message)]
            assert min(abs(v - c["length_mm"]) for v in lengths) < 0.1, (c, message)
        if e["file"].endswith(".svg"):
            assert all(c["id"] in message for c in e["candidates"])


def test_selected_candidate_is_the_one_named():
    """Every candidate of a several-candidates SVG can be selected by the id the list shows."""
    for e in MANIFEST:
        if e.get("reason") != "several-candidates" or not e["file"].endswith(".svg"):
            continue
        for c in e["candidates"]:
            tf = read_target_file(ROOT / e["file"], select=c["id"])
            assert tf.length_mm == pytest.approx(c["length_mm"], rel=0.005)


def test_dxf_candidates_by_layer_and_handle():
    """The hidden construction layer of an Inkscape DXF: refused as two candidates, read when
    the layer (or the handle the list names) is chosen."""
    f = ROOT / "dxf/inkscape/hidden_layer_arc90.r14.dxf"
    with pytest.raises(TargetError, match="Layer_1") as info:
        read_target_file(f)
    assert read_target_file(f, select="Layer_1").length_mm == pytest.approx(196.35, rel=1e-3)
    handle = re.search(r"(\w+) \w+ on layer Construction", str(info.value))
    assert handle, str(info.value)
    line = read_target_file(f, select="Construction")
    assert line.length_mm == pytest.approx(170.0, rel=1e-3)
    with pytest.raises(TargetError, match="nothing called 'Nope'") as info:
        read_target_file(f, select="Nope")
    assert info.value.reason == "not-selected"
