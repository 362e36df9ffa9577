#!/bin/bash
# Regenerate the whole corpus (not run by CI). From tests/data/targets:
#   apt-get update && apt-get install -y inkscape librecad freecad xvfb xdotool python3-lxml \
#       python3-numpy libreoffice-calc-nogui
#   bash make/make_all.sh            # ~8 min; needs an ezdxf python (PY_EZDXF, default the project venv)
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${BUILD:-$(mktemp -d)}
PY_SYS=/usr/bin/python3                          # has numpy + Inkscape's inkex (python3-lxml)
PY_EZDXF=${PY_EZDXF:-/work/main/.venv/bin/python} # any python with ezdxf + numpy
rm -rf svg dxf csv
$PY_SYS make/make_svg.py . "$BUILD"                                   # Inkscape 1.2.2
CORPUS_MAKE=$PWD/make CORPUS_OUT=$PWD CORPUS_BUILD=$BUILD freecadcmd make/make_freecad.py  # FreeCAD
$PY_EZDXF make/make_synthetic.py . "$BUILD"                            # ezdxf synthetic + LibreCAD inputs
$PY_SYS make/make_librecad_cmds.py "$BUILD"
bash make/make_librecad.sh "$BUILD" .                                  # LibreCAD 2.2.0 under Xvfb
$PY_SYS make/make_csv.py . "$BUILD"                                    # hand-written CSV
bash make/make_libreoffice.sh "$BUILD" .                               # LibreOffice Calc CSV
$PY_SYS make/make_manifest.py . "$BUILD"
# second-way checks -> verification.json
$PY_EZDXF make/verify_dxf.py . "$BUILD/verify_dxf.json"
$PY_SYS make/verify_svg.py . "$BUILD" "$BUILD/verify_svg.json"
$PY_SYS make/verify_csv.py . "$BUILD/verify_csv.json"
$PY_SYS - "$BUILD" <<'PY'
import json, sys
b = sys.argv[1]
out = {k: json.load(open(f"{b}/verify_{k}.json")) for k in ("svg", "dxf", "csv")}
json.dump(out, open("verification.json", "w"), indent=1)
print({k: f"{sum(r['ok'] for r in v)}/{len(v)} ok" for k, v in out.items()})
PY
