"""The cross-validation harness: every engine built from one description, compared under one rule.
Every law of the program is registered here: the device's and the baseline isolators' laws join the
registry (nsd_core.model.laws) when their packages are imported."""
import nsd_core.device  # noqa: F401 (the device's laws and its "device_path" motion)
import nsd_core.structure  # noqa: F401 (the baseline isolators' law)
