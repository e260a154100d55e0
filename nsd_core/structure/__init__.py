"""The isolated structure: the isolation level (the device, the baseline isolators, the restrainer),
the building above it, the design to a code's design point and the code checks, and the seismic run.
Importing it registers the baseline isolators' law."""
from nsd_core.structure import isolator_laws as _isolator_laws  # noqa: F401 (registers bidirectional_hysteresis)
