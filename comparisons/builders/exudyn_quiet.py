"""Exudyn's "large amount of memory allocations" warning, silenced.

After every ``SolveDynamic`` Exudyn compares its count of C++ allocations with the number of solver
evaluations (``exudyn.solver.CheckSolverInfoStatistics``) and, above
``exudyn.solver.solverCheckMemoryAllocationsThreshold`` (100 000), prints on stdout "WARNING:
implicit second order time integration detected large amount (N) of memory allocations, which seem
to occur in every time step; this may be due to user functions; solver may be slow". Here they do
come from the user function, by design: the pre-step function reads the bodies' positions
(``GetNodeOutput`` returns a new array each call) to evaluate the shared force laws. The warning is
about speed, which the harness measures and reports itself, and a user cannot act on it; on stdout
it also interleaves with ``nsd compare``'s table. Exudyn has no switch for it
(``solverCheckMemoryAllocations`` exists but is not read in 1.13), so the threshold is raised.
"""
from __future__ import annotations

import math

import exudyn.solver


def quiet_allocation_warning() -> None:
    """Raise the threshold so that the check never prints (idempotent; results are unaffected)."""
    exudyn.solver.solverCheckMemoryAllocationsThreshold = math.inf
