"""Scale sanity: unit slips and impossible lengths are refused in one line of mm that names
the likely slip; the drawing's own frame round-trips."""

import numpy as np
import pytest

from snapmorph.design.target_io import read_target_file
from snapmorph.design.targets_frame import write_in_drawing_frame, write_target_csv
from snapmorph.design.targets_pieces import TargetError
from snapmorph.design.targets_scale import LONG_FACTOR, check_scale, unit_length_range

T, W = 0.5e-3, 5e-3
L_RANGE = (0.05, 0.2)  # the default map at t = 0.5 mm, w = 5 mm


def test_unit_length_range_from_the_map(design_map):
    """t/L and w/L inside the map: L >= max(t / max t/L, w / max w/L), and so on."""
    r = design_map.ranges
    lo, hi = unit_length_range(T, W, design_map)
    assert lo == pytest.approx(max(T / r["t_over_L"][1], W / r["w_over_L"][1]))
    assert hi == pytest.approx(min(T / r["t_over_L"][0], W / r["w_over_L"][0]))
    assert unit_length_range(T, W, design_map, L_range=(0.0, lo * 1.1))[1] == pytest.approx(
        lo * 1.1)


def test_default_map_range():
    from snapmorph.maps import DesignMap

    assert unit_length_range(T, W, DesignMap.load()) == pytest.approx(L_RANGE)


@pytest.mark.parametrize("length_mm, message, reason", [
    (0.52, "target 0.52 mm long: shorter than the shortest unit the map allows at t = 0.5 mm, "
           "w = 5 mm (50.0 mm): is the file in metres (520.0 mm)?", "probably-metres"),
    (9.7, "target 9.7 mm long: .* is the file in inches (246.4 mm) or cm (97.0 mm)?",
     "too-short"),
    (0.01, "target 0.01 mm long: shorter than the shortest unit .* \\(50.0 mm\\)$", "too-short"),
    (300e3, "target 300000.0 mm long: far longer than the longest array .* is the file in mm "
            "but read as metres \\(300.0 mm\\)\\?", "too-long"),
])
def test_slips_are_one_line(length_mm, message, reason):
    with pytest.raises(TargetError) as info:
        check_scale(length_mm * 1e-3, T, W, L_range=L_RANGE)
    text = str(info.value)
    assert info.value.reason == reason
    assert "\n" not in text
    if "(" in message and "\\(" not in message:
        assert message.split(".*")[-1] in text and text.startswith(message.split(".*")[0])
    else:
        import re

        assert re.match(message, text), text


def test_lengths_an_array_can_have():
    for mm in (50.0, 300.0, 4000.0, LONG_FACTOR * 40 * 200.0):
        check_scale(mm * 1e-3, T, W, L_range=L_RANGE)
    with pytest.raises(TargetError, match="40 units"):
        check_scale(LONG_FACTOR * 40 * 0.2 * 1.01, T, W, L_range=L_RANGE)
    check_scale(LONG_FACTOR * 40 * 0.2 * 1.01, T, W, L_range=L_RANGE, max_units=41)


# ----------------------------------------------------------------------------- drawing frame
ROOT = "tests/data/targets"


def test_svg_overlay_lands_on_the_drawing(tmp_path):
    """The target written back in the SVG's frame (same page and viewBox, user units) reads
    back as the same curve; its DXF lands where Inkscape's own DXF export puts the curve."""
    from pathlib import Path

    root = Path(__file__).resolve().parents[1] / "data" / "targets"
    for name in ("svg/v092_c270.inkscape.svg", "svg/viewbox_scale2_hook.inkscape.svg",
                 "svg/mm_arc90.inkscape.svg", "svg/in_s2arc.inkscape.svg"):
        tf = read_target_file(root / name)
        shifted = tf.points + [0.01, 0.0]
        svg, dxf = write_in_drawing_frame(tf.frame, {"target": tf.points, "predicted": shifted},
                                          tmp_path / name.split("/")[1])
        again = read_target_file(svg, select="target")
        assert np.allclose(again.points, tf.points, atol=1e-8), name
        assert np.allclose(read_target_file(svg, select="predicted").points, shifted, atol=1e-8)
        assert read_target_file(dxf, select="TARGET").length_mm == pytest.approx(tf.length_mm,
                                                                                 rel=1e-6)
    own = read_target_file(root / "dxf/inkscape/mm_arc90.r14.dxf")
    tf = read_target_file(root / "svg/mm_arc90.inkscape.svg")
    _, dxf = write_in_drawing_frame(tf.frame, {"target": tf.points}, tmp_path / "again")
    back = read_target_file(dxf)
    assert np.allclose(back.points[[0, -1]], own.points[[0, -1]], atol=1e-6)


def test_dxf_overlay_keeps_the_drawing_unit(tmp_path):
    from pathlib import Path

    root = Path(__file__).resolve().parents[1] / "data" / "targets"
    tf = read_target_file(root / "dxf/synthetic/insunits_1_inch.dxf")
    svg, dxf = write_in_drawing_frame(tf.frame, {"target": tf.points}, tmp_path)
    import ezdxf

    doc = ezdxf.readfile(dxf)
    assert doc.header["$INSUNITS"] == 1
    assert np.allclose(read_target_file(dxf).points, tf.points, atol=1e-9)
    view = read_target_file(svg).points  # an SVG in mm, its page the bounding box
    assert np.allclose(view - view[0], tf.points - tf.points[0], atol=1e-8)
    csv = write_target_csv(tf.points, tmp_path / "target.csv")
    assert np.allclose(read_target_file(csv).points, tf.points, atol=1e-8)
