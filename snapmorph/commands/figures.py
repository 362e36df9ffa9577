"""`snapmorph figures`: reproduce the paper's figures into a folder."""

from __future__ import annotations

import argparse

FIGURES = ("specimens", "maps", "fk", "inverse", "arrays")


def add_parser(sub):
    p = sub.add_parser("figures", help="write the paper's figures (PNG) and tables (Markdown)")
    p.add_argument("--out", default="figures", help="output folder (default figures/)")
    p.add_argument("--only", nargs="*", choices=FIGURES, help="make only these figures")
    p.add_argument("--map", default=None, help="design map file for the map figures (default: the committed map)")
    p.set_defaults(run=run)
    return p


def run(args: argparse.Namespace) -> int:
    import importlib
    import os

    os.makedirs(args.out, exist_ok=True)
    wanted = args.only or FIGURES
    for name in wanted:
        module = importlib.import_module(f"snapmorph.figures_{name}")
        for path in module.make(args.out, args):
            print(f"wrote {path}")
    return 0
