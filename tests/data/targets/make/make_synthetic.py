"""ezdxf part of the corpus: the clearly labelled synthetic DXF files, and the inputs that LibreCAD
re-saves (make_librecad.sh). Run with a python that has ezdxf:
    /work/main/.venv/bin/python make/make_synthetic.py OUTDIR BUILDDIR
Expected numbers come from geom.py and the INSERT / OCS maps written here (construction).
"""
from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import ezdxf
import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import geom as G  # noqa: E402

PROGRAM = f"ezdxf {ezdxf.__version__} (synthetic)"
S = G.base_shapes()
UNIT_MM = {0: 1.0, 1: 25.4, 4: 1.0, 5: 10.0, 6: 1000.0}


def r(v, n=3):
    if hasattr(v, "__len__"):
        return [round(float(x), n) + 0.0 for x in v]
    return round(float(v), n) + 0.0


def add_shape(msp, shape, lw=False, dxfattribs=None):
    """LINE/ARC entities, or one LWPOLYLINE with bulges (lines and arcs only) when lw=True."""
    at = dict(dxfattribs or {})
    if lw:
        if any(p[0] == "C" for p in shape):
            pts = G.sample(shape, 2.0)  # sampled in block/model coordinates
            return msp.add_lwpolyline([(x, y) for x, y in pts], format="xy", dxfattribs=at)
        return msp.add_lwpolyline(G.bulge_vertices(shape), format="xyb", dxfattribs=at)
    for p in shape:
        if p[0] == "L":
            msp.add_line(tuple(p[1]), tuple(p[2]), dxfattribs=at)
        elif p[0] == "A":
            _, c, rr, a0, sw = p
            lo, hi = (a0, a0 + sw) if sw > 0 else (a0 + sw, a0)
            msp.add_arc(tuple(c), rr, math.degrees(lo), math.degrees(hi), dxfattribs=at)
        else:
            raise ValueError("cubic: use lw=True")


def new(insunits=4, version="R2000"):
    doc = ezdxf.new(version, setup=False)
    if insunits is not None:
        doc.header["$INSUNITS"] = insunits
    return doc


def expect_read(shape, T=G.I, unit_mm=1.0, **kw):
    sh = G.transform(shape, G.scale(unit_mm) @ T)
    step = kw.pop("poly", None)
    if step:
        # the LWPOLYLINE holds the shape sampled every `step` mm; a map applied afterwards (INSERT)
        pts = [G.apply(G.scale(unit_mm) @ T, q) for q in G.sample(shape, step)]
        L, tr, hd = G.polyline_length(pts), G.polyline_turn(pts), G.polyline_heading_deg(pts)
    else:
        L, tr, hd = G.length(sh), G.turn(sh), G.heading_deg(sh)
    e = dict(expect="read", length_mm=r(L), start_mm=r(G.start(sh)), end_mm=r(G.end(sh)),
             turn_deg=r(math.degrees(tr), 2), start_heading_deg=r(hd, 2), frame="dxf-mm", direction="file",
             tol_mm=0.05, turn_tol_deg=1.0)
    e.update(kw)
    return e


CASES = []   # (name, what, writer(doc) , expectation dict, for_librecad)


def case(name, what, exp, lc=True, insunits=4, version="R2000"):
    def deco(fn):
        CASES.append(dict(name=name, what=what, exp=exp, fn=fn, lc=lc, insunits=insunits, version=version))
        return fn
    return deco


OFF = G.translate(20, 30)


# --- polylines with and without bulges -------------------------------------------------------------
@case("lwpolyline_bulges_s2arc", "one LWPOLYLINE of 3 vertices with bulges +-tan(22.5 deg) (S of two R100 arcs)",
      expect_read(S["s2arc"], OFF, insunits=4))
def _(doc):
    add_shape(doc.modelspace(), G.transform(S["s2arc"], OFF), lw=True)


@case("lwpolyline_bulges_mround", "LWPOLYLINE: 4 straight spans + 3 bulge spans (M with R50 rounded corners)",
      expect_read(S["mround"], OFF, insunits=4))
def _(doc):
    add_shape(doc.modelspace(), G.transform(S["mround"], OFF), lw=True)


@case("lwpolyline_sine_points", "LWPOLYLINE without bulges: the sine sampled every 2 mm (217 vertices)",
      expect_read(S["sine"], OFF, insunits=4, poly=2.0))
def _(doc):
    add_shape(doc.modelspace(), G.transform(S["sine"], OFF), lw=True)


@case("lwpolyline_closed_flag", "LWPOLYLINE of the S with the closed flag set (70 = 1): it closes back to the start",
      dict(expect="refuse", reason="closed", note="the closed flag adds a straight span from the last vertex to the first"))
def _(doc):
    add_shape(doc.modelspace(), G.transform(S["s2arc"], OFF), lw=True).closed = True


@case("lwpolyline_elevation", "LWPOLYLINE hook at elevation 50 (planar, but z = 50 everywhere)",
      expect_read(S["hook"], OFF, insunits=4,
                  note="a constant elevation is still planar: read it, ignore z"), lc=False)
def _(doc):
    add_shape(doc.modelspace(), G.transform(S["hook"], OFF), lw=True, dxfattribs={"elevation": 50.0})


# --- INSERT -----------------------------------------------------------------------------------------
T_INS = G.translate(100, 50) @ G.rotate(30) @ G.scale(1.5) @ G.translate(-10, -5)


@case("insert_block_hook", "INSERT of block TARGET (LINE+ARC hook, base point (10,5)) at (100,50), rotation 30, scale 1.5",
      expect_read(S["hook"], T_INS, insunits=4, direction="either",
                  note="WCS = insert + R(30) * 1.5 * (block coords - base point); length 1.5 x 338.496"))
def _(doc):
    blk = doc.blocks.new("TARGET", base_point=(10, 5))
    add_shape(blk, S["hook"])
    doc.modelspace().add_blockref("TARGET", (100, 50), dxfattribs={"xscale": 1.5, "yscale": 1.5, "zscale": 1.5,
                                                                   "rotation": 30})


T_NU = G.translate(30, 60) @ G.scale(1.2, 0.8)


@case("insert_nonuniform_sine", "INSERT with xscale 1.2, yscale 0.8 of a block holding the 2-mm-sampled sine LWPOLYLINE",
      expect_read(S["sine"], T_NU, insunits=4, poly=2.0, note="non-uniform scale: length of the scaled vertices"))
def _(doc):
    blk = doc.blocks.new("SINE")
    add_shape(blk, S["sine"], lw=True)
    doc.modelspace().add_blockref("SINE", (30, 60), dxfattribs={"xscale": 1.2, "yscale": 0.8})


T_NEST = G.translate(200, 20) @ G.rotate(90) @ G.translate(40, 0) @ G.scale(0.8)


@case("insert_nested_arc", "INSERT of block OUTER (rotation 90) whose content is an INSERT of block ARC at (40,0) scale 0.8",
      expect_read(S["arc90"], T_NEST, insunits=4, note="nested blocks: 0.8 x 196.350"), lc=True)
def _(doc):
    b1 = doc.blocks.new("ARC")
    add_shape(b1, S["arc90"])
    b2 = doc.blocks.new("OUTER")
    b2.add_blockref("ARC", (40, 0), dxfattribs={"xscale": 0.8, "yscale": 0.8, "zscale": 0.8})
    doc.modelspace().add_blockref("OUTER", (200, 20), dxfattribs={"rotation": 90})


T_MIRINS = G.translate(250, 40) @ G.scale(-1, 1)


@case("insert_mirrored_arc", "INSERT with xscale -1 (mirror) of a block holding ARC R125/90deg",
      expect_read(S["arc90"], T_MIRINS, insunits=4, direction="either",
                  note="the mirrored ARC runs clockwise in WCS; turn as seen = -90 along the original direction"))
def _(doc):
    blk = doc.blocks.new("ARCM")
    add_shape(blk, S["arc90"])
    doc.modelspace().add_blockref("ARCM", (250, 40), dxfattribs={"xscale": -1, "yscale": 1})


# --- OCS ----------------------------------------------------------------------------------------------
MIRROR = G.scale(-1, 1)   # OCS with extrusion (0,0,-1): OCS x axis = WCS -x, y axis = WCS y


@case("ocs_arc_extrusion_neg_z", "ARC with extrusion (0,0,-1): OCS centre (-250,155), angles -90..0 (what a CAD mirror leaves)",
      expect_read(S["arc90"], MIRROR @ G.translate(-250, 30), insunits=4,
                  note="WCS x = -OCS x: the arc appears clockwise, from (250,30) to (125,155)"))
def _(doc):
    sh = G.transform(S["arc90"], G.translate(-250, 30))
    _, c, rr, a0, sw = sh[0]
    doc.modelspace().add_arc(tuple(c), rr, math.degrees(a0), math.degrees(a0 + sw),
                             dxfattribs={"extrusion": (0, 0, -1)})


@case("ocs_lwpolyline_neg_z", "LWPOLYLINE (S, bulges) with extrusion (0,0,-1): x mirrored, bulges change sense",
      expect_read(S["s2arc"], MIRROR @ G.translate(-300, 30), insunits=4))
def _(doc):
    add_shape(doc.modelspace(), G.transform(S["s2arc"], G.translate(-300, 30)), lw=True,
              dxfattribs={"extrusion": (0, 0, -1)})


# --- $INSUNITS ------------------------------------------------------------------------------------------
for code, nm in [(0, "unitless"), (1, "inch"), (4, "mm"), (5, "cm"), (6, "m")]:
    f = UNIT_MM[code]
    extra = {"insunits": code}
    if code == 0:
        extra["units_note"] = "unitless ($INSUNITS=0): values are mm, taken as mm"

    def writer(doc, f=f):
        add_shape(doc.modelspace(), G.transform(S["hook"], G.scale(1 / f) @ OFF))

    CASES.append(dict(name=f"insunits_{code}_{nm}", what=f"$INSUNITS={code} ({nm}): hook as LINE+ARC, coordinates in {nm}"
                      + ("" if code in (0, 4) else f" (338.496 mm = {338.496 / f:.5g} {nm})"),
                      exp=expect_read(S["hook"], OFF, direction="either", **extra), fn=writer, lc=True,
                      insunits=code, version="R2000"))


@case("no_header_units_r12", "R12 file without $INSUNITS (AC1009 header has none): hook, values in mm",
      expect_read(S["hook"], OFF, insunits=None, direction="either", units_note="no $INSUNITS: taken as mm"),
      lc=False, insunits=None, version="R12")
def _(doc):
    add_shape(doc.modelspace(), G.transform(S["hook"], OFF))


# --- refusals ---------------------------------------------------------------------------------------------
@case("polyline3d_nonplanar", "3-D POLYLINE (flag 8) along the hook with z rising 0 -> 80 mm",
      dict(expect="refuse", reason="non-planar", note="z from 0 to 80 mm: not a planar curve"))
def _(doc):
    pts = G.sample(G.transform(S["hook"], OFF), 5.0)
    z = np.linspace(0, 80, len(pts))
    doc.modelspace().add_polyline3d([(x, y, zz) for (x, y), zz in zip(pts, z)])


@case("unitless_metres", "$INSUNITS=0 and the hook drawn in metres (0.3385 units long)",
      dict(expect="refuse", reason="probably-metres", length_mm=0.338,
           note="0.34 units: as mm far too short, as metres 338 mm", units_note="unitless"), insunits=0)
def _(doc):
    add_shape(doc.modelspace(), G.transform(S["hook"], G.scale(0.001) @ OFF))


@case("circle_only", "one CIRCLE R60 and nothing else", dict(expect="refuse", reason="closed",
                                                             note="the only curve is closed"))
def _(doc):
    doc.modelspace().add_circle((100, 100), 60)


@case("tiny_arc", "an ARC 9.70 mm long (R12.35 through 45 deg)",
      dict(expect="refuse", reason="too-short", length_mm=9.7, note="9.70 mm"), lc=False)
def _(doc):
    add_shape(doc.modelspace(), G.transform(S["arc_tiny"], OFF))


@case("empty_modelspace", "valid R2000 file with an empty model space",
      dict(expect="refuse", reason="no-curve", note="no entities"), lc=False)
def _(doc):
    pass


@case("gap_2mm_hook", "LINE and ARC of the hook with a 2 mm gap between them",
      dict(expect="refuse", reason="several-candidates",
           candidates=[{"id": "LINE", "length_mm": 148.0}, {"id": "ARC", "length_mm": 188.496}],
           note="2 mm is far more than any joining tolerance: two separate open curves"), lc=False)
def _(doc):
    sh = G.transform(S["hook"], OFF)
    sh[0] = ("L", sh[0][1], sh[0][2] - np.array([2.0, 0]))
    add_shape(doc.modelspace(), sh)


def _lc_overrides():
    """What LibreCAD 2.2.0 changes when it re-saves these inputs (seen in its output, explained)."""
    o = {}
    pts = [G.apply(OFF, q) for q in G.sample(S["hook"], 5.0)]
    o["polyline3d_nonplanar"] = dict(
        expect="read", reason=None, length_mm=r(G.polyline_length(pts)), start_mm=r(pts[0]), end_mm=r(pts[-1]),
        turn_deg=r(math.degrees(G.polyline_turn(pts)), 2), start_heading_deg=r(G.polyline_heading_deg(pts), 2),
        frame="dxf-mm", direction="file", tol_mm=0.05, turn_tol_deg=1.0, insunits=4,
        note="LibreCAD 2.2 drops z: the 3-D POLYLINE comes back as a planar 2-D LWPOLYLINE (69 vertices of "
             "the hook sampled every 5 mm), so this file must be READ although its input was non-planar")
    o["ocs_arc_extrusion_neg_z"] = dict(
        direction="either", note="LibreCAD rewrites the OCS arc in WCS (extrusion +z, angles 180..270): same "
                                 "curve, but the ARC now runs from (125,155) to (250,30)")
    # LibreCAD mirrors the vertices into WCS but keeps the OCS bulge signs: the arcs flip sides
    sh = G.transform(S["s2arc"], G.translate(-300, 30))
    verts = [(-x, y, b) for x, y, b in G.bulge_vertices(sh)]
    got = G.shape_from_bulges(verts)
    o["ocs_lwpolyline_neg_z"] = dict(
        length_mm=r(G.length(got)), start_mm=r(G.start(got)), end_mm=r(G.end(got)),
        turn_deg=r(math.degrees(G.turn(got)), 2), start_heading_deg=r(G.heading_deg(got), 2),
        note="LibreCAD bug: it converts the vertices to WCS (x mirrored) but keeps the OCS bulge signs and "
             "writes extrusion +z, so each arc now bulges to the other side of its chord. Same ends, length "
             "and turn as the input, different start heading (90 instead of 180 deg)")
    return o


LC_OVERRIDES = _lc_overrides()


def main(outdir, build):
    outdir, build = Path(outdir).resolve(), Path(build).resolve()
    syn = outdir / "dxf" / "synthetic"
    syn.mkdir(parents=True, exist_ok=True)
    lc_in = build / "lc_in"
    lc_in.mkdir(parents=True, exist_ok=True)
    man, lc = [], []
    for c in CASES:
        doc = new(c["insunits"], c["version"])
        c["fn"](doc)
        doc.saveas(syn / f"{c['name']}.dxf")
        e = {"file": f"dxf/synthetic/{c['name']}.dxf", "program": PROGRAM, "what": c["what"]}
        e.update(c["exp"])
        if c["version"] != "R12" and "insunits" not in e:
            e["insunits"] = c["insunits"]
        man.append(e)
        if c["lc"]:
            doc.saveas(lc_in / f"{c['name']}.dxf")
            le = dict(e, file=f"dxf/librecad/{c['name']}.dxf", program="LibreCAD 2.2.0",
                      what="re-saved by LibreCAD (ezdxf input opened, File > Save as, DXF 2007): " + c["what"])
            le.update(LC_OVERRIDES.get(c["name"], {}))
            lc.append(le)
    (build / "manifest_synthetic.json").write_text(json.dumps(man, indent=1))
    (build / "manifest_librecad_resave.json").write_text(json.dumps(lc, indent=1))
    print(len(man), "synthetic,", len(lc), "LibreCAD inputs")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
