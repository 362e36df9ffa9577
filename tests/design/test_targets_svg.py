"""SVG targets on small hand-made documents: units, transforms, path syntax, what is not
drawn, pieces chained, candidates."""

import math

import numpy as np
import pytest

from snapmorph.design.target_io import read_target, read_target_file
from snapmorph.design.targets_pieces import TargetError

NS = 'xmlns="http://www.w3.org/2000/svg"'
INK = 'xmlns:inkscape="http://www.inkscape.org/namespaces/inkscape"'
MM_PER_PX = 25.4 / 96


def _svg(tmp_path, body, root='width="200mm" height="100mm" viewBox="0 0 200 100"', name="t.svg"):
    f = tmp_path / name
    f.write_text(f"<svg {NS} {INK} {root}>{body}</svg>")
    return f


def _length_mm(points):
    return float(np.sum(np.hypot(*np.diff(points, axis=0).T))) * 1e3


@pytest.mark.parametrize("root, mm_per_user", [
    ('width="200mm" height="100mm" viewBox="0 0 200 100"', 1.0),
    ("", MM_PER_PX),  # no width, no viewBox: user units are px (96 per inch)
    ('width="200mm" height="100mm"', MM_PER_PX),  # a size but no viewBox: still px
    ('width="8in" height="4in" viewBox="0 0 8 4"', 25.4),
    ('width="20cm" height="10cm" viewBox="0 0 20 10"', 10.0),
    ('width="576pt" height="288pt" viewBox="0 0 576 288"', 25.4 / 72),
    ('width="0.2m" height="0.1m" viewBox="0 0 0.2 0.1"', 1000.0),  # Inkscape's metre document
    ('width="210mm" height="297mm" viewBox="0 0 793.70079 1122.5197"', MM_PER_PX),  # 0.92 style
])
def test_document_units(tmp_path, root, mm_per_user):
    f = _svg(tmp_path, '<path d="M 0 3 L 4 3"/>', root)
    pts, tangents = read_target(f)
    assert tangents is None
    assert _length_mm(pts) == pytest.approx(4 * mm_per_user, rel=1e-5)
    assert pts[0, 1] * 1e3 == pytest.approx(-3 * mm_per_user, rel=1e-5)  # y flipped


def test_ancestor_transforms(tmp_path):
    """Layer translate, group scale 1.5, a flip and a rotation all apply (the issue's 349 mm
    instead of 524 mm, the un-mirrored flip)."""
    arc = '<path id="a" d="M 10 50 A 40 40 0 0 1 50 10"/>'  # quarter circle, bends right on screen
    plain = read_target(_svg(tmp_path, arc, name="plain.svg"))[0]
    scaled = read_target(_svg(tmp_path, f'<g transform="translate(5,7)"><g transform="scale(1.5)">'
                                        f'{arc}</g></g>', name="scaled.svg"))[0]
    assert _length_mm(plain) == pytest.approx(20 * math.pi, rel=1e-5)
    assert _length_mm(scaled) == pytest.approx(1.5 * 20 * math.pi, rel=1e-5)
    assert scaled[0] * 1e3 == pytest.approx([5 + 15, -(7 + 75)], abs=1e-6)
    flipped = read_target(_svg(tmp_path, f'<g transform="matrix(-1,0,0,1,200,0)">{arc}</g>',
                               name="flip.svg"))[0]
    assert flipped[:, 0] * 1e3 == pytest.approx(200 - plain[:, 0] * 1e3, abs=1e-6)
    rotated = read_target(_svg(tmp_path, f'<g transform="rotate(90)">{arc}</g>',
                               name="rot.svg"))[0]
    assert rotated[0] * 1e3 == pytest.approx([-50, -10], abs=1e-6)  # (x, y) -> (-y, x), y down


def test_compact_arc_flags_and_relative_commands(tmp_path):
    spaced = read_target(_svg(tmp_path, '<path d="M 10 50 a 20 20 0 0 1 40 0 a 20 20 0 0 0 40 0"/>',
                              name="a.svg"))[0]
    packed = read_target(_svg(tmp_path, '<path d="M10 50a20 20 0 0140 0 20 20 0 0040 0"/>',
                              name="b.svg"))[0]
    assert np.allclose(spaced, packed)
    assert _length_mm(packed) == pytest.approx(40 * math.pi, rel=1e-5)


def test_not_drawn_is_not_read(tmp_path):
    """Paths in <defs>, markers, symbols, clip paths and hidden layers are no candidates."""
    body = ('<defs><path id="d" d="M 0 0 L 90 0"/>'
            '<marker id="m"><path d="M 0 0 L 5 5"/></marker>'
            '<clipPath id="c"><path d="M 0 0 L 100 100"/></clipPath></defs>'
            '<symbol id="s"><path d="M 0 0 L 70 0"/></symbol>'
            '<g style="display:none"><path id="hidden" d="M 0 90 L 150 90"/></g>'
            '<path id="target" d="M 10 10 L 110 10" style="marker-end:url(#m)"/>')
    tf = read_target_file(_svg(tmp_path, body))
    assert tf.length_mm == pytest.approx(100.0)
    assert "target" in tf.source


def test_use_clone_is_read_where_it_is_drawn(tmp_path):
    body = ('<defs><path id="src" d="M 10 10 L 60 10"/></defs>'
            '<use id="clone" href="#src" transform="translate(5,20)"/>')
    tf = read_target_file(_svg(tmp_path, body))
    assert tf.points[0] * 1e3 == pytest.approx([15, -30])
    assert read_target_file(_svg(tmp_path, body), select="clone").length_mm == pytest.approx(50)


def test_pieces_are_chained_in_the_first_ones_direction(tmp_path):
    """Two paths and a subpath: the second path runs backwards from the far end."""
    body = ('<path id="p1" d="M 0 50 L 50 50 M 50 50 L 50 20"/>'
            '<path id="p2" d="M 100 20 L 50.01 20"/>')
    tf = read_target_file(_svg(tmp_path, body))
    assert tf.length_mm == pytest.approx(50 + 30 + 49.99, abs=0.02)
    assert tf.points[0] * 1e3 == pytest.approx([0, -50])
    assert tf.points[-1] * 1e3 == pytest.approx([100, -20])
    assert any("3 pieces joined" in n for n in tf.notes)


def test_candidates_listed_and_selected(tmp_path):
    body = ('<g id="layer1" inkscape:groupmode="layer" inkscape:label="Target">'
            '<path id="curveA" d="M 0 0 L 100 0"/></g>'
            '<g id="layer2" inkscape:groupmode="layer" inkscape:label="Construction">'
            '<path id="curveB" d="M 0 50 L 40 50"/><rect x="0" y="0" width="190" height="90"/></g>')
    f = _svg(tmp_path, body)
    with pytest.raises(TargetError) as info:
        read_target(f)
    message = str(info.value)
    assert info.value.reason == "several-candidates"
    assert "curveA" in message and "100.00 mm" in message
    assert "curveB" in message and "40.00 mm" in message
    assert "\n" not in message
    assert read_target_file(f, select="curveB").length_mm == pytest.approx(40)
    assert read_target_file(f, select="layer Target").length_mm == pytest.approx(100)
    assert read_target_file(f, select="layer1").length_mm == pytest.approx(100)
    with pytest.raises(TargetError, match="nothing called 'curveC'.*curveA"):
        read_target(f, select="curveC")


@pytest.mark.parametrize("body, reason", [
    ('<circle cx="50" cy="50" r="20"/><path d="M 0 0 L 10 0 L 10 10 Z"/>', "closed"),
    ('<path d="M 0 0 L 10 0 L 10 10 L 0 0"/>', "closed"),  # ends meet without a Z
    ('<text x="0" y="0">no curve</text>', "no-curve"),
    ('<path d="M 0 0 L 50 0"/><path d="M 50 0 L 50 50"/><path d="M 50 0 L 100 0"/>', "branched"),
])
def test_refusals(tmp_path, body, reason):
    with pytest.raises(TargetError) as info:
        read_target(_svg(tmp_path, body))
    assert info.value.reason == reason


def test_units_are_the_documents(tmp_path):
    with pytest.raises(TargetError, match="carries its own units"):
        read_target(_svg(tmp_path, '<path d="M 0 0 L 50 0"/>'), units="mm")
    broken = tmp_path / "broken.svg"
    broken.write_text("<svg><path d='M 0 0 L")
    with pytest.raises(TargetError, match="not a readable SVG"):
        read_target(broken)
