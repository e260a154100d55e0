"""The library entry point for one drive: what ``nsd cycle`` does, as a function.

    from nsd_core.api import cycle
    from nsd_core.device.drive import Drive
    from nsd_core.device.params import Params
    result, summary = cycle(Params().replace(rope_stiffness=7e5), Drive(0.015, 1.0))
    result["F"], summary["loop_area"], summary["stiffness_regions"]
    steady = result.steady()            # the last (steady) cycle, the one the summary describes
    steady["u"], steady["F"]
    result, summary = cycle(Params(), Drive(0.015, 1.0, cycles=3, path="circle"))
    result["F_x"], result["F_y"], summary["peak_force_magnitude"], summary["work_per_cycle"]
"""
from __future__ import annotations

from typing import Any

from nsd_core.device.cycle import analyse
from nsd_core.device.model import simulate
from nsd_core.device.drive import Drive
from nsd_core.device.params import Params
from nsd_core.device.results import RunResult, versions


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
