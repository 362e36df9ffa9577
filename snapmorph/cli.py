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

COMMANDS = ("unit", "maps", "design", "fk", "array", "figures")


class CommandError(Exception):
    """A user-facing error: printed as one line, exit status 2."""


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
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
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "command", None):
        parser.print_help()
        return 0
    try:
        return int(args.run(args) or 0)
    except CommandError as exc:
        print(f"snapmorph {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except ValueError as exc:
        # Validation errors from the library name the parameter and its range.
        print(f"snapmorph {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    raise SystemExit(main())
