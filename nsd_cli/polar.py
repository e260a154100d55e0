"""``nsd polar``: the direction study (issue 13). For n_w = n_r = n in --wires, versus the drive's
azimuth over a full turn: X_max, K0, K_min, loop area and peak force at --amplitude (quasi-static,
nsd_core.study.polar). Writes DIR/polar.json, DIR/polar.csv and DIR/polar.png.

Exit codes: 0 written; 2 bad input (one line, nothing written).
"""
from __future__ import annotations

import argparse
import os
from pathlib import Path

from nsd_cli.options import add_param_arguments, base_params, check_out_dir
from nsd_core.device.params import ParameterError

HELP = "the device's response versus drive direction, per number of wires"


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--wires", default="3,4,6,8", help="comma-separated n = n_w = n_r (each >= 3; default 3,4,6,8)")
    p.add_argument("--step", type=float, default=15.0, help="azimuth step [deg], dividing 360 (default 15)")
    p.add_argument("--amplitude", type=float, default=0.015, help="A [m] for the loop area and K_min (default 0.015)")
    p.add_argument("--points-per-cycle", type=int, default=100, help="quasi-static points per cycle (default 100)")
    add_param_arguments(p)
    p.add_argument("--workers", type=int, default=os.cpu_count() or 1, help="local processes")
    p.add_argument("--out", required=True, help="output folder (put it under a compare folder as DIR/polar for the report)")


def run(args) -> int:
    from nsd_core.device.results import atomic_write_json, atomic_write_text
    from nsd_core.study.polar import polar_csv, polar_study
    try:
        wires = tuple(int(w) for w in args.wires.split(",") if w.strip())
    except ValueError:
        raise ParameterError(f"--wires {args.wires!r}: must be comma-separated whole numbers >= 3") from None
    if args.points_per_cycle < 16:
        raise ParameterError(f"--points-per-cycle = {args.points_per_cycle}: must be >= 16")
    if args.workers < 1:
        raise ParameterError(f"--workers = {args.workers}: must be >= 1")
    if args.workers > 64:
        raise ParameterError(f"--workers = {args.workers}: must be in [1, 64]")
    if args.points_per_cycle > 10000:
        raise ParameterError(f"--points-per-cycle = {args.points_per_cycle}: must be in [16, 10000]")
    base = base_params(args)
    out = check_out_dir("--out", args.out)
    result = polar_study(wires, args.step, args.amplitude, base, args.points_per_cycle, args.workers)
    atomic_write_json(out / "polar.json", result)
    atomic_write_text(out / "polar.csv", polar_csv(result))
    _png(result, out / "polar.png")
    for n, d in result["designs"].items():
        sp = d["spread"]
        print(f"n = {n}: spread over the turn X_max {100 * sp['x_max']:.2f} %, K0 {100 * sp['k0']:.2f} %, "
              f"K_min {100 * sp['k_min']:.2f} %, loop area {100 * sp['loop_area']:.2f} %")
    print(f"wrote {out / 'polar.json'}, {out / 'polar.csv'} and {out / 'polar.png'}")
    return 0


def _png(result: dict, path: Path) -> None:
    import matplotlib.pyplot as plt
    from reports import style
    from reports.polar import polar_figure
    with plt.rc_context(style.RC):
        fig = polar_figure(result)
        tmp = path.parent / f".{path.name}.{os.getpid()}.tmp.png"
        fig.savefig(tmp)
        plt.close(fig)
    os.replace(tmp, path)
