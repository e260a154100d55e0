"""A peer's seismic-mode run built from the device's description: the gate's seismic engine interface
(``run_seismic(params, structure, ground, duration, dt_out, settings) -> RunResult``) over a builder
(comparisons/builders), which comparisons/engines/peers.py puts behind each peer's name.

The case is written as a description by ``nsd_core.structure.describe_seismic.seismic_description``: the
case's parameters, its structure (supports, restrainer, building) and its ground motion as the
``[excitation]`` (a FEMA P695 record as the ``record`` table, a closed form as ``ground``; the excitation
parsed from the file must give the case's ground motion's block exactly, else the run is refused), with
the outputs the columns need beyond the description's own (the plate's velocity, the wall's height,
every wire's stress, the spring's zeta, the floors' velocities and absolute accelerations).

The columns, names and units are the in-house seismic run's: t, x, y, theta, vx, vy, ax_abs,
ay_abs, support_F, device_F, base_shear, cap_z, wall_z, spring_zeta, spring_push, closure (the run's
largest loop gap at the output times, as the drive mode's described engine), wire stresses, u, the
floors' columns (nsd_core.structure.building.floor_columns) and the restrainer's (the shared law on the
sampled motion). device_F has the in-house sign (nsd_core.structure.seismic._device_outputs: the force the
plate applies to the device, -(rod + ropes + wires on the cap), horizontal). No output of a builder
gives the rod's force on the cap (a loop closure's multiplier), so it comes from Newton's law on the
plate and the cap together: the cap slides along the plate's Z axis with its centre of mass on it
(device_geometry: cap com (0, 0, 0)), so its plan acceleration is the plate's, and horizontally

    (M + m_cap) a_abs = (device on the cap) - support_F - restrainer_F + story_shear1,

story_shear1 = -sum m_i a_i,abs the building's force on the slab (floor_columns), hence
device_F = -(M + m_cap) a_abs - support_F - restrainer_F + story_shear1, and the base shear
support_F + device_F + restrainer_F = -(M + m_cap) a_abs + story_shear1.

The energy balance (E_* columns, ``energy_columns``) comes from the builders' own ``work`` outputs:
every force element's work and the excitation's, with the kinetic and gravity energy, so the gate's
energy metric checks each builder's own state.

Settings: the gate's (comparisons.engines.described.builder_settings: MuJoCo's timestep, integrator
(Euler by default), solref_factor, passive; Exudyn's step_size and ``builder_forces``); Exudyn's per-cycle cap of the drive mode does not apply to a ground motion.
"""
from __future__ import annotations

import importlib
import tomllib

import numpy as np

from comparisons.engines.base import EngineError
from comparisons.engines.described import builder_settings
from comparisons.engines.perturb import perturbed, perturbed_structure
from nsd_core.structure.building import floor_columns
from nsd_core.device.columns import units_of
from nsd_core.structure.describe_seismic import seismic_description
from nsd_core.device.forces import restrainer_forces, restrainer_stored_scalar, spring_push
from nsd_core.device.geometry import device_geometry
from nsd_core.ground.motions import Harmonic, Pulse
from nsd_core.ground.records import Record
from nsd_core.device.params import ParameterError
from nsd_core.device.results import RunResult
from nsd_core.structure.seismic import output_times
from nsd_core.model.errors import ModelError
from nsd_core.model.load import parse_model


def ground_table(ground):
    """The case's ground motion as ``[excitation]`` writes it: a record's table {set, id, scale,
    time_factor, window, rotate} or a closed form's text; EngineError for a motion it cannot write."""
    m = getattr(ground, "meta", {})
    if isinstance(ground, Record) and m.get("normalised", True) and "set" in m:
        return {"set": m["set"], "id": int(m["record"]), "scale": float(m["scale"]),
                "time_factor": float(m["time_factor"]), "window": [float(w) for w in m["window"]],
                "rotate": float(m["rotate_deg"])}
    if isinstance(ground, Harmonic):
        return (f"harmonic:amplitude={ground.amplitude!r},frequency={ground.frequency!r},"
                f"azimuth={ground.azimuth_deg!r},duration={ground.duration!r}")
    if isinstance(ground, Pulse):
        return (f"pulse:velocity={ground.velocity!r},frequency={ground.frequency!r},gamma={ground.gamma!r},"
                f"phase={ground.phase_deg!r},azimuth={ground.azimuth_deg!r}")
    raise EngineError(f"described seismic: ground motion {type(ground).__name__} {m!r}: an [excitation] writes a "
                      "FEMA P695 record (normalised) or a closed form (harmonic, pulse) only")


def _output(name: str, kind: str, **keys) -> str:
    body = "".join(f"{k} = {v}\n" for k, v in keys.items())
    return f'\n[[outputs]]\nname = "{name}"\nkind = "{kind}"\n{body}'


def _outputs(n_wires: int, structure) -> str:
    """The outputs the columns need beyond the description's own."""
    blocks = [_output(f"plate{k}_v{c}", "point_velocity", body='"plate"', point=f"[{k}.0, 0.0, 0.0]",
                      component=f'"{c}"') for k in (0, 1) for c in "xy"]   # at the centre and 1 m off: the turn rate
    blocks += [_output("wall_z", "coordinate", joint='"wall"', dof=0),
               _output("spring_zeta", "state", element='"spring"')]
    blocks += [_output(f"wire{j}_stress", "state", element=f'"wire{j}"') for j in range(n_wires)]
    for i in range(1, structure.building.stories + 1 if structure.building is not None else 1):
        for kind, prefix in (("point_velocity", "v"), ("point_acceleration", "a")):
            blocks += [_output(f"floor{i}_{prefix}{c}_out", kind, body=f'"floor{i}"', point="[0.0, 0.0, 0.0]",
                               component=f'"{c}"') for c in "xy"]
    return "".join(blocks)


def _energy_outputs(forces) -> str:
    """The energy balance's outputs: every force element's work, the excitation's, kinetic and gravity energy."""
    blocks = [_output(f"work_{f}", "work", element=f'"{f}"') for f in forces]
    blocks += [_output("work_excitation", "work", source='"excitation"'),
               _output("energy_kinetic", "energy", term='"kinetic"'),
               _output("energy_gravity", "energy", term='"gravity"')]
    return "".join(blocks)


def described_seismic_model(params, structure, ground, duration: float, dt_out: float, perturb: dict | None = None):
    """The case as a parsed description with the columns' outputs, and the device's geometry; ``perturb``:
    a modelling error injected into this engine's description only (comparisons.engines.perturb)."""
    g = perturbed(device_geometry(params), perturb, seismic=True)
    text = seismic_description(params, structure, ground_table(ground), duration, dt_out,
                               geometry=g) + _outputs(g.n_wires, structure)
    forces = [f.name for f in parse_model(tomllib.loads(text)).forces]
    model = parse_model(tomllib.loads(text + _energy_outputs(forces)))
    if not np.array_equal(model.excitation.block, np.ascontiguousarray(ground.block(), dtype=float)):
        raise EngineError(f"described seismic: the [excitation] written for {ground.describe()!r} is not the case's "
                          "ground motion (its a_g differs)")
    return model, g


def energy_columns(o: dict, st, x, y, theta, floors: dict) -> dict:
    """The energy balance's columns in the frame of the ground (the in-house run's names and meaning) from the
    builder's outputs ``o``: work_<element> (each force element's work on the mechanism since t = 0),
    work_excitation (the -m a_g loads': E_input), energy_kinetic and energy_gravity. What an element
    group absorbed is minus its work: the device's (ropes, wires, spring) is E_device; the supports'
    and the building's less what they store are their dissipation; the restrainer's less its stored
    energy its dissipation. E_residual: input less every term, as the in-house run's (the loop closure's
    work, zero in the model, is what is left besides the builder's quadrature)."""
    def absorbed(test) -> np.ndarray:
        return -sum((v for k, v in o.items() if k.startswith("work_") and k != "work_excitation" and test(k[5:])),
                    np.zeros_like(x))
    group = {"support": lambda n: n.startswith("support_"), "restrainer": lambda n: n == "restrainer",
             "building": lambda n: n.startswith(("story", "slab_damper"))}
    device = absorbed(lambda n: not any(t(n) for t in group.values()))
    stored = 0.5 * st.stiffness * (x * x + y * y + st.support_radius ** 2 * theta * theta)
    kinetic, gravity = o["energy_kinetic"], o["energy_gravity"] - o["energy_gravity"][0]
    cols = {"E_input": o["work_excitation"], "E_kinetic": kinetic, "E_gravity": gravity, "E_supports_stored": stored,
            "E_supports_dissipated": absorbed(group["support"]) - stored, "E_device": device}
    rest = absorbed(group["restrainer"])
    building = absorbed(group["building"])
    if st.building is not None:
        cols["E_building_dissipated"] = building - floors["E_building_stored"]
    cols["E_residual"] = cols["E_input"] - (kinetic + gravity + stored + cols["E_supports_dissipated"] + device + rest
                                            + building)
    if st.restrainer is not None:
        r = st.restrainer
        delta = np.maximum(np.hypot(x, y) - r.gap, 0.0)
        cols["E_restrainer_stored"] = np.array([restrainer_stored_scalar(d, r.stiffness, r.exponent) for d in delta])
        cols["E_restrainer_dissipated"] = rest - cols["E_restrainer_stored"]
    return cols


class DescribedSeismic:
    """The gate's seismic engine interface over ``comparisons.builders.<engine>``."""

    def __init__(self, engine: str):
        self.name = engine
        self.builder = importlib.import_module(f"comparisons.builders.{engine}")

    def run_seismic(self, params, structure, ground, duration=None, dt_out=1e-3, settings: dict | None = None):
        duration = ground.duration if duration is None else float(duration)
        t_out = output_times(duration, dt_out)   # the in-house run's output times (ceil): the builders round
        try:
            perturb = (settings or {}).get("perturb")
            structure = perturbed_structure(structure, perturb)   # the columns read this model's own masses
            model, g = described_seismic_model(params, structure, ground, duration, dt_out, perturb)
            s = builder_settings(self.name, settings, 1.0, "seismic")
            run = self.builder.simulate(model, duration, duration / (len(t_out) - 1), s)
        except (ModelError, ParameterError) as e:
            raise EngineError(f"{self.name} (described): {e}") from None
        if len(run.t) != len(t_out) or np.max(np.abs(run.t - t_out)) > 1e-12:
            raise EngineError(f"{self.name} (described): output times differ from the in-house run's")
        cols = seismic_columns(run, g, structure, t_out)
        stats = {**run.stats, "engine": self.name, "mode": "seismic", "model": "described", "settings": s}
        return RunResult(self.name, cols, units_of(cols), stats)


def seismic_columns(run, g, st, t) -> dict:
    """The seismic columns (the in-house run's names; Exudyn's also carry omega, the plate's turn rate, as
    its hand-written model's did) from a builder's run."""
    o = run.outputs
    x, y, vx, vy, ax, ay = o["u_x"], o["u_y"], o["plate0_vx"], o["plate0_vy"], o["a_x"], o["a_y"]
    n = len(t)
    sx, sy = st.stiffness * x + st.damping * vx, st.stiffness * y + st.damping * vy
    floors = _floors(o, st, x, y, vx, vy) if st.building is not None else {}
    bx, by = (floors["story_shear1_x"], floors["story_shear1_y"]) if floors else (0.0, 0.0)
    rest = {}
    rx = ry = 0.0
    if st.restrainer is not None:
        r = st.restrainer
        rx, ry, F, delta, _ = restrainer_forces(x, y, vx, vy, r.gap, r.stiffness, r.exponent, r.damping)
        rest = {"restrainer_Fx": rx, "restrainer_Fy": ry, "restrainer_F": F, "restrainer_indentation": delta}
    mass = st.mass + g.cap.mass
    dfx, dfy = -mass * ax - sx - rx + bx, -mass * ay - sy - ry + by
    wz, zeta = o["wall_z"], o["spring_zeta"]
    cols = {"t": np.asarray(t, dtype=float), "x": x, "y": y, "theta": o["theta"], "vx": vx, "vy": vy, "ax_abs": ax,
            "ay_abs": ay, "support_Fx": sx, "support_Fy": sy, "device_Fx": dfx, "device_Fy": dfy,
            "base_shear_x": sx + dfx + rx, "base_shear_y": sy + dfy + ry, "cap_z": o["cap_z"], "wall_z": wz,
            "spring_zeta": zeta, "spring_push": spring_push(wz, 0.0, zeta, g.spring)[0],
            "closure": np.full(n, float(run.stats.get("closure_max", 0.0)))}
    if run.engine == "exudyn":   # the plate's turn rate: (v_p - v_0) . (e_z x r_p) / |r_p|^2
        th = o["theta"]
        cols["omega"] = -(o["plate1_vx"] - vx) * np.sin(th) + (o["plate1_vy"] - vy) * np.cos(th)
    cols.update({f"wire{j}_stress": o[f"wire{j}_stress"] for j in range(g.n_wires)})
    cols.update(energy_columns(o, st, x, y, o["theta"], floors))
    cols["u"] = np.hypot(x, y)
    cols.update(floors)
    cols.update(rest)
    return {k: np.array(np.broadcast_to(v, (n,)), dtype=float) for k, v in cols.items()}


def _floors(o, st, x, y, vx, vy) -> dict:
    """The building's columns as every engine writes them (floor_columns): (N, 2, samples) arrays."""
    b = st.building
    rng = range(1, b.stories + 1)
    d = np.array([[o[f"floor{i}_x"], o[f"floor{i}_y"]] for i in rng])
    v = np.array([[o[f"floor{i}_vx_out"], o[f"floor{i}_vy_out"]] for i in rng])
    a = np.array([[o[f"floor{i}_ax_out"], o[f"floor{i}_ay_out"]] for i in rng])
    below = np.concatenate([np.array([x, y])[None], d[:-1]])
    return floor_columns(b, d, a, d - below, v, np.array([vx, vy]))
