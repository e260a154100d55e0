"""``nsd tables``: the paper's Tables 5 and 6 (X_max versus l_d and F_press) next to the model."""
from __future__ import annotations

import argparse

from nsd_cli.options import WORKERS_HELP, add_param_arguments, base_params, check_out_dir, positive, resolved_workers
from nsd_core.device.params import ParameterError

HELP = "the paper's Tables 5 and 6 next to the model"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    add_param_arguments(parser, "parameter overrides (the base set)")
    parser.add_argument("--method", default="slack", help="slack (direct, default) or path (the quasi-static path)")
    parser.add_argument("--step", type=float, default=2e-5, help="path method's displacement step [m]")
    parser.add_argument("--workers", type=int, default=None, help=WORKERS_HELP)
    parser.add_argument("--out", default=None, help="folder for tables.csv")


def run(args) -> int:
    from nsd_core.study.tables import format_rows, table_rows, write_csv
    base = base_params(args)
    if args.method not in ("slack", "path"):
        raise ParameterError(f"--method {args.method!r}: allowed: slack, path")
    positive("--step", args.step)
    positive("--step", args.step)
    if args.step is not None and not 1e-7 <= args.step <= 1e-3:
        raise ParameterError(f"--step = {args.step}: must be in [1e-7, 1e-3] m")
    args.workers = resolved_workers(args.workers)
    out = check_out_dir("--out", args.out)
    rows = table_rows(base, method=args.method, step=args.step, workers=args.workers)
    print(format_rows(rows))
    if out is not None:
        write_csv(out / "tables.csv", rows)
        print(f"wrote {out / 'tables.csv'}")
    return 0
