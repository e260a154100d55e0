"""Cost of one evaluation of the in-house model on the compiled path, and of each of its parts.

    python benchmarks/bench_rhs.py [--loops 20000] [--repeats 25] [--out out/bench]

A right-hand side of the Figure 6 drive (A = 15 mm, 1 Hz) near its start, called in a compiled
loop with t moving 10 us a call; each part (the dependent velocities, element kinematics, the force
laws, the reduced dynamics, ...) timed the same way on the same state; the evaluation generated for
the mechanism (nsd_core.engine.codegen) and the generic one, both called through the function
pointer the step loop uses. The minimum over ``repeats`` loops of ``loops``
calls: a shared machine only ever adds time, so the minimum is the least disturbed reading.
Counters: Newton iterations per assembly in the loop.
"""
from __future__ import annotations

import argparse
import os
import platform
import time
from pathlib import Path

import numpy as np
from numba import njit

from nsd_core.device.compiled import compiled_model, device_forces, device_motion
from nsd_core.device.drive import Drive
from nsd_core.device.model import device_system, rest_state
from nsd_core.device.params import Params
from nsd_core.common.files import atomic_write_json
from nsd_core.engine import compiled as C
from nsd_core.engine.codegen import generated_evaluator, generic_evaluator
from nsd_core.engine.compiled_model import make_workspace
from nsd_core.engine.dynamics import body_terms_kernel
from nsd_core.engine.elements import element_kinematics
from nsd_core.engine.kinematics import positions_kernel


@njit
def _rhs(N, y, m, w, forces, motion, dydt, reactions):
    for i in range(N):  # t moves 10 us a call, as between stages, so Newton has work to do
        C.rhs_into(0.25 + i * 1e-5, y, m, w, forces, motion, dydt, reactions)


@njit
def _evaluator(N, evaluator, y, m, w, forces, motion, reactions):
    for i in range(N):  # through a function pointer, as the step loop calls it
        evaluator(0.25 + i * 1e-5, y, m, w, forces, motion, reactions)


@njit
def _velocities(N, y, m, w):
    nf = m.free.shape[0]
    for _ in range(N):
        w.kin_current[0] = 1
        C.velocities_and_predictor(m, w, y[nf:2 * nf])


@njit
def _positions(N, m, w):
    for _ in range(N):
        positions_kernel(m.parent, m.jtype, m.axis, m.offset, w.z, w.A, w.r, w.B, w.scratch)


@njit
def _elements(N, m, w):
    for _ in range(N):
        element_kinematics(m.elem_up, m.elem_pu, m.elem_lo, m.elem_pl, w.A, w.r, w.Z, w.P_up, w.P_lo, w.N,
                           w.L, w.Ld, w.scratch)


@njit
def _forces(N, m, w, forces):
    for _ in range(N):
        forces(0.25, w.z, w.zd, w.momentum, w.L, w.Ld, w.extra, m.force_params, w.T, w.gen, w.extra_rate)


@njit
def _body_terms(N, m, w):
    for _ in range(N):
        w.Mb[:, :, :] = 0.0
        body_terms_kernel(m.mass, m.com, m.inertia, m.gravity, w.A, w.r, w.Z, True, w.Mb, w.Qb, w.scratch)


@njit
def _reduced(N, m, w, reactions):
    for _ in range(N):
        C.reduced_dynamics(m, w, reactions)


def start_state(p: Params, drive: Drive):
    """(model, workspace, y): the compiled model and the rest state the drive starts from."""
    system, g = device_system(p, drive)
    z_rest, y0 = rest_state(system, g, system.workspace())
    model = compiled_model(system, g, drive, system.forces.elements)
    return model, make_workspace(model, z_rest), y0


def best(fn, args, loops: int, repeats: int) -> float:
    fn(10, *args)
    out = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn(loops, *args)
        out = min(out, (time.perf_counter() - t0) / loops)
    return out


def positive_int(text: str) -> int:
    if not text.isdigit() or int(text) < 1:
        raise argparse.ArgumentTypeError(f"{text!r}: allowed a whole number >= 1")
    return int(text)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--loops", type=positive_int, default=20000)
    ap.add_argument("--repeats", type=positive_int, default=25)
    ap.add_argument("--out", default="out/bench")
    a = ap.parse_args()
    m, w, y = start_state(Params(), Drive(0.015, 1.0))
    dydt = np.zeros_like(y)
    rows = {}
    w.counters[:] = 0
    rows["rhs (a step's stage: no reactions)"] = best(_rhs, (y, m, w, device_forces, device_motion, dydt, False),
                                                      a.loops, a.repeats)
    newton_per_assembly = w.counters[1] / max(w.counters[0], 1)
    rows["evaluation with reactions (an output sample)"] = best(
        _rhs, (y, m, w, device_forces, device_motion, dydt, True), a.loops, a.repeats)
    generated = generated_evaluator(m)
    w.counters[:] = 0
    rows["generated evaluation (a stage: no reactions)"] = best(
        _evaluator, (generated, y, m, w, device_forces, device_motion, False), a.loops, a.repeats)
    newton_generated = w.counters[1] / max(w.counters[0], 1)
    rows["generated evaluation with reactions"] = best(
        _evaluator, (generated, y, m, w, device_forces, device_motion, True), a.loops, a.repeats)
    rows["generic evaluation through the pointer, no reactions"] = best(
        _evaluator, (generic_evaluator(), y, m, w, device_forces, device_motion, False), a.loops, a.repeats)
    rows["positions (one pass)"] = best(_positions, (m, w), a.loops, a.repeats)
    rows["dependent velocities + predictor"] = best(_velocities, (y, m, w), a.loops, a.repeats)
    rows["element kinematics"] = best(_elements, (m, w), a.loops, a.repeats)
    rows["force laws (device callback)"] = best(_forces, (m, w, device_forces), a.loops, a.repeats)
    rows["body terms (M_i, Q_i)"] = best(_body_terms, (m, w), a.loops, a.repeats)
    rows["reduced dynamics, no reactions"] = best(_reduced, (m, w, False), a.loops, a.repeats)
    rows["reduced dynamics with reactions"] = best(_reduced, (m, w, True), a.loops, a.repeats)
    for k, v in rows.items():
        print(f"{k:46s} {1e6 * v:.3f} us")
    print(f"Newton iterations per assembly: {newton_per_assembly:.2f} (generic), {newton_generated:.2f} (generated)")
    report = {"machine": platform.platform(), "cpus": os.cpu_count(), "load_average": os.getloadavg(),
              "seconds": rows, "newton_iterations_per_assembly": newton_per_assembly,
              "newton_iterations_per_assembly_generated": newton_generated,
              "loops": a.loops, "repeats": a.repeats}
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    atomic_write_json(out / "bench_rhs.json", report)


if __name__ == "__main__":
    main()
