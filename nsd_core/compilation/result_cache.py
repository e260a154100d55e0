"""Results of pure computations kept on disk: a JSON file per result under
``$XDG_CACHE_HOME/nsd-harness/results/KIND`` (``~/.cache`` when unset), named by a hash of the
computation's inputs and of every source file of the project's packages (a new version of any file
computes again). The value returned is the JSON form, on the first call as on the later ones, so a kept
result and a computed one are the same numbers to the last digit. A file that cannot be read or written
is computed again."""
from __future__ import annotations

import hashlib
import json
import os
from functools import lru_cache
from pathlib import Path
from typing import Any, Callable

ROOT = Path(__file__).resolve().parents[2]


@lru_cache(maxsize=1)
def _source_version() -> str:
    from nsd_core.compilation.numba_cache import source_fingerprint
    return source_fingerprint(ROOT)


def result_file(kind: str, inputs: Any, environ=os.environ) -> Path:
    """Where the result of ``kind`` on ``inputs`` (JSON-able) is kept."""
    text = json.dumps(inputs, sort_keys=True, default=repr) + "|" + _source_version()
    from nsd_core.common.files import cache_root
    return cache_root("results", environ) / kind / f"{hashlib.sha256(text.encode()).hexdigest()[:24]}.json"


def cached_json(kind: str, inputs: Any, compute: Callable[[], Any]) -> Any:
    """``compute()`` in its JSON form, kept for ``inputs``: read back where kept, else computed and kept
    (an exception from ``compute`` is raised and nothing is kept)."""
    path = result_file(kind, inputs)
    try:
        if path.is_file():   # a FIFO or a folder in its place is never opened: computed again
            return json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        pass
    from nsd_core.common.files import _json_default, atomic_write_text   # as summary.json writes it
    text = json.dumps(compute(), default=_json_default)
    value = json.loads(text)
    try:
        atomic_write_text(path, text)
    except (OSError, ValueError):   # a folder that cannot be made or written, a non-file in the way
        pass
    return value
