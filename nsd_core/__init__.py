__version__ = "0.1.0"

from nsd_core.numba_cache import use_versioned_cache

use_versioned_cache()  # before any kernel is compiled: numba's cache does not see edits to callees
