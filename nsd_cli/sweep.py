"""``nsd sweep``: parametric sweeps (the paper's Section 4.3, Figures 8-20), resumable, on local
cores or a Dask scheduler. A sweep in which some design failed exits 3."""
from __future__ import annotations

import argparse
import os
from pathlib import Path

from nsd_cli.options import (add_param_arguments, add_solver_arguments, base_params, parse_engines, parse_numbers,
                             positive, solver_settings)
from nsd_core.device.params import FIELDS, ParameterError

HELP = "parametric sweeps (the paper's Section 4.3)"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    add_param_arguments(parser, "parameter overrides (the base set)")
    parser.add_argument("--param", help="parameter to vary (a Params field, e.g. rod_length)")
    parser.add_argument("--values", help="comma-separated values of --param, SI units")
    parser.add_argument("--paper", action="store_true", help="all seven studies of Section 4.3")
    parser.add_argument("--amplitude", type=float, default=None,
                        help="A [m]; default min(0.024, 0.95 X_max) per design (Figure 8's working ranges)")
    parser.add_argument("--frequency", type=float, default=10.0, help="f [Hz] (default 10, Section 4.3)")
    parser.add_argument("--direction", type=float, default=0.0, help="psi [deg], 0 = +X")
    parser.add_argument("--cycles", type=int, default=2, help="cycles per run; the last is analysed")
    parser.add_argument("--samples-per-cycle", type=int, default=500)
    parser.add_argument("--engines", default="semirecursive", help="comma-separated: semirecursive, mujoco, exudyn")
    parser.add_argument("--workers", type=int, default=os.cpu_count() or 1, help="local processes")
    parser.add_argument("--scheduler", default=None, help="address of a running Dask scheduler")
    parser.add_argument("--retry-failed", action="store_true", help="run designs stored as failed again")
    add_solver_arguments(parser)
    parser.add_argument("--out", required=True, help="output folder (resumable)")


def run(args) -> int:
    from comparisons.engines import run_engine
    from nsd_core.study.designs import make_designs, paper_designs
    from nsd_core.study.sweep import run_sweep
    base = base_params(args)
    for n in ("amplitude", "frequency"):
        positive(f"--{n}", getattr(args, n))
    for n in ("cycles", "samples_per_cycle", "workers"):
        positive(f"--{n.replace('_', '-')}", getattr(args, n), whole=True)
    if args.samples_per_cycle < 16:
        raise ParameterError(f"--samples-per-cycle = {args.samples_per_cycle}: must be >= 16")
    if args.paper == bool(args.param):
        raise ParameterError("--param / --paper: give exactly one (--param NAME --values ... or --paper)")
    engines = tuple(parse_engines(args.engines, check_available=True))
    kw = dict(base=base, amplitude=args.amplitude, frequency=args.frequency, engines=engines,
              settings=solver_settings(args), cycles=args.cycles, samples_per_cycle=args.samples_per_cycle,
              direction_deg=args.direction)
    if args.paper:
        designs = paper_designs(**kw)
    else:
        if args.param not in FIELDS:
            raise ParameterError(f"--param {args.param}: unknown parameter; allowed: {', '.join(sorted(FIELDS))}")
        designs = make_designs(args.param, parse_numbers("--values", args.values, f" with --param {args.param}"), **kw)
    for d in designs:
        if d.amplitude >= d.params["rod_length"]:
            raise ParameterError(f"--amplitude = {d.amplitude}: must be < rod_length = {d.params['rod_length']} "
                                 f"(design {d.label})")
    index = run_sweep(designs, args.out, workers=args.workers, scheduler=args.scheduler,
                      retry_failed=args.retry_failed, run_engine=run_engine)
    print(f"{index['ok']} design entries ok, {len(index['failed'])} failed, {len(index['missing'])} missing; "
          f"{index['elapsed_this_run_s']:.1f} s; wrote {Path(args.out) / 'sweep.json'}")
    for study, path in index["studies"].items():
        print(f"  {study}: {Path(args.out) / path}")
    return 3 if index["failed"] or index["missing"] else 0
