#!/bin/bash
# LibreCAD 2.2 has no batch DXF writer, so it is driven like a person would: under Xvfb, with
# xdotool clicking File > Save as... and typing into its command line. Run through make_librecad.sh:
#   xvfb-run -a -s "-screen 0 1600x1000x24" bash make/librecad_session.sh BUILD OUTDIR
# BUILD/lc_in/*.dxf (written by make_synthetic.py) are opened and re-saved by LibreCAD;
# BUILD/lc_draw/*.cmd are command-line scripts typed into a new drawing and saved.
# Screen positions below are those of LibreCAD's default window (no window manager).
set -u
BUILD=$(readlink -f "$1"); OUT=$(readlink -f "$2")
mkdir -p "$OUT/dxf/librecad"
export HOME="$BUILD/lc_home"; mkdir -p "$HOME/.config/LibreCAD"
cat > "$HOME/.config/LibreCAD/LibreCAD.conf" <<CONF
[Appearance]
Language=en
LanguageCmd=en
[Defaults]
Unit=Millimeter
UseQtFileOpenDialog=1
[Startup]
FirstLoad=0
[WindowOptions]
SubWindowMode=0
CONF

wait_title() {  # wait until a window whose name contains $1 exists
  for _ in $(seq 1 100); do xdotool search --name "$1" >/dev/null 2>&1 && return 0; sleep 0.2; done
  echo "timeout waiting for window '$1'" >&2; return 1
}
save_as() {
  sleep 0.5
  xdotool mousemove 68 42 click 1; sleep 0.8             # File
  xdotool mousemove 113 178 click 1                       # Save as...
  wait_title "Save Drawing As" || return 1; sleep 0.8
  local W X Y
  W=$(xdotool search --name "Save Drawing As" | head -1)
  eval "$(xdotool getwindowgeometry --shell "$W")"          # sets X Y WIDTH HEIGHT
  xdotool mousemove $((X + 317)) $((Y + 360)) click --repeat 3 1; sleep 0.3  # File name field
  xdotool key ctrl+a; xdotool type --delay 5 "$1"; sleep 0.2; xdotool key Return
  for _ in $(seq 1 50); do [ -s "$1" ] && break; sleep 0.2; done
  sleep 1
}
run_lc() {  # run_lc INPUT(optional) -> sets LCPID
  librecad $1 >/dev/null 2>&1 &
  LCPID=$!
  wait_title "LibreCAD - " || return 1; sleep 1.5
}
stop_lc() { kill "$LCPID" 2>/dev/null; wait "$LCPID" 2>/dev/null; }

for f in "$BUILD"/lc_in/*.dxf; do
  n=$(basename "$f")
  rm -f "$OUT/dxf/librecad/$n"
  for try in 1 2 3; do     # LibreCAD 2.2.0 sometimes aborts while opening a file: try again
    run_lc "$f" && save_as "$OUT/dxf/librecad/$n"
    stop_lc
    [ -s "$OUT/dxf/librecad/$n" ] && break
  done
  echo "re-saved $n: $(stat -c %s "$OUT/dxf/librecad/$n" 2>/dev/null || echo MISSING)"
done

draw() {  # draw CMDFILE OUTFILE: type the command script into a new drawing, save it
  run_lc "" || return 1
  cmdline() { xdotool mousemove 400 400; sleep 0.1; xdotool key ctrl+m; sleep 0.3; }  # focus Command:
  cmdline
  while IFS= read -r line; do
    case "$line" in
      "<esc>") xdotool key Escape; sleep 0.2; cmdline ;;
      *) xdotool type --delay 5 "$line"; xdotool key Return ;;
    esac
    sleep 0.15
  done < "$1"
  xdotool key Escape; sleep 0.2; xdotool key Escape
  save_as "$2"
}

for c in "$BUILD"/lc_draw/*.cmd; do
  n=$(basename "$c" .cmd)
  rm -f "$OUT/dxf/librecad/$n.dxf"
  for try in 1 2 3; do
    draw "$c" "$OUT/dxf/librecad/$n.dxf"
    stop_lc
    [ -s "$OUT/dxf/librecad/$n.dxf" ] && break
  done
  echo "drawn $n: $(stat -c %s "$OUT/dxf/librecad/$n.dxf" 2>/dev/null || echo MISSING)"
done
