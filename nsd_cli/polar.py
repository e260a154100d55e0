"""``nsd polar``: the direction study. For n_w = n_r = n in --wires, versus the drive's
azimuth over a full turn: X_max, K0, K_min, loop area and peak force at --amplitude (quasi-static,
nsd_core.study.polar). Writes DIR/polar.json, DIR/polar.csv and DIR/polar.png.

Exit codes: 0 written; 2 bad input (one line, nothing written).
"""
from __future__ import annotations

import argparse
import os
from pathlib import Path

from nsd_cli import limits as lim
from nsd_cli.options import WORKERS_HELP, add_param_arguments, base_params, check_finite, check_out_dir, resolved_workers
from nsd_core.device.drive import Drive
from nsd_core.device.params import ParameterError

HELP = "the device's response versus drive direction, per number of wires"


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--wires", default="3,4,6,8",
                   help=f"comma-separated n = n_w = n_r, each once, each in [{lim.POLAR_WIRES[0]}, {lim.POLAR_WIRES[1]}], "
                        f"at most {lim.POLAR_DESIGNS_MAX} (default 3,4,6,8)")
    p.add_argument("--step", type=float, default=15.0,
                   help=f"azimuth step [deg], dividing 360, in [{lim.POLAR_STEP[0]:g}, {lim.POLAR_STEP[1]:g}] (default 15)")
    p.add_argument("--amplitude", type=float, default=0.015,
                   help="A [m] for the loop area and K_min, in (0, rod_length) (default 0.015)")
    p.add_argument("--points-per-cycle", type=int, default=100,
                   help=f"quasi-static points per cycle, in [{lim.POLAR_POINTS[0]}, {lim.POLAR_POINTS[1]}] (default 100); "
                        f"designs x 360/step x points <= {lim.POLAR_WORK_MAX}")
    add_param_arguments(p)
    p.add_argument("--workers", type=int, default=None, help=WORKERS_HELP)
    p.add_argument("--out", required=True, help="output folder (put it under a compare folder as DIR/polar for the report)")


def run(args) -> int:
    try:
        wires = tuple(int(w) for w in args.wires.split(","))
    except ValueError:
        raise ParameterError(f"--wires {args.wires!r}: must be comma-separated whole numbers in "
                             f"[{lim.POLAR_WIRES[0]}, {lim.POLAR_WIRES[1]}]") from None
    lim.check_polar_work(wires, args.step, args.points_per_cycle)
    args.workers = resolved_workers(args.workers)
    base = base_params(args)
    lim.in_range("--amplitude", args.amplitude, (Drive.A_MIN, base.rod_length * (1 - 1e-12)), "m (below rod_length)")
    for n in wires:
        base.replace(n_wires=n, n_ropes=n)  # each design's parameters checked (one line) before any work
    from nsd_core.common.files import atomic_write_json, atomic_write_text
    from nsd_core.study.polar import polar_csv, polar_study  # after the checks: a refusal starts light
    out = check_out_dir("--out", args.out)
    result = polar_study(wires, args.step, args.amplitude, base, args.points_per_cycle, args.workers)
    check_finite(result, "polar")
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
    from nsd_core.common.files import check_output_target
    from reports.build import naming
    check_output_target(path)
    tmp = path.parent / f".{path.name}.{os.getpid()}.tmp.png"
    try:
        with plt.rc_context(style.RC), naming(path):
            fig = polar_figure(result)
            fig.savefig(tmp)
            plt.close(fig)
            os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)  # a full disk leaves no half-written figure behind
        raise
