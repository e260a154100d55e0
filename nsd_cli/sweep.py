"""``nsd sweep``: parametric sweeps (the paper's Section 4.3, Figures 8-20), resumable, on local
cores or a Dask scheduler. A sweep in which some design failed exits 3."""
from __future__ import annotations

import argparse
import re
import socket

from nsd_cli.options import (WORKERS_HELP, add_param_arguments, add_solver_arguments, base_params, check_out_dir,
                             parse_engines, parse_numbers, positive, resolved_workers, solver_settings, draw_figures)
from nsd_cli.limits import SWEEP_STEPS_MAX, check_drive_work
from nsd_core.device.params import FIELDS, ParameterError

MAX_VALUES = 200
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
    parser.add_argument("--samples-per-cycle", type=int, default=500,
                        help="output samples per cycle (default 500, the parametric study's own; one drive's default "
                             "in nsd cycle, nsd compare and the Python API is 2000)")
    parser.add_argument("--engines", default="semirecursive", help="comma-separated: semirecursive, mujoco, exudyn")
    parser.add_argument("--workers", type=int, default=None, help=WORKERS_HELP)
    parser.add_argument("--scheduler", default=None, help="address of a running Dask scheduler")
    parser.add_argument("--scheduler-timeout", type=float, default=None, metavar="S",
                        help="with --scheduler: seconds to wait for the connection and for the scheduler's answer, "
                             "each (default 10, in [0.1, 600])")
    parser.add_argument("--retry-failed", action="store_true", help="run designs stored as failed again")
    add_solver_arguments(parser)
    parser.add_argument("--out", required=True, help="output folder (resumable)")


def scheduler_timeout(args) -> float:
    """--scheduler-timeout (seconds for the connection and for the handshake, each), checked."""
    from nsd_cli import limits as lim
    t = getattr(args, "scheduler_timeout", None)
    if t is None:
        return lim.SCHEDULER_TIMEOUT_DEFAULT
    if getattr(args, "scheduler", None) is None:
        raise ParameterError("--scheduler-timeout: applies to --scheduler only")
    return lim.in_range("--scheduler-timeout", t, lim.SCHEDULER_TIMEOUT, "s")


def start_scheduler_hint() -> str:
    """How to start a Dask scheduler with what this Python has: the `dask` command beside it, or the
    `[dask]` extra to install first (README, Quick start)."""
    import importlib.util
    import sys
    from pathlib import Path
    here = Path(sys.executable).parent / "dask"
    if importlib.util.find_spec("distributed") is not None and here.exists():
        return (f"start one with `{here} scheduler` and its workers with `{here} worker tcp://HOST:PORT` "
                "(the [dask] extra; README, Quick start)")
    return (f"Dask is not installed here: `{sys.executable} -m pip install -e '.[dask]'` from the repository "
            "adds it (then `dask scheduler`, `dask worker tcp://HOST:PORT`)")


def check_scheduler(address: str | None, timeout: float = 10.0) -> None:
    """--scheduler: tcp://HOST:PORT (or HOST:PORT) where a Dask scheduler answers, checked in at most
    2 x ``timeout`` seconds before anything is written: the connection, then the scheduler's own
    handshake (a Dask scheduler speaks first), so a listener that accepts and never speaks is exit 2
    naming the address rather than a run that never answers."""
    if address is None:
        return
    from nsd_core.common.files import printable
    m = re.fullmatch(r"(?:tcp://)?([A-Za-z0-9.\-]+|\[[0-9a-fA-F:]+\]):([0-9]{1,5})", address.strip())
    if not m or not 0 < int(m.group(2)) < 65536:
        raise ParameterError(f"--scheduler {printable(repr(address))}: must be tcp://HOST:PORT of a running Dask "
                             "scheduler")
    host = m.group(1).strip("[]")
    try:
        sock = socket.create_connection((host, int(m.group(2))), timeout=timeout)
    except (OSError, UnicodeError) as e:
        why = "no answer" if isinstance(e, socket.timeout) else (getattr(e, "strerror", None) or e)
        raise ParameterError(f"--scheduler {address}: nothing answers there within {timeout:g} s ({why}); "
                             f"{start_scheduler_hint()}, or leave --scheduler out for local workers") from None
    try:
        first = _peek_handshake(sock, timeout)
    finally:
        sock.close()
    if not first:
        raise ParameterError(f"--scheduler {address}: accepts connections but "
                             + ("closed without a handshake" if first == b"" else
                                f"sent no Dask handshake within {timeout:g} s")
                             + "; not a Dask scheduler, or it is hung (see --scheduler-timeout)")
    if not _is_dask_header(first):
        raise ParameterError(f"--scheduler {address}: accepts connections but what it sends "
                             f"({printable(repr(first[:16]))}) is not a Dask handshake; not a Dask scheduler")


HANDSHAKE_MAX = 1 << 20  # bytes: a scheduler's handshake is a few hundred


def _peek_handshake(sock, timeout: float) -> bytes | None:
    """The first 16 bytes the peer sends (fewer if it stops or closes; b"" closed at once, None nothing
    within ``timeout``), left unread."""
    import time
    deadline, data = time.monotonic() + timeout, None
    while True:
        left = deadline - time.monotonic()
        if left <= 0:
            return data
        try:
            sock.settimeout(left)
            data = sock.recv(16, socket.MSG_PEEK)
        except OSError:
            return data
        if len(data) >= 16 or data == b"":
            return data
        time.sleep(0.02)


def _is_dask_header(data: bytes) -> bool:
    """Dask's TCP framing (distributed.comm.tcp): the message's byte count, then its frame count, each
    a little-endian uint64. Anything else (a web server, garbage) would make the client allocate what
    those bytes say (2.8 EiB for one such listener): refused here instead."""
    import struct
    if len(data) < 16:
        return False
    total, frames = struct.unpack("<QQ", data[:16])
    return 16 <= total <= HANDSHAKE_MAX and 1 <= frames <= 64 and 8 * (1 + frames) <= total


def run(args) -> int:
    from comparisons.engines import get_engine, run_engine
    from comparisons.engines.base import check_settings
    from nsd_core.device.drive import Drive
    from nsd_core.study.designs import make_designs, paper_designs
    from nsd_core.study.sweep import run_sweep
    base = base_params(args)
    for n in ("amplitude", "frequency"):
        positive(f"--{n}", getattr(args, n))
    args.workers = resolved_workers(args.workers)
    if args.paper == bool(args.param):
        raise ParameterError("--param / --paper: give exactly one (--param NAME --values ... or --paper)")
    if args.paper and args.values is not None:
        raise ParameterError("--values: only with --param (--paper has its own values)")
    engines = tuple(parse_engines(args.engines, check_available=True))
    settings = solver_settings(args)
    kw = dict(base=base, amplitude=args.amplitude, frequency=args.frequency, engines=engines,
              settings=settings, cycles=args.cycles, samples_per_cycle=args.samples_per_cycle,
              direction_deg=args.direction)
    Drive(Drive.A_MIN if args.amplitude is None else args.amplitude, args.frequency, args.direction, args.cycles,
          args.samples_per_cycle)  # (no --amplitude: each design its own)
    if args.paper:
        designs = paper_designs(**kw)
    else:
        if args.param not in FIELDS:
            raise ParameterError(f"--param {args.param}: unknown parameter; allowed: {', '.join(sorted(FIELDS))}")
        values = parse_numbers("--values", args.values, f" with --param {args.param}")
        if len(values) > MAX_VALUES:
            raise ParameterError(f"--values: {len(values)} values; at most {MAX_VALUES}")
        designs = make_designs(args.param, values, **kw)
    for d in designs:
        if d.amplitude >= d.params["rod_length"]:
            raise ParameterError(f"--amplitude = {d.amplitude}: must be < rod_length = {d.params['rod_length']} "
                                 f"(design {d.label})")
        check_settings(get_engine(d.engine), d.settings, d.engine)
    total = sum(check_drive_work(d.cycles / d.frequency, (d.settings or {}).get("max_step") or 1e-3,
                                 f"design {d.label}") for d in {d.key: d for d in designs}.values())
    if total > SWEEP_STEPS_MAX:
        raise ParameterError(f"--values: {len(designs)} designs would take about {total:.3g} solver steps together; "
                             f"at most {SWEEP_STEPS_MAX:.0e} per sweep")
    timeout = scheduler_timeout(args)
    check_scheduler(args.scheduler, timeout)
    out = check_out_dir("--out", args.out)
    index = run_sweep(designs, out, workers=args.workers, scheduler=args.scheduler, scheduler_timeout=timeout,
                      retry_failed=args.retry_failed, run_engine=run_engine, tally=args.tally)
    print(f"{index['ok']} design entries ok, {len(index['failed'])} failed, {len(index['missing'])} missing; "
          f"{index['elapsed_this_run_s']:.1f} s; wrote {out / 'sweep.json'}")
    for study, path in index["studies"].items():
        print(f"  {study}: {out / path}")
    draw_figures(out)  # the study's PNGs into its own folder
    return 3 if index["failed"] or index["missing"] else 0
