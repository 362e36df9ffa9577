"""Helpers every `snapmorph` command uses: typed options that fail in the user's units, and one
rule for the files a command reads and writes.

Numbers typed on the command line are checked by argparse `type=` callables built here, so a bad
value ends at parse time with one line such as

    snapmorph unit: error: argument --t: must be > 0 mm (sheet thickness); got '-1'

The output rule, applied by every command BEFORE any long computation:

- missing parent folders are created;
- a path that runs through a file, names an existing folder (for a file) or cannot be written
  is refused with one line (`CommandError`, exit 2).

Only argparse is imported at module level (``snapmorph --help`` stays fast).
"""

from __future__ import annotations

import argparse
import math
import os
from pathlib import Path

from snapmorph.cli import CommandError

__all__ = [
    "CommandError",
    "PLOT_SUFFIXES",
    "TARGET_UNITS",
    "add_target_options",
    "bed_size",
    "input_file",
    "integer",
    "length_mm",
    "number",
    "output_dir",
    "output_file",
    "per_target",
    "plot_file",
    "read_target_arg",
]

# File types matplotlib's Agg/PDF/SVG/PS backends write.
PLOT_SUFFIXES = (".png", ".pdf", ".svg", ".eps", ".ps", ".jpg", ".jpeg", ".tif", ".tiff", ".webp")


def _range_text(unit: str, low, high, low_inclusive: bool, high_inclusive: bool) -> str:
    u = f" {unit}" if unit else ""
    if low is not None and high is not None:
        lb = "[" if low_inclusive else "("
        hb = "]" if high_inclusive else ")"
        return f"in {lb}{low:g}, {high:g}{hb}{u}"
    if low is not None:
        return f"{'>=' if low_inclusive else '>'} {low:g}{u}"
    if high is not None:
        return f"{'<=' if high_inclusive else '<'} {high:g}{u}"
    return f"a finite number{(' in' + u) if unit else ''}"


def number(unit: str = "", low=None, high=None, *, low_inclusive: bool = False,
           high_inclusive: bool = True, what: str = ""):
    """An argparse ``type=`` for a finite float in [low, high] (bounds optional), in `unit`.

    argparse prefixes the option name ("argument --t: ..."), so the message names the option,
    its unit and the valid range, and repeats what the user typed.
    """
    rng = _range_text(unit, low, high, low_inclusive, high_inclusive)
    note = f" ({what})" if what else ""

    def parse(text: str) -> float:
        try:
            value = float(text)
        except (TypeError, ValueError):
            raise argparse.ArgumentTypeError(
                f"must be a number {rng}{note}; got {text!r}") from None
        if not math.isfinite(value):
            raise argparse.ArgumentTypeError(f"must be finite, {rng}{note}; got {text!r}")
        bad = ((low is not None and (value < low or (value == low and not low_inclusive)))
               or (high is not None and (value > high or (value == high and not high_inclusive))))
        if bad:
            raise argparse.ArgumentTypeError(f"must be {rng}{note}; got {text!r}")
        return value

    parse.__name__ = f"number_{unit or 'dimensionless'}"  # argparse shows it on odd errors
    return parse


def length_mm(low=0.0, high=None, *, low_inclusive: bool = False, high_inclusive: bool = True,
              what: str = ""):
    """An argparse ``type=`` for a length typed in millimetres (returned in mm, not m).

    Default: strictly positive. ``length_mm(0, low_inclusive=True)`` allows zero."""
    return number("mm", low, high, low_inclusive=low_inclusive, high_inclusive=high_inclusive,
                  what=what)


def integer(low=None, high=None, *, what: str = ""):
    """An argparse ``type=`` for an integer in [low, high] (both inclusive, optional)."""
    rng = _range_text("", low, high, True, True).replace("a finite number", "an integer")

    def parse(text: str) -> int:
        try:
            value = int(text)
        except (TypeError, ValueError):
            raise argparse.ArgumentTypeError(
                f"must be an integer {rng}{(' (' + what + ')') if what else ''}; "
                f"got {text!r}") from None
        if (low is not None and value < low) or (high is not None and value > high):
            raise argparse.ArgumentTypeError(
                f"must be an integer {rng}{(' (' + what + ')') if what else ''}; got {text!r}")
        return value

    parse.__name__ = "integer"
    return parse


def bed_size(text: str) -> tuple:
    """An argparse ``type=`` for --bed: "600x400" (a sheet, mm) or "600" (a strip length,
    mm), as (width, height) or (length,)."""
    from snapmorph.design.nesting import parse_bed

    try:
        width, height = parse_bed(text)
    except (TypeError, ValueError):
        raise argparse.ArgumentTypeError(
            f"must be WIDTHxHEIGHT of the laser bed in mm (e.g. 600x400), or one length in mm "
            f"(the longest base piece), each > 0; got {text!r}") from None
    return (width,) if height is None else (width, height)


#: length units a target file (CSV, DXF) may be declared in
TARGET_UNITS = ("mm", "cm", "m", "in")


def add_target_options(p, units_option: str = "--units", what: str = "the target",
                       several: bool = False) -> None:
    """--select ID|LAYER and the length unit (`units_option`, dest ``target_units``) of a
    target file; `several`: given once for every target or once per target, in order."""
    each = (" Once for every target, or once per target in order ('-': none)." if several
            else "")
    kw = {"action": "append"} if several else {}
    p.add_argument("--select", metavar="ID|LAYER", default=None, **kw,
                   help=f"the curve of {what} when the drawing holds several: an SVG element "
                        f"id, Inkscape layer or group, DXF layer or handle.{each}")
    allowed = TARGET_UNITS + (("-",) if several else ())

    def unit(text: str) -> str:
        if text not in allowed:
            raise argparse.ArgumentTypeError(
                f"must be one of {', '.join(TARGET_UNITS)} (the target file's length unit"
                + ("; '-': none for that target" if several else "") + f"); got {text!r}")
        return text

    p.add_argument(units_option, dest="target_units", default=None, metavar="|".join(TARGET_UNITS),
                   type=unit, **kw,
                   help=f"length unit of {what} when a CSV header or a DXF's $INSUNITS does "
                        f"not say (an SVG carries its own).{each}")


def per_target(args, n: int) -> list:
    """[(select, units)] for n targets from --select and --units (`add_target_options` with
    several=True), each given never, once (for every target) or once per target ('-': none)."""
    out = []
    for option, values in (("--select", args.select), ("--units", args.target_units)):
        values = list(values or [None])
        if len(values) not in (1, n):
            raise CommandError(f"{option} is given {len(values)} times for {n} target(s): give "
                               f"it once (every target) or once per target ('-': none)")
        out.append([None if v == "-" else v for v in (values * n if len(values) == 1
                                                      else values)])
    return list(zip(*out))


def read_target_arg(path, option: str | None = None, select=None, units=None,
                    units_option: str = "--units"):
    """A target file as a `design.target_io.TargetFile`; every refusal (no such file, several
    curves, closed, wrong units, ...) a `CommandError` of one line in mm."""
    from snapmorph.design.target_io import read_target_file

    where = f"{option} {path}" if option else str(path)
    if not Path(os.path.expanduser(str(path))).exists():
        raise CommandError(f"{option + ': ' if option else ''}target file not found: {path}")
    input_file(path, option or "target")
    suffix = Path(str(path)).suffix.lower()
    if units is not None and suffix == ".svg":
        raise CommandError(f"{units_option} {units}: {where} is an SVG, which carries its own "
                           f"units (width, height, viewBox); {units_option} is for CSV and DXF "
                           "files")
    if select is not None and suffix not in (".svg", ".dxf"):
        raise CommandError(f"--select {select}: {where} is a CSV, which holds one curve; "
                           "--select is for SVG and DXF files")
    try:
        return read_target_file(path, select=select, units=units)
    except ValueError as exc:
        message = str(exc) if units_option == "--units" else \
            str(exc).replace("--units", units_option)
        raise CommandError(message if not option else f"{option}: {message}") from None


def add_unit_dimensions(p, *, L_what: str = "base length", L_help: str = "base length, mm",
                        flat_ok: bool = False, b_help: str = "extra flat length of the arch "
                        "ends, mm (default 0; the paper's specimens use b = w)",
                        nu: bool = False) -> None:
    """The unit commands' dimension options --L --h --t --w --b --E (and --nu): mm and Pa,
    each failing with one line naming the option, its unit and its range. ``flat_ok``:
    h = 0 (an arch-less unit) is accepted."""
    p.add_argument("--L", type=length_mm(what=L_what), required=True, help=L_help)
    p.add_argument("--h", type=length_mm(0, low_inclusive=flat_ok, what="arch apex height"),
                   required=True, help="arch apex height, mm" + (" (0 = arch-less)" if flat_ok
                                                                  else ""))
    p.add_argument("--t", type=length_mm(what="sheet thickness"), required=True,
                   help="sheet thickness, mm")
    p.add_argument("--w", type=length_mm(what="strip width"), required=True, help="strip width, mm")
    p.add_argument("--b", type=length_mm(0.0, low_inclusive=True, what="extra flat length"),
                   default=0.0, help=b_help)
    p.add_argument("--E", type=number("Pa", 0.0, what="Young's modulus"), default=2.2e9,
                   help="Young's modulus, Pa (default 2.2e9, PETG)")
    if nu:
        p.add_argument("--nu", type=number("", -1.0, 0.5, what="Poisson's ratio"), default=0.38,
                       help="Poisson's ratio (default 0.38, PETG)")


class _OldName(argparse.Action):
    """An option's snapmorph 0.1 name: stores into the new option's dest, remembers that the old
    name was typed (the messages then name it, as the user wrote it) and leaves a one-line
    deprecation note in ``args.deprecation_notes`` (`cli.main` prints it)."""

    def __init__(self, option_strings, dest, new_name="", **kw):
        self.new_name = new_name
        super().__init__(option_strings, dest, **kw)

    def __call__(self, parser, namespace, values, option_string=None):
        setattr(namespace, self.dest, values)
        typed = dict(getattr(namespace, "typed_names", {}))
        typed[self.dest] = option_string
        namespace.typed_names = typed
        note = f"note: {option_string} is deprecated; use {self.new_name}"
        notes = list(getattr(namespace, "deprecation_notes", []))
        namespace.deprecation_notes = notes + ([note] if note not in notes else [])


def add_renamed_option(p, new: str, old: str, **kw) -> None:
    """Option `new` (argparse keywords `kw`) and its old name `old`, hidden from --help, which
    still works: `cli.main` prints one line on stderr saying the new name."""
    action = p.add_argument(new, **kw)
    p.add_argument(old, dest=action.dest, action=_OldName, new_name=new, help=argparse.SUPPRESS,
                   default=argparse.SUPPRESS, type=kw.get("type"), choices=kw.get("choices"))


def typed_name(args, dest: str, new: str) -> str:
    """The name the user typed for option `dest`: its old name if that was used, else `new`."""
    return getattr(args, "typed_names", {}).get(dest, new)


def add_shape_options(p, *, plot: str, csv: str, overlay: str, start: str) -> None:
    """--plot, --csv, --overlay TARGET_CSV and --no-placement of the array commands (fk, array):
    help texts `plot`, `csv`, `overlay`, and where the array `start`s without its placement."""
    p.add_argument("--plot", default=None, help=plot)
    p.add_argument("--csv", default=None, help=csv)
    p.add_argument("--overlay", default=None, metavar="TARGET_CSV", help=overlay)
    p.add_argument("--no-placement", action="store_true",
                   help=f"ignore units.csv's placement line: {start}")


def add_snapped_option(p, what: str) -> None:
    """--snapped PATTERN (snapmorph 0.1: --state), a snap pattern: one character per unit."""
    add_renamed_option(p, "--snapped", "--state", default=None, metavar="PATTERN",
                       help=f"snap pattern, one character per unit, '1' = snapped{what}")


def add_unit_state_option(p, what: str) -> None:
    """--unit-state released|actuated (snapmorph 0.1: --state), the units' state."""
    add_renamed_option(p, "--unit-state", "--state", choices=("released", "actuated"),
                       default="released", help=what)


def _check_parent(path: Path, option: str) -> None:
    """Create the missing folders above `path`; refuse a parent that is a file."""
    parent = path.parent
    # Walk up to the first existing ancestor: it must be a folder.
    probe = parent
    while not probe.exists():
        if probe == probe.parent:
            break
        probe = probe.parent
    if probe.exists() and not probe.is_dir():
        raise CommandError(f"{option} {path}: {probe} is a file, not a folder")
    try:
        parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise CommandError(f"{option} {path}: cannot create the folder {parent} "
                           f"({exc.strerror or exc})") from None


def output_file(path, option: str = "output") -> Path:
    """Check that a file can be written at `path` (creating its parent folders); return it.

    Call before any long computation. The probe opens the file for appending and removes it
    again if it did not exist, so it works for root too (where `os.access` always says yes)."""
    if path is None:
        return None
    path = Path(os.path.expanduser(str(path)))
    if str(path) in ("", "."):
        raise CommandError(f"{option}: empty file name")
    if path.is_dir():
        raise CommandError(f"{option} {path}: is a folder; give a file name")
    _check_parent(path, option)
    existed = path.exists()
    try:
        with path.open("ab"):
            pass
    except OSError as exc:
        raise CommandError(f"{option} {path}: cannot write ({exc.strerror or exc})") from None
    if not existed:
        try:
            path.unlink()
        except OSError:
            pass
    return path


def plot_file(path, option: str = "--plot") -> Path:
    """`output_file` for a figure: the suffix must be one matplotlib writes."""
    if path is None:
        return None
    suffix = Path(str(path)).suffix.lower()
    if suffix not in PLOT_SUFFIXES:
        raise CommandError(f"{option} {path}: unknown figure type {suffix or '(no suffix)'!r}; "
                           f"use one of {', '.join(PLOT_SUFFIXES)}")
    return output_file(path, option)


def output_dir(path, option: str = "--out") -> Path:
    """Create the folder `path` (and its parents) if missing and check that it is writable."""
    if path is None:
        return None
    path = Path(os.path.expanduser(str(path)))
    if path.exists() and not path.is_dir():
        raise CommandError(f"{option} {path}: is a file, not a folder")
    _check_parent(path, option)
    try:
        path.mkdir(exist_ok=True)
    except OSError as exc:
        raise CommandError(f"{option} {path}: cannot create the folder "
                           f"({exc.strerror or exc})") from None
    probe = path / f".snapmorph-write-test-{os.getpid()}"
    try:
        probe.write_bytes(b"")
        probe.unlink()
    except OSError as exc:
        raise CommandError(f"{option} {path}: folder is not writable "
                           f"({exc.strerror or exc})") from None
    return path


def input_file(path, option: str = "input") -> Path:
    """Check that `path` is an existing, readable file; return it as a Path."""
    if path is None:
        return None
    path = Path(os.path.expanduser(str(path)))
    if not path.exists():
        raise CommandError(f"{option} {path}: no such file")
    if path.is_dir():
        raise CommandError(f"{option} {path}: is a folder, not a file")
    try:
        with path.open("rb") as fh:
            fh.read(1)
    except OSError as exc:
        raise CommandError(f"{option} {path}: cannot read ({exc.strerror or exc})") from None
    return path


def format_value(value, scale=1.0, digits=4) -> str:
    """A value for a printed table: "-" for None, yes/no for a flag, "n/a" for NaN, else
    ``value * scale`` to ``digits`` significant digits."""
    if value is None:
        return "-"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if value != value:  # NaN
        return "n/a"
    return f"{value * scale:.{digits}g}"


# --- what the unit commands (unit, unit3d, unit2d) share
def add_result_files(p, plot_help: str) -> None:
    """--plot PNG and --json FILE of a unit command."""
    p.add_argument("--plot", metavar="PNG", help=plot_help)
    p.add_argument("--json", metavar="FILE", help="write the metrics and the curve as JSON")


def result_files(args) -> tuple:
    """(--plot path or None, --json path or None), checked before anything is simulated."""
    return plot_file(args.plot), output_file(args.json, "--json")


def frame_unit_geometry(args):
    """The unit of the 3-D and 2-D commands (--L --h --t --w --b in mm, --E) in SI."""
    from snapmorph.units.frame3d import UnitGeometry

    mm = 1e-3
    return UnitGeometry(L=args.L * mm, h=args.h * mm, t=args.t * mm, w=args.w * mm,
                        b=args.b * mm, E=args.E)


def push_rows(r) -> list:
    """The first rows a unit command prints, (name, value, unit): how the push went."""
    return [("status", r.status, ""), ("bistable", format_value(r.bistable), ""),
            ("F_cr", format_value(r.F_cr), "N"), ("d_cr", format_value(r.d_cr, 1e3), "mm"),
            ("d_unstable (ii)", format_value(r.d_unstable, 1e3), "mm"),
            ("d_second (iii)", format_value(r.d_second, 1e3), "mm")]


def print_why_not(r, self_standing: bool = True) -> None:
    """Why the unit is not bistable (or, with `self_standing`, not self-standing), if so."""
    if r.reason and not r.bistable:
        print(f"  not bistable: {r.reason}")
    elif self_standing and r.self_standing is False:
        print(f"  not self-standing: {r.stability.get('released_reason', '')}")


def write_result_json(path, r, geometry, fields=("L", "h", "t", "w", "b", "E")) -> None:
    """A unit result as JSON: its summary (NaN as null), the geometry's `fields` in m and the
    force-displacement curve; says so on stdout."""
    import json

    payload = {k: (None if isinstance(v, float) and v != v else v) for k, v in r.summary().items()}
    payload["geometry_m"] = {k: getattr(geometry, k) for k in fields}
    payload["curve"] = {"d_m": r.curve[0].tolist(), "F_N": r.curve[1].tolist()}
    with open(path, "w") as fh:
        json.dump(payload, fh, indent=1)
    print(f"wrote {path}")
