__version__ = "0.1.0"

from nsd_core.compilation.numba_cache import quiet_cache_warnings, use_versioned_cache

quiet_cache_warnings()  # numba's "Cannot cache compiled function" (NUMBA_OPT=0) never reaches stderr
use_versioned_cache()  # before any kernel is compiled: numba's cache does not see edits to callees
