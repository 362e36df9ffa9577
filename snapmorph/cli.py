"""The `snapmorph` command line.

Each subcommand lives in `snapmorph/commands/<name>.py` and exposes `add_parser(subparsers)`
and `run(args) -> int`. Command modules import only argparse at module level, so that
`snapmorph --help` stays fast; the heavy stack (numba, xarray, dask, matplotlib) is imported
inside `run`.
"""

from __future__ import annotations

import argparse
import importlib
import sys

COMMANDS = ("unit", "maps", "design", "fk", "array", "figures", "unit3d", "unit2d", "tolerance",
            "sheet")


class CommandError(Exception):
    """A user-facing error: printed as one line, exit status 2."""


class OneLineParser(argparse.ArgumentParser):
    """argparse with usage errors in one line (no usage dump): the option, its unit and range
    come from the `snapmorph.commands._common` types; ``--help`` shows the usage."""

    def error(self, message):
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def build_parser() -> argparse.ArgumentParser:
    parser = OneLineParser(
        prog="snapmorph",
        description="Bistable arch-on-base units: simulate one unit, build design maps, "
        "design arrays that morph into target shapes.",
    )
    from snapmorph import __version__

    parser.add_argument("--version", action="version", version=f"snapmorph {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in COMMANDS:
        try:
            module = importlib.import_module(f"snapmorph.commands.{name}")
        except ModuleNotFoundError:
            continue
        module.add_parser(sub)
    return parser


def main(argv=None) -> int:
    """Run one command; return its exit status (2 for any expected failure, printed as one
    line on stderr; ``--help`` and usage errors return instead of raising SystemExit)."""
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:
        return exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 2)
    if not getattr(args, "command", None):
        parser.print_help()
        return 0
    # notes on old option names: after the output, or in the one line of an error
    notes = getattr(args, "deprecation_notes", [])
    try:
        status = int(args.run(args) or 0)
    except (CommandError, ValueError) as exc:
        # ValueError: validation errors from the library name the parameter and its range.
        _error(args.command, str(exc), notes)
        return 2
    except OSError as exc:
        # Files the command could not read or write (the paths are checked up front by
        # `commands._common`; this catches what slips through, e.g. a disk that fills up).
        where = f": {exc.filename}" if getattr(exc, "filename", None) else ""
        _error(args.command, f"{exc.strerror or exc}{where}", notes)
        return 2
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130
    for note in notes:
        print(f"snapmorph {args.command}: {note}", file=sys.stderr)
    return status


def _error(command, message, notes) -> None:
    print(f"snapmorph {command}: error: {message}" + "".join(f" ({n})" for n in notes),
          file=sys.stderr)


if __name__ == "__main__":
    raise SystemExit(main())
