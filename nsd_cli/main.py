"""The ``nsd`` command: the top layer. Exit codes: 0 ok, 1 a tolerance failed (compare) or a
benchmark missed its goal, 2 bad input, 3 solver or engine failure, 4 a drive the mechanism cannot
follow or a state outside the force laws' validity.

One module per subcommand in this package, each with ``HELP``, ``add_arguments(parser)`` and
``run(args) -> int``; the options several share are defined once in ``nsd_cli.options``.
"""
from __future__ import annotations

import argparse
import importlib
import sys

from nsd_core.device.drive import DriveError
from nsd_core.engine.errors import InputError, SolverError

SUBCOMMANDS = ("cycle", "compare", "report", "sweep", "tables", "calibrate", "benchmark")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="nsd", description=__doc__.split("\n\n")[0].replace("\n", " "))
    sub = parser.add_subparsers(dest="command", required=True)
    for name in SUBCOMMANDS:
        mod = importlib.import_module(f"nsd_cli.{name}")
        p = sub.add_parser(name, help=mod.HELP, description=(mod.__doc__ or mod.HELP).strip())
        mod.add_arguments(p)
        p.set_defaults(handler=mod.run)
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return int(args.handler(args) or 0)
    except InputError as e:
        print(f"nsd: error: {e}", file=sys.stderr)
        return 2
    except DriveError as e:
        print(f"nsd: error: {e}", file=sys.stderr)
        return 4
    except SolverError as e:
        print(f"nsd: solver failure: {e}", file=sys.stderr)
        return 3


if __name__ == "__main__":
    sys.exit(main())
