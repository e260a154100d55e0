"""The helper process of a first run's compilation (nsd_core.compilation.first_compile): a module of its own,
as it needs the runs themselves (device.model, device.seismic), which import device.warmup, which
imports first_compile."""
from __future__ import annotations

import json
from functools import partial

from nsd_core.compilation import first_compile, warmup
from nsd_core.engine.compile_once import quiet_notices, share_work


def run_function(mode: str):
    """The in-house run of ``mode``; only its own modules imported (the helper starts while the
    command compiles: the seismic mode's imports would delay a drive cycle's helper)."""
    if mode == "drive":
        from nsd_core.device.model import simulate
        return simulate
    from nsd_core.structure.seismic import simulate_seismic
    return simulate_seismic


def helper(key_json: str) -> None:
    """The same items as the process that started it, quietly (that process prints the one line)."""
    quiet_notices()
    key = tuple(json.loads(key_json))
    warmup._WARM.add(key)   # its tiny run is the last item, not again inside the wrapped run
    share_work(first_compile.items(key, partial(warmup.TINY[key[0]], run_function(key[0]), *key[1:])))
