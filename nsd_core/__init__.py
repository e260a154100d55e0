__version__ = "0.1.0"

from nsd_core.compilation.numba_cache import quiet_cache_warnings, use_versioned_cache

quiet_cache_warnings()  # numba's "Cannot cache compiled function" (NUMBA_OPT=0) never reaches stderr
use_versioned_cache()  # before any kernel is compiled: numba's cache does not see edits to callees

# the warm-up every in-house run calls before its clock starts (nsd_core.engine.timing.warm_and_time),
# installed from the compilation layer: the engine and the device below it name none of it
import nsd_core.compilation.warmup  # noqa: E402,F401
