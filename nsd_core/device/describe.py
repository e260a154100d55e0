"""The device in drive mode as a model description (docs/models.md): a file a user can read, copy and
change, built by every engine's builder like any other mechanism.

The description is the in-house device model's tree (nsd_core.device.model) with the base held
fixed (drive mode locks it) and the massless driven plate folded into the cap's joint: the cap
slides on three translations (X and Y prescribed: the plate's line path; Z free), the wall slides
along Z on the base, the rod hangs on the wall by a universal joint (about X, then Y), and a point
closure joins the rod's upper end to the cap's reference point (the cut spherical joint of Eq. 13).
The ropes (Eq. 16), SMA wires (Eq. 17) and the push spring (Eq. 18) are force elements whose laws
come from the registry (nsd_core.model.laws); every number comes from ``device_geometry(params)``.

    python -m nsd_core.device.describe --amplitude 0.015 --frequency 1 --out models/nsd_drive.toml

writes it for the nominal parameters (``--set NAME=VALUE`` for a variant).
"""
from __future__ import annotations

import argparse
import json
import math

import numpy as np

from nsd_core.device.geometry import device_geometry
from nsd_core.device.params import Params, parse_set, with_overrides


def _v(x) -> str:
    return "[" + ", ".join(repr(float(a)) for a in np.asarray(x, float).ravel()) + "]"


def _inertia(J) -> str:
    J = np.asarray(J, float)
    return _v([J[0, 0], J[1, 1], J[2, 2], J[0, 1], J[0, 2], J[1, 2]])


def _changed(params: Params) -> dict:
    nominal = Params().to_dict()
    return {k: v for k, v in params.to_dict().items() if nominal.get(k) != v}


def device_description(params: Params, amplitude: float, frequency: float, direction_deg: float = 0.0,
                       cycles: int = 2, samples_per_cycle: int = 500, drive=None, case: str | None = None,
                       geometry=None) -> str:
    """The drive-mode device under a line drive (u = A sin(2 pi f t) along the direction), as TOML.
    drive: a nsd_core.device.drive.Drive whose plate path (circle, figure8, ... with its ramp) the cap
    follows instead (motion "device_path"); case: the [[case]] table's text instead of the default;
    geometry: the device's DeviceGeometry when it is not ``device_geometry(params)`` (the gate's
    injected modelling errors, comparisons.engines.perturb, live in one engine's model only)."""
    g = device_geometry(params) if geometry is None else geometry
    psi = math.radians(direction_deg)
    lines = [f'''# The negative-stiffness device (Dai et al. 2024) in drive mode, as a model description.
# Written by `python -m nsd_core.device.describe` from the device's parameters (nsd params lists each
# with its unit and provenance; docs/model.md gives the equations). Parameters that differ from the
# nominal ones: {", ".join(f"{k} = {v!r}" for k, v in _changed(params).items()) or "none"}.
# Drive: a line of amplitude {amplitude!r} m at {frequency!r} Hz, {direction_deg!r} degrees from X.

[model]
name = "nsd_drive"
source = "Dai et al. 2024 (doi:10.1002/msd2.12118); nominal values in nsd_core/device/params.py"
gravity = {_v(g.gravity_vector)}

[[bodies]]   # the cap: X and Y follow the plate (prescribed), Z is free
name = "cap"
joint = {{ type = "translational", position = [0.0, 0.0, 0.0] }}
mass = {g.cap.mass!r}
com = {_v(g.cap.com)}
inertia = {_inertia(g.cap.inertia)}

{wall_and_rod(g)}
{rod_loop(g.params)}
{_prescribed(amplitude, frequency, psi, drive)}[initial]    # the precompressed rest state
coordinates = {{ cap = [0.0, 0.0, {g.cap_rest_z!r}], wall = {g.wall_rest_z!r} }}
free = ["cap"]
''']
    lines.append(device_forces(g))
    lines.append(f'''
{force_outputs(params, psi, drive)}
[[outputs]]
name = "cap_z"
kind = "coordinate"
joint = "cap"
dof = 2

[[outputs]]
name = "wall_z"
kind = "coordinate"
joint = "wall"

{ELEMENT_OUTPUTS}
[[outputs]]    # the laws' internal states (Eqs. 17, 18): the wire's stress [Pa] and the spring's zeta [N]
name = "wire0_stress"
kind = "state"
element = "wire0"

[[outputs]]
name = "spring_zeta"
kind = "state"
element = "spring"

{case if case is not None else _default_case(amplitude, frequency, cycles, samples_per_cycle)}''')
    return "".join(lines)


def force_outputs(params: Params, psi: float, drive) -> str:
    """F_x and F_y, the drive's forces. A component that is zero in exact arithmetic is judged in newtons
    (``scale = 1.0``; its own peak is round-off): the force across a line drive along X (the wires are
    symmetric about X for any number), and along Y where the number of wires is even. On any other
    path both are judged against their own peaks."""
    angle = psi if drive is None else math.radians(drive.direction_deg)
    line = drive is None or drive.path == "line"
    zero = {"x": line and abs(math.cos(angle)) < 1e-12 and params.n_wires % 2 == 0,
            "y": line and abs(math.sin(angle)) < 1e-12}
    return "\n".join(f'''[[outputs]]
name = "F_{c}"
kind = "drive_force"
element = "drive_{c}"
''' + ("scale = 1.0    # N: the force across a line drive is zero up to round-off; judged in newtons\n"
       if zero[c] else "") for c in "xy")


ELEMENT_OUTPUTS = '''[[outputs]]
name = "rope0_tension"
kind = "force"
element = "rope0"

[[outputs]]
name = "spring_tension"
kind = "force"
element = "spring"
'''


def rod_loop(params) -> str:
    """The loop closure joining the rod's upper end to the cap's reference point."""
    return f'''[[loops]]    # the rod's upper joint: the cut spherical joint of Eq. 13
name = "cap_rod"
body_a = "cap"
point_a = [0.0, 0.0, 0.0]
body_b = "rod"
point_b = [0.0, 0.0, {params.rod_length!r}]
'''


def wall_and_rod(g) -> str:
    """The wall (prismatic along Z on the base) and the rod (universal on the wall) as TOML bodies."""
    return f'''[[bodies]]   # the wall: slides along Z in the base's guide, on the spring
name = "wall"
joint = {{ type = "prismatic", position = [0.0, 0.0, 0.0], axis = [0.0, 0.0, 1.0] }}
mass = {g.wall.mass!r}
com = {_v(g.wall.com)}
inertia = {_inertia(g.wall.inertia)}

[[bodies]]   # the rod: a universal joint at the wall's reference point (no spin about its own axis)
name = "rod"
parent = "wall"
joint = {{ type = "universal", position = [0.0, 0.0, 0.0], axis = [1.0, 0.0, 0.0], axis2 = [0.0, 1.0, 0.0] }}
mass = {g.rod.mass!r}
com = {_v(g.rod.com)}
inertia = {_inertia(g.rod.inertia)}
'''


def _prescribed(amplitude: float, frequency: float, psi: float, drive) -> str:
    """The cap's X and Y drives: harmonic along the line, or the components of ``drive``'s path."""
    if drive is None:
        return f'''[[prescribed]]
name = "drive_x"
joint = "cap"
dof = 0
motion = "harmonic"
amplitude = {amplitude * math.cos(psi)!r}
frequency = {frequency!r}

[[prescribed]]
name = "drive_y"
joint = "cap"
dof = 1
motion = "harmonic"
amplitude = {amplitude * math.sin(psi)!r}
frequency = {frequency!r}

'''
    minor = f"\nminor = {drive.minor_axis!r}" if drive.path in ("ellipse", "figure8") else ""   # (a table: its own)
    return "".join(f'''[[prescribed]]
name = "drive_{c}"
joint = "cap"
dof = {k}
motion = "device_path"   # the plate's {drive.path} path (nsd cycle --path), its {c} coordinate
path = {json.dumps(drive.path)}
amplitude = {drive.amplitude!r}
frequency = {drive.frequency!r}
direction = {drive.direction_deg!r}
component = "{c}"{minor}

''' for k, c in enumerate("xy"))


def _default_case(amplitude: float, frequency: float, cycles: int, samples_per_cycle: int) -> str:
    return f'''[[case]]
name = "drive_A{amplitude * 1e3:g}mm_f{frequency:g}Hz"
duration = {cycles / frequency!r}   # s: {cycles} cycles
dt_out = {1.0 / (frequency * samples_per_cycle)!r}
# the peers' steps for 1e-3 of the peak force on the nominal device at 1 Hz, A = 15 mm (measured against
# the in-house run at rtol 1e-10: MuJoCo RK4 3.5e-4 at 5e-5 s, Exudyn 3.5e-4 at 1e-3 s; their own h/2
# runs say whether another device or drive needs less)
mujoco = {{ timestep = 5e-5 }}
exudyn = {{ step_size = 1e-3 }}
'''


def device_forces(g) -> str:
    """The device's force elements as TOML: ropes (Eq. 16) base -> cap, SMA wires (Eq. 17) cap ->
    wall, the push spring (Eq. 18) wall -> base; the cap's points are in the cap's frame."""
    w, s = g.wire, g.spring
    stiffness = np.broadcast_to(np.asarray(g.rope_stiffness, dtype=float), (g.n_ropes,))   # one per rope
    lines = []
    for k in range(g.n_ropes):
        lines.append(f'''
[[forces]]   # rope {k}: base point -> cap point (Eq. 16)
name = "rope{k}"
law = "rope"
body_a = "cap"
point_a = {_v(g.rope_cap_points[k])}
body_b = "ground"
point_b = {_v(g.rope_base_points[k])}
parameters = {{ stiffness = {float(stiffness[k])!r}, free_length = {float(g.rope_natural_length[k])!r} }}
''')
    stress0 = g.initial_wire_stress()
    for k in range(g.n_wires):
        lines.append(f'''
[[forces]]   # SMA wire {k}: cap point -> wall point (Eq. 17)
name = "wire{k}"
law = "sma_wire"
body_a = "cap"
point_a = {_v(g.wire_cap_points[k])}
body_b = "wall"
point_b = {_v(g.wire_wall_points[k])}
parameters = {{ area = {w.area!r}, natural_length = {w.natural_length!r}, E = {w.E!r}, Y = {w.Y!r}, alpha = {w.alpha!r}, n = {w.n!r}, fT = {w.fT!r}, a = {w.a!r}, Em = {w.Em!r}, eps_t = {w.eps_t!r}, c = {w.c!r}, initial_stress = {float(stress0[k])!r} }}
''')
    lines.append(f'''
[[forces]]   # the precompressed push spring: wall reference -> base origin, along Z (Eq. 18)
name = "spring"
law = "push_spring"
body_a = "wall"
body_b = "ground"
parameters = {{ kse = {s.kse!r}, ksd = {s.ksd!r}, beta = {s.beta!r}, gamma = {s.gamma!r}, n = {s.n!r}, free_length = {s.free_length!r}, initial_zeta = {g.spring_zeta0!r} }}
''')
    return "".join(lines)


def main(argv=None) -> None:
    from nsd_core.common.files import atomic_write_text
    p = argparse.ArgumentParser(description="write the device in drive mode as a model description (TOML)")
    p.add_argument("--amplitude", type=float, required=True, help="m")
    p.add_argument("--frequency", type=float, required=True, help="Hz")
    p.add_argument("--direction", type=float, default=0.0, help="degrees from X")
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE")
    p.add_argument("--out", required=True)
    a = p.parse_args(argv)
    params = with_overrides(Params(), parse_set(a.set))
    atomic_write_text(a.out, device_description(params, a.amplitude, a.frequency, a.direction))


if __name__ == "__main__":
    main()
