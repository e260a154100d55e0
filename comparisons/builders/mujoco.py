"""The MuJoCo builder: a model description (nsd_core.model) run on MuJoCo, with no per-mechanism code.

``simulate(model, duration, dt_out, settings) -> ModelRun``. The MJCF comes from
comparisons.builders.mujoco_mjcf (nested bodies, one hinge/slide per joint coordinate, loop closures
as equality connects; see there). Every engine starts from ``initial_state(model)``: qpos from its
coordinates, qvel from its rates.

Two paths, one model (setting ``passive``): "python", the readable reference described here (Passive,
a Python loop), and "compiled" (default): a numba C callback generated from the description that calls
each element's registry law function directly, and this loop in native code (mujoco_compiled,
mujoco_codegen, mujoco_kernels); outputs equal to round-off (tests/test_mujoco_codegen.py). On the
gate's drive cases at the adapter's own step and Euler, the stepping costs 0.56-1.25x the hand-written
device adapter's (benchmarks/bench_described_gate.py; docs/validation.md); the Python path: ~60 s per
model second.

Forces: one ``mjcb_passive`` callback (installed for the run only, the previous one restored)
evaluates every force element through the law registry and nothing else (mujoco_passive.Passive,
which says how: points elements along their line or along a ``direction``, joint elements on their
coordinate); no line here knows which laws exist. An excitation (``[excitation]``: the frame moves
with the ground) adds -m a_g(t) at every body's centre of mass in the same callback, at each
integrator stage's own time, so RK4 keeps its order (measured on models/nsd_seismic.toml: see
tests/test_model_mujoco_seismic.py).

A law with an internal state (``Law.state``) keeps it in an activation of a zero-force actuator
(mujoco_mjcf). RK4: MuJoCo integrates it with the motion, its rate ``element.rate(x, x', s)`` computed
by the passive callback of the same stage and handed over by ``mjcb_act_dyn``. Euler: the callback
advances it itself, at each evaluation, along the actual change of its element's x since the last
one (mujoco_passive), before the force uses it. MuJoCo's Euler would add h rate(x_n, x'_n, s_n): the
state then lags the configuration by about one step's change (a stiff hysteretic wire: a force error
of first order in h with a large constant), and x'_n can have the wrong sign at a reversal.
Measured on the device's drive case A = 15 mm, 10 Hz, Euler h = 2.5e-5 s (max|F - F_ref| / peak, the
gate's converged reference): 2.25e-3 before; the advance alone 1.04e-3, Euler's drive force taken as
a step average alone 1.40e-3, solref factor 2 alone 2.36e-3; advance and point force 1.38e-4; all
three 4.69e-5, the hand-written adapter's 4.70e-5 (order 2.0 at h, h/2, h/4; A15mm 1 Hz 2.2e-5,
A25.5mm 10 Hz at 5e-6 s 3.7e-5, order 1.9). Stepping 1.2x the adapter's (1 Hz: 0.29 s vs 0.24 s,
load 2 on 2 cores; the advance's four rate calls per state cost ~0.4 us of a ~3.7 us step).

Prescribed motions (the heavy virtual drive): a driven coordinate gets an armature A =
``drive_armature`` x its own inertia at t = 0, and the callback adds, at every stage (each stage's
own time), the feed-forward A q''(t) + tau_est(t), tau_est the drive force of the last steps,
extrapolated linearly. The driven coordinate's acceleration then misses q''(t) by only
(tau - tau_est) / A, and after each step its qpos/qvel are reset to q(t), q'(t) exactly;
``tracking_error`` is the largest miss before the reset (slider-crank, RK4, h = 1.25e-4 s: 7e-15 rad).
The drive force (the sign of the in-house engine's ``Evaluation.drive_force``: positive drives q up)
is measured per step (Euler: at its one evaluation, the step's start state, so an output time's force
is that step's; RK4 as follows) as its average over the step: the stages' feed-forward (RK4 weights) less A
times the step's average acceleration (MuJoCo's qacc after the step), i.e. the impulse the virtual
drive gave the real mechanism / h. One evaluation's force would not do: RK4 leaves the soft loop
constraints with a velocity offset at the step's ends (their time constant is a few steps), and the
constraints' damping turns it into a force error that does not shrink with the step (slider-crank,
solref 2h: 1.8e-3 of the peak torque at every step). The value at an output time is then
reconstructed from the four nearest steps' averages (the cubic with those averages; one-sided at
the run's ends), fourth order like RK4.

The step: MuJoCo's own pieces, in a plain loop: mj_forward (the step's first stage, whose state also
gives the outputs at output times) then mj_RungeKutta (RK4) or mj_Euler, as mj_step does. The step
used divides the output interval (<= ``timestep``). The loop constraints are soft: solref time
constant ``solref_factor`` x h; its default is the integrator's (SOLREF_FACTOR): Euler 2, the
stiffest, as the hand-written device adapter (the cause measured below); RK4 4. With RK4 a factor of
2 (MuJoCo's floor) leaves that velocity offset
largest (an error of first order in h in velocities and the drive force); 4 is the compromise
measured: slider-crank drive torque at h = 1.25e-4 s: 2.8e-5 (factor 2), 3.9e-6 (4), 2.2e-6 (8);
Andrews at h = 1e-5 s: 5.3e-7 (2), 1.3e-6 (4), 6.9e-6 (8) (the position-level softness grows as
(factor h)^2).

Outputs: coordinate = qpos (hinges are not wrapped: angles stay continuous); point and
point_velocity from the body's pose and mj_jac; point_acceleration = J qacc + J' qvel (mj_jac,
mj_jacDot; qacc of the output time's own mj_forward) plus a_g(t); force = the law's value at that
state; state = the law's activation after that evaluation (the value its force used); drive_force as
above; kinetic energy = 1/2 v^T M v less the virtual drives' armature share; gravity potential =
-sum m g . r_com (both as nsd_core.engine.dynamics); work = the trapezoid of its power at the steps'
first evaluations (a drive's: each step's average force times q's change): the energy balance's
residual second order with RK4 (nsd_seismic 9.2e-5 of the peak work at 1e-4 s), first with Euler
(1.5e-4 at 1e-5 s; fourbar_spring 3.1e-2 at 1e-4 s). stats: wall_time (steps and outputs only),
steps, timestep, closure_max (largest distance between the two sites of any connect at the output
times [m]; a revolute loop's second pair measures the axes' misalignment times the arm),
tracking_error.

Step each model needs for ~1e-3 relative error (RK4, defaults otherwise; error = the largest over the
outputs of max|y - y_ref| / scale, scale the output's own or the peak |y_ref|, y_ref the in-house
builder at rtol 1e-11 over the model's case; wall = stepping and outputs, loaded 2-core machine):
- andrews (0.03 s): h = 1e-4 s (the output interval, the largest step) 1.7e-4, 0.10 s wall; 5e-5
  4.6e-5; the default 1e-5: 1.3e-6, 0.7 s. Test set reference at 0.03 s: tests/test_model_mujoco.py.
- iftomm_a01_pendulum (20 s): h = 0.05 s 2.4e-4 (0.1 s: 1.1e-2; 0.025 s: 2.7e-6), 0.01 s wall.
- iftomm_a02_fourbar (N = 4, 5 s, through the singular flat position): h = 1e-3 s 9.8e-4, 0.4 s wall
  (2e-3: 4.1e-3; 5e-4: 2.9e-4; 2.5e-4: 1.1e-4): order ~1.5 near the singular position.
- iftomm_a04_bricard (5 s, revolute closure, one redundant equation): h = 0.05 s (the output
  interval) 2.4e-4, 0.01 s wall; 1e-2: 7e-6.
- slider_crank (0.4 s, prescribed crank): h = 2e-3 s (the output interval) 7.9e-5 (drive torque),
  tracking error 3e-11 rad; 5e-4: 1.5e-5.
- fourbar_spring (2 s): h = 1e-2 s 1.5e-3, 5e-3 s 9.5e-5, 0.03 s wall.
- nsd_seismic (1 s, harmonic ground acceleration): the error is the soft loop closure's, set by its
  time constant tau = solref_factor x h alone (factor 2 at h = 1e-4 s and factor 4 at 5e-5 s give the
  same 2.9e-4 of u_y's peak), order 1.97 (RK4; Euler: 1.1-1.35 at h = 2e-5 ... 5e-6 s); case setting
  h = 1e-4 s, factor 2 (loop gap 7.6e-7 m), 0.14 s wall. Euler at h = 1e-5 s, factor 2: 0.36 s, 0.82x
  the hand-written seismic adapter (comparisons/engines/mujoco_seismic.py, native loop) on the same
  device and ground motion (0.44 s; load 1.2 on 2 cores).
- nsd_building (1 s, 3 stories, restrainer): at tau = 2e-4 s the restrainer's force misses by 45 N of
  its ~37 kN impact; its output scale of 1 N (1 mN tolerance) needs h = 4e-7 s, factor 2 (8.0e-4 N,
  every other output ~1e-8), 45 s wall.
"""
from __future__ import annotations

import math

import mujoco
import numpy as np

from comparisons.builders import mujoco_codegen, mujoco_compiled, mujoco_python
from comparisons.builders.mujoco_passive import Passive, work_plan
from comparisons.builders.mujoco_mjcf import build_mjcf, connects, joint_name, state_activations
from comparisons.engines.base import EngineError, check_step_count
from nsd_core.model.assemble import initial_state
from nsd_core.model.description import GROUND, Model
from nsd_core.model.errors import ModelError
from nsd_core.model.run import ModelRun, output_times

name = "mujoco"
default_settings = {
    "timestep": 1e-5,           # [s] largest step; the step used divides the output interval
    "integrator": "RK4",        # RK4 | Euler (semi-implicit)
    "solref_factor": 0.0,       # connect time constant = factor x step (>= 2, MuJoCo's smallest); not
                                # given (or None): the integrator's (SOLREF_FACTOR, see above). A float
                                # default: the CLI types a case's settings by the defaults' (a None
                                # default is checked as a count, rejecting solref_factor = 2.0)
    "solref_dampratio": 1.0,    # connect damping ratio (1: critical)
    "solimp": [0.9999, 0.9999, 0.001, 0.5, 2.0],   # connect impedance (closer to 1: harder)
    "solver_tolerance": 1e-12,  # MuJoCo's constraint solver (Newton) tolerance
    "solver_iterations": 20,    # and its iteration limit
    "drive_armature": 1e6,      # virtual drive inertia of a prescribed coordinate / its own at t = 0
    "inertia_floor": 1e-12,     # [kg m^2] smallest principal moment passed to MuJoCo (point masses)
    "closure_limit": 1e-2,      # [m] a larger loop gap at an output time is an instability (EngineError)
    "passive": "compiled",      # compiled: generated C callback and native loop (mujoco_compiled); python: Passive
}
INTEGRATORS = ("RK4", "Euler")
SOLREF_FACTOR = {"RK4": 4.0, "Euler": 2.0}   # the default solref_factor of each integrator (see above)
PASSIVE = ("compiled", "python")
RK4_WEIGHTS = np.array([1.0, 2.0, 2.0, 1.0]) / 6.0   # the classic RK4 stages' weights, as MuJoCo's
_POSITIVE = ("timestep", "solref_factor", "drive_armature", "inertia_floor", "closure_limit", "solver_tolerance")


def merged_settings(settings: dict | None) -> dict:
    """The defaults updated by ``settings``; an unknown key or a bad value raises ModelError."""
    if settings is not None and not isinstance(settings, dict):
        raise ModelError(f"mujoco settings = {settings!r}: must be a table of setting = value")
    s = dict(default_settings)
    for k, v in (settings or {}).items():
        if k not in default_settings:
            raise ModelError(f"mujoco.{k}: unknown setting; allowed: {', '.join(sorted(default_settings))}")
        s[k] = v
    if s["passive"] not in PASSIVE:
        raise ModelError(f"mujoco.passive = {s['passive']!r}: allowed: {', '.join(PASSIVE)}")
    if s["integrator"] not in INTEGRATORS:
        raise ModelError(f"mujoco.integrator = {s['integrator']!r}: allowed: {', '.join(INTEGRATORS)}")
    if (settings or {}).get("solref_factor") is None:
        s["solref_factor"] = SOLREF_FACTOR[s["integrator"]]
    for k in _POSITIVE:
        v = s[k]
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v <= 0:
            raise ModelError(f"mujoco.{k} = {v!r}: must be a number > 0")
    if s["solref_factor"] < 2.0:
        raise ModelError(f"mujoco.solref_factor = {s['solref_factor']!r}: must be >= 2 (MuJoCo's smallest time constant)")
    if s["inertia_floor"] < 1e-14:
        raise ModelError(f"mujoco.inertia_floor = {s['inertia_floor']!r}: must be >= 1e-14 kg m^2 (MuJoCo rejects less)")
    it = s["solver_iterations"]
    if isinstance(it, bool) or not isinstance(it, int) or it < 1:
        raise ModelError(f"mujoco.solver_iterations = {it!r}: must be a whole number >= 1")
    return s


def simulate(model: Model, duration: float, dt_out: float, settings: dict | None = None) -> ModelRun:
    s = merged_settings(settings)
    init = initial_state(model)
    t_out = output_times(duration, dt_out)
    n_sub = max(1, math.ceil((t_out[1] - t_out[0]) / float(s["timestep"]) - 1e-9))
    h = float(t_out[1] - t_out[0]) / n_sub
    n_steps = n_sub * (len(t_out) - 1)
    check_step_count(name, n_steps)
    compiled = s["passive"] == "compiled"
    m, d, drives = _compile(model, s, h, init, mujoco_codegen.layout(model).size if compiled else 0)
    pairs = [(m.site(f"{c[0]}:a").id, m.site(f"{c[0]}:b").id) for c in connects(model, init.rotation)]
    weights = RK4_WEIGHTS if s["integrator"] == "RK4" else np.ones(1)
    uses = drive_force_uses(n_steps, n_sub, s["integrator"]) if drives else {}
    plan = work_plan(model, m)
    if compiled:
        data, drive_at, wall, closure, tracking, work = mujoco_compiled.run(
            model, s, m, d, drives, pairs, t_out, n_sub, h, n_steps, weights, uses,
            lambda forces: _sampler(model, m, d, forces), plan)
    else:
        data, drive_at, wall, closure, tracking, work = mujoco_python.run(
            model, s, m, d, drives, pairs, t_out, n_sub, h, n_steps, weights, uses,
            lambda forces: _sampler(model, m, d, forces), plan)
    for k, o in enumerate(model.outputs):
        if o.kind == "drive_force":
            data[:, k] = drive_at[:, [p.name for p in model.prescribed].index(o.element)]
    data[:, [k for k, o in enumerate(model.outputs) if o.kind == "work"]] = work
    return ModelRun(name, t_out, {o.name: data[:, k] for k, o in enumerate(model.outputs)},
                    {o.name: o.unit for o in model.outputs},
                    {"wall_time": wall, "steps": n_steps, "closure_max": closure,
                     "tracking_error": tracking, "mujoco_version": mujoco.__version__, **s,
                     "timestep": h})   # the step used (the setting is its largest)


def drive_force_uses(n_steps: int, n_sub: int, integrator: str) -> dict[int, list[tuple[int, float]]]:
    """How the drive force at each output time comes from the steps' measured forces: step n -> [(output
    index, weight)]. Euler's measurement is the force at the step's start (its one evaluation): output k
    is step k n_sub's own, the last one included (the loops measure it at n = n_steps). RK4's is the
    step's average: point_from_averages."""
    if integrator == "Euler":
        return {k * n_sub: [(k, 1.0)] for k in range(n_steps // n_sub + 1)}
    return point_from_averages(n_steps, n_sub)


def point_from_averages(n_steps: int, n_sub: int) -> dict[int, list[tuple[int, float]]]:
    """How the drive force at each output time comes from the steps' average forces: step n -> [(output
    index, weight)]. The value at a step boundary is the one of the cubic whose averages over the four
    nearest steps (two on either side; one-sided at the run's ends) are the measured ones: fourth
    order, like RK4, where the nearest two steps' mean would be second order."""
    uses: dict[int, list] = {}
    cells = min(4, n_steps)
    for k in range(n_steps // n_sub + 1):
        at = k * n_sub
        first = min(max(at - cells // 2, 0), n_steps - cells)
        steps = np.arange(first, first + cells)
        # the average of (t - t_at)^j / h^j over step i is ((i + 1 - at)^(j+1) - (i - at)^(j+1)) / (j + 1)
        j = np.arange(cells)
        averages = ((steps[:, None] + 1 - at) ** (j + 1) - (steps[:, None] - at) ** (j + 1)) / (j + 1)
        w = np.linalg.solve(averages.T.astype(float), np.eye(cells)[0])
        for i, wi in zip(steps, w):
            uses.setdefault(int(i), []).append((k, float(wi)))
    return uses


def _compile(model: Model, s: dict, h: float, init, nuserdata: int = 0):
    """The compiled model and its data at the initial state, and the drives as (Prescribed, qposadr,
    dofadr, armature). The model is compiled once without armature to read each driven coordinate's
    own inertia at the initial state, which scales its virtual drive."""
    def compiled(armature: dict):
        try:
            m = mujoco.MjModel.from_xml_string(build_mjcf(model, s, h, init.rotation, armature, nuserdata))
        except ValueError as e:
            raise EngineError(f"mujoco: model rejected: {str(e).splitlines()[0]}") from None
        d = mujoco.MjData(m)
        for (body, k), q in init.q.items():
            j = m.joint(joint_name(body, k))
            d.qpos[j.qposadr[0]] = q
            d.qvel[j.dofadr[0]] = init.qd[(body, k)]
        for f in model.forces:
            if f.law.state is not None:
                k = state_activations(model, m)[f.name]
                d.act[k:k + f.law.state_size] = f.initial_states
        return m, d

    armature = {}
    if model.prescribed:
        m, d = compiled({})
        mujoco.mj_forward(m, d)
        M = np.zeros((m.nv, m.nv))
        mujoco.mj_fullM(m, d, M)
        for p in model.prescribed:
            dof = int(m.joint(joint_name(p.joint, p.dof)).dofadr[0])
            armature[(p.joint, p.dof)] = float(s["drive_armature"]) * M[dof, dof]
    m, d = compiled(armature)
    drives = []
    for p in model.prescribed:
        j = m.joint(joint_name(p.joint, p.dof))
        drives.append((p, int(j.qposadr[0]), int(j.dofadr[0]), armature[(p.joint, p.dof)]))
    return m, d, drives


def _sampler(model: Model, m: mujoco.MjModel, d: mujoco.MjData, forces: Passive):
    """A function giving every named output at d's state, in the description's order (a drive force
    is left NaN: simulate fills it from the steps on either side)."""
    jac, jacdot = np.zeros((3, m.nv)), np.zeros((3, m.nv))
    acts = state_activations(model, m)
    vel = np.zeros(6)
    coordinate = {}
    for o in model.outputs:
        if o.kind == "coordinate":
            coordinate[o.name] = int(m.joint(joint_name(o.body, o.dof)).qposadr[0])
    gravity = np.asarray(model.gravity, float)
    mass = m.body_mass.copy()

    body_id = {b.name: m.body(b.name).id for b in model.bodies}
    done: dict = {}   # this sample's points and accelerations, once per (kind, body, point): not per component

    def point(o):
        if o.body == GROUND:
            return np.asarray(o.point, float), np.zeros(3)
        key = ("point", o.body, tuple(o.point))
        if key not in done:
            b = body_id[o.body]
            x = d.xpos[b] + d.xmat[b].reshape(3, 3) @ np.asarray(o.point, float)
            mujoco.mj_jac(m, d, jac, None, x, b)
            done[key] = x, jac @ d.qvel, jac.copy()
        return done[key][:2]

    def acceleration(o):
        """J qacc + J' qvel at the body point (qacc: this evaluation's, the soft loop constraints'
        forces included), plus the frame's a_g(t) with an excitation: the absolute acceleration."""
        a = np.zeros(3)
        if o.body != GROUND:
            key = ("acceleration", o.body, tuple(o.point))
            if key not in done:
                x = point(o)[0]
                mujoco.mj_jacDot(m, d, jacdot, None, x, body_id[o.body])
                done[key] = done[("point", o.body, tuple(o.point))][2] @ d.qacc + jacdot @ d.qvel
            a = done[key]
        return a + model.excitation.acceleration(d.time) if model.excitation is not None else a

    def kinetic():   # body by body: 1/2 v^T M v less the drives' armature share cancels ~1e-10 of it
        total = 0.0
        for b in range(1, m.nbody):
            mujoco.mj_objectVelocity(m, d, mujoco.mjtObj.mjOBJ_BODY, b, vel, 1)   # at the centre, inertia axes
            total += 0.5 * (m.body_mass[b] * float(vel[3:] @ vel[3:]) + float(vel[:3] @ (m.body_inertia[b] * vel[:3])))
        return total

    def one(o, laws):
        if o.kind == "coordinate":
            return d.qpos[coordinate[o.name]]
        if o.kind == "point":
            return point(o)[0][o.component]
        if o.kind == "point_velocity":
            return point(o)[1][o.component]
        if o.kind == "point_acceleration":
            return acceleration(o)[o.component]
        if o.kind == "force":   # a plane law's value is its pair (Q_x, Q_y)
            v = laws[o.element]
            return v[o.component] if isinstance(v, tuple) else v
        if o.kind == "state":   # the activation the law's state lives in (after this evaluation's advance)
            return d.act[acts[o.element] + o.component]
        if o.kind in ("drive_force", "work"):   # filled by simulate from the steps
            return math.nan
        if o.term == "kinetic":
            return kinetic()
        return -float(mass @ (d.xipos @ gravity))

    def sample():
        laws = forces.law_values(m, d) if model.forces else {}
        done.clear()
        return [float(one(o, laws)) for o in model.outputs]
    return sample
