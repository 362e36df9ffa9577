"""`snapmorph figures`: reproduce the paper's figures into a folder, with a gallery page."""

from __future__ import annotations

import argparse

FIGURES = ("specimens", "maps", "fk", "inverse", "arrays", "unit3d")


def add_parser(sub):
    p = sub.add_parser("figures", help="write the paper's figures (PNG), tables (Markdown) and "
                                       "a gallery page index.md")
    p.add_argument("--out", default="figures", help="output folder (default figures/)")
    p.add_argument("--only", nargs="*", choices=FIGURES, help="make only these figures")
    p.add_argument("--map", default=None,
                   help="design map file for the map figures (default: the committed map)")
    p.set_defaults(run=run)
    return p


def run(args: argparse.Namespace) -> int:
    import importlib
    from pathlib import Path

    from snapmorph.commands._common import input_file, output_dir

    if args.map:
        input_file(args.map, "--map")
    out = output_dir(args.out, "--out")
    wanted = args.only or FIGURES
    from tqdm import tqdm

    written, failed = [], []
    bar = tqdm(wanted, desc="figures", unit="group", leave=False)
    for name in bar:
        bar.set_postfix_str(name)
        module = importlib.import_module(f"snapmorph.figures_{name}")
        try:
            for path in module.make(str(out), args):
                tqdm.write(f"wrote {path}")
                written.append(Path(path))
        except ValueError as exc:  # one group's expected failure (e.g. an old map): go on
            failed.append(f"{name}: {exc}")
    bar.close()
    from snapmorph.figures_gallery import write_gallery

    print(f"wrote {write_gallery(out)}")
    if failed:
        import sys

        for line in failed:
            print(f"snapmorph figures: error: {line}", file=sys.stderr)
        return 1  # the other figures and the gallery are written
    return 0
