"""CSV part of the corpus (hand-written by this script: CSV has no drawing program here).
    python3 make/make_csv.py OUTDIR BUILDDIR
Length/turn of a CSV target are those of the polyline through its points (construction points,
sampled from geom.py shapes); the smooth curve they sample is given in `note`.
"""
import json
import math
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import geom as G  # noqa: E402

S = G.base_shapes()
OFF = G.translate(20, 30)
PROGRAM = "hand-written (make_csv.py)"


def r(v, n=3):
    if hasattr(v, "__len__"):
        return [round(float(x), n) + 0.0 for x in v]
    return round(float(v), n) + 0.0


def pts_of(name, step=1.0, T=OFF):
    return np.array([G.apply(T, q) for q in G.sample(S[name], step)])


def read_exp(pts_mm, **kw):
    e = dict(expect="read", length_mm=r(G.polyline_length(pts_mm)), start_mm=r(pts_mm[0]), end_mm=r(pts_mm[-1]),
             turn_deg=r(math.degrees(G.polyline_turn(pts_mm)), 2),
             start_heading_deg=r(G.polyline_heading_deg(pts_mm), 2), frame="csv-mm", direction="file",
             tol_mm=0.05, turn_tol_deg=2.0, tangents=False)
    e.update(kw)
    return e


def rows(pts, scale=1.0, fmt="{:.4f}", extra=None):
    out = []
    for i, p in enumerate(pts):
        cells = [fmt.format(p[0] * scale), fmt.format(p[1] * scale)]
        if extra is not None:
            cells.append(extra[i])
        out.append(",".join(cells))
    return out


def main(outdir, build):
    out = Path(outdir).resolve() / "csv"
    out.mkdir(parents=True, exist_ok=True)
    man = []

    def put(name, text, what, exp, newline="\n"):
        (out / name).write_bytes(text.replace("\n", newline).encode("utf-8"))
        e = {"file": f"csv/{name}", "program": PROGRAM, "what": what}
        e.update(exp)
        man.append(e)

    # values are printed with 4 decimals (6 for inch/m): expected numbers use the printed values
    def printed(pts, scale, nd):
        return np.round(pts * scale, nd) / scale

    p = pts_of("hook")
    put("hook_x_mm.csv", "x_mm,y_mm\n" + "\n".join(rows(p)) + "\n",
        "header x_mm,y_mm; hook sampled every 1 mm (339 points)",
        read_exp(printed(p, 1, 4), note="polyline through the points; the hook itself is 338.496 mm"))
    p = pts_of("arc90")
    q = printed(p, 1 / 25.4, 6)
    put("arc90_inches.csv", "x (in),y (in)\n" + "\n".join(rows(p, 1 / 25.4, "{:.6f}")) + "\n",
        "header 'x (in),y (in)': values in inches (arc R125/90deg = R4.921 in)",
        read_exp(q, note="x 25.4 to mm; the arc itself is 196.350 mm"))
    p = pts_of("s2arc")
    put("s2arc_metres.csv", "x_m,y_m\n" + "\n".join(rows(p, 1e-3, "{:.7f}")) + "\n",
        "header x_m,y_m: values in metres (0.02 .. 0.22)", read_exp(printed(p, 1e-3, 7),
                                                                   note="declared metres: 314 mm, read it"))
    p = pts_of("sine")
    body = rows(p)
    text = ("# target: shallow sine, amplitude 15 mm, wavelength 200 mm\n# exported 2024-05-02\n\nx_mm,y_mm\n"
            + "\n".join(body[:200]) + "\n# second half\n\n" + "\n".join(body[200:]) + "\n")
    put("comments_sine.csv", text, "'#' comment lines before the header and in the middle, blank lines",
        read_exp(printed(p, 1, 4), note="the sine itself is 421.337 mm"))
    p = pts_of("bezier")
    put("xyz_mm_flat.csv", "x_mm,y_mm,z_mm\n" + "\n".join(rows(p, extra=["5.0000"] * len(p))) + "\n",
        "3 columns x_mm,y_mm,z_mm with z = 5 everywhere: planar; the 3rd column is NOT a tangent",
        read_exp(printed(p, 1, 4), note="z constant: planar. A reader taking column 3 as tangent_deg would "
                                          "get 5 deg everywhere: it must not (tangents=false)"))
    p = pts_of("bezier")
    z = [f"{v:.4f}" for v in np.linspace(0, 50, len(p))]
    put("xyz_mm_nonplanar.csv", "x_mm,y_mm,z_mm\n" + "\n".join(rows(p, extra=z)) + "\n",
        "3 columns x_mm,y_mm,z_mm with z rising 0 -> 50 mm",
        dict(expect="refuse", reason="non-planar", note="z varies by 50 mm"))
    sh = G.transform(S["arc90"], OFF)
    p = pts_of("arc90", 2.0)
    _, c, R, a0, sw = sh[0]
    ang = np.arctan2(p[:, 1] - c[1], p[:, 0] - c[0])
    tang = [f"{math.degrees(a) + 90:.4f}" for a in ang]   # CCW arc: tangent = radius angle + 90
    put("tangent_deg_arc90.csv", "x_mm,y_mm,tangent_deg\n" + "\n".join(rows(p, extra=tang)) + "\n",
        "3 columns x_mm,y_mm,tangent_deg: arc R125/90deg every 2 mm with the exact tangent angle",
        read_exp(printed(p, 1, 4), tangents=True, tangent_start_deg=0.0, tangent_end_deg=90.0,
                 note="tangent column: 0 deg at the start rising to 90 deg at the end"))
    p = pts_of("hook")
    put("metres_in_mm_header.csv", "x_mm,y_mm\n" + "\n".join(rows(p, 1e-3, "{:.7f}")) + "\n",
        "header says x_mm,y_mm but the values are metres (0.02 .. 0.21)",
        dict(expect="refuse", reason="probably-metres", length_mm=0.338,
             note="0.338 'mm' long: certainly metres typed under a mm header"))
    p = pts_of("arc90")
    put("no_header.csv", "\n".join(rows(p)) + "\n", "no header line, two columns",
        read_exp(printed(p, 1, 4), units_note="no header: taken as mm (the project's CSV convention)"))
    p = pts_of("hook")
    put("excel_bom_crlf.csv", "\ufeffx_mm,y_mm\n" + "\n".join(rows(p, fmt="{:.2f}")) + "\n",
        "UTF-8 byte-order mark and CRLF line ends (as Excel writes 'CSV UTF-8'), 2 decimals",
        read_exp(printed(p, 1, 2)), newline="\r\n")
    p = pts_of("arc_tiny", 0.2)
    put("tiny_arc.csv", "x_mm,y_mm\n" + "\n".join(rows(p)) + "\n", "a 9.70 mm arc",
        dict(expect="refuse", reason="too-short", length_mm=9.7, note="9.70 mm"))
    circ = [(100 + 60 * math.cos(t), 100 + 60 * math.sin(t)) for t in np.linspace(0, 2 * math.pi, 121)]
    put("closed_circle.csv", "x_mm,y_mm\n" + "\n".join(rows(np.array(circ))) + "\n",
        "a full circle R60: the last point repeats the first",
        dict(expect="refuse", reason="closed", note="first point = last point"))
    (Path(build) / "manifest_csv.json").write_text(json.dumps(man, indent=1))
    print(len(man), "CSV entries")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
