"""``nsd warm``: compile the in-house engine and the peers' callbacks for every mode, once for this
version of the source, on every core (nsd_core.compilation.warm_all): an install step, or a CI runner's first
step, pays it before the tests and the gate. Without it each command compiles what it uses at its first
use (compiling every mode at any command's first run made the first drive cycle slower, measured). A second ``nsd warm`` of the same version finds the cache and exits
at once. Exit 0."""
from __future__ import annotations

import argparse

HELP = "compile every mode once for this version of the source (an install or CI step; otherwise each command compiles what it uses)"


def add_arguments(p: argparse.ArgumentParser) -> None:
    pass


def run(args) -> int:
    from nsd_core.compilation.warm_all import cache_dir, ensure_all
    seconds = ensure_all(peers=True)
    state = "compiled" if seconds > 0 else "already compiled"
    print(f"every mode {state} for this version: {cache_dir()}")
    return 0
