"""Write IFToMM A02 (N four-bar linkages in a row, 2N+1 links) as a model description (docs/models.md).

    python -m references.iftomm_a02 --n 40 --out models/iftomm_a02_fourbar_n40.toml
    python -m references.iftomm_a02 --n 4 --out models/iftomm_a02_fourbar.toml

The bodies, loops, initial state and outputs follow from N alone. The [[case]] table holds each
engine's step, chosen by running and recorded with its measured errors, so it is kept here per N
(CASES); an N without a measured case is written without one (give one with --cases FILE). The
reference of a case is the exact one-angle reduction (references/model_references.py), which depends
on N: J phi'' = C sin(phi) with J = (N+1)/3 + N and C = g ((N+1)/2 + N).
"""
from __future__ import annotations

import argparse
from pathlib import Path

BAR = repr(1.0 / 12.0)   # a 1 m, 1 kg slender bar about a transverse axis through its centre [kg m^2]
COMMAND = "python -m references.iftomm_a02 --n {n} --out models/{stem}.toml"

CASES = {
    4: '''[[case]]
name = "a02_5s"
duration = 5.0     # s (the library's run is 20 s)
dt_out = 0.05      # s: the library's output step (400 over 20 s)
mujoco = { timestep = 2.5e-4 }    # s: 1e-3 gives 9.8e-4 (first order near the singular positions)
exudyn = { step_size = 5e-4 }     # s: 2.8e-5 m; near the singular positions its Newton is relaxed to 1e-8 (builder docstring)
reference = { file = "iftomm_a02_reference.csv", source = "exact one-angle reduction J phi'' = C sin(phi), references/model_references.py" }
''',
    40: '''# Measured with `nsd compare --model` (2 cores, loaded). Errors: the largest |engine - exact
# reference| over the 401 samples as a fraction of the output's scale (its peak: B0_x, B0_y 1 m,
# B0_vx 6.73, B0_vy 5.21 m/s), worst output named; "estimate": the engine's own (Richardson from h, h/2).
# 20 singular instants in 20 s (0.7216, 1.2440, 2.6872, 3.2096, ... s).
# semirecursive: max_step 0.02 s (the converged runs too): 2.2e-6 (B0_vy), 31 s. At the default
#   0.01 s the converged run (rtol 1e-12) stops at t = 0.721581 s, the first singular instant (DOP853:
#   "step size less than spacing between numbers"); at 0.05 s its check (rtol 1e-13) stops there.
# mujoco: 9.3e-4 (B0_vy), estimate 7.5e-4, 17 s (h/2 17 s); 1e-3 s gives 2.8e-3, 2.5e-4 s 3.7e-4
#   (order 1.3 near the singular positions).
# exudyn: 8.7e-4 (B0_vy), estimate 8.8e-4; both runs relaxed (Newton 1e-8) after a failure at 12.515 s
#   (h) and 1.244 s (h/2); 6.25e-4 s gives 2.1e-4. Relaxed, 5e-4 s fails at 8.584 s, 4e-4 s at 6.618 s,
#   2.5e-4 s at 5.175 s (a step ends within 3e-5 s of a singular instant): 1e-3 s and 8e-4 s pass but
#   have no h/2. 34 s (h/2 37 s): the builder solves systems of over 1000 unknowns with Eigen's sparse
#   LU (a dense one took ~120 ms a step against 1.8 ms, the same outputs to 2e-11).
[[case]]
name = "a02_20s"
duration = 20.0    # s: the library's run
dt_out = 0.05      # s: the library's output step (400 over 20 s)
semirecursive = { max_step = 0.02 }
mujoco = { timestep = 5e-4 }
exudyn = { step_size = 1.25e-3 }
reference = { file = "iftomm_a02_n40_reference.csv", source = "exact one-angle reduction J phi'' = C sin(phi) for N = 40, references/model_references.py" }
''',
}


def stem(n: int) -> str:
    return "iftomm_a02_fourbar" if n == 4 else f"iftomm_a02_fourbar_n{n}"


def _header(n: int) -> str:
    if n == 4:   # the file written by hand before this generator, kept byte for byte
        return """# IFToMM / MBS benchmark library A02: the one-degree-of-freedom assembly of N four-bar linkages, N = 4.
#
# Source: Gonzalez et al. 2006 (see references/iftomm_group_a.toml for the quoted specification):
# 2N+1 uniform links of 1 m and 1 kg, gravity 9.81 in -y; cranks start vertical, couplers
# horizontal; the x-velocity of B0 is 1 m/s. When all cranks are horizontal the mechanism is
# singular (1 -> N+1 degrees of freedom). The library's problem has N = 40; this file has N = 4
# so that the gate runs it in seconds (the motion is the same parallelogram motion for any N).
"""
    size = "the library's problem" if n == 40 else "the library's problem has N = 40"
    return f"""# IFToMM / MBS benchmark library A02: the one-degree-of-freedom assembly of N four-bar linkages, N = {n}.
# Written by `{COMMAND.format(n=n, stem=stem(n))}`.
#
# Source: Gonzalez et al. 2006 (see references/iftomm_group_a.toml for the quoted specification):
# 2N+1 uniform links of 1 m and 1 kg, gravity 9.81 in -y; cranks start vertical, couplers
# horizontal; the x-velocity of B0 is 1 m/s. When all cranks are horizontal the mechanism is
# singular (1 -> N+1 degrees of freedom). N = {n}: {size}.
# Every crank turns by the same angle phi and the couplers translate, for any N, but phi(t) depends
# on N (J phi'' = C sin(phi), J = (N+1)/3 + N, C = g ((N+1)/2 + N)): each N has its own reference.
"""


def _body(name: str, joint_at: str, com: str, inertia: str, parent: str | None = None) -> str:
    parent_line = f'parent = "{parent}"\n' if parent else ""
    return f'''
[[bodies]]
name = "{name}"
{parent_line}joint = {{ type = "revolute", position = {joint_at}, axis = [0.0, 0.0, 1.0] }}
mass = 1.0
com = {com}
inertia = {inertia}
'''


def _output(name: str, kind: str, component: str) -> str:
    return f'''
[[outputs]]
name = "{name}"
kind = "{kind}"
body = "crank0"
point = [0.0, 1.0, 0.0]
component = "{component}"
'''


def description(n: int, case: str | None = None) -> str:
    """A02 with N four-bar linkages (N+1 cranks, N couplers, N loops) as TOML; case: the [[case]]
    text (default: CASES[n], none for an N without a measured case)."""
    if n < 1:
        raise ValueError(f"--n {n}: at least 1 four-bar")
    if case is None:
        case = CASES.get(n)
    parts = [_header(n), """# Crank i is hinged to the ground at (i, 0); coupler i hangs on crank i-1's tip B_(i-1) and is
# closed on crank i's tip B_i. Inertias: a 1 m, 1 kg slender bar about its centre (1/12 kg m^2
# about its two transverse axes).

[model]
""", f'''name = "{stem(n)}"
source = "IFToMM MBS benchmark A02 (Gonzalez et al. 2006), N = {n}"
gravity = [0.0, -9.81, 0.0]
''']
    for i in range(n + 1):
        parts.append(_body(f"crank{i}", f"[{float(i)!r}, 0.0, 0.0]", "[0.0, 0.5, 0.0]", f"[{BAR}, 0.0, {BAR}]"))
    for i in range(1, n + 1):
        parts.append(_body(f"coupler{i}", "[0.0, 1.0, 0.0]", "[0.5, 0.0, 0.0]", f"[0.0, {BAR}, {BAR}]",
                           parent=f"crank{i - 1}"))
    for i in range(1, n + 1):
        parts.append(f'''
[[loops]]
name = "B{i}"
body_a = "coupler{i}"
point_a = [1.0, 0.0, 0.0]
body_b = "crank{i}"
point_b = [0.0, 1.0, 0.0]
''')
    rates = ", ".join(f"crank{i} = -1.0" for i in range(n + 1))
    parts.append(f'''
[initial]   # every crank at -1 rad/s about +Z: B0 moves along +x at 1 m/s
velocities = {{ {rates} }}
free = ["crank0"]
''')
    for name, kind, comp in (("B0_x", "point", "x"), ("B0_y", "point", "y"),
                             ("B0_vx", "point_velocity", "x"), ("B0_vy", "point_velocity", "y")):
        parts.append(_output(name, kind, comp))
    if case:
        parts.append("\n" + case)
    else:
        parts.append("\n# No [[case]]: no engine's step has been measured for this N (nsd compare --cases FILE).\n")
    return "".join(parts)


def main(argv=None) -> None:
    p = argparse.ArgumentParser(description="write IFToMM A02 with N four-bar linkages as a model description")
    p.add_argument("--n", type=int, required=True, help="number of four-bar linkages (the library's: 40)")
    p.add_argument("--out", required=True)
    a = p.parse_args(argv)
    Path(a.out).write_text(description(a.n))


if __name__ == "__main__":
    main()
