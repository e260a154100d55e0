"""The baseline isolators and the design basis (docs/design.md).

Every expected number here is computed in the test from closed forms or by an independent method
(quadrature and root finding, scipy's integrator), never by the code under test: the bilinear loop's
energy per cycle, the friction pendulum's free-vibration decay of 4 mu R per cycle, the design
displacement of ASCE 7 Eq. 17.5-1, the lead-rubber sizing's effective period and damping; the peers
(the isolator's description built by MuJoCo and Exudyn) against the in-house engine on a short
record; bad input for the new options.
"""
import math

import numpy as np
import pytest
from scipy.integrate import quad, solve_ivp
from scipy.optimize import brentq

from nsd_cli.main import main
from nsd_core.structure.isolator_laws import hysteretic_force_scalar
from nsd_core.structure.isolators import Isolator, sized
from nsd_core.device.params import Params

G = 9.80665


def _loop_energy(Q, D_y, n, D, cycles=3, points=4001):
    """The last cycle's area of Q z du under u = D sin(2 pi t), z from the law integrated by scipy."""
    def rhs(t, z):
        v = 2 * math.pi * D * math.cos(2 * math.pi * t)
        return list(hysteretic_force_scalar(v, 0.0, z[0], z[1], Q, Q, 0.0, D_y, n)[2:4])
    t = np.linspace(cycles - 1, cycles, points)
    sol = solve_ivp(rhs, (0, cycles), [0.0, 0.0], t_eval=t, rtol=1e-11, atol=1e-13, max_step=1e-3)
    u = D * np.sin(2 * math.pi * sol.t)
    return float(np.trapezoid(Q * sol.y[0], u))


def _exact_loop_energy(Q, D_y, n, D):
    """The steady loop's area by quadrature, area = 2 Q int z du over the ascending branch: elastic
    from -z_m to 0 (z' = u'/D_y), then du = D_y dz / (1 - z^n) up to z_m, the branch 2 D long.
    n = 2 in closed form; where z_m is 1 to machine precision (D >> D_y, n large: 1 - z_m ~ exp(-n (2 D - D_y) / D_y)),
    int z du = length - int (1 - z) du with the convergent D_y int_0^1 dz / (1 + z + ... + z^(n-1))."""
    if n == 2:   # closed form: int dz/(1 - z^2) = atanh z, int z dz/(1 - z^2) = -ln(1 - z^2)/2
        zm = brentq(lambda z: z + math.atanh(z) - 2 * D / D_y, 1e-9, 1 - 1e-16, xtol=1e-16)
        return 2 * Q * D_y * (-zm * zm / 2 - 0.5 * math.log1p(-zm * zm))
    assert n * (2 * D - D_y) / D_y > 100, "z_m = 1 to machine precision"
    inner = D_y * quad(lambda z: 1.0 / sum(z ** k for k in range(int(n))), 0.0, 1.0)[0]
    return 2 * Q * (-D_y / 2 + (2 * D - D_y) - inner)


@pytest.mark.parametrize("n,D", [(2.0, 3.9e-3), (10.0, 13.0e-3)])   # n = 2: D = 3 D_y keeps 1 - z_m resolvable
def test_bilinear_loop_energy_per_cycle_matches_quadrature_and_the_ideal_bilinear(n, D):
    Q, D_y = 675.0, 1.3e-3
    got = _loop_energy(Q, D_y, n, D)
    assert got == pytest.approx(_exact_loop_energy(Q, D_y, n, D), rel=1e-5)
    ideal = 4 * Q * (D - D_y)   # the ideal bilinear loop (closed form)
    if n == 10.0:   # the design's exponent: the smooth corner costs under 2 % of the ideal loop
        assert got == pytest.approx(ideal, rel=0.02)
    assert got < ideal   # a smooth corner lies inside the ideal one


def test_unloading_is_elastic_with_the_initial_stiffness():
    # z . v < 0: z' = v / D_y exactly, whatever |z|
    _, _, dzx, dzy, _ = hysteretic_force_scalar(-0.3, 0.1, 0.9, -0.2, 1.0, 1.0, 0.0, 2e-3, 10.0)
    assert (dzx, dzy) == pytest.approx((-0.3 / 2e-3, 0.1 / 2e-3), rel=1e-15)


def test_friction_pendulum_free_vibration_loses_4_mu_R_per_cycle():
    from comparisons.seismic import parse_ground
    from nsd_core.structure.isolation import designed_structure
    from nsd_core.structure.seismic import simulate_seismic
    s = designed_structure()
    W = s.mass * 9.81
    R, mu = 0.25, 0.01
    iso = Isolator("friction-pendulum", W / R, 0.0, mu * W, mu * W, 0.0, 2e-5, 2.0)
    ground = parse_ground("harmonic:amplitude=3,frequency=1,azimuth=0,duration=1", "--ground")
    r = simulate_seismic(Params(), s.with_isolator(iso), ground, duration=6.0, dt_out=2e-4, device=False)
    t, x = r["t"], r["x"]
    free = t > 1.2
    i = np.flatnonzero(free[1:-1] & (x[1:-1] > x[:-2]) & (x[1:-1] >= x[2:]) & (x[1:-1] > 4 * mu * R)) + 1
    assert len(i) >= 2, "at least two positive peaks in free vibration"
    drops = -np.diff(x[i])
    assert drops == pytest.approx(4 * mu * R, rel=0.02)
    period = np.diff(t[i])
    assert period == pytest.approx(2 * math.pi * math.sqrt(R / 9.81), rel=0.02)   # the pendulum's period


def test_the_lead_rubber_sizing_matches_the_design_period_and_damping():
    from nsd_core.structure.isolation import designed_structure
    s = designed_structure(True)
    iso = sized("bilinear", s.mass)
    T_model, beta = 2 * math.pi * math.sqrt(3743.7968184920674 / 147799.17422629456), 0.20   # model scale
    D = 0.1 * G * 0.25 * (T_model / math.sqrt(0.1)) / (4 * math.pi ** 2 * 1.5)   # Eq. 17.5-1, B(20 %) = 1.5
    k_eff = iso.stiffness + iso.q_fast / D
    assert 2 * math.pi * math.sqrt(s.mass / k_eff) == pytest.approx(T_model, rel=1e-12)
    assert 4 * iso.q_fast * (D - iso.yield_displacement) / (2 * math.pi * k_eff * D * D) == pytest.approx(beta, rel=1e-12)
    assert iso.yield_displacement == pytest.approx(0.1 * D, rel=1e-12)


def test_design_displacement_and_stroke_margin():
    from nsd_core.structure.design import damping_coefficient, design
    d = design()
    T = 2 * math.pi * math.sqrt(3743.7968184920674e3 / 1.4779917422629456e7)
    assert d["D_D_m"] == pytest.approx(G * 0.25 * T / (4 * math.pi ** 2 * 1.5), rel=1e-12)
    assert d["D_D_model_m"] * 1.5 < 0.02546109338901315   # inside X_max with margin 1.5
    assert damping_coefficient(0.15) == pytest.approx(1.35) and damping_coefficient(0.01) == 0.8
    assert damping_coefficient(0.6) == 2.0


def test_a_device_variant_leaves_the_designed_structure_unchanged():
    from nsd_core.structure.isolation import designed_structure_with
    a = designed_structure_with(Params(), {})
    b = designed_structure_with(Params(n_wires=8), {})
    assert (a.mass, a.stiffness, a.damping) == (b.mass, b.stiffness, b.damping)
    assert a.mass == pytest.approx(3743.7968184920674)   # the nominal rule's value, 1e-3 of the full scale's


@pytest.mark.parametrize("engine", ["mujoco", "exudyn"])
@pytest.mark.parametrize("kind", ["bilinear", "friction-pendulum"])
def test_the_peers_agree_with_the_in_house_engine_on_a_short_record(kind, engine):
    """Each peer builds the isolator's description (the registry's plane law, the real engines)."""
    from comparisons.engines.described_isolator import isolator_metrics, run_isolator
    from nsd_core.structure.isolation import designed_structure
    from nsd_core.ground.records import SIMILITUDE_TIME_FACTOR, fema_record
    from nsd_core.structure.seismic import simulate_seismic
    s = designed_structure(True)
    st = s.with_isolator(sized(kind, s.mass))
    g = fema_record("nearfield-pulse", "1", scale=0.6, time_factor=SIMILITUDE_TIME_FACTOR, window=[2, 5])
    ref = simulate_seismic(Params(), st, g, device=False)
    other = run_isolator(engine, st, g)
    m = isolator_metrics(ref, other)
    assert ref["u"].max() > 2 * st.isolator.yield_displacement   # the isolator yielded: the law was exercised
    assert other.stats["model"] == "described" and other.stats["engine"] == engine
    assert m["du"] < 1e-4 and m["dF"] < 1e-3 and m["da"] < 1e-3, m


def test_nsd_seismic_cross_checks_a_baseline_in_mujoco_and_exudyn(tmp_path):
    """The command's peers on the isolator's description: each one's CSV and metrics in summary.json."""
    import json
    out = tmp_path / "out"
    code = main(["seismic", "--record", "nearfield-pulse:1", "--window", "2,5", "--scale", "0.6", "--isolator",
                 "friction-pendulum", "--engines", "semirecursive,mujoco,exudyn", "--out", str(out)])
    assert code == 0
    engines = json.loads((out / "summary.json").read_text())["engines"]
    assert set(engines) == {"mujoco", "exudyn"}
    for name, m in engines.items():
        assert (out / f"seismic_{name}.csv").exists()
        assert m["du"] < 1e-4 and m["dF"] < 1e-3 and m["da"] < 1e-3, (name, m)


@pytest.mark.parametrize("argv,fragment", [
    (["--record", "nearfield-pulse:1", "--isolator", "rubber"], "--isolator"),
    (["--ground", "harmonic:amplitude=1,frequency=2,duration=0.05", "--design-level"], "--design-level"),
    (["--record", "nearfield-pulse:1", "--design-level", "--scale", "2"], "--scale"),
    (["--record", "nearfield-pulse:1", "--isolator", "bilinear", "--no-device"], "--no-device"),
    (["--record", "nearfield-pulse:1", "--isolator", "bilinear", "--restrainer", "--engines", "semirecursive,mujoco"],
     "--engines"),
])
def test_bad_isolator_and_design_options_are_one_line_exit_2_nothing_written(tmp_path, capsys, argv, fragment):
    out = tmp_path / "out"
    try:
        code = main(["seismic", *argv, "--out", str(out)])
    except SystemExit as e:
        code = e.code
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and fragment in err[0], err
    assert not out.exists()
