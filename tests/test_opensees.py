"""OpenSees (openseespy, its own bearing elements) as a peer of the in-house engine on the baseline
isolators and the building above them (docs/seismic.md, "OpenSees as a peer").

The verdicts are the gate's rule (comparisons.verdict): OpenSees's difference from the in-house
converged reference against 3 x its own error estimate (its runs at h and h/2) and the engineering
tolerance. Nothing expected here comes from the code under test: the mapping of the isolator's
constants onto the element's is checked against the element's own definitions (OpenSees's
ElastomericBearingBoucWen3d: k0 = (1 - alpha1) Kinit, k2 = alpha1 Kinit, u_y = qd / k0), and one test
shows the rule fails when the law differs (OpenSees's friction pendulum element, rigid-plastic friction,
against the project's smooth n = 2 law).
"""
import json
import math

import numpy as np
import pytest

from comparisons.builders.opensees import bearing_constants, friction_constants, merged_settings, opensees
from comparisons.engines.opensees_peer import judge
from nsd_cli.main import main
from nsd_core.ground.records import fema_record
from nsd_core.structure.isolation import designed_structure
from nsd_core.structure.isolators import sized
from nsd_core.device.params import ParameterError, Params


def _structure(kind: str, building: bool = False):
    st = designed_structure(True)
    st = st.with_isolator(sized(kind, st.mass))
    if building:
        from nsd_core.structure.building import building_from
        st = st.with_building(building_from(st.mass, {"stories": 3}))
    return st


def test_openseespy_loads_and_the_constants_map_onto_the_elements():
    """The loader imports openseespy (its bundled libraries first); the element's own definitions give
    back the isolator's k_d, Q and D_y, and the friction pendulum's mu N = Q, N / R = k_d."""
    assert opensees().version().startswith("3.7")
    for kind in ("bilinear", "friction-pendulum"):
        iso = sized(kind, designed_structure(True).mass)
        c = bearing_constants(iso)
        k0, k2 = (1 - c["alpha1"]) * c["Kinit"], c["alpha1"] * c["Kinit"]
        assert k2 == pytest.approx(iso.stiffness, rel=1e-14)
        assert c["qd"] / k0 == pytest.approx(iso.yield_displacement, rel=1e-14)
        assert c["qd"] == iso.q_fast and c["eta"] == iso.exponent and c["beta"] == c["gamma"] == 0.5
        f = friction_constants(iso, 3743.8)
        assert f["mu"] * f["N"] == pytest.approx(iso.q_fast, rel=1e-14)
        assert f["N"] / f["R"] == pytest.approx(iso.stiffness, rel=1e-14)
    with pytest.raises(ParameterError, match="opensees.element"):
        merged_settings({"element": "rubber"})


def test_lead_rubber_bearing_and_building_agree_by_the_rule_on_a_short_window():
    """The default run's check (a few seconds): the lead-rubber bearing with the default 3-story building,
    0.3 model s of near-field pulse 1: consistent and accurate enough, the bearing yielded."""
    st = _structure("bilinear", building=True)
    g = fema_record("nearfield-pulse", 1, scale=0.6, window=(2.0, 3.0))
    j = judge(Params(), st, g)
    ref = j["runs"]["converged"]
    assert float(np.max(np.hypot(ref["x"], ref["y"]))) > st.isolator.yield_displacement / 2
    v = j["verdict"]
    assert v["pass"], v["text"]
    assert {"max_dfloor_rel", "max_ddrift_rel", "max_dfloor_a_rel"} <= set(j["values"])
    # OpenSees's error falls with its step: the h/2 run is nearer the reference than the h run
    h2 = j["runs"]["h2"]
    from comparisons.engines.opensees_peer import gate_values
    assert gate_values(ref, h2)["max_du_rel"] < j["values"]["max_du_rel"]


@pytest.mark.parametrize("argv", [
    ["--isolator", "device"],
    ["--isolator", "linear"],
    ["--isolator", "bilinear", "--compare-supports"],
])
def test_opensees_refuses_what_it_cannot_build_in_one_line_exit_2(tmp_path, capsys, argv):
    out = tmp_path / "out"
    try:
        code = main(["seismic", "--record", "nearfield-pulse:1", "--window", "2,2.2", *argv,
                     "--engines", "semirecursive,opensees", "--out", str(out)])
    except SystemExit as e:
        code = e.code
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1, err
    assert "opensees" in err[0] and "bilinear or friction-pendulum" in err[0], err
    assert not out.exists()


def test_a_record_set_refuses_opensees_in_one_line_naming_the_single_run(tmp_path, capsys):
    out = tmp_path / "out"
    code = main(["seismic", "--record-set", "farfield", "--records", "1", "--engines", "semirecursive,opensees",
                 "--out", str(out)])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "nsd seismic --record SET:ID" in err[0], err
    assert not out.exists()


@pytest.mark.slow
@pytest.mark.parametrize("kind", ["bilinear", "friction-pendulum"])
def test_nsd_seismic_with_opensees_writes_its_run_and_verdict(tmp_path, kind):
    out = tmp_path / "out"
    code = main(["seismic", "--record", "nearfield-pulse:1", "--window", "2,3", "--scale", "0.6", "--isolator",
                 kind, "--engines", "semirecursive,opensees", "--out", str(out)])
    assert code == 0
    m = json.loads((out / "summary.json").read_text())["engines"]["opensees"]
    assert (out / "seismic_opensees.csv").exists()
    assert m["verdict"]["pass"], m["verdict"]["text"]
    assert m["element"] == "elastomericBearingBoucWen"


# the two records of the agreement (docs/seismic.md): near-field pulse 1 (the isolator tests' record) and
# far-field 17 (no other test's); each whole strong-motion window
RECORDS = [("nearfield-pulse", 1, 0.6, (2.0, 5.0)), ("farfield", 17, 1.0, (3.0, 9.0))]


@pytest.mark.slow
@pytest.mark.parametrize("kind", ["bilinear", "friction-pendulum"])
@pytest.mark.parametrize("record", RECORDS, ids=lambda r: f"{r[0]}:{r[1]}")
def test_opensees_agrees_with_the_in_house_engine_by_the_rule(kind, record):
    set_, rid, scale, window = record
    st = _structure(kind)
    j = judge(Params(), st, fema_record(set_, rid, scale=scale, window=window))
    ref = j["runs"]["converged"]
    assert float(np.max(np.hypot(ref["x"], ref["y"]))) > 4 * st.isolator.yield_displacement   # it slid / yielded
    assert j["verdict"]["pass"], j["verdict"]["text"]
    # the estimate is not vacuous: the observed order against the reference is near the assumed 1
    assert 0.5 < j["evidence"]["observed_order"] < 2.0, j["evidence"]


@pytest.mark.slow
def test_the_rule_sees_openSees_friction_pendulum_element_differ_from_the_smooth_law():
    """singleFPBearing (rigid-plastic Coulomb friction with pre-slip) against the project's n = 2 law: the
    difference is a model difference, beyond OpenSees's own numerical error (the rule can fail)."""
    st = _structure("friction-pendulum")
    g = fema_record("nearfield-pulse", 1, scale=0.6, window=(2.0, 3.0))
    j = judge(Params(), st, g, settings={"element": "single-fp"})
    assert j["runs"]["h"].stats["element"] == "singleFPBearing"
    assert j["verdict"]["consistent"] is False, j["verdict"]["text"]
    assert "disagrees beyond numerical error" in j["verdict"]["text"]
    assert math.isfinite(j["values"]["max_du_rel"]) and j["values"]["max_du_rel"] > 1e-3
