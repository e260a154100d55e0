"""The library entry points: one drive (what ``nsd cycle`` does) and one seismic run (what ``nsd
seismic`` does), as functions.

    from nsd_core.api import cycle
    from nsd_core.device.drive import Drive
    from nsd_core.device.params import Params
    result, summary = cycle(Params().replace(rope_stiffness=7e5), Drive(0.015, 1.0))
    result["F"], summary["loop_area"], summary["stiffness_regions"]
    steady = result.steady()            # the last (steady) cycle, the one the summary describes
    steady["u"], steady["F"]
    result, summary = cycle(Params(), Drive(0.015, 1.0, cycles=3, path="circle"))
    result["F_x"], result["F_y"], summary["peak_force_magnitude"], summary["work_per_cycle"]

    from nsd_core.api import building_from, default_structure, fema_record, seismic
    ground = fema_record("nearfield-pulse", 1, scale=0.4, window=(4.8, 6.0), rotate_deg=20)
    result, summary = seismic(Params(), ground)            # the default structure on the device
    summary["peak_displacement"], result["x"], result["base_shear_x"]
    structure = default_structure(Params())
    structure = structure.with_building(building_from(structure.mass, {"stories": 3}))
    result, summary = seismic(Params(), ground, structure, device=False)   # on the supports alone
"""
from __future__ import annotations

from typing import Any

from nsd_core.device.cycle import analyse
from nsd_core.device.model import simulate
from nsd_core.device.drive import Drive
from nsd_core.device.params import Params
from nsd_core.device.results import RunResult, versions
from nsd_core.structure.building import building_from  # noqa: F401 (this module's API)
from nsd_core.ground.motions import GroundMotion, parse_ground_spec
from nsd_core.ground.records import fema_record  # noqa: F401 (this module's API)
from nsd_core.structure.isolation import Structure, default_structure
from nsd_core.structure.seismic_summary import seismic_summary


def cycle(params: Params, drive: Drive, progress=None, **solver) -> tuple[RunResult, dict[str, Any]]:
    """Run ``drive`` on the in-house model; return the time series and the summary that summary.json holds.

    Raises ParameterError (bad input), DriveError (a drive the mechanism cannot follow, or a state
    outside the laws' validity) and SolverError (integration failure), as the CLI's exit codes 2, 4, 3.
    """
    drive.check_followable(params)
    result = simulate(params, drive, progress=progress, **solver)
    summary = {"drive": drive.describe(),
               **analyse(result, drive.amplitude, drive.frequency, drive.path), "solver": result.stats,
               "wall_time": result.stats["wall_time"], "versions": versions(), "params": params.describe()}
    return result, summary


def seismic(params: Params, ground: GroundMotion, structure: Structure | None = None, device: bool = True,
            duration: float | None = None, dt_out: float = 1e-3, progress=None,
            **solver) -> tuple[RunResult, dict[str, Any]]:
    """Run the isolated structure (default: ``default_structure(params)``) on the device (or, with
    ``device=False``, on its supports alone) under ``ground`` (``fema_record``, or
    ``parse_ground_spec("harmonic:amplitude=1,frequency=2,duration=1")`` as ``nsd seismic --ground``),
    sampled every ``dt_out`` s up to ``duration`` (default: the ground motion's). Returns the time series
    (the columns of seismic.csv) and the summary that summary.json holds (peaks with their times, the
    residual displacement, the energy balance, the building's peaks, events, peaks on the last sample).

    Raises ParameterError (bad input), RodReachError and DriveError (|u| reaches the rod, or a state
    outside the laws' validity; ``err.partial`` holds the series up to then) and SolverError, as the
    CLI's exit codes 2, 4, 3.
    """
    from nsd_core.structure.seismic import simulate_seismic
    structure = structure if structure is not None else default_structure(params)
    result = simulate_seismic(params, structure, ground, duration=duration, dt_out=dt_out, device=device,
                              progress=progress, **solver)
    summary = {"ground": ground.describe(), "structure": structure.to_dict(), "device": device,
               **seismic_summary(result), "solver": result.stats, "versions": versions(),
               "params": params.describe()}
    return result, summary
