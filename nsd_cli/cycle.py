"""``nsd cycle``: one drive on the in-house model -> DIR/cycle.csv and DIR/summary.json."""
from __future__ import annotations

import argparse

from nsd_cli.options import (Progress, add_param_arguments, add_solver_arguments, base_params, check_out_dir,
                             solver_settings)

HELP = "one force-displacement cycle of the in-house model"


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--amplitude", type=float, required=True, help="A [m]")
    p.add_argument("--frequency", type=float, required=True, help="f [Hz]")
    p.add_argument("--direction", type=float, default=0.0, help="psi [deg], 0 = +X")
    p.add_argument("--cycles", type=int, default=2, help="cycles to run; the last is the steady one")
    p.add_argument("--samples-per-cycle", type=int, default=2000, help="output samples per cycle")
    add_param_arguments(p)
    add_solver_arguments(p)
    p.add_argument("--out", required=True, help="output folder")


def run(args) -> int:
    from nsd_core.api import cycle
    from nsd_core.device.drive import Drive
    from nsd_core.device.model import DEFAULT_SOLVER
    from nsd_core.device.results import atomic_write_json, write_csv
    params = base_params(args)
    drive = Drive(args.amplitude, args.frequency, args.direction, args.cycles, args.samples_per_cycle)
    solver = {**DEFAULT_SOLVER, **solver_settings(args)}
    drive.check_followable(params)
    out = check_out_dir("--out", args.out)
    result, summary = cycle(params, drive, progress=Progress("nsd cycle"), **solver)
    write_csv(out / "cycle.csv", result)
    atomic_write_json(out / "summary.json", summary)
    regions = " ".join(f"{r['sign']}[{r['from'] * 1e3:.2f},{r['to'] * 1e3:.2f}]mm" for r in summary["stiffness_regions"])
    print(f"A = {drive.amplitude} m, f = {drive.frequency} Hz: peak |F| = {summary['peak_force']:.2f} N, "
          f"loop area = {summary['loop_area']:.4f} J, stiffness {regions}, "
          f"{result.stats['steps']} steps in {result.stats['wall_time']:.2f} s")
    for e in summary["events"]:
        print(f"  event {e['kind']}: t = {e['start']:.5f} s for {e['duration'] * 1e3:.3f} ms (u = {e['u_start'] * 1e3:.2f} mm)")
    if summary["outside_working_range"]:
        print("  WARNING: the ropes went slack: part of this cycle lies outside the working range")
    print(f"wrote {out / 'cycle.csv'} and {out / 'summary.json'}")
    return 0
