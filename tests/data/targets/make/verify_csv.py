"""Second-way check of the CSV entries (independent little parser, not the project's reader).
    python3 make/verify_csv.py TARGETS_DIR OUT_JSON
"""
import json
import math
import sys
from pathlib import Path

import numpy as np

UNIT = {"mm": 1.0, "in": 25.4, "m": 1000.0}


def parse(path):
    text = path.read_bytes().decode("utf-8-sig")
    rows, unit = [], 1.0
    for line in text.splitlines():
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        if ";" in line:   # LibreOffice German locale: ';' between fields, ',' as decimal mark
            cells = [c.strip().replace(",", ".") for c in line.split(";")]
        else:
            cells = [c.strip() for c in line.split(",")]
        cells = [c.strip('"') for c in cells]
        try:
            rows.append([float(c) for c in cells])
        except ValueError:
            h = cells[0].lower()
            for k in ("mm", "in", "m"):
                if h.endswith("_" + k) or h.endswith("(" + k + ")"):
                    unit = UNIT[k]
                    break
    return np.array(rows), unit


def main(root, out):
    root = Path(root)
    res, bad = [], 0
    for e in json.loads((root / "manifest.json").read_text()):
        if not e["file"].endswith(".csv"):
            continue
        a, unit = parse(root / e["file"])
        xy = a[:, :2] * unit
        d = np.diff(xy, axis=0)
        L = float(np.hypot(d[:, 0], d[:, 1]).sum())
        ang = np.arctan2(d[:, 1], d[:, 0])
        turn = math.degrees(float(np.sum((np.diff(ang) + np.pi) % (2 * np.pi) - np.pi)))
        r = dict(file=e["file"], points=len(a), columns=a.shape[1], length_mm=round(L, 4),
                 z_range=round(float(np.ptp(a[:, 2])), 3) if a.shape[1] == 3 and "z_mm" in
                 (root / e["file"]).read_text() else None)
        if e["expect"] == "read":
            ok = (abs(L - e["length_mm"]) <= e["tol_mm"] and math.dist(xy[0], e["start_mm"]) < 0.01
                  and math.dist(xy[-1], e["end_mm"]) < 0.01 and abs(turn - e["turn_deg"]) < 0.05)
            r.update(d_length_mm=round(L - e["length_mm"], 4), turn_deg=round(turn, 2))
        else:
            why = e["reason"]
            ok = {"closed": math.dist(xy[0], xy[-1]) < 1e-6, "non-planar": (r["z_range"] or 0) > 1,
                  "probably-metres": L < 1.0, "too-short": L < 20}.get(why, False)
            r["reason"] = why
        r["ok"] = bool(ok)
        bad += not ok
        res.append(r)
        print("ok  " if ok else "BAD ", e["file"], r.get("d_length_mm"), r.get("reason"))
    Path(out).write_text(json.dumps(res, indent=1))
    print(f"{len(res)} CSV entries, {bad} not matching")


if __name__ == "__main__":
    main(*sys.argv[1:])
