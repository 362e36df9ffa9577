"""FreeCAD 0.20 part of the corpus. Run:  freecadcmd make/make_freecad.py   (env CORPUS_OUT, CORPUS_BUILD)

FreeCAD writes every DXF here through its C++ exporter (Import.writeDXFShape / writeDXFObject,
the exporter Draft uses by default; the Python "legacy" exporter needs dxfLibrary.py, which FreeCAD
downloads on demand and cannot get offline). Version 14 writes AC1015 (R2000) with $INSUNITS=4,
version 12 writes AC1009 with no $INSUNITS. Splines become polylines when the Import preference
"DiscretizeEllipses" is on (it covers B-splines too) or when version 12 is asked for.
Expected numbers come from geom.py (construction), not from reading the DXF back.
"""
import json
import math
import os
import sys

import FreeCAD  # noqa: E402
import Import  # noqa: E402
import Part  # noqa: E402
from FreeCAD import Vector as V  # noqa: E402

HERE = os.environ.get("CORPUS_MAKE", "make")
sys.path.insert(0, HERE)
import geom as G  # noqa: E402

OUT = os.environ.get("CORPUS_OUT", ".")
BUILD = os.environ.get("CORPUS_BUILD", "/tmp/build")
PROGRAM = "FreeCAD %s.%s.%s" % tuple(FreeCAD.Version()[:3])
DIR = os.path.join(OUT, "dxf", "freecad")
os.makedirs(DIR, exist_ok=True)
PREF = FreeCAD.ParamGet("User parameter:BaseApp/Preferences/Mod/Import")
S = G.base_shapes()
OFF = G.translate(20, 30)          # every construction is moved by (20, 30) mm
man = []


def edges(shape):
    out = []
    for p in shape:
        if p[0] == "L":
            out.append(Part.LineSegment(V(*p[1], 0), V(*p[2], 0)).toShape())
        elif p[0] == "A":
            _, c, r, a0, sw = p
            lo, hi = (a0, a0 + sw) if sw > 0 else (a0 + sw, a0)
            circ = Part.Circle(V(*c, 0), V(0, 0, 1), r)
            out.append(Part.ArcOfCircle(circ, lo, hi).toShape())
        else:
            bz = Part.BezierCurve()
            bz.setPoles([V(*q, 0) for q in p[1:]])
            out.append(bz.toBSpline().toShape())   # FreeCAD cannot export Bezier edges
    return out


def bspline_of_chain(shape):
    """One degree-3 B-spline exactly equal to a C1 chain of cubic Beziers."""
    poles = [V(*shape[0][1], 0)]
    for p in shape:
        poles += [V(*q, 0) for q in p[2:]]
    n = len(shape)
    bs = Part.BSplineCurve()
    bs.buildFromPolesMultsKnots(poles, [4] + [3] * (n - 1) + [4], list(range(n + 1)), False, 3)
    return bs.toShape()


def r(v, n=3):
    if isinstance(v, (list, tuple)) or hasattr(v, "__len__"):
        return [round(float(x), n) + 0.0 for x in v]
    return round(float(v), n) + 0.0


def read_entry(fname, what, shape, T=OFF, **kw):
    sh = G.transform(shape, T)
    e = {"file": "dxf/freecad/" + fname, "program": PROGRAM, "what": what, "expect": "read",
         "length_mm": r(kw.pop("length", G.length(sh))), "start_mm": r(G.start(sh)), "end_mm": r(G.end(sh)),
         "turn_deg": r(kw.pop("turn", math.degrees(G.turn(sh))), 2),
         "start_heading_deg": r(G.heading_deg(sh), 2), "frame": "dxf-mm"}
    e.update(kw)
    e.setdefault("direction", "file")
    e.setdefault("tol_mm", 0.05)
    e.setdefault("turn_tol_deg", 1.0)
    man.append(e)


def refuse(fname, what, reason, note, **kw):
    e = {"file": "dxf/freecad/" + fname, "program": PROGRAM, "what": what, "expect": "refuse",
         "reason": reason, "note": note}
    e.update(kw)
    man.append(e)


def write(shapes, fname, version=14):
    Import.writeDXFShape(shapes, os.path.join(DIR, fname), version, False)


def wire(shape, T=OFF):
    return Part.Wire(edges(G.transform(shape, T)))


PREF.SetBool("DiscretizeEllipses", False)
PREF.SetFloat("maxsegmentlength", 5.0)

# --- LINE + ARC chains -------------------------------------------------------------------------
write([wire(S["arc90"])], "arc90_single.r14.dxf")
read_entry("arc90_single.r14.dxf", "a single ARC R125/90deg (AC1015, $INSUNITS 4)", S["arc90"], insunits=4,
           note="ARC entities always run counter-clockwise from start to end angle")
write([wire(S["arc90"])], "arc90_single.r12.dxf", 12)
read_entry("arc90_single.r12.dxf", "a single ARC, R12 (AC1009, no $INSUNITS)", S["arc90"], insunits=None,
           units_note="R12 has no $INSUNITS: unitless, taken as mm (FreeCAD works in mm)")
write([wire(S["hook"])], "hook_line_arc.r14.dxf")
read_entry("hook_line_arc.r14.dxf", "LINE + ARC chain (hook: 150 mm straight + R60 half circle)", S["hook"],
           insunits=4, direction="either", note="separate entities: chain by shared end points")
write([wire(S["hook"])], "hook_line_arc.r12.dxf", 12)
read_entry("hook_line_arc.r12.dxf", "LINE + ARC chain, R12", S["hook"], insunits=None, direction="either",
           units_note="R12 has no $INSUNITS: unitless, taken as mm")
write([wire(S["s2arc"])], "s2arc_two_arcs.r14.dxf")
read_entry("s2arc_two_arcs.r14.dxf", "S of two ARCs; the clockwise one is written as a CCW ARC (angles swapped)",
           S["s2arc"], insunits=4, direction="either",
           note="the second ARC's own start is the S's end: its direction must be flipped while chaining")
write([wire(S["mround"])], "mround_lines_arcs.r14.dxf")
read_entry("mround_lines_arcs.r14.dxf", "M of 4 LINEs joined by 3 R50 ARCs (7 entities, FreeCAD wire)", S["mround"],
           insunits=4, direction="either")
write([wire(S["mround"])], "mround_lines_arcs.r12.dxf", 12)
read_entry("mround_lines_arcs.r12.dxf", "M of LINEs and ARCs, R12", S["mround"], insunits=None, direction="either",
           units_note="R12 has no $INSUNITS: unitless, taken as mm")
# loose edges (not a wire), written in a shuffled order
es = edges(G.transform(S["mround"], OFF))
write([Part.Compound([es[i] for i in (3, 0, 6, 2, 5, 1, 4)])], "mround_shuffled_edges.r14.dxf")
read_entry("mround_shuffled_edges.r14.dxf", "the same 7 edges as a compound in shuffled order (entity order != curve order)",
           S["mround"], insunits=4, direction="either")

# --- B-splines -----------------------------------------------------------------------------------
write([Part.Wire(edges(G.transform(S["bezier"], OFF)))], "bezier_spline.r14.dxf")
read_entry("bezier_spline.r14.dxf", "cubic Bezier exported as a degree-3 SPLINE (4 control points, clamped knots)",
           S["bezier"], insunits=4)
write([bspline_of_chain(G.transform(S["sine"], OFF))], "sine_spline.r14.dxf")
read_entry("sine_spline.r14.dxf", "shallow sine (A15, lambda 200, 2 waves) as one degree-3 SPLINE, 16 spans",
           S["sine"], insunits=4)
write([bspline_of_chain(G.transform(S["sine"], OFF))], "sine_spline_as_polyline.r12.dxf", 12)
read_entry("sine_spline_as_polyline.r12.dxf", "the sine SPLINE exported R12: FreeCAD writes a POLYLINE (2-D vertices)",
           S["sine"], insunits=None, tol_mm=0.3, turn_tol_deg=6.0,
           units_note="R12 has no $INSUNITS: unitless, taken as mm")
PREF.SetBool("DiscretizeEllipses", True)
write([Part.Wire(edges(G.transform(S["bezier"], OFF)))], "bezier_discretized.r14.dxf")
read_entry("bezier_discretized.r14.dxf", "Bezier with Import pref DiscretizeEllipses=True: LWPOLYLINE of chords <= 5 mm",
           S["bezier"], insunits=4, tol_mm=0.3, turn_tol_deg=6.0)
write([bspline_of_chain(G.transform(S["sine"], OFF))], "sine_discretized.r14.dxf")
read_entry("sine_discretized.r14.dxf", "sine B-spline with DiscretizeEllipses=True: LWPOLYLINE", S["sine"], insunits=4,
           tol_mm=0.3, turn_tol_deg=6.0)
PREF.SetBool("DiscretizeEllipses", False)

# --- ellipse arc --------------------------------------------------------------------------------------
a, b = 150.0, 80.0
ell = Part.ArcOfEllipse(Part.Ellipse(V(20, 30, 0), a, b), 0, math.pi / 2).toShape()
write([ell], "ellipse_arc.r14.dxf")
Le = G.ellipse_arc_length(a, b, 0, math.pi / 2)
e0 = {"start": G.P(20 + a, 30), "end": G.P(20, 30 + b)}
man.append({"file": "dxf/freecad/ellipse_arc.r14.dxf", "program": PROGRAM,
            "what": "quarter ELLIPSE arc a=150, b=80 (min radius of curvature b^2/a = 42.7 mm)", "expect": "read",
            "length_mm": r(Le), "start_mm": r(e0["start"]), "end_mm": r(e0["end"]), "turn_deg": 90.0,
            "start_heading_deg": 90.0, "frame": "dxf-mm", "direction": "file", "tol_mm": 0.05, "turn_tol_deg": 1.0, "insunits": 4,
            "note": "length = integral of sqrt(a^2 sin^2 t + b^2 cos^2 t), t in [0, pi/2]"})
PREF.SetBool("DiscretizeEllipses", True)
write([ell], "ellipse_arc_discretized.r14.dxf")
man.append(dict(man[-1], file="dxf/freecad/ellipse_arc_discretized.r14.dxf",
                what="the quarter ellipse with DiscretizeEllipses=True: LWPOLYLINE", tol_mm=0.3, turn_tol_deg=6.0))
PREF.SetBool("DiscretizeEllipses", False)

# --- mirror, placement ---------------------------------------------------------------------------------
arc = wire(S["arc90"], G.I)
mir = arc.mirror(V(0, 0, 0), V(1, 0, 0))     # x -> -x: the edge's circle axis becomes (0,0,-1)
mir.translate(V(250, 30, 0))
write([mir], "arc90_mirrored.r14.dxf")
read_entry("arc90_mirrored.r14.dxf", "ARC mirrored in FreeCAD (Shape.mirror, circle axis (0,0,-1)): FreeCAD "
           "re-expresses it as a CCW ARC with extrusion (0,0,1), no OCS", S["arc90"],
           T=G.translate(250, 30) @ G.scale(-1, 1), insunits=4, direction="either",
           note="direction lost: the ARC runs CCW, i.e. from the mirrored end to the mirrored start")
doc = FreeCAD.newDocument("corpus")
obj = doc.addObject("Part::Feature", "Hook")
obj.Shape = wire(S["hook"], G.I)
obj.Placement = FreeCAD.Placement(V(60, 40, 0), FreeCAD.Rotation(V(0, 0, 1), 30))
doc.recompute()
Import.writeDXFObject([obj], os.path.join(DIR, "hook_placement.r14.dxf"), 14, False)
read_entry("hook_placement.r14.dxf", "Part::Feature with Placement (rotate 30 deg about z, move (60,40)) via "
           "writeDXFObject: the placement is baked into the coordinates", S["hook"],
           T=G.translate(60, 40) @ G.rotate(30), insunits=4, direction="either")

# --- refusals ------------------------------------------------------------------------------------------
write([Part.makeCircle(60, V(100, 100, 0))], "circle_only.r14.dxf")
refuse("circle_only.r14.dxf", "a single closed CIRCLE R60", "closed", "the only curve is closed")
helix = Part.makeHelix(100, 300, 60)
write([helix], "helix_spline.r14.dxf")
refuse("helix_spline.r14.dxf", "helix (pitch 100, height 300, R60) exported as one SPLINE with 3-D control points",
       "non-planar", "control points z from 0 to 300 mm; the SPLINE's extrusion is still (0,0,1)")
p3 = Part.makePolygon([V(0, 0, 0), V(100, 0, 30), V(200, 50, 0), V(300, 50, 60)])
write([p3], "polyline3d_lines.r14.dxf")
refuse("polyline3d_lines.r14.dxf", "3-D polygon wire: FreeCAD writes 3 LINEs with z = 0/30/0/60 (no POLYLINE)",
       "non-planar", "end points leave the z = 0 plane")
twoc = [wire(S["arc90"]), wire(S["line"], G.translate(20, 250))]
write(twoc, "two_curves.r14.dxf")
refuse("two_curves.r14.dxf", "two separate open curves: arc90 and a 200 mm line", "several-candidates",
       "two open chains that do not meet", candidates=[{"id": "ARC (arc90)", "length_mm": r(G.length(S["arc90"]))},
                                                         {"id": "LINE", "length_mm": 200.0}])
metre = wire(S["arc90"], G.scale(0.001))
write([metre], "arc_in_metres.r12.dxf", 12)
refuse("arc_in_metres.r12.dxf", "arc90 drawn in metres: R0.125, 0.196 units long, unitless R12", "probably-metres",
       "0.19635 units; as mm far too short, as metres 196 mm", length_mm=r(G.length(S["arc90"]) * 0.001, 5),
       units_note="R12: unitless")
write([metre], "arc_in_metres.r14.dxf", 14)
refuse("arc_in_metres.r14.dxf", "the same 0.196-unit arc, R14: $INSUNITS says mm", "too-short",
       "the header says mm, so 0.196 mm; a reader may also say probably-metres", reason_alt=["probably-metres"],
       length_mm=r(G.length(S["arc90"]) * 0.001, 5), insunits=4)

json.dump(man, open(os.path.join(BUILD, "manifest_freecad.json"), "w"), indent=1)
print(len(man), "FreeCAD entries")
