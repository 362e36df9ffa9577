#!/bin/bash
# LibreCAD part: needs make_synthetic.py (writes BUILD/lc_in) and make_librecad_cmds.py (BUILD/lc_draw) first.
#   bash make/make_librecad.sh BUILD OUTDIR
set -e
xvfb-run -a -s "-screen 0 1600x1000x24" bash "$(dirname "$0")/librecad_session.sh" "$1" "$2"
