"""docs/models.md, "The contract in detail", against the code: every claim there is checked here with
an expectation of its own (a hand formula, a number written in this file or read from the page), never
one the code under test produced, so that the page and the code cannot drift apart unnoticed.

- products of inertia: the tensor convention (the matrix holds +Ixy as written), in all three engines,
  through a free spin's kinetic energy and initial acceleration computed by hand (Euler's equations);
- the engines' default settings: the page's tables equal the builders' defaults, key for key;
- the defaults of every optional field of a description;
- the signs of drive_force and of the law outputs: a held arm's statics by hand;
- the assembly branch: the start closes a four-bar on the branch of the guesses (circle intersection);
- a reference CSV is found next to the file holding the [[case]] table.
"""
from __future__ import annotations

import math
import re
import tomllib
from pathlib import Path

import numpy as np
import pytest

from comparisons.model_cases import load_model_cases
from nsd_core.model.assemble import initial_state
from nsd_core.model.load import load_model, parse_model

ROOT = Path(__file__).resolve().parents[1]
DOC = ROOT / "docs" / "models.md"
ENGINES = ("semirecursive", "mujoco", "exudyn")


def builder(engine: str):
    if engine == "semirecursive":
        from nsd_core.model import semirecursive
        return semirecursive
    if engine == "mujoco":
        from comparisons.builders import mujoco
        return mujoco
    from comparisons.builders import exudyn
    return exudyn


def contract() -> str:
    text = DOC.read_text()
    start = text.index("## The contract in detail")
    return text[start:text.index("\n## ", start + 1)]


# ---- products of inertia ------------------------------------------------------------------------------

SPIN_INERTIA = [2.0, 3.0, 4.0, 0.5, -0.3, 0.2]   # Ixx, Iyy, Izz, Ixy, Ixz, Iyz [kg m^2]
SPIN_RATE = np.array([1.0, 2.0, 0.5])            # rad/s: the spherical joint's rates, = omega at q = 0
SPIN_POINT = np.array([0.1, 0.2, 0.3])           # m, body frame

SPIN = f"""
[[bodies]]
name = "top"
joint = {{ type = "spherical" }}        # at its centre of mass: no gravity, a free spin
mass = 2.0
inertia = {SPIN_INERTIA}
[initial]
velocities = {{ top = {SPIN_RATE.tolist()} }}
[[outputs]]
name = "T"
kind = "energy"
term = "kinetic"
""" + "".join(f"""
[[outputs]]
name = "a{c}"
kind = "point_acceleration"
body = "top"
point = {SPIN_POINT.tolist()}
component = "{c}"
""" for c in "xyz")


def by_hand(convention: str):
    """(kinetic energy, acceleration of SPIN_POINT at t = 0) of the spin, the matrix built from the
    six numbers as docs/models.md says ("tensor": J[0, 1] = +Ixy) or the other way ("engineering")."""
    xx, yy, zz, xy, xz, yz = SPIN_INERTIA
    s = 1.0 if convention == "tensor" else -1.0
    J = np.array([[xx, s * xy, s * xz], [s * xy, yy, s * yz], [s * xz, s * yz, zz]])
    w = SPIN_RATE
    wdot = -np.linalg.solve(J, np.cross(w, J @ w))   # Euler: J w' + w x J w = 0
    return 0.5 * w @ J @ w, np.cross(wdot, SPIN_POINT) + np.cross(w, np.cross(w, SPIN_POINT))


def test_the_conventions_differ_on_the_spin():
    """The spin tells the two conventions apart (else the engine test below would prove nothing), and
    the page quotes its numbers."""
    (T, a), (T_other, a_other) = by_hand("tensor"), by_hand("engineering")
    assert abs(T - T_other) / T > 0.2
    assert np.max(np.abs(a - a_other)) / np.max(np.abs(a)) > 0.05
    text = contract()
    assert f"{T_other:.2f} J of kinetic energy instead of {T:.2f} J" in text
    assert "`inertia = [2, 3, 4, 0.5, -0.3, 0.2]`" in text and "ω = (1, 2, 0.5) rad/s" in text


@pytest.mark.parametrize("engine", ENGINES)
def test_products_of_inertia_follow_the_tensor_convention(engine):
    model = parse_model(tomllib.loads(SPIN))
    run = builder(engine).simulate(model, 0.01, 0.005, {})
    T, a = by_hand("tensor")
    assert run.outputs["T"][0] == pytest.approx(T, rel=1e-12)
    assert run.outputs["T"][-1] == pytest.approx(T, rel=1e-6)    # kept by the spin
    got = np.array([run.outputs[f"a{c}"][0] for c in "xyz"])
    assert np.max(np.abs(got - a)) <= 1e-9 * np.max(np.abs(a)), (got, a)


def test_the_pages_inertia_example_is_the_turned_box():
    """The example of the page (a 1.2 kg box 0.4 x 0.1 x 0.1 m along the body's (1, 1, 0) diagonal) by
    summing point masses: the matrix's entry is -sum(m x y), negative where the mass lies at x y > 0."""
    assert "inertia = [0.0095, 0.0095, 0.017, -0.0075, 0.0, 0.0]" in contract()
    # eight equal point masses at the 2-point Gauss abscissae of each side, +-side / (2 sqrt 3): their
    # second moments are the box's, exactly (the rule integrates cubics exactly)
    half = np.array([0.4, 0.1, 0.1]) / (2.0 * math.sqrt(3.0))
    p = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]) * half
    c = math.sqrt(0.5)
    p = p @ np.array([[c, c, 0.0], [-c, c, 0.0], [0.0, 0.0, 1.0]])   # long side along (1, 1, 0)
    dm = 1.2 / len(p)
    x, y, z = p.T
    J = dm * np.array([[np.sum(y * y + z * z), -np.sum(x * y), -np.sum(x * z)],
                       [-np.sum(x * y), np.sum(x * x + z * z), -np.sum(y * z)],
                       [-np.sum(x * z), -np.sum(y * z), np.sum(x * x + y * y)]])
    given = parse_model(tomllib.loads("""
[[bodies]]
name = "box"
joint = { type = "spherical" }
mass = 1.2
inertia = [0.0095, 0.0095, 0.017, -0.0075, 0.0, 0.0]
[[outputs]]
kind = "coordinate"
joint = "box"
""")).bodies[0].inertia
    assert np.max(np.abs(given - J)) < 1e-15, (given, J)
    assert given[0, 1] < 0


def plate(inertia: str):
    return parse_model(tomllib.loads(f"""
[[bodies]]
name = "plate"
joint = {{ type = "revolute" }}
mass = 1.0
com = [0.5, 0.0, 0.0]
inertia = {inertia}
[model]
gravity = [0.0, -9.81, 0.0]
[[outputs]]
name = "q"
kind = "coordinate"
joint = "plate"
"""))


def test_mujoco_takes_a_thin_plate_turned_in_its_plane():
    """Principal moments on the triangle inequality with products of inertia: MuJoCo's own decomposition of
    the full tensor once refused it; the builder's (principal) runs it, with the plate's exact motion."""
    run = builder("mujoco").simulate(plate("[1.0, 1.0, 2.0, 0.3, 0.0, 0.0]"), 0.2, 0.1, {"timestep": 1e-4})
    exact = builder("semirecursive").simulate(plate("[1.0, 1.0, 2.0, 0.3, 0.0, 0.0]"), 0.2, 0.1,
                                              {"rtol": 1e-12, "atol": 1e-14})
    assert np.allclose(run.outputs["q"], exact.outputs["q"], rtol=1e-8, atol=1e-12)


# ---- the engines' default settings ----------------------------------------------------------------------

def settings_table(engine: str) -> dict:
    """{key: default} of the page's table for ``engine`` (the first `...` of the default cell, as TOML)."""
    text = contract()
    rows = text[text.index(f"**`{engine}`**"):].split("\n\n")[1].splitlines()
    assert rows[0].startswith("| key | default | unit | meaning |"), rows[0]
    out = {}
    for row in rows[2:]:
        cells = [c.strip() for c in row.strip("|").split(" | ")]
        value = re.match(r"`([^`]*)`", cells[1]).group(1)
        out[cells[0].strip("`")] = tomllib.loads(f"v = {value}")["v"]
    return out


def effective_defaults(engine: str) -> dict:
    """The settings a case that names none runs with."""
    if engine == "mujoco":
        from comparisons.builders.mujoco import merged_settings
        return merged_settings({})
    if engine == "exudyn":
        from comparisons.builders.exudyn_solver import check_settings
        return check_settings({}, parse_model(tomllib.loads(SPIN)))
    return dict(builder(engine).default_settings)


@pytest.mark.parametrize("engine", ENGINES)
def test_the_pages_settings_tables_are_the_engines_defaults(engine):
    documented, code = settings_table(engine), effective_defaults(engine)
    assert list(documented) == list(builder(engine).default_settings)   # every key, in the code's order
    assert documented == code


def test_mujocos_solref_factor_follows_the_integrator():
    from comparisons.builders.mujoco import merged_settings
    assert merged_settings({})["solref_factor"] == 4.0
    assert merged_settings({"integrator": "Euler"})["solref_factor"] == 2.0


# ---- defaults of the description's optional fields ------------------------------------------------------

MINIMAL = """
[[bodies]]
name = "a"
joint = { type = "revolute" }
mass = 1.0
[[bodies]]
name = "u"
parent = "a"
joint = { type = "universal" }
mass = 1.0
[[bodies]]
name = "p"
joint = { type = "planar" }
mass = 1.0
[[loops]]
body_a = "u"
body_b = "ground"
[[forces]]
law = "linear_spring_damper"
body_a = "a"
parameters = { stiffness = 1.0, free_length = 0.1 }
[[forces]]
law = "joint_spring_damper"
joint = "p"
parameters = { stiffness = 1.0 }
[[prescribed]]
joint = "a"
motion = "constant_speed"
speed = 1.0
[[prescribed]]
joint = "p"
dof = 2
motion = "harmonic"
amplitude = 0.1
frequency = 1.0
[[outputs]]
kind = "point"
body = "u"
[[outputs]]
kind = "coordinate"
joint = "p"
[excitation]
ground = "harmonic:amplitude=1,frequency=2,duration=1"
"""


def test_omitted_fields_take_the_documented_defaults(tmp_path):
    path = tmp_path / "my_mechanism.toml"
    path.write_text(MINIMAL)
    m = load_model(path)
    assert m.name == "my_mechanism" and m.source == "" and m.gravity == (0.0, 0.0, 0.0)
    a, u, p = m.bodies
    assert a.parent == "ground" and u.parent == "a"
    assert a.joint.position == (0.0, 0.0, 0.0) and a.joint.axis == (0.0, 0.0, 1.0)
    assert u.joint.axis == (0.0, 0.0, 1.0) and u.joint.axis2 == (0.0, 1.0, 0.0)
    assert p.joint.axis == (0.0, 0.0, 1.0)   # the planar joint's normal
    assert a.com == (0.0, 0.0, 0.0) and np.array_equal(a.inertia, np.zeros((3, 3)))   # a point mass
    (lp,) = m.loops
    assert (lp.name, lp.type, lp.point_a, lp.point_b) == ("loop0", "point", (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
    spring, twist = m.forces
    assert spring.name == "force0" and twist.name == "force1"
    assert (spring.body_b, spring.point_a, spring.point_b, spring.direction) == ("ground", (0.0, 0.0, 0.0),
                                                                                (0.0, 0.0, 0.0), None)
    assert spring.given == {"stiffness": 1.0, "free_length": 0.1}
    assert list(spring.parameters) == [1.0, 0.0, 0.1, 0.0]   # damping 0, preload 0 (the law table)
    assert (twist.joint, twist.dof) == ("p", 0) and list(twist.parameters) == [1.0, 0.0, 0.0]
    run, wave = m.prescribed
    assert (run.name, run.dof, run.values) == ("drive0", 0, {"start": 0.0, "speed": 1.0})
    assert wave.name == "drive1" and wave.values["centre"] == 0.0 and wave.values["phase"] == 0.0
    point, coordinate = m.outputs
    assert (point.name, point.point, point.component) == ("output0", (0.0, 0.0, 0.0), 0)   # component x
    assert (coordinate.name, coordinate.dof) == ("output1", 0)
    assert point.tolerance == 1e-3 and point.scale == 0.0
    assert m.initial_coordinates == {} and m.initial_velocities == {} and m.free == ()
    assert m.excitation.kind == "ground_acceleration"
    assert parse_model(tomllib.loads(MINIMAL)).name == "model"   # no file: no file name


def test_coordinates_not_given_start_at_zero():
    """[initial] omitted: every coordinate and rate 0 (a tree, nothing to correct)."""
    st = initial_state(parse_model(tomllib.loads("""
[[bodies]]
name = "a"
joint = { type = "universal" }
mass = 1.0
inertia = [1.0, 1.0, 1.0]
[[outputs]]
kind = "coordinate"
joint = "a"
""")))
    assert st.q == {("a", 0): 0.0, ("a", 1): 0.0} and st.qd == {("a", 0): 0.0, ("a", 1): 0.0}


# ---- signs: drive_force and the laws' values ---------------------------------------------------------

M, G, L = 2.0, 9.81, 0.5                      # kg, m/s^2, m: the arm's mass, gravity, centre of mass
K, H, L0 = 100.0, 0.3, 0.2                    # a spring from the arm's centre to a ground point H above it
KJ, Q0 = 4.0, 0.2                             # a joint spring, neutral at Q0 (the arm held at q = 0)

HELD = f"""
[model]
gravity = [0.0, {-G}, 0.0]
[[bodies]]
name = "arm"
joint = {{ type = "revolute" }}
mass = {M}
com = [{L}, 0.0, 0.0]
inertia = [1e-3, 1e-3, 2e-3]
[[forces]]
name = "spring"
law = "linear_spring_damper"
body_a = "arm"
point_a = [{L}, 0.0, 0.0]
point_b = [{L}, {H}, 0.0]
parameters = {{ stiffness = {K}, free_length = {L0} }}
[[forces]]
name = "twist"
law = "joint_spring_damper"
joint = "arm"
parameters = {{ stiffness = {KJ}, neutral = {Q0} }}
[[prescribed]]
name = "hold"
joint = "arm"
motion = "constant_speed"
speed = 0.0
[[outputs]]
name = "tau"
kind = "drive_force"
element = "hold"
[[outputs]]
name = "T"
kind = "force"
element = "spring"
[[outputs]]
name = "Q"
kind = "force"
element = "twist"
"""


@pytest.mark.parametrize("engine", ENGINES)
def test_the_drive_holds_the_weight_with_a_positive_torque(engine):
    """The page's example: the arm held horizontal, q = 0, gravity along -y. Statics about the pivot,
    by hand: gravity turns it by -M G L about z; the stretched spring (L = H > L0) pulls its end up,
    +T L; the joint spring, below its neutral, pushes q up, +KJ Q0. The drive holds the rest:
    tau = M G L - T L - KJ Q0, positive (it drives q up)."""
    run = builder(engine).simulate(parse_model(tomllib.loads(HELD)), 0.01, 0.005, {})
    T, Q = K * (H - L0), KJ * Q0
    assert np.allclose(run.outputs["T"], T, rtol=1e-12) and T > 0        # tension: pulls the points together
    assert np.allclose(run.outputs["Q"], Q, rtol=1e-12) and Q > 0        # drives q up, toward the neutral
    tau = M * G * L - T * L - Q
    assert tau > 0
    assert np.allclose(run.outputs["tau"], tau, rtol=1e-9, atol=1e-9 * M * G * L), run.outputs["tau"]


@pytest.mark.parametrize("engine", ENGINES)
def test_a_slide_drive_pushes_along_its_axis(engine):
    """A slide along (0.6, 0.8, 0) held at q = 0.1 m: gravity's force on q is -M G 0.8; the drive's +M G 0.8."""
    model = parse_model(tomllib.loads(f"""
[model]
gravity = [0.0, {-G}, 0.0]
[[bodies]]
name = "slider"
joint = {{ type = "prismatic", axis = [0.6, 0.8, 0.0] }}
mass = {M}
[[prescribed]]
name = "hold"
joint = "slider"
motion = "constant_speed"
start = 0.1
speed = 0.0
[[outputs]]
name = "tau"
kind = "drive_force"
element = "hold"
"""))
    run = builder(engine).simulate(model, 0.01, 0.005, {})
    assert np.allclose(run.outputs["tau"], M * G * 0.8, rtol=1e-9)


def test_the_page_quotes_the_held_arms_torque():
    text = contract()
    assert f"`drive_force = +m g l = +{M * G * L:.2f} N m`" in text
    assert "motion = \"constant_speed\"     # start = 0 by default" in text


# ---- the assembly branch --------------------------------------------------------------------------------

def fourbar(coupler: float, rocker: float):
    text = (ROOT / "models" / "fourbar_spring.toml").read_text().split("[initial]")[0]
    text += (f"\n[initial]\ncoordinates = {{ crank = {math.pi / 3!r}, coupler = {coupler}, rocker = {rocker} }}\n"
             'free = ["crank"]\n[[outputs]]\nname = "crank_angle"\nkind = "coordinate"\njoint = "crank"\n')
    q = initial_state(parse_model(tomllib.loads(text))).q
    return q[("crank", 0)], q[("coupler", 0)], q[("rocker", 0)]


def closures():
    """Both positions of C for the crank at 60 deg (A = 0, D = (0.3, 0); AB 0.1, BC 0.25, DC 0.2 m):
    the circles about B and D meet at two points; (coupler angle relative to the crank, rocker angle)
    of the one above AD, then of the one below."""
    B, D = 0.1 * np.array([math.cos(math.pi / 3), math.sin(math.pi / 3)]), np.array([0.3, 0.0])
    d = np.linalg.norm(D - B)
    along = (0.25 ** 2 - 0.2 ** 2 + d * d) / (2 * d)
    across = math.sqrt(0.25 ** 2 - along ** 2)
    e = (D - B) / d
    n = np.array([-e[1], e[0]])
    out = []
    for C in (B + along * e + across * n, B + along * e - across * n):
        coupler = math.atan2(C[1] - B[1], C[0] - B[0]) - math.pi / 3
        out.append((C[1], coupler, math.atan2(C[1] - D[1], C[0] - D[0])))
    return out


def test_the_guesses_pick_the_four_bars_branch():
    (up_y, up_coupler, up_rocker), (down_y, down_coupler, down_rocker) = closures()
    assert up_y > 0 > down_y
    text = contract()
    for (coupler, rocker), (want_coupler, want_rocker) in (((-0.9, 1.6), (up_coupler, up_rocker)),
                                                           ((-1.5, -1.2), (down_coupler, down_rocker))):
        crank, got_coupler, got_rocker = fourbar(coupler, rocker)
        assert crank == math.pi / 3   # free: kept as given
        assert got_coupler == pytest.approx(want_coupler, abs=1e-9)
        assert got_rocker == pytest.approx(want_rocker, abs=1e-9)
        # the page's line for that branch
        assert (f"coupler = {coupler}, rocker = {rocker} }}" in text and
                f"(coupler {want_coupler:.4f}, rocker {want_rocker:.4f})" in text)


# ---- where a reference file is found ----------------------------------------------------------------------

def test_a_reference_is_found_next_to_the_file_holding_the_case(tmp_path, monkeypatch):
    model_dir, cases_dir, elsewhere = tmp_path / "model", tmp_path / "runs", tmp_path / "elsewhere"
    for d in (model_dir, cases_dir, elsewhere):
        d.mkdir()
    case = '[[case]]\nname = "c"\nduration = 0.02\ndt_out = 0.01\nreference = { file = "ref.csv" }\n'
    body = ('[[bodies]]\nname = "arm"\njoint = { type = "revolute" }\nmass = 1.0\n'
            '[[outputs]]\nname = "q"\nkind = "coordinate"\njoint = "arm"\n')
    (model_dir / "m.toml").write_text(body + case)
    (cases_dir / "cases.toml").write_text(case)
    for d, value in ((model_dir, 1.0), (cases_dir, 2.0), (elsewhere, 3.0)):   # the same name in three folders
        (d / "ref.csv").write_text(f"t,q\n0.0,{value}\n0.01,{value}\n")
    monkeypatch.chdir(elsewhere)   # never the working directory
    model = load_model(model_dir / "m.toml")
    (with_cases,) = load_model_cases(model, str(cases_dir / "cases.toml"), ENGINES)
    (without,) = load_model_cases(model, None, ENGINES)
    assert Path(with_cases.reference.path) == cases_dir / "ref.csv"
    assert list(with_cases.reference.columns["q"]) == [2.0, 2.0]
    assert Path(without.reference.path) == model_dir / "ref.csv"
    assert list(without.reference.columns["q"]) == [1.0, 1.0]
    assert without.reference.accuracy == 0.0 and without.reference.source == ""   # the defaults
