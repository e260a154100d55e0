"""The device in seismic mode, with or without a shear building, as a model description
(docs/models.md): the same file format as every mechanism, built by every engine's builder.

The frame translates with the ground ([excitation]: every body feels -m a_g(t)), so the described
coordinates are the seismic mode's relative ones (docs/model.md, "Seismic mode"):
- the plate carries the isolated mass M (polar inertia M r_g^2) on a planar joint (x, y, turn about
  Z); the cap hangs on the plate by a prismatic joint along Z and turns with it, so its rope and wire
  points turn with the plate; the wall slides along Z on the base; the rod hangs on the wall by a
  universal joint and a point closure joins its upper end to the cap (Eq. 13), as in drive mode;
- the supports are joint springs and dashpots on the plate's coordinates: k_b, c_b along x and y,
  k_b r_b^2, c_b r_b^2 about Z;
- the restrainer (when the structure has one) is a Hunt-Crossley stop between the plate's centre and
  the base's: the distance is |u|, the force radial, as nsd_core.structure.restrainer says;
- a building's floors slide in the plane (planar_translation, relative to the ground); each story is
  two per-direction spring-dashpots (k_i, c_i, along x and along y) between floor i and the floor
  below (the slab is the plate), and the Rayleigh mass-proportional part is a dashpot b_i between
  floor i and the slab in each direction (nsd_core.structure.building's forces).
The device's elements are the drive description's (describe.device_forces).

    python -m nsd_core.structure.describe_seismic --ground "harmonic:amplitude=2,frequency=1.5,azimuth=30" \
        --duration 1 --out models/nsd_seismic.toml [--stories 3] [--restrainer]
"""
from __future__ import annotations

import argparse
import sys

from nsd_core.device.describe import ELEMENT_OUTPUTS, _changed, _inertia, _v, device_forces, rod_loop, wall_and_rod
from nsd_core.device.geometry import device_geometry
from nsd_core.structure.isolation import Structure
from nsd_core.device.params import Params


def plate_body(st: Structure) -> str:
    """The plate carrying the isolated structure (mass M, polar inertia M r_g^2) on its planar joint."""
    J = st.polar_inertia
    return f'''[[bodies]]   # the plate with the isolated structure: x, y relative to the ground, a turn about Z
name = "plate"
joint = {{ type = "planar", position = [0.0, 0.0, 0.0], normal = [0.0, 0.0, 1.0] }}
mass = {st.mass!r}
com = [0.0, 0.0, 0.0]
inertia = {_v([J / 2, J / 2, J])}
'''


def _structure_lines(st: Structure) -> str:
    kt, ct = st.stiffness * st.support_radius ** 2, st.damping * st.support_radius ** 2
    out = "\n" + plate_body(st)
    forces = "".join(f'''
[[forces]]   # the supports {label} (k_b{extra}, c_b{extra})
name = "support_{label}"
law = "joint_spring_damper"
joint = "plate"
dof = {dof}
parameters = {{ stiffness = {k!r}, damping = {c!r} }}
''' for label, dof, k, c, extra in (("x", 0, st.stiffness, st.damping, ""), ("y", 1, st.stiffness, st.damping, ""),
                                    ("turn", 2, kt, ct, " r_b^2")))
    r = st.restrainer
    if r is not None:
        forces += f'''
[[forces]]   # the displacement restrainer: radial, past the gap u_gap (Hunt-Crossley; nsd_core.structure.restrainer)
name = "restrainer"
law = "hunt_crossley_stop"
body_a = "plate"
body_b = "ground"
parameters = {{ gap = {r.gap!r}, stiffness = {r.stiffness!r}, exponent = {r.exponent!r}, damping = {r.damping!r} }}
'''
    return out, forces


def _inline(t: dict) -> str:
    """A flat table of strings, numbers and number lists as a TOML inline table (floats by repr)."""
    def value(v):
        if isinstance(v, str):
            return f'"{v}"'
        if isinstance(v, (list, tuple)):
            return "[" + ", ".join(value(x) for x in v) + "]"
        return repr(v) if isinstance(v, int) and not isinstance(v, bool) else repr(float(v))
    return "{ " + ", ".join(f"{k} = {value(v)}" for k, v in t.items()) + " }"


def _spring_along(name: str, comment: str, a: str, b: str, e: str, k: float, c: float) -> str:
    """A linear spring-dashpot between the origins of bodies a and b acting along the direction e."""
    return f'''
[[forces]]   # {comment}
name = "{name}"
law = "linear_spring_damper"
body_a = "{a}"
body_b = "{b}"
direction = {e}
parameters = {{ stiffness = {float(k)!r}, damping = {float(c)!r}, free_length = 0.0 }}
'''


def _building_lines(st: Structure) -> tuple[str, str, str]:
    b = st.building
    bodies, forces, outputs = [], [], []
    r_g = st.radius_of_gyration
    for i in range(b.stories):
        m = b.masses[i]
        below = "plate" if i == 0 else f"floor{i}"
        bodies.append(f'''
[[bodies]]   # floor {i + 1}: slides in the plane (no torsion), relative to the ground
name = "floor{i + 1}"
joint = {{ type = "planar_translation", position = [0.0, 0.0, {float(sum(b.heights[:i + 1]))!r}], normal = [0.0, 0.0, 1.0] }}
mass = {float(m)!r}
inertia = {_v([m * r_g ** 2 / 2, m * r_g ** 2 / 2, m * r_g ** 2])}   # never felt: the floor does not turn
''')
        for axis, e in (("x", "[1.0, 0.0, 0.0]"), ("y", "[0.0, 1.0, 0.0]")):
            forces.append(_spring_along(f"story{i + 1}_{axis}", f"story {i + 1} along {axis}: k_i, c_i on the drift "
                                        "d_i - d_(i-1)", f"floor{i + 1}", below, e, b.stiffnesses[i], b.story_damping[i]))
            if b.slab_damping[i] > 0:
                forces.append(_spring_along(f"slab_damper{i + 1}_{axis}", f"Rayleigh's mass-proportional part along "
                                            f"{axis}: b_i on d_i - d_0", f"floor{i + 1}", "plate", e, 0.0,
                                            b.slab_damping[i]))
            outputs.append(f'''
[[outputs]]
name = "floor{i + 1}_{axis}"
kind = "coordinate"
joint = "floor{i + 1}"
dof = {0 if axis == "x" else 1}
''')
    return "".join(bodies), "".join(forces), "".join(outputs)


PLATE_OUTPUTS = '''
[[outputs]]
name = "u_x"
kind = "coordinate"
joint = "plate"
dof = 0

[[outputs]]
name = "u_y"
kind = "coordinate"
joint = "plate"
dof = 1

[[outputs]]
name = "theta"
kind = "coordinate"
joint = "plate"
dof = 2
scale = 1e-3   # rad: a rotation below a milliradian is judged against one

[[outputs]]
name = "cap_z"
kind = "coordinate"
joint = "cap"

[[outputs]]    # the plate's absolute acceleration: relative to the ground plus a_g(t) [m/s^2]
name = "a_x"
kind = "point_acceleration"
body = "plate"
point = [0.0, 0.0, 0.0]
component = "x"

[[outputs]]
name = "a_y"
kind = "point_acceleration"
body = "plate"
point = [0.0, 0.0, 0.0]
component = "y"

[[outputs]]
name = "support_x"
kind = "force"
element = "support_x"

'''


def _case(st: Structure, name: str, duration: float, dt_out: float) -> str:
    """The one [[case]]: ``duration`` s sampled every ``dt_out``, with MuJoCo's and Exudyn's steps for ``st``."""
    # Exudyn's step: the largest dividing dt_out whose own (Richardson) error estimate meets 1e-3 of every
    # output's scale: 1e-3 s on the device alone; 2e-4 s with the building and its restrainer (at 5e-4 s
    # the restrainer's force estimate is 4.0e-3 of k_b u_gap; the compare asked for <= 2.23e-4 s)
    exudyn_step = 2e-4 if st.building is not None else 1e-3
    # MuJoCo (RK4): its error here is the soft loop closure's, set by the time constant solref_factor x
    # timestep alone, so MuJoCo's floor factor 2 needs half the steps of the default 4. The largest step
    # dividing dt_out whose own (Richardson) estimate meets the tolerances and whose loop gap stays
    # below 1e-6 m: 1e-4 s on the device (estimate 2.9e-4 of u_y's peak, gap 7.6e-7 m); with the
    # restrainer's impacts 2.5e-5 s (its force's estimate 8.4e-4 of k_b u_gap)
    mujoco_step = 2.5e-5 if st.restrainer is not None else 1e-4
    return f'''
[[case]]
name = "{name}_{duration:g}s"
duration = {duration!r}
dt_out = {dt_out!r}
mujoco = {{ timestep = {mujoco_step!r}, solref_factor = 2.0 }}
exudyn = {{ step_size = {exudyn_step!r} }}
'''


def seismic_description(params: Params, st: Structure, ground: str | dict, duration: float, dt_out: float = 1e-3,
                        name: str = "nsd_seismic", command: str = "", geometry=None) -> str:
    """The seismic-mode device on the structure ``st`` (its building, its restrainer) under the closed
    form ``ground`` (``nsd seismic --ground``'s syntax) or a FEMA P695 record table ({set, id, scale,
    time_factor, window, rotate}: [excitation].record), as TOML with one case of ``duration`` s.
    geometry: the device's DeviceGeometry when it is not ``device_geometry(params)`` (an injected
    modelling error, comparisons.engines.perturb)."""
    g = device_geometry(params) if geometry is None else geometry
    excitation = f"record = {_inline(ground)}" if isinstance(ground, dict) else f'ground = "{ground}"'
    plate, supports = _structure_lines(st)
    floors, stories, floor_outputs = _building_lines(st) if st.building is not None else ("", "", "")
    head = f'''# The negative-stiffness device (Dai et al. 2024) in seismic mode{" under a " + str(st.building.stories) + "-story building" if st.building else ""}, as a model description.
# Written by `python -m nsd_core.structure.describe_seismic` from the device's parameters and the isolated
# structure (docs/seismic.md; every value with its provenance in `nsd params`). Device parameters that
# differ from the nominal ones: {", ".join(f"{k} = {v!r}" for k, v in _changed(params).items()) or "none"}.
# Coordinates are relative to the ground: the frame moves with it ([excitation]).{chr(10) + "#   " + command if command else ""}

[model]
name = "{name}"
source = "Dai et al. 2024 (doi:10.1002/msd2.12118); structure: nsd_core.structure.isolation (assumed rules)"
gravity = {_v(g.gravity_vector)}

[excitation]   # every body feels -m a_g(t): a_g from the ground motion below
type = "ground_acceleration"
{excitation}
{plate}
[[bodies]]   # the cap: rides on the plate (turns with it), its height free
name = "cap"
parent = "plate"
joint = {{ type = "prismatic", position = [0.0, 0.0, 0.0], axis = [0.0, 0.0, 1.0] }}
mass = {g.cap.mass!r}
com = {_v(g.cap.com)}
inertia = {_inertia(g.cap.inertia)}

{wall_and_rod(g)}{floors}
{rod_loop(g.params)}
[initial]    # relative rest, the device precompressed
coordinates = {{ cap = {g.cap_rest_z!r}, wall = {g.wall_rest_z!r} }}
free = ["plate", "cap"]
'''
    outputs = PLATE_OUTPUTS + ELEMENT_OUTPUTS + floor_outputs
    if st.restrainer is not None:   # judged against the supports' force at the gap, k_b u_gap
        outputs += f'''
[[outputs]]
name = "restrainer_force"
kind = "force"
element = "restrainer"
scale = {st.stiffness * st.restrainer.gap!r}   # N: k_b u_gap, the supports' force when the stop engages
'''
    return head + device_forces(g) + supports + stories + outputs + _case(st, name, duration, dt_out)


def structure_for(params: Params, stories: int = 0, restrainer: bool = False) -> Structure:
    """The default isolated structure of ``params`` (nsd_core.structure.isolation), with the default
    restrainer and a default building of ``stories`` stories when asked."""
    from nsd_core.structure.building import building_from
    from nsd_core.structure.isolation import structure_with
    from nsd_core.structure.restrainer import default_restrainer
    st = structure_with(params, {})
    if restrainer:
        st = Structure(**{**st.__dict__, "restrainer": default_restrainer(params, st)})
    if stories:
        st = Structure(**{**st.__dict__, "building": building_from(st.mass, {"stories": stories})})
    return st


def main(argv=None) -> None:
    from nsd_core.device.params import parse_set, with_overrides
    from nsd_core.common.files import atomic_write_text
    p = argparse.ArgumentParser(description="write the device in seismic mode as a model description (TOML)")
    p.add_argument("--ground", required=True, help="a closed form, nsd seismic --ground's syntax")
    p.add_argument("--duration", type=float, required=True, help="s")
    p.add_argument("--dt-out", type=float, default=1e-3, help="s")
    p.add_argument("--stories", type=int, default=0, help="a shear building of this many stories (default: none)")
    p.add_argument("--restrainer", action="store_true", help="with the default displacement restrainer")
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE")
    p.add_argument("--name", default="nsd_seismic")
    p.add_argument("--out", required=True)
    a = p.parse_args(argv)
    params = with_overrides(Params(), parse_set(a.set))
    st = structure_for(params, a.stories, a.restrainer)
    command = "python -m nsd_core.structure.describe_seismic " + " ".join(
        f"'{x}'" if any(c in x for c in " :,") else x for x in (argv if argv is not None else sys.argv[1:]))
    atomic_write_text(a.out, seismic_description(params, st, a.ground, a.duration, a.dt_out, a.name, command))


if __name__ == "__main__":
    main()
