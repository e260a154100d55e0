"""The isolated structure on a baseline isolator (a lead-rubber bearing or a friction pendulum,
nsd_core.structure.isolators), without the device, as a model description (docs/models.md): what
``simulate_seismic(..., device=False)`` runs for a structure whose ``isolator`` is set, in the file
format every builder reads.

The frame translates with the ground ([excitation]: every body feels -m a_g(t)):
- the plate carries the isolated mass M (polar inertia M r_g^2) on a planar joint (x, y, turn about Z);
- the isolator's linear part is three joint springs and dashpots on the plate's coordinates: k_d, c
  along x and y, k_d r_b^2, c r_b^2 about Z (the torsional pair of Structure.on_isolator);
- its hysteretic part is one ``bidirectional_hysteresis`` element on the plate's (x, y): the registry's
  plane law, whose state z = (z_x, z_y) couples the two directions (nsd_core.structure.isolator_laws).
No building, no restrainer: a structure with either is refused (the in-house engine runs those).

    python -m nsd_core.structure.describe_isolator --isolator bilinear --ground "harmonic:amplitude=2,frequency=1.5" \\
        --duration 1 --out out/isolator.toml
"""
from __future__ import annotations

import argparse

from nsd_core.structure.describe_seismic import _inline, plate_body
from nsd_core.structure.isolation import Structure
from nsd_core.device.params import ParameterError

# Each peer's step on this model: MuJoCo's Euler at 2e-5 s (1e-4 s changes the peak displacement of a
# 0.6-scaled near-fault window by ~1e-3 relative); Exudyn's generalized-alpha at 1e-4 s
MUJOCO_STEP, EXUDYN_STEP = 2e-5, 1e-4


def _output(name: str, kind: str, **keys) -> str:
    return f'\n[[outputs]]\nname = "{name}"\nkind = "{kind}"\n' + "".join(f"{k} = {v}\n" for k, v in keys.items())


def isolator_description(st: Structure, ground: str | dict, duration: float, dt_out: float = 1e-3,
                         name: str = "nsd_isolator") -> str:
    """The structure ``st`` on its baseline isolator ``st.isolator`` under the closed form ``ground``
    (``nsd seismic --ground``'s syntax) or a FEMA P695 record table ([excitation].record), as TOML with
    one case of ``duration`` s sampled every ``dt_out`` s."""
    iso = st.isolator
    if iso is None or st.building is not None or st.restrainer is not None:
        raise ParameterError("isolator description: a structure with a baseline isolator, no building, no restrainer")
    excitation = f"record = {_inline(ground)}" if isinstance(ground, dict) else f'ground = "{ground}"'
    r2 = st.support_radius ** 2
    supports = "".join(f'''
[[forces]]   # the isolator's linear part {label} (k_d{extra}, c{extra})
name = "support_{label}"
law = "joint_spring_damper"
joint = "plate"
dof = {dof}
parameters = {{ stiffness = {k!r}, damping = {c!r} }}
''' for label, dof, k, c, extra in (("x", 0, iso.stiffness, iso.damping, ""), ("y", 1, iso.stiffness, iso.damping, ""),
                                    ("turn", 2, iso.stiffness * r2, iso.damping * r2, " r_b^2")))
    q_fast, q_slow, rate, d_y, n = iso.block()
    outputs = [_output("u_x", "coordinate", joint='"plate"', dof=0), _output("u_y", "coordinate", joint='"plate"', dof=1),
               _output("theta", "coordinate", joint='"plate"', dof=2, scale="1e-3")]
    outputs += [_output(f"v_{c}", "point_velocity", body='"plate"', point="[0.0, 0.0, 0.0]", component=f'"{c}"')
                for c in "xy"]
    outputs += [_output(f"a_{c}", "point_acceleration", body='"plate"', point="[0.0, 0.0, 0.0]", component=f'"{c}"')
                for c in "xy"]
    outputs += [_output(f"hysteresis_{c}", "force", element='"isolator"', component=f'"{c}"') for c in "xy"]
    outputs += [_output(f"z_{c}", "state", element='"isolator"', component=f'"{c}"', scale="1.0") for c in "xy"]
    return f'''# The isolated structure on a {iso.kind} isolator, without the device, as a model description.
# Written by nsd_core.structure.describe_isolator from the structure (nsd_core.structure.isolation) and its
# isolator (nsd_core.structure.isolators: {iso.provenance.get("source", "given constants")}).
# Coordinates are relative to the ground: the frame moves with it ([excitation]).

[model]
name = "{name}"
source = "nsd_core.structure.isolators ({iso.kind}); structure: nsd_core.structure.isolation (assumed rules)"
gravity = [0.0, 0.0, -9.81]

[excitation]   # every body feels -m a_g(t)
type = "ground_acceleration"
{excitation}

{plate_body(st)}{supports}
[[forces]]   # the isolator's hysteretic part on the plate's (x, y): -Q z, z its coupled state
name = "isolator"
law = "bidirectional_hysteresis"
joint = "plate"
dofs = [0, 1]
parameters = {{ strength = {q_fast!r}, strength_at_rest = {q_slow!r}, rate = {rate!r}, yield_displacement = {d_y!r}, exponent = {n!r} }}
{"".join(outputs)}
[[case]]
name = "{name}_{duration:g}s"
duration = {float(duration)!r}
dt_out = {float(dt_out)!r}
mujoco = {{ timestep = {MUJOCO_STEP!r}, integrator = "Euler" }}
exudyn = {{ step_size = {EXUDYN_STEP!r} }}
'''


def main(argv=None) -> None:
    from nsd_core.structure.isolation import designed_structure
    from nsd_core.structure.isolators import KINDS, sized
    from nsd_core.common.files import atomic_write_text
    p = argparse.ArgumentParser(description="write the structure on a baseline isolator as a model description (TOML)")
    p.add_argument("--isolator", required=True, choices=KINDS)
    p.add_argument("--ground", required=True, help="a closed form, nsd seismic --ground's syntax")
    p.add_argument("--duration", type=float, required=True, help="s")
    p.add_argument("--dt-out", type=float, default=1e-3, help="s")
    p.add_argument("--out", required=True)
    a = p.parse_args(argv)
    s = designed_structure(True)
    atomic_write_text(a.out, isolator_description(s.with_isolator(sized(a.isolator, s.mass)), a.ground, a.duration,
                                                  a.dt_out))


if __name__ == "__main__":
    main()
