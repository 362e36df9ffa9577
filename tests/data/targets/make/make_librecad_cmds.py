"""Command-line scripts typed into LibreCAD (by librecad_session.sh) and their expected numbers.
    python3 make/make_librecad_cmds.py BUILDDIR
Each BUILDDIR/lc_draw/NAME.cmd holds one LibreCAD command-line entry per line; '<esc>' ends a tool.
"""
import json
import math
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import geom as G  # noqa: E402

PROGRAM = "LibreCAD 2.2.0"
S = G.base_shapes()
OFF = G.translate(20, 30)


def r(v, n=3):
    if hasattr(v, "__len__"):
        return [round(float(x), n) + 0.0 for x in v]
    return round(float(v), n) + 0.0


def pt(p):
    return f"{p[0]:.4f},{p[1]:.4f}"


def main(build):
    d = Path(build) / "lc_draw"
    d.mkdir(parents=True, exist_ok=True)
    man = []
    # 1. polyline through 49 points of the sine
    pts = [tuple(round(float(v), 4) for v in p) for p in G.sample(G.transform(S["sine"], OFF), 10.0)]
    (d / "drawn_polyline_sine.cmd").write_text("polyline\n" + "\n".join(pt(p) for p in pts) + "\n<esc>\n")
    man.append(dict(file="dxf/librecad/drawn_polyline_sine.dxf", program=PROGRAM,
                    what="drawn in LibreCAD with the polyline command through 49 typed points of the sine (every ~8.3 mm) "
                         "(LWPOLYLINE, no bulges)", expect="read", length_mm=r(G.polyline_length(pts)),
                    start_mm=r(pts[0]), end_mm=r(pts[-1]), turn_deg=r(math.degrees(G.polyline_turn(pts)), 2),
                    start_heading_deg=r(G.polyline_heading_deg(pts), 2), frame="dxf-mm", direction="file", tol_mm=0.05, turn_tol_deg=1.0, insunits=4,
                    note="length/turn of the 49-point polyline (the sine itself is 421.337 mm)"))
    # 2. line + 3-point arc: the hook
    h = G.transform(S["hook"], OFF)
    c = h[1][1]
    mid = c + 60 * G.P(1, 0)
    (d / "drawn_line_arc_hook.cmd").write_text(
        f"line\n{pt(G.start(h))}\n{pt(G.prim_end(h[0]))}\n<esc>\narc\n{pt(G.prim_end(h[0]))}\n{pt(mid)}\n{pt(G.end(h))}\n<esc>\n")
    man.append(dict(file="dxf/librecad/drawn_line_arc_hook.dxf", program=PROGRAM,
                    what="drawn in LibreCAD: line command (150 mm) then 3-point arc command (R60 half circle)",
                    expect="read", length_mm=r(G.length(h)), start_mm=r(G.start(h)), end_mm=r(G.end(h)),
                    turn_deg=r(math.degrees(G.turn(h)), 2), start_heading_deg=r(G.heading_deg(h), 2), frame="dxf-mm", direction="either", tol_mm=0.05,
                    turn_tol_deg=1.0, insunits=4))
    # 3. 3-point arc alone
    a = G.transform(S["arc90"], OFF)
    _, c, R, a0, sw = a[0]
    mid = c + R * G.P(math.cos(a0 + sw / 2), math.sin(a0 + sw / 2))
    (d / "drawn_arc3p_arc90.cmd").write_text(f"arc\n{pt(G.start(a))}\n{pt(mid)}\n{pt(G.end(a))}\n<esc>\n")
    man.append(dict(file="dxf/librecad/drawn_arc3p_arc90.dxf", program=PROGRAM,
                    what="drawn in LibreCAD with the 3-point arc command: R125 through 90 deg", expect="read",
                    length_mm=r(G.length(a)), start_mm=r(G.start(a)), end_mm=r(G.end(a)),
                    turn_deg=r(math.degrees(G.turn(a)), 2), start_heading_deg=r(G.heading_deg(a), 2), frame="dxf-mm", direction="file", tol_mm=0.05,
                    turn_tol_deg=1.0, insunits=4))
    # 4. two lines and a circle: a closed circle next to an open curve
    (d / "drawn_circle_only.cmd").write_text("circle\n100,100\n60\n<esc>\n")
    man.append(dict(file="dxf/librecad/drawn_circle_only.dxf", program=PROGRAM,
                    what="drawn in LibreCAD with the circle command (centre 100,100, R60)", expect="refuse",
                    reason="closed", note="the only curve is a closed CIRCLE"))
    (Path(build) / "manifest_librecad_draw.json").write_text(json.dumps(man, indent=1))
    print(len(man), "LibreCAD drawings")


if __name__ == "__main__":
    main(sys.argv[1])
