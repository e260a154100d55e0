"""The helper process of a first run's compilation (nsd_core.device.first_compile): a module of its own,
as it needs the runs themselves (device.model, device.seismic), which import device.warmup, which
imports first_compile."""
from __future__ import annotations

import json
from functools import partial

from nsd_core.device import first_compile, warmup
from nsd_core.device.model import simulate
from nsd_core.device.seismic import simulate_seismic
from nsd_core.engine.compile_once import quiet_notices, share_work

RUNS = {"drive": simulate, "seismic": simulate_seismic}


def helper(key_json: str) -> None:
    """The same items as the process that started it, quietly (that process prints the one line)."""
    quiet_notices()
    key = tuple(json.loads(key_json))
    warmup._WARM.add(key)   # its tiny run is the last item, not again inside the wrapped run
    share_work(first_compile.items(key, partial(warmup.TINY[key[0]], RUNS[key[0]], *key[1:])))
