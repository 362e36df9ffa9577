#!/bin/bash
# LibreOffice Calc CSV exports:  bash make/make_libreoffice.sh BUILD OUTDIR
exec /usr/bin/python3 "$(dirname "$0")/make_libreoffice.py" "$2" "$1"
