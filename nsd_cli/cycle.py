"""``nsd cycle``: one drive on the in-house model -> DIR/cycle.csv, DIR/summary.json and the
force-displacement loop DIR/01_cycle_loop.png (``nsd report --from DIR`` draws it as a PDF too)."""
from __future__ import annotations

import argparse

from nsd_cli.limits import check_drive_work
from nsd_cli.options import (Progress, add_param_arguments, add_solver_arguments, base_params, check_finite,
                             check_out_dir, solver_settings, draw_figures)

HELP = "one force-displacement cycle of the in-house model"


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--path", default="line", metavar="line|circle|ellipse|figure8|FILE",
                   help="the plate's path in the plane; FILE: a CSV table of t [s], x [m], y [m] (default line)")
    p.add_argument("--amplitude", type=float, default=None,
                   help="A [m] >= 1e-6: amplitude, circle radius or major semi-axis (required, except for a FILE path, "
                        "which refuses it); |u| >= rod_length is exit 4")
    p.add_argument("--minor", type=float, default=None,
                   help="B [m] >= 0: ellipse (required), figure8 (default A/2); refused for line, circle and FILE")
    p.add_argument("--frequency", type=float, required=True, help="f [Hz], in [0.05, 100]")
    p.add_argument("--direction", type=float, default=None,
                   help="psi [deg] in [-360, 360], 0 = +X: the line's or major axis' azimuth (default 0; refused for "
                        "a FILE path, whose x, y are world coordinates)")
    p.add_argument("--cycles", type=int, default=2, help="cycles to run, in [1, 1000]; the last is the steady one")
    p.add_argument("--samples-per-cycle", type=int, default=None,
                   help="output samples per cycle (default 2000, as the Python API's Drive and nsd compare's cases), "
                        "in [16, 200000]; cycles x samples <= 2e6; the run's estimated solver steps (about 1100 per "
                        "model second, at least duration / max-step) <= 2e6")
    add_param_arguments(p)
    add_solver_arguments(p)
    p.add_argument("--out", required=True, help="output folder")


def drive_from_args(args):
    """The Drive of the options; bad input is a one-line ParameterError."""
    from nsd_core.device.drive import PATHS, Drive
    from nsd_core.device.params import ParameterError
    if args.path in PATHS:
        if args.amplitude is None:
            raise ParameterError(f"--amplitude: missing; the {args.path} path needs A [m]")
        amplitude = args.amplitude
    else:
        if args.amplitude is not None:
            raise ParameterError(f"--amplitude = {args.amplitude}: a table path {args.path!r} gives its own "
                                 "positions; leave --amplitude out")
        amplitude = 0.0
    if args.path not in PATHS and args.direction is not None:
        raise ParameterError(f"--direction = {args.direction}: a table path {args.path!r} gives world x, y; "
                             "leave --direction out")
    if args.path not in PATHS and args.minor is not None:
        raise ParameterError(f"--minor = {args.minor}: a table path {args.path!r} gives its own positions; "
                             "leave --minor out")
    direction = 0.0 if args.direction is None else args.direction
    samples = {} if args.samples_per_cycle is None else {"samples_per_cycle": args.samples_per_cycle}
    return Drive(amplitude, args.frequency, direction, args.cycles, path=args.path, minor=args.minor, **samples)


def run(args) -> int:
    params = base_params(args)
    drive = drive_from_args(args)
    given = solver_settings(args)
    check_drive_work(drive.duration, given.get("max_step", 1e-3), "--cycles / --frequency")  # 1e-3: the default
    from nsd_core.api import cycle
    from nsd_core.device.model import DEFAULT_SOLVER
    from nsd_core.device.results import write_csv
    from nsd_core.common.files import atomic_write_json
    solver = {**DEFAULT_SOLVER, **given}
    drive.check_followable(params)
    out = check_out_dir("--out", args.out)
    result, summary = cycle(params, drive, progress=Progress("nsd cycle"), **solver)
    check_finite({"cycle.csv": result, "summary.json": summary}, "nsd cycle")
    write_csv(out / "cycle.csv", result)
    atomic_write_json(out / "summary.json", summary)
    if drive.is_line:
        regions = " ".join(f"{r['sign']}[{r['from'] * 1e3:.2f},{r['to'] * 1e3:.2f}]mm" for r in summary["stiffness_regions"])
        print(f"A = {drive.amplitude} m, f = {drive.frequency} Hz: peak |F| = {summary['peak_force']:.2f} N, "
              f"loop area = {summary['loop_area']:.4f} J, stiffness {regions}, "
              f"{result.stats['steps']} steps in {result.stats['wall_time']:.2f} s")
    else:
        print(f"path {drive.path}, f = {drive.frequency} Hz: peak |F| = {summary['peak_force_magnitude']:.2f} N, "
              f"work per cycle = {summary['work_per_cycle']:.4f} J (x {summary['loop_area_x']:.4f}, "
              f"y {summary['loop_area_y']:.4f}), {result.stats['steps']} steps in {result.stats['wall_time']:.2f} s")
    for e in summary["events"]:
        print(f"  event {e['kind']}: t = {e['start']:.5f} s for {e['duration'] * 1e3:.3f} ms (u = {e['u_start'] * 1e3:.2f} mm)")
    if summary["outside_working_range"]:
        print("  WARNING: the ropes went slack: part of this cycle lies outside the working range")
    print(f"wrote {out / 'cycle.csv'} and {out / 'summary.json'}")
    draw_figures(out)  # the force-displacement loop as a PNG into the same folder
    return 0
