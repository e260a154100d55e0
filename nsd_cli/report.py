"""``nsd report``: the validation report (PDF and one PNG per page) from an ``nsd compare`` folder.

Exit codes: 0 written; 2 bad input (missing folder, no or malformed results.json), nothing written.
"""
from __future__ import annotations

import argparse
from pathlib import Path

from nsd_cli.options import check_out_dir


HELP = "write the validation report (PDF and PNGs) from a results folder"


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--from", dest="source", required=True, metavar="DIR",
                   help="results folder written by nsd compare, seismic, ida, sweep, polar or cycle (--out DIR)")
    p.add_argument("--out", required=True, metavar="DIR2", help="folder for validation.pdf and the PNGs")


def run(args) -> int:
    from nsd_cli.options import no_special_files
    from reports.build import build_report, checked_plan
    if args.source and Path(args.source).is_dir():  # every file read is a regular one (a FIFO would block)
        no_special_files("--from", args.source, Path(args.source), "a results folder is read as regular files only")
    planned = checked_plan(args.source)  # the results folder first: bad input is found before anything else
    out = check_out_dir("--out", args.out)
    paths = build_report(args.source, out, planned=planned)
    print(f"report: {paths['pdf']} ({len(paths['pngs'])} pages, {paths['seconds']:.1f} s); "
          f"PNGs in {Path(paths['pdf']).parent}")
    return 0
