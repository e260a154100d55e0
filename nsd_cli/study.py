"""``nsd sweep``, ``nsd tables`` and ``nsd calibrate``: the command-line glue for the paper's
Section 4.3 (sweeps, Figures 8-20), Tables 5 and 6, and the calibration of the unprinted values.

Bad input raises ParameterError (one line naming the option, the value and what is allowed); the
``nsd`` command turns it into exit code 2. A sweep in which some design failed exits 3.
"""
from __future__ import annotations

import argparse
import math
import os
from pathlib import Path

from nsd_core.device.params import ParameterError, load_params, parse_set


def _params_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("--params", help="TOML file of parameter overrides (the base set)")
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE", help="override one parameter")


def add_arguments(parser: argparse.ArgumentParser, name: str = "sweep") -> None:
    _params_args(parser)
    if name == "sweep":
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
        parser.add_argument("--method", default=None, help="semirecursive integrator (RK45, DOP853, ...)")
        parser.add_argument("--rtol", type=float, default=None)
        parser.add_argument("--atol", type=float, default=None)
        parser.add_argument("--max-step", type=float, default=None)
        parser.add_argument("--out", required=True, help="output folder (resumable)")
    elif name == "tables":
        parser.add_argument("--method", default="slack", help="slack (direct, default) or path (quasistatic.x_max)")
        parser.add_argument("--step", type=float, default=2e-5, help="path method's displacement step [m]")
        parser.add_argument("--workers", type=int, default=os.cpu_count() or 1)
        parser.add_argument("--out", default=None, help="folder for tables.csv")
    elif name == "calibrate":
        parser.add_argument("--fit", default=None,
                            help="comma-separated parameters to fit (default: rope_upper_height and the spring's "
                                 "Bouc-Wen values)")
        parser.add_argument("--out", default=None, help="folder for calibrated_params.toml and calibration.json")


def _positive(name: str, v, whole: bool = False) -> None:
    if v is None:
        return
    if not math.isfinite(v) or v <= 0 or (whole and v != int(v)):
        raise ParameterError(f"{name} = {v}: must be a {'whole number >= 1' if whole else 'finite number > 0'}")


def _values(text: str | None, param: str) -> list[float]:
    if not text:
        raise ParameterError(f"--values: required with --param {param} (comma-separated numbers)")
    out = []
    for item in text.split(","):
        try:
            v = float(item)
        except ValueError:
            raise ParameterError(f"--values {item.strip()!r}: not a number (comma-separated numbers expected)") from None
        if not math.isfinite(v):
            raise ParameterError(f"--values {item.strip()!r}: must be finite")
        out.append(v)
    return out


def run(args) -> int:
    return {"sweep": run_sweep_cmd, "tables": run_tables, "calibrate": run_calibrate}[args.command](args)


def run_sweep_cmd(args) -> int:
    from nsd_core.device.params import FIELDS
    from nsd_core.study.study import check_engines, make_designs, paper_designs, run_sweep
    base = load_params(args.params, parse_set(args.set))
    for n in ("amplitude", "frequency", "max_step", "rtol", "atol"):
        _positive(f"--{n.replace('_', '-')}", getattr(args, n))
    for n in ("cycles", "samples_per_cycle", "workers"):
        _positive(f"--{n.replace('_', '-')}", getattr(args, n), whole=True)
    if args.samples_per_cycle < 16:
        raise ParameterError(f"--samples-per-cycle = {args.samples_per_cycle}: must be >= 16")
    if args.paper == bool(args.param):
        raise ParameterError("--param / --paper: give exactly one (--param NAME --values ... or --paper)")
    engines = tuple(e.strip() for e in args.engines.split(",") if e.strip())
    if not engines:
        raise ParameterError(f"--engines {args.engines!r}: name at least one engine")
    check_engines(list(engines))
    settings = {k: getattr(args, k) for k in ("method", "rtol", "atol", "max_step") if getattr(args, k) is not None}
    kw = dict(base=base, amplitude=args.amplitude, frequency=args.frequency, engines=engines, settings=settings,
              cycles=args.cycles, samples_per_cycle=args.samples_per_cycle, direction_deg=args.direction)
    if args.paper:
        designs = paper_designs(**kw)
    else:
        if args.param not in FIELDS:
            raise ParameterError(f"--param {args.param}: unknown parameter; allowed: {', '.join(sorted(FIELDS))}")
        designs = make_designs(args.param, _values(args.values, args.param), **kw)
    for d in designs:
        if d.amplitude >= d.params["rod_length"]:
            raise ParameterError(f"--amplitude = {d.amplitude}: must be < rod_length = {d.params['rod_length']} "
                                 f"(design {d.label})")
    index = run_sweep(designs, args.out, workers=args.workers, scheduler=args.scheduler,
                      retry_failed=args.retry_failed)
    print(f"{index['ok']} design entries ok, {len(index['failed'])} failed, {len(index['missing'])} missing; "
          f"{index['elapsed_this_run_s']:.1f} s; wrote {Path(args.out) / 'sweep.json'}")
    for study, path in index["studies"].items():
        print(f"  {study}: {Path(args.out) / path}")
    return 3 if index["failed"] or index["missing"] else 0


def run_tables(args) -> int:
    from nsd_core.study.tables import format_rows, table_rows, write_csv
    base = load_params(args.params, parse_set(args.set))
    if args.method not in ("slack", "path"):
        raise ParameterError(f"--method {args.method!r}: allowed: slack, path")
    _positive("--step", args.step)
    _positive("--workers", args.workers, whole=True)
    rows = table_rows(base, method=args.method, step=args.step, workers=args.workers)
    print(format_rows(rows))
    if args.out:
        write_csv(Path(args.out) / "tables.csv", rows)
        print(f"wrote {Path(args.out) / 'tables.csv'}")
    return 0


def run_calibrate(args) -> int:
    from nsd_core.study.calibrate import DEFAULT_FIT, calibrate, format_report, write_outputs
    base = load_params(args.params, parse_set(args.set))
    fit = DEFAULT_FIT if not args.fit else tuple(s.strip() for s in args.fit.split(",") if s.strip())
    result = calibrate(base, fit)
    print(format_report(result))
    if args.out:
        for path in write_outputs(result, args.out, base, start_file=args.params):
            print(f"wrote {path}")
    return 0
