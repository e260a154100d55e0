"""The negative-stiffness device (Dai et al. 2024): its parameters, geometry, force laws, the in-house
model of its drive and the quasi-static checks. Importing it registers the device's force laws."""
from nsd_core.device import laws as _laws  # noqa: F401 (registers rope, SMA wire, push spring, stop)
from nsd_core.device import path_motion as _path_motion  # noqa: F401 (registers the motion "device_path")
