"""``nsd benchmark``: standard closed-loop multibody benchmarks on the generic semirecursive engine.

Prints a table (problem, error vs reference, digits, wall time), writes DIR/results.json
atomically, and exits 0 when every problem meets its stated goal, 1 otherwise.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from nsd_core.device.results import atomic_write_json


HELP = "standard multibody benchmarks on the generic engine"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--out", required=True, help="output folder (results.json)")
    parser.add_argument("--quick", action="store_true", help="shorter runs and fewer tolerances (about a minute)")
    parser.add_argument("--repeats", type=int, default=1, help="runs per problem; times are medians")


def run(args) -> int:
    from nsd_core.engine.problems.runner import run_all, table
    res = run_all(quick=args.quick, repeats=args.repeats, log=lambda m: print(m, file=sys.stderr))
    print(table(res))
    out = Path(args.out)
    atomic_write_json(out / "results.json", {"quick": bool(args.quick), "repeats": args.repeats, "problems": res,
                                             "all_passed": all(r["passed"] for r in res.values())})
    print(f"wrote {out / 'results.json'}")
    return 0 if all(r["passed"] for r in res.values()) else 1
