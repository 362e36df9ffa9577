"""Second-way check of every DXF entry of manifest.json with ezdxf (not the project's reader).

    /work/main/.venv/bin/python make/verify_dxf.py TARGETS_DIR [OUT_JSON]

For each DXF: INSERTs exploded with Insert.virtual_entities() (recursively), every curve entity
turned into an ezdxf.path (OCS/extrusion applied), flattened to 0.001 drawing units, scaled by
$INSUNITS, chained end to end (0.01 mm), closed loops set aside. Reports the open chains (length,
ends, turning, z-range) next to the manifest's numbers.
"""
from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import ezdxf
import numpy as np
from ezdxf import path as ezpath

INS_MM = {None: 1.0, 0: 1.0, 1: 25.4, 2: 304.8, 4: 1.0, 5: 10.0, 6: 1000.0}
CURVES = {"LINE", "ARC", "CIRCLE", "ELLIPSE", "SPLINE", "LWPOLYLINE", "POLYLINE"}


def entities(container, depth=0):
    for e in container:
        t = e.dxftype()
        if t == "INSERT" and depth < 8:
            yield from entities(list(e.virtual_entities()), depth + 1)
        elif t in CURVES:
            yield e


def pieces(doc, f=1.0):
    out = []
    for e in entities(doc.modelspace()):
        p = ezpath.make_path(e)
        pts = np.array([(v.x, v.y, v.z) for v in p.flattening(0.001 / f)])
        if len(pts) >= 2:
            out.append(pts)
    return out


def chain(pieces, tol):
    pieces = [p.copy() for p in pieces]
    chains = []
    while pieces:
        cur = pieces.pop(0)
        grown = True
        while grown:
            grown = False
            for i, p in enumerate(pieces):
                for a, b in ((cur[-1], p[0]), (cur[-1], p[-1]), (cur[0], p[-1]), (cur[0], p[0])):
                    if np.linalg.norm(a[:2] - b[:2]) < tol:
                        break
                else:
                    continue
                q = pieces.pop(i)
                if np.linalg.norm(cur[-1][:2] - q[0][:2]) < tol:
                    cur = np.vstack([cur, q[1:]])
                elif np.linalg.norm(cur[-1][:2] - q[-1][:2]) < tol:
                    cur = np.vstack([cur, q[::-1][1:]])
                elif np.linalg.norm(cur[0][:2] - q[-1][:2]) < tol:
                    cur = np.vstack([q[:-1], cur])
                else:
                    cur = np.vstack([q[::-1][:-1], cur])
                grown = True
                break
        chains.append(cur)
    return chains


def describe(c, f):
    xy = c[:, :2] * f
    d = np.diff(xy, axis=0)
    keep = np.hypot(d[:, 0], d[:, 1]) > 1e-9
    d = d[keep]
    a = np.arctan2(d[:, 1], d[:, 0])
    da = (np.diff(a) + np.pi) % (2 * np.pi) - np.pi
    closed = np.linalg.norm(xy[0] - xy[-1]) < 0.01
    h0 = math.degrees(math.atan2(d[0, 1], d[0, 0]))
    h1 = math.degrees(math.atan2(-d[-1, 1], -d[-1, 0]))  # heading at the far end, walking backwards
    return dict(length_mm=float(np.sum(np.hypot(d[:, 0], d[:, 1]))), start_mm=xy[0].tolist(),
                heading0=h0, heading1=h1,
                end_mm=xy[-1].tolist(), turn_deg=math.degrees(float(np.sum(da))), closed=bool(closed),
                z_range=float(np.ptp(c[:, 2]) * f))


def check(path):
    doc = ezdxf.readfile(path)
    for blk in doc.blocks:  # LibreCAD writes INSERT zscale (43) = 0: ezdxf cannot explode that
        for e in blk:
            if e.dxftype() == "INSERT" and e.dxf.zscale == 0:
                e.dxf.zscale = 1.0
    ins = doc.header.get("$INSUNITS") if doc.dxfversion > "AC1009" else None
    f = INS_MM.get(ins, 1.0)
    ch = [describe(c, f) for c in chain(pieces(doc, f), 0.01 / f)]
    return dict(insunits=ins, dxfversion=doc.dxfversion, chains=ch)


def main(root, out=None):
    root = Path(root)
    man = json.loads((root / "manifest.json").read_text())
    results, bad = [], 0
    for e in man:
        if not e["file"].endswith(".dxf"):
            continue
        r = check(root / e["file"])
        opens = [c for c in r["chains"] if not c["closed"]]
        res = dict(file=e["file"], select=e.get("select"), expect=e["expect"], insunits=r["insunits"],
                   open_chains=len(opens), closed_chains=len(r["chains"]) - len(opens))
        ok = True
        if e["expect"] == "read":
            cands = opens
            if len(opens) != 1:
                ok = False
            c = max(cands, key=lambda c: c["length_mm"]) if cands else None
            if c:
                s, t = c["start_mm"], c["end_mm"]
                tr = c["turn_deg"]
                hd = c["heading0"]
                if math.dist(s, e["start_mm"]) > math.dist(t, e["start_mm"]):
                    s, t, tr, hd = t, s, -tr, c["heading1"]
                    res["reversed"] = True
                    if e.get("direction") == "file":
                        ok = False
                res.update(length_mm=round(c["length_mm"], 4), start_mm=[round(v, 3) for v in s],
                           end_mm=[round(v, 3) for v in t], turn_deg=round(tr, 2), z_range=c["z_range"])
                dl = c["length_mm"] - e["length_mm"]
                res["d_length_mm"] = round(dl, 4)
                res["d_ends_mm"] = round(max(math.dist(s, e["start_mm"]), math.dist(t, e["end_mm"])), 4)
                res["d_turn_deg"] = round(tr - e["turn_deg"], 3)
                res["d_heading_deg"] = round((hd - e["start_heading_deg"] + 180) % 360 - 180, 3)
                tol = e.get("tol_mm", 0.05)
                if abs(dl) > tol or res["d_ends_mm"] > max(tol, 0.05) or abs(res["d_turn_deg"]) > e.get("turn_tol_deg", 1.0) \
                        or abs(res["d_heading_deg"]) > e.get("turn_tol_deg", 1.0):
                    ok = False
        else:
            res["reason"] = e["reason"]
            res["chains"] = [dict(length_mm=round(c["length_mm"], 3), closed=c["closed"],
                                  z_range=round(c["z_range"], 3)) for c in r["chains"]]
            why = e["reason"]
            if why == "closed":
                ok = not opens and len(r["chains"]) > 0
            elif why == "several-candidates":
                ok = len(opens) >= 2
                if e.get("candidates"):
                    got = sorted(round(c["length_mm"], 1) for c in opens)
                    want = sorted(round(c["length_mm"], 1) for c in e["candidates"])
                    ok = ok and np.allclose(got, want, atol=0.6)
            elif why == "no-curve":
                ok = not r["chains"]
            elif why == "non-planar":
                ok = any(c["z_range"] > 1e-6 for c in r["chains"])
            elif why in ("too-short", "probably-metres"):
                ok = len(opens) == 1 and opens[0]["length_mm"] < 20
                if "length_mm" in e:
                    ok = ok and abs(opens[0]["length_mm"] - e["length_mm"]) < max(0.01, 0.01 * e["length_mm"])
        res["ok"] = ok
        bad += not ok
        results.append(res)
        print(("ok  " if ok else "BAD ") + e["file"], {k: res.get(k) for k in
              ("open_chains", "length_mm", "d_length_mm", "d_ends_mm", "d_turn_deg", "d_heading_deg", "reason")})
    if out:
        Path(out).write_text(json.dumps(results, indent=1))
    print(f"{len(results)} DXF entries, {bad} not matching")


if __name__ == "__main__":
    main(*sys.argv[1:])
