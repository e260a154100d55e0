"""``nsd warm``: compile the in-house engine and the peers' callbacks for every mode, once for this
version of the source, on every core (nsd_core.engine.warm_all). Any command's first run compiles the
in-house modes the same way; this one adds the peers and lets an install step, or a CI runner's first
step, pay it before the tests and the gate. A second ``nsd warm`` of the same version finds the cache and exits
at once. Exit 0."""
from __future__ import annotations

import argparse

HELP = "compile every mode once for this version of the source (an install or CI step; any command does it otherwise)"


def add_arguments(p: argparse.ArgumentParser) -> None:
    pass


def run(args) -> int:
    from nsd_core.engine.warm_all import cache_dir, complete, ensure_all
    seconds = ensure_all(peers=True)
    state = ("compiled" if seconds > 0 else "already compiled" if complete(peers=True)
             else "not compiled (NSD_WARM_ALL=0)")
    print(f"every mode {state} for this version: {cache_dir()}")
    return 0
