"""``nsd benchmark``: standard closed-loop multibody benchmarks on the generic semirecursive engine.

Prints a table (problem, error vs reference, digits, wall time), writes DIR/results.json
atomically when --out is given, and exits 0 when every problem meets its stated goal, 1 otherwise.
"""
from __future__ import annotations

import argparse
import sys

from nsd_cli.options import check_out_dir, whole
from nsd_core.common.files import atomic_write_json


HELP = "standard multibody benchmarks on the generic engine"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--out", default=None, help="output folder for results.json (default: print only)")
    parser.add_argument("--quick", action="store_true", help="shorter runs and fewer tolerances (about a minute)")
    parser.add_argument("--repeats", type=int, default=1, help="runs per problem; times are medians")


def run(args) -> int:
    from nsd_core.engine.problems.runner import run_all, table
    whole("--repeats", args.repeats, 1, 20)
    out = check_out_dir("--out", args.out)
    res = run_all(quick=args.quick, repeats=args.repeats, log=lambda m: print(m, file=sys.stderr))
    print(table(res))
    if out is not None:
        atomic_write_json(out / "results.json", {"quick": bool(args.quick), "repeats": args.repeats,
                                                 "problems": res, "all_passed": all(r["passed"] for r in res.values())})
        print(f"wrote {out / 'results.json'}")
    return 0 if all(r["passed"] for r in res.values()) else 1
