"""Merge BUILD/manifest_*.json into manifest.json (fixed order) and check each entry's fields.
    python3 make/make_manifest.py OUTDIR BUILDDIR
"""
import json
import sys
from pathlib import Path

PARTS = ["svg", "freecad", "librecad_draw", "librecad_resave", "synthetic", "csv", "libreoffice"]
READ_KEYS = ["length_mm", "start_mm", "end_mm", "turn_deg", "start_heading_deg", "frame", "direction",
             "tol_mm", "turn_tol_deg"]
REASONS = {"closed", "several-candidates", "no-curve", "non-planar", "probably-metres", "too-short",
           "unit-unknown", "unsupported-format"}
ORDER = ["file", "program", "what", "expect", "select", "reason", "reason_alt", "length_mm", "start_mm", "end_mm",
         "turn_deg", "start_heading_deg", "frame", "page_mm", "bbox_mm", "svg_ids", "direction", "tol_mm", "turn_tol_deg", "insunits",
         "units_note", "length_if_px_mm", "tangents", "tangent_start_deg", "tangent_end_deg", "candidates", "note"]


def main(outdir, build):
    outdir, build = Path(outdir), Path(build)
    man = []
    for p in PARTS:
        man += json.loads((build / f"manifest_{p}.json").read_text())
    out = []
    for e in man:
        e = {k: v for k, v in e.items() if v is not None or k == "insunits"}
        if e["expect"] == "read":
            e.pop("reason", None)
            missing = [k for k in READ_KEYS if k not in e]
            assert not missing, (e["file"], missing)
        else:
            assert e["reason"] in REASONS, e
            for k in ("start_mm", "end_mm", "turn_deg", "start_heading_deg", "direction", "frame",
                      "tol_mm", "turn_tol_deg", "page_mm", "bbox_mm", "svg_ids"):
                e.pop(k, None)
        assert (outdir / e["file"]).is_file(), e["file"]
        if "insunits" in e and e["insunits"] is None and not e["file"].endswith(".dxf"):
            e.pop("insunits")
        keys = [k for k in ORDER if k in e] + [k for k in e if k not in ORDER]
        out.append({k: e[k] for k in keys})
    (outdir / "manifest.json").write_text(json.dumps(out, indent=1, ensure_ascii=False) + "\n")
    files = {e["file"] for e in out}
    on_disk = {str(p.relative_to(outdir)) for p in outdir.rglob("*") if p.is_file()
               and p.suffix in (".svg", ".dxf", ".csv") and "make" not in p.parts}
    print(f"{len(out)} entries for {len(files)} files; files without entry: {sorted(on_disk - files)}")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
