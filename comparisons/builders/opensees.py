"""The OpenSees builder: the isolated structure on a baseline isolator (a lead-rubber bearing or a friction
pendulum, nsd_core.structure.isolators), and the shear building on its slab when there is one
(nsd_core.structure.building), built in OpenSees (openseespy) with OpenSees's own bearing elements, from
the structure's own numbers (Structure, Isolator, Building: nothing typed twice).

The model (3-D, 6 dof per node; X, Y horizontal, Z vertical):
- node 1, the ground: fixed; the ground acceleration enters as UniformExcitation in X and Y (each a
  Path series of a_g at the step times, so every Newmark step sees the motion's exact value);
- node 2, the plate: the isolated mass M in X and Y, the polar inertia M r_g^2 about Z; its Z and its
  tilts held;
- the isolator between them, a zero-length element whose local x is the vertical and local y, z are
  X, Y (its shear forces are the plate's push on the isolator, the in-house run's support_F):
  * ``bouc-wen``: elastomericBearingBoucWen (ElastomericBearingBoucWen3d, A. Schellenberg): the
    bidirectional Park-Wen-Ang law F = k2 u + qYield z, u_y z' = A u' - |z|^(eta-2) (z.u')(gamma +
    beta sgn(z.u')) z, with A = 1, beta = gamma = 1/2 and eta = the project's n: term for term
    nsd_core.structure.isolator_laws' law (H(z.u') = gamma + beta sgn(z.u')), integrated by OpenSees's
    own backward-Euler Newton iteration on each step's displacement increment. k2 = k_d, qYield = Q,
    u_y = D_y: Kinit = Q / D_y + k_d, alpha1 = k_d / Kinit, qd = Q (u_y = qd / ((1 - alpha1) Kinit));
  * ``single-fp``: singleFPBearing (SingleFPSimple3d) with a Coulomb friction model: OpenSees's own
    friction pendulum, rigid-plastic friction with an elastic pre-slip stiffness (return mapping on a
    circular surface: the limit n -> infinity of the law above), the spherical surface's radius
    R = N / k_d and the restoring force N / sqrt(R^2 - u^2) u, N the axial force (the weight
    N = M g, applied first, plus the shear's own component along the surface's normal):
    mu = Q / N, kInit = Q / D_y + k_d. Its law differs from ours by construction (docs/seismic.md);
  * ``plasticity``: elastomericBearingPlasticity, the lead-rubber bearing as coupled bilinear
    plasticity on a circular surface (the same constants as ``bouc-wen``; n -> infinity);
  * the torsional pair k_d r_b^2, c r_b^2 about Z as the element's torsion material;
- a building: floor i a node with m_i in X and Y (nothing else free); story i a zeroLength of an
  Elastic material (k_i, damping tangent c_i) per direction between floors i-1 and i (floor 0 the
  plate); the Rayleigh mass part b_i a zeroLength of a damper (Elastic, E = 0, eta = b_i) between
  floor i and the slab: the project's damping form, not OpenSees's ``rayleigh`` (whose mass part acts
  on velocities relative to the ground; ``building_damping = "rayleigh"`` runs that for comparison).

Integration: Newmark's average acceleration (gamma = 1/2, beta = 1/4: second order, no numerical
damping), full Newton on the displacement increment to ``tolerance`` [m], at a fixed step that divides
the output interval. The hysteretic state's backward Euler is first order in the step, so the error
estimate assumes order 1 (comparisons.estimate).
"""
from __future__ import annotations

import ctypes
import importlib
import importlib.util
import math
import os
import time

import numpy as np

from comparisons.engines.base import EngineError
from nsd_core.device.params import ParameterError

# the shared libraries openseespylinux bundles, in the order their dependencies need them
_BUNDLED = ("libquadmath.so.0", "libgfortran.so.4", "libblas.so.3", "liblapack.so.3", "libgomp.so.1")
_OPS = None
ELEMENTS = ("bouc-wen", "plasticity", "single-fp")
DAMPING_FORMS = ("slab", "rayleigh")
DEFAULT_SETTINGS = {"step": 1e-4, "element": "bouc-wen", "tolerance": 1e-12, "max_iterations": 50,
                    "building_damping": "slab"}
SYSTEM = "UmfPack"
STEPS_MAX = 20_000_000   # one run's Newmark steps (about 5 us each)


def opensees():
    """openseespy's module. Its import needs the libraries openseespylinux bundles loaded first (global
    symbols), and the package cannot be imported to find them: they are found from its spec."""
    global _OPS
    if _OPS is None:
        spec = importlib.util.find_spec("openseespylinux")
        if spec is None or spec.origin is None:
            raise ParameterError("engine opensees: openseespy is not installed (pip install 'nsd[opensees]')")
        folder = os.path.join(os.path.dirname(spec.origin), "lib")
        present = sorted(f for f in os.listdir(folder) if ".so" in f) if os.path.isdir(folder) else []
        # the known ones in their dependencies' order, then any other a later build bundles
        for name in [n for n in _BUNDLED if n in present] + [n for n in present if n not in _BUNDLED]:
            ctypes.CDLL(os.path.join(folder, name), mode=ctypes.RTLD_GLOBAL)
        _OPS = importlib.import_module("openseespy.opensees")
    return _OPS


def merged_settings(settings: dict | None) -> dict:
    """The defaults updated by ``settings``; an unknown key or a bad value is one line."""
    s = {**DEFAULT_SETTINGS}
    for key, value in (settings or {}).items():
        if key not in DEFAULT_SETTINGS:
            raise ParameterError(f"opensees.{key}: unknown setting; allowed: {', '.join(DEFAULT_SETTINGS)}")
        s[key] = value
    for key in ("step", "tolerance"):
        if not (isinstance(s[key], (int, float)) and math.isfinite(s[key]) and s[key] > 0):
            raise ParameterError(f"opensees.{key} = {s[key]!r}: must be a finite number > 0")
    for key, allowed in (("element", ELEMENTS), ("building_damping", DAMPING_FORMS)):
        if s[key] not in allowed:
            raise ParameterError(f"opensees.{key} = {s[key]!r}: allowed: {', '.join(allowed)}")
    if not (isinstance(s["max_iterations"], int) and s["max_iterations"] >= 1):
        raise ParameterError(f"opensees.max_iterations = {s['max_iterations']!r}: must be an integer >= 1")
    return s


def bearing_constants(iso) -> dict:
    """elastomericBearingBoucWen's constants from the isolator: k2 = k_d, qYield = Q, u_y = D_y."""
    k_init = iso.q_fast / iso.yield_displacement + iso.stiffness
    return {"Kinit": k_init, "qd": iso.q_fast, "alpha1": iso.stiffness / k_init,
            "alpha2": 0.0, "mu": 2.0, "eta": float(iso.exponent), "beta": 0.5, "gamma": 0.5}


def friction_constants(iso, mass: float, g: float = 9.80665) -> dict:
    """singleFPBearing's constants from the isolator: the axial force N = M g, mu = Q / N, R = N / k_d,
    kInit = Q / D_y + k_d (the pre-slip stiffness Q / D_y beside the pendulum's k_d)."""
    N = mass * g
    return {"N": N, "mu": iso.q_fast / N, "R": N / iso.stiffness,
            "kInit": iso.q_fast / iso.yield_displacement + iso.stiffness}


def _check(structure) -> None:
    iso = structure.isolator
    if iso is None:
        raise ParameterError("engine opensees: builds the structure on a baseline isolator (--isolator bilinear or "
                             "friction-pendulum) only; it cannot build the negative-stiffness device")
    if structure.restrainer is not None:
        raise ParameterError("engine opensees: the displacement restrainer is not built in OpenSees; leave out "
                             "--restrainer")
    if iso.rate != 0.0 and iso.q_slow != iso.q_fast:
        raise ParameterError("engine opensees: a velocity-dependent friction coefficient is not built; the "
                             "isolator's q_slow must equal q_fast")


def _bearing(ops, structure, s: dict) -> str:
    """The isolator between nodes 1 (ground) and 2 (plate) as element 1; returns the element's kind."""
    iso, r2 = structure.isolator, structure.support_radius ** 2
    ops.uniaxialMaterial("Elastic", 1, 1e12)                                   # axial: rigid
    ops.uniaxialMaterial("Elastic", 2, iso.stiffness * r2, iso.damping * r2)   # torsion: k_d r_b^2, c r_b^2
    ops.uniaxialMaterial("Elastic", 3, 1e12)                                   # tilts: held anyway
    mats = ["-P", 1, "-T", 2, "-My", 3, "-Mz", 3]
    orient = ["-orient", 0.0, 0.0, 1.0, 1.0, 0.0, 0.0]
    if s["element"] == "single-fp":
        c = friction_constants(iso, structure.mass)
        ops.frictionModel("Coulomb", 1, c["mu"])
        ops.element("singleFPBearing", 1, 1, 2, 1, c["R"], c["kInit"], *mats, *orient, "-iter", 100, 1e-12)
        return "singleFPBearing"
    c = bearing_constants(iso)
    if s["element"] == "plasticity":
        ops.element("elastomericBearingPlasticity", 1, 1, 2, c["Kinit"], c["qd"], c["alpha1"], c["alpha2"], c["mu"],
                    *mats, *orient)
        return "elastomericBearingPlasticity"
    ops.element("elastomericBearingBoucWen", 1, 1, 2, c["Kinit"], c["qd"], c["alpha1"], c["alpha2"], c["mu"],
                c["eta"], c["beta"], c["gamma"], *mats, *orient)
    return "elastomericBearingBoucWen"


def _building(ops, b, s: dict) -> None:
    """Floors 3..N+2 on the plate (node 2): stories and floor-slab dampers (module docstring)."""
    tag = 10
    for i in range(b.stories):
        node, below = 3 + i, 2 + i
        ops.node(node, 0.0, 0.0, 0.0)
        ops.fix(node, 0, 0, 1, 1, 1, 1)
        ops.mass(node, b.masses[i], b.masses[i], 0.0, 0.0, 0.0, 0.0)
        c = 0.0 if s["building_damping"] == "rayleigh" else b.story_damping[i]
        ops.uniaxialMaterial("Elastic", tag, b.stiffnesses[i], c)
        rayleigh = ["-doRayleigh", 1] if s["building_damping"] == "rayleigh" else []
        ops.element("zeroLength", 100 + i, below, node, "-mat", tag, tag, "-dir", 1, 2, *rayleigh)
        if s["building_damping"] == "slab" and b.slab_damping[i] > 0:
            ops.uniaxialMaterial("Elastic", tag + 1, 0.0, b.slab_damping[i])
            ops.element("zeroLength", 200 + i, 2, node, "-mat", tag + 1, tag + 1, "-dir", 1, 2)
        tag += 2
    if s["building_damping"] == "rayleigh":   # OpenSees's own: C = a_0 M + a_1 K on the floors (ground-relative)
        a0, a1 = b.rayleigh
        ops.region(1, "-ele", *[100 + i for i in range(b.stories)], "-rayleigh", 0.0, a1, 0.0, 0.0)
        ops.region(2, "-node", *[3 + i for i in range(b.stories)], "-rayleigh", a0, 0.0, 0.0, 0.0)


def build(ops, structure, ground, h: float, n_steps: int, s: dict) -> str:
    """The whole model, its gravity (the friction pendulum's axial force) and the ground excitation."""
    ops.wipe()
    ops.model("basic", "-ndm", 3, "-ndf", 6)
    ops.node(1, 0.0, 0.0, 0.0)
    ops.fix(1, 1, 1, 1, 1, 1, 1)
    ops.node(2, 0.0, 0.0, 0.0)
    element = _bearing(ops, structure, s)
    if element == "singleFPBearing":   # the weight on the slider: Z free, loaded statically first
        ops.fix(2, 0, 0, 0, 1, 1, 0)
    else:
        ops.fix(2, 0, 0, 1, 1, 1, 0)
    M = structure.mass
    ops.mass(2, M, M, 0.0, 0.0, 0.0, structure.polar_inertia)
    if structure.building is not None:
        _building(ops, structure.building, s)
    if element == "singleFPBearing":
        ops.timeSeries("Constant", 1)
        ops.pattern("Plain", 1, 1)
        ops.load(2, 0.0, 0.0, -friction_constants(structure.isolator, M)["N"], 0.0, 0.0, 0.0)
        _static(ops)
    t = np.arange(n_steps + 2) * h   # one value past the end: the last step's time must lie inside the series
    _, _, a = ground(t)
    nodes = [2] + [3 + i for i in range(structure.building.stories if structure.building is not None else 0)]
    for k, direction in ((0, 1), (1, 2)):
        ops.timeSeries("Path", 10 + direction, "-dt", h, "-values", *a[:, k].tolist())
        ops.pattern("UniformExcitation", 10 + direction, direction, "-accel", 10 + direction)
        for n in nodes:   # Newmark's start: the acceleration consistent with rest (no force: -a_g(0))
            ops.setNodeAccel(n, direction, -float(a[0, k]), "-commit")
    return element


def _static(ops) -> None:
    """The weight applied in one static step, held constant after it (time reset to 0)."""
    ops.system(SYSTEM)
    ops.numberer("Plain")
    ops.constraints("Plain")
    ops.test("NormDispIncr", 1e-14, 50)
    ops.algorithm("Newton")
    ops.integrator("LoadControl", 1.0)
    ops.analysis("Static")
    if ops.analyze(1) != 0:
        raise EngineError("opensees: the static step applying the weight did not converge")
    ops.loadConst("-time", 0.0)
    ops.wipeAnalysis()


def _transient(ops, s: dict) -> None:
    ops.system(SYSTEM)
    ops.numberer("Plain")
    ops.constraints("Plain")
    ops.test("NormDispIncr", float(s["tolerance"]), int(s["max_iterations"]))
    ops.algorithm("Newton")
    ops.integrator("Newmark", 0.5, 0.25)
    ops.analysis("Transient")


def _sample(ops, stories: int, element: str) -> list[float]:
    """One output row: plate (u, v, relative a, theta), the bearing's shear forces and state, floors."""
    row = [ops.nodeDisp(2, 1), ops.nodeDisp(2, 2), ops.nodeDisp(2, 6), ops.nodeVel(2, 1), ops.nodeVel(2, 2),
           ops.nodeAccel(2, 1), ops.nodeAccel(2, 2)]
    q = ops.eleResponse(1, "basicForce")
    row += [q[1], q[2]]
    row += list(ops.eleResponse(1, "z")[:2]) if element == "elastomericBearingBoucWen" else [math.nan, math.nan]
    for i in range(stories):
        n = 3 + i
        row += [ops.nodeDisp(n, 1), ops.nodeDisp(n, 2), ops.nodeVel(n, 1), ops.nodeVel(n, 2), ops.nodeAccel(n, 1),
                ops.nodeAccel(n, 2)]
    return row


def simulate(structure, ground, t_out: np.ndarray, settings: dict | None = None) -> tuple[np.ndarray, dict]:
    """Run the model on the output times ``t_out`` (equal intervals from 0): (rows, stats). Each row is
    ``_sample``'s, the accelerations relative to the ground."""
    s = merged_settings(settings)
    _check(structure)
    dt = float(t_out[1] - t_out[0])
    n_sub = max(1, math.ceil(dt / float(s["step"]) - 1e-9))
    h = dt / n_sub
    n_steps = n_sub * (len(t_out) - 1)
    if n_steps > STEPS_MAX:
        raise ParameterError(f"engine opensees: {n_steps} steps of {h:.3g} s; at most {STEPS_MAX} a run")
    ops = opensees()
    start = time.perf_counter()
    element = build(ops, structure, ground, h, n_steps, s)
    _transient(ops, s)
    stories = structure.building.stories if structure.building is not None else 0
    rows = [_sample(ops, stories, element)]
    for k in range(1, len(t_out)):
        if ops.analyze(n_sub, h) != 0:   # the solver's failure on this run (exit 3), not bad input
            ops.wipe()
            raise EngineError(f"opensees: Newton did not converge in the step ending near t = "
                                 f"{t_out[k]:.6g} s (tolerance {s['tolerance']:g} m, {s['max_iterations']} iterations)")
        rows.append(_sample(ops, stories, element))
    ops.wipe()
    stats = {"engine": "opensees", "element": element, "step": h, "steps": n_steps, "integrator": "Newmark 1/2, 1/4",
             "wall_time": time.perf_counter() - start, "settings": s,
             "opensees_version": ops.version() if hasattr(ops, "version") else None}
    return np.asarray(rows, dtype=float), stats
