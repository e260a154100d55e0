"""``nsd calibrate``: fit the parameters the paper does not print to its Tables 5 and 6."""
from __future__ import annotations

import argparse

from nsd_cli.options import add_param_arguments, base_params, check_out_dir

HELP = "fit the unprinted parameters to Tables 5 and 6"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    add_param_arguments(parser, "parameter overrides (the starting set)")
    parser.add_argument("--fit", default=None,
                        help="comma-separated parameters to fit (default: rope_upper_height and the spring's "
                             "Bouc-Wen values)")
    parser.add_argument("--out", default=None, help="folder for calibrated_params.toml and calibration.json")


def run(args) -> int:
    from nsd_core.study.calibrate import DEFAULT_FIT, calibrate, format_report, write_outputs
    base = base_params(args)
    fit = DEFAULT_FIT if args.fit is None else tuple(s.strip() for s in args.fit.split(",") if s.strip())
    out = check_out_dir("--out", args.out)
    result = calibrate(base, fit)
    print(format_report(result))
    if out is not None:
        for path in write_outputs(result, out, base, start_file=args.params):
            print(f"wrote {path}")
    return 0

