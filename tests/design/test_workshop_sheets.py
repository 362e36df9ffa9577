"""Workshop sheets: nesting on a bed (parts inside, not overlapping, MARKS too), the path checks
that run before writing, overlap tabs at the joints, kerf compensation, the bed warning."""

import warnings

import ezdxf
import numpy as np
import pytest

from snapmorph.design.drawing_checks import check_layout, check_paths, part_boxes
from snapmorph.design.drawings import (BedWarning, Entity, Sheet, arch_sheet, base_sheet,
                                       split_pieces, tab_ends, tab_face, tab_sheet,
                                       write_drawings)
from snapmorph.design.kerf import compensate, offset_polygon, signed_area
from snapmorph.design.nesting import nest_parts, oversize, parse_bed, parts_of

from five_units import FIVE, T, W
LONG = FIVE * 3  # 1429 mm of strip


def test_parse_bed():
    assert parse_bed("600x400") == (600.0, 400.0)
    assert parse_bed("600 X 400") == (600.0, 400.0)
    assert parse_bed((300, 200)) == (300.0, 200.0)
    assert parse_bed("600") == (600.0, None)
    for bad in ("600x", "axb", "0x400", "600x-4", "1x2x3"):
        with pytest.raises(ValueError, match="WIDTHxHEIGHT"):
            parse_bed(bad)


@pytest.mark.parametrize("bed", [(600, 400), (400, 300), (300, 600), (250, 250)])
def test_nested_sheets_inside_and_not_overlapping(bed):
    bed_length = max(bed) - 10
    sheets_in = [base_sheet(LONG, bed_length), tab_sheet(LONG, bed_length), arch_sheet(LONG)]
    parts = parts_of(*sheets_in)
    sheets = nest_parts(parts, bed)
    assert sum(len(s.parts) for s in sheets) == len(parts)  # every part placed once
    for s in sheets:
        assert check_layout(s, bed) == []
        boxes = part_boxes(s)
        for x0, y0, x1, y1 in boxes.values():  # the checker's own arithmetic, once more
            assert 0 <= x0 and 0 <= y0 and x1 <= bed[0] and y1 <= bed[1]
        names = list(boxes)
        for i, a in enumerate(names):
            for b in names[i + 1:]:
                A, B = boxes[a], boxes[b]
                assert A[2] <= B[0] or B[2] <= A[0] or A[3] <= B[1] or B[3] <= A[1], (a, b)
        assert check_paths(s) == []
    # part sizes survive (turned or not)
    before = {n: sorted(np.ptp(np.vstack([e.points for e in ents if not e.text]), axis=0))
              for n, ents in parts if any(not e.text for e in ents)}
    after = {}
    for s in sheets:
        for n, idx in s.parts.items():
            if all(s.entities[i].text for i in idx):
                continue
            after[n] = sorted(np.ptp(np.vstack([s.entities[i].points for i in idx
                                                if not s.entities[i].text]), axis=0))
    for n in before:  # texts alone (notes) have no outline to compare
        assert after[n] == pytest.approx(before[n])


def test_checker_finds_what_it_should():
    """An overlap, a part off the sheet, an open cut, a line drawn twice, a zero segment."""
    s = Sheet("bad")
    square = np.array([[0, 0], [10, 0], [10, 10], [0, 10]], float)
    s.add("a", Entity("CUT", square, True))
    s.add("b", Entity("CUT", square + 5, True))
    s.add("c", Entity("CUT", square + [95, 0], True))
    s.add("d", Entity("CUT", np.array([[20, 20], [30, 20], [30, 30]], float)))
    s.add("e", Entity("ENGRAVE", np.array([[0, 0], [10, 0]], float)))  # on a's edge
    s.add("f", Entity("ENGRAVE", np.array([[40, 40], [40, 40], [50, 40]], float)))
    s.add("g", Entity("MARKS", np.array([[80, 95.0]]), text="a note that runs off", height=3.0))
    layout = check_layout(s, (100, 100))
    assert any("a and b overlap" in p for p in layout)
    assert any(p.startswith("c ") and "not inside" in p for p in layout)
    assert any(p.startswith("g ") and "not inside" in p for p in layout)  # the text box
    paths = check_paths(s)
    assert any("d (CUT): open cut path" in p for p in paths)
    assert any("drawn twice (also in a (CUT))" in p for p in paths)
    assert any("zero-length segment" in p for p in paths)


def test_split_strip_gets_overlap_tabs():
    """Split where both neighbours leave a face free; each joint has a tab over both solid
    end regions, on the free face."""
    assert split_pieces(FIVE, 300.0) == [(0, 3), (3, 5)]
    assert tab_face(FIVE[2], FIVE[3]) == -1  # spacer | arch on +: the - face is free
    assert tab_face(FIVE[3], FIVE[4]) is None  # + | -: no face free
    assert tab_face(FIVE[4], FIVE[4]) == 1
    assert tab_ends(FIVE[2], FIVE[3]) == pytest.approx((W, W))  # the spacer side as the other
    assert tab_ends(FIVE[3], FIVE[4]) == pytest.approx((W, W + 2e-3))
    tabs = tab_sheet(FIVE, 300.0)
    assert list(tabs.parts) == ["tab 1"]
    rect = [e for e in tabs.entities if e.layer == "CUT"][0].points
    assert np.ptp(rect[:, 0]) == pytest.approx(2 * W * 1e3)
    assert np.ptp(rect[:, 1]) == pytest.approx(4 * W * 1e3)
    assert any("across J1, - face" in e.text for e in tabs.entities)
    assert tab_sheet(FIVE, None).entities == []
    # a run that could be cut at a free boundary is cut there, not at the last one that fits
    mixed = [FIVE[0], FIVE[4], FIVE[0], FIVE[4]]  # +, -, +, -: no boundary is free
    assert split_pieces(mixed, 220.0) == [(0, 2), (2, 4)]
    free_first = [FIVE[0], FIVE[1], FIVE[4], FIVE[0]]  # + + - +: only the first is free
    assert split_pieces(free_first, 290.0) == [(0, 1), (1, 4)]


def test_kerf_offsets_outlines_out_and_holes_in():
    square = np.array([[0, 0], [10, 0], [10, 10], [0, 10]], float)
    out = offset_polygon(square, 0.1)
    assert np.ptp(out, axis=0) == pytest.approx([10.2, 10.2])
    assert signed_area(out) > 0
    assert np.ptp(offset_polygon(square[::-1], 0.1), axis=0) == pytest.approx([10.2, 10.2])
    assert np.ptp(offset_polygon(square, -0.1), axis=0) == pytest.approx([9.8, 9.8])
    base = base_sheet(FIVE)
    k = compensate(base, 0.2)
    sizes = sorted((np.ptp(e.points[:, 0]), np.ptp(e.points[:, 1])) for e in k.entities
                   if e.layer == "CUT")
    outer = [s for s in sizes if s[1] == pytest.approx(4 * W * 1e3 + 0.2)]
    holes = [s for s in sizes if s[1] == pytest.approx(2 * W * 1e3 - 0.2)]
    assert len(outer) == 1 and len(holes) == 4
    assert outer[0][0] == pytest.approx(sum(u.L for u in FIVE) * 1e3 + 0.2)
    engraved = [e for e in base.entities if e.layer != "CUT"]
    assert [e for e in k.entities if e.layer != "CUT"] == engraved  # untouched
    with pytest.raises(ValueError, match="kerf"):
        compensate(base, -1.0)


def test_write_drawings_on_a_bed(tmp_path):
    """With a bed the parts come out on sheet-<k> files of that size: every entity of the
    written DXF inside the sheet, the parts' cut outlines apart, the SVG page the sheet."""
    from sheet_files import sheet_problems

    paths = write_drawings(LONG, tmp_path, bed="300x200", kerf_mm=0.15)
    names = sorted(p.name for p in paths)
    sheets = [n for n in names if n.startswith("sheet-") and n.endswith(".dxf")]
    assert len(sheets) >= 2 and "molds.dxf" in names
    total_holes = 0
    for name in sheets:
        problems, holes = sheet_problems(tmp_path / name, (300, 200))
        assert not problems, problems
        total_holes += holes
    assert total_holes == sum(not u.is_spacer for u in LONG)
    with pytest.raises(ValueError, match="unit 4 .129.4 mm. is longer than the bed .90.0 mm."):
        write_drawings(LONG, tmp_path / "small", bed="100x100")
    with pytest.raises(ValueError, match="does not fit the 160 x 20 mm bed"):
        write_drawings(FIVE, tmp_path / "narrow", bed="160x20")


def test_bed_warning_without_a_bed(tmp_path):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        write_drawings(LONG, tmp_path)
    msgs = [str(w.message) for w in caught if issubclass(w.category, BedWarning)]
    assert len(msgs) == 1 and "larger than a 600 x 400 mm laser bed" in msgs[0]
    assert oversize(parts_of(base_sheet(FIVE), arch_sheet(FIVE))) == []
