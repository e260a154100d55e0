"""Random open chains (trees) for the campaign's generator (comparisons.campaign.generate)."""
from __future__ import annotations

import math

import numpy as np

from comparisons.campaign.parts import (JOINTS, SLIDES, TURNS, body, case, gravity, inertia, outputs_for, spring,
                                           unit, vec)

# the device's stateful laws at a scale a 0.1-2 kg body feels (the device's own wire is 3.5e6 N/m)
SMA = {"E": 5e10, "Y": 4e8, "alpha": 0.03, "n": 3.0, "fT": 0.36, "a": 500.0, "Em": 2.5e10, "eps_t": 0.07, "c": 300.0}
PUSH = {"beta": 0.5, "gamma": 0.3, "n": 1.0}


def _joint(d, kind: str) -> dict:
    j = {"type": kind, "position": vec(np.array([d.uniform(-1, 1) for _ in range(3)]) * 0.15)}
    if kind in ("revolute", "prismatic", "universal"):
        j["axis"] = vec(unit(d) if d.integer(0, 1) else d.choice([[1.0, 0, 0], [0, 1.0, 0], [0, 0, 1.0]]))
    if kind == "universal":
        a2 = np.cross(j["axis"], unit(d))
        j["axis2"] = vec(a2 / np.linalg.norm(a2)) if np.linalg.norm(a2) > 0.3 else vec(np.cross(j["axis"], [0.3, 0.5, 0.8]))
    if kind.startswith("planar"):
        j["normal"] = vec(unit(d) if d.integer(0, 1) else [0.0, 0.0, 1.0])
    return j


def open_chain(d) -> dict:
    n = d.choice([1, 1, 2, 2, 3, 3, 4, 5, 6])
    bodies, forces, coords, rates, names = [], [], {}, {}, []
    total = 0.0
    for i in range(n):
        name = f"b{i}"
        parent = "ground" if i == 0 else (names[-1] if d.integer(0, 2) else d.choice(["ground"] + names))
        kind = d.choice(JOINTS)
        m = d.uniform(0.2, 2.0)
        total += m
        bodies.append(body(name, parent, _joint(d, kind), m, np.array([d.uniform(-1, 1) for _ in range(3)]) * 0.1,
                           inertia(d, m, d.uniform(0.05, 0.3))))
        dofs = {"revolute": 1, "prismatic": 1, "universal": 2, "spherical": 3, "planar": 3,
                "planar_translation": 2, "translational": 3}[kind]
        q = [d.uniform(-0.3, 0.3) if k in TURNS.get(kind, ()) else d.uniform(-0.02, 0.02) for k in range(dofs)]
        spin = 0.3 if kind == "spherical" else 1.0   # rad/s (a ball's Euler angles: far from +-90 deg)
        v = [d.uniform(-spin, spin) if k in TURNS.get(kind, ()) else d.uniform(-0.1, 0.1) for k in range(dofs)]
        coords[name], rates[name] = (q[0], v[0]) if dofs == 1 else (q, v)
        for k in SLIDES.get(kind, ()):   # every slide on a spring: nothing drifts out of reach
            forces.append({"name": f"{name}_slide{k}", "law": "joint_spring_damper", "joint": name, "dof": k,
                           "parameters": {"stiffness": m * d.uniform(25.0, 900.0), "damping": d.uniform(0.0, 2.0) * m}})
        for k in TURNS.get(kind, ()):   # (revolute and planar turns: Exudyn measures no Tait-Bryan angle)
            if kind in ("revolute", "planar") and d.integer(0, 2) == 0:
                forces.append({"name": f"{name}_turn{k}", "law": "joint_spring_damper", "joint": name, "dof": k,
                               "parameters": {"stiffness": d.uniform(0.05, 5.0), "damping": d.uniform(0.0, 0.05),
                                              "neutral": d.uniform(-0.2, 0.2)}})
        if kind in ("planar", "planar_translation") and parent == "ground" and d.integer(0, 2) == 0:
            forces.append({"name": f"{name}_hysteresis", "law": "bidirectional_hysteresis", "joint": name, "dofs": [0, 1],
                           "parameters": {"strength": 0.05 * m * G_LOAD, "strength_at_rest": 0.05 * m * G_LOAD, "yield_displacement": d.uniform(1e-3, 5e-3),
                                          "exponent": 2.0}})
        names.append(name)
    forces += _point_laws(d, names, total)
    # a ball joint has no spring (Exudyn measures no Tait-Bryan angle), so nothing may swing it far: no
    # gravity and no ground motion where there is one (its Euler angles then stay within ~0.6 rad)
    ball = any(b["joint"]["type"] == "spherical" for b in bodies)
    description = {"model": {"name": f"open_chain_{n}", "source": "generated: open chain of "
                             + ", ".join(b["joint"]["type"] for b in bodies),
                             "gravity": [0.0, 0.0, 0.0] if ball else gravity(d)},
                   "bodies": bodies, "forces": forces}
    prescribed = _drive(d, bodies, coords, rates)
    if prescribed:
        description["prescribed"] = [prescribed]
    if d.integer(0, 3) == 0 and not ball:
        description["excitation"] = {"type": "ground_acceleration", "ground": (
            f"harmonic:amplitude={d.uniform(0.5, 3.0):.4g},frequency={d.uniform(0.5, 4.0):.4g},"
            f"azimuth={d.uniform(0.0, 360.0):.4g},duration=10")}
    description["initial"] = {"coordinates": coords, "velocities": rates}
    description["outputs"] = _outputs(d, bodies, forces, prescribed)
    description["case"] = [case(d)]
    _hang(d, description)
    return description


def _hang(d, description: dict) -> None:
    """Each point-to-point law set to start near its free length, measured at the assembled start (the
    shared initial state's poses: kinematics, no dynamics): a spring within 10 %, a rope just taut, a stop
    just open, a wire barely stretched, a push spring barely pushing."""
    from nsd_core.model.assemble import initial_state
    from nsd_core.model.load import parse_model
    state = initial_state(parse_model(description, "generated.toml"))

    def world(body, point):
        p = np.asarray(point, float)
        return p if body == "ground" else state.origin[body] + state.rotation[body] @ p
    for f in description["forces"]:
        if "body_a" not in f:
            continue
        a = world(f["body_a"], f["point_a"])
        L = float(np.linalg.norm(a - world(f["body_b"], f["point_b"])))
        if L < 0.03:   # too near to give the line a direction that lasts: the ground end moved out
            f["point_b"] = vec(np.asarray(f["point_b"], float) + 0.05 * unit(d))
            L = float(np.linalg.norm(a - world(f["body_b"], f["point_b"])))
        par = f["parameters"]
        if f["law"] == "linear_spring_damper":
            par["free_length"] = L * d.uniform(0.9, 1.1)
        elif f["law"] == "rope":
            par["free_length"] = L * d.uniform(0.97, 1.0)
        elif f["law"] == "hunt_crossley_stop":
            par["gap"] = L * d.uniform(1.0, 1.03)
        elif f["law"] == "sma_wire":
            par["area"] *= L / par["natural_length"] * 0.998   # E A / L as drawn, at the real length
            par["natural_length"] = L * 0.998
        elif f["law"] == "push_spring":
            par["free_length"] = L * 1.02


G_LOAD = 9.81   # N/kg: the plane law's strength scale


def _point_laws(d, names: list[str], total: float) -> list[dict]:
    """Point-to-point laws between random points: a spring always, a rope, a stop, a wire, a push spring
    sometimes (their lengths set by ``_hang`` once the start is assembled)."""
    out = []
    for i in range(d.integer(1, 2)):
        a = d.choice(names)
        pa = np.array([d.uniform(-1, 1) for _ in range(3)]) * 0.1
        pb = np.array([d.uniform(-1, 1) for _ in range(3)]) * 0.3
        out.append(spring(f"spring{i}", a, pa, "ground", pb, _length_hint(pa, pb), d, total))
    extra = d.choice(["none", "none", "rope", "stop", "sma_wire", "push_spring"])
    a = d.choice(names)
    pa, pb = np.array([d.uniform(-1, 1) for _ in range(3)]) * 0.1, np.array([d.uniform(-1, 1) for _ in range(3)]) * 0.3
    L = _length_hint(pa, pb)
    if extra == "rope":
        out.append({"name": "rope", "law": "rope", "body_a": a, "point_a": vec(pa), "body_b": "ground", "point_b": vec(pb),
                    "parameters": {"stiffness": total * d.uniform(50.0, 500.0), "free_length": L * d.uniform(0.9, 1.02)}})
    elif extra == "stop":
        out.append({"name": "stop", "law": "hunt_crossley_stop", "body_a": a, "point_a": vec(pa), "body_b": "ground",
                    "point_b": vec(pb), "parameters": {"gap": L * d.uniform(0.98, 1.05), "stiffness": total * 2e4,
                                                       "exponent": 1.5, "damping": d.uniform(0.0, 0.5)}})
    elif extra == "sma_wire":
        area = total * d.uniform(100.0, 1000.0) * L / SMA["E"]   # E A / L: 100-1000 N/m per kg
        out.append({"name": "wire", "law": "sma_wire", "body_a": a, "point_a": vec(pa), "body_b": "ground",
                    "point_b": vec(pb), "parameters": {"area": area, "natural_length": L * 0.998, **SMA}})
    elif extra == "push_spring":
        k = total * d.uniform(50.0, 500.0)
        out.append({"name": "push", "law": "push_spring", "body_a": a, "point_a": vec(pa), "body_b": "ground",
                    "point_b": vec(pb), "parameters": {"kse": k, "ksd": 0.5 * k, "free_length": L * 1.02, **PUSH}})
    return out


def _length_hint(pa, pb) -> float:
    """The distance of two points as drawn (before the joints move the body): a free length scale."""
    return max(float(np.linalg.norm(np.asarray(pb) - np.asarray(pa))), 0.05)


def _drive(d, bodies: list[dict], coords: dict, rates: dict) -> dict | None:
    """Sometimes a harmonic drive of a revolute turn or of a slide on the ground (every builder drives those;
    Exudyn no slide of a joint on a moving parent with its other translations locked)."""
    if d.integer(0, 2):
        return None
    options = [(b["name"], 0) for b in bodies if b["joint"]["type"] == "revolute"]
    options += [(b["name"], k) for b in bodies if b["parent"] == "ground" and b["joint"]["type"] != "spherical"
                for k in SLIDES.get(b["joint"]["type"], ())]
    if not options:
        return None
    name, k = d.choice(options)
    kind = next(b["joint"]["type"] for b in bodies if b["name"] == name)
    angle = k in TURNS.get(kind, ())
    amp = d.uniform(0.05, 0.4) if angle else d.uniform(0.005, 0.03)
    centre = coords[name] if not isinstance(coords[name], list) else coords[name][k]
    frequency = d.uniform(0.5, 3.0)
    if isinstance(coords[name], list):   # a prescribed coordinate takes its motion's start and rate
        rates[name][k] = amp * 2.0 * math.pi * frequency
    else:
        del coords[name], rates[name]
    return {"name": "drive", "joint": name, "dof": k, "motion": "harmonic", "centre": centre, "amplitude": amp,
            "frequency": frequency}


def _outputs(d, bodies: list[dict], forces: list[dict], prescribed) -> list[dict]:
    last = bodies[-1]["name"]
    p = vec(np.array([d.uniform(-1, 1) for _ in range(3)]) * 0.1)
    items = [(f"{b['name']}_q0", "coordinate", {"joint": b["name"]}) for b in bodies[:3]]
    items += [("tip", "point", {"body": last, "point": p, "component": d.choice("xyz"), "scale": 0.1}),
              ("tip_v", "point_velocity", {"body": last, "point": p, "component": d.choice("xyz")})]
    if d.integer(0, 2) == 0:
        items.append(("tip_a", "point_acceleration", {"body": last, "point": p, "component": d.choice("xyz")}))
    items += [(f"{f['name']}_out", "force", {"element": f["name"], **({"component": "x"} if "dofs" in f else {})})
              for f in forces if f["law"] != "joint_spring_damper"][:3]
    if prescribed:
        items.append(("drive_force", "drive_force", {"element": prescribed["name"]}))
    items.append(("kinetic", "energy", {"term": "kinetic"}))
    return outputs_for(items)
