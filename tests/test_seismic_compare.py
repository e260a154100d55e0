"""nsd seismic --compare-supports, the restrainer's options and the last-sample warning: both runs written with their ratios, the supports-alone run checked against the
closed-form single-degree-of-freedom solution, bad input to every new option exit 2."""
from __future__ import annotations

import json
import math

import numpy as np
import pytest

from nsd_core.device.results import read_csv

from tests.test_seismic import STRUCTURE, sdof_harmonic_from_rest


@pytest.mark.parametrize("args, words", [
    (["--ground", "harmonic:amplitude=1,frequency=1,duration=0.2", "--compare-supports", "--no-device"],
     "--compare-supports"),
    (["--ground", "harmonic:amplitude=1,frequency=1,duration=0.2", "--compare-supports", "--engines",
      "semirecursive,mujoco"], "--compare-supports runs the in-house engine only"),
    (["--record-set", "nearfield-pulse", "--records", "1", "--compare-supports"], "--compare-supports"),
    (["--ground", "harmonic:amplitude=1,frequency=1,duration=0.2", "--structure", "restrainer_gap=0.031"],
     "restrainer_gap = 0.031: must be < rod_length"),
    (["--ground", "harmonic:amplitude=1,frequency=1,duration=0.2", "--restrainer", "--structure",
      "restrainer_stiffness=-5"], "restrainer_stiffness = -5.0: must be a finite number > 0"),
    (["--ground", "harmonic:amplitude=1,frequency=1,duration=0.2", "--structure", "restrainer_exponent=abc"],
     "restrainer_exponent = 'abc': not a number"),
    (["--ground", "harmonic:amplitude=1,frequency=1,duration=0.2", "--structure", "restrainer_damping=inf"],
     "restrainer_damping = inf"),
    (["--ground", "harmonic:amplitude=1,frequency=1,duration=0.2", "--structure", "restrainer_size=1"],
     "restrainer_size: unknown"),
])
def test_bad_input_to_the_new_options_is_exit_2_one_line_nothing_written(tmp_path, capsys, args, words):
    from nsd_cli.main import main
    out = tmp_path / "x"
    code = main(["seismic", *args, "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 2, err
    assert words in err and len(err.strip().splitlines()) == 1, err
    assert not out.exists()


def test_compare_supports_writes_both_runs_and_their_ratios(tmp_path, capsys):
    from nsd_cli.main import main
    A, f, psi, T = 0.4, 1.5, 30.0, 0.8
    out = tmp_path / "cmp"
    code = main(["seismic", "--ground", f"harmonic:amplitude={A},frequency={f},azimuth={psi},duration={T}",
                 "--compare-supports", "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 0, err
    top = json.loads((out / "summary.json").read_text())
    dev, sup = (json.loads((out / n / "summary.json").read_text()) for n in ("device", "supports"))
    assert top["compare_supports"] and dev["device"] is True and sup["device"] is False
    r_dev, r_sup = read_csv(out / "device" / "seismic.csv"), read_csv(out / "supports" / "seismic.csv")
    # the supports alone, as written, against the exact linear solution (shares no code with the run)
    u = sdof_harmonic_from_rest(r_sup["t"], A, f, STRUCTURE.period, STRUCTURE.damping_ratio)
    e = (math.cos(math.radians(psi)), math.sin(math.radians(psi)))
    assert np.max(np.abs(r_sup["x"] - u * e[0])) < 1e-5 * np.max(np.abs(u))
    # each ratio is the two runs' own numbers, recomputed here from their series (the CSV keeps 10 digits)
    peak = {n: np.max(np.hypot(r["x"], r["y"])) for n, r in (("dev", r_dev), ("sup", r_sup))}
    assert top["ratios"]["peak_displacement"]["ratio"] == pytest.approx(peak["dev"] / peak["sup"], rel=1e-9)
    acc = {n: np.max(np.hypot(r["ax_abs"], r["ay_abs"])) for n, r in (("dev", r_dev), ("sup", r_sup))}
    assert top["ratios"]["peak_absolute_acceleration"]["ratio"] == pytest.approx(acc["dev"] / acc["sup"], rel=1e-9)
    assert top["ratios"]["residual_displacement"]["with_device"] == pytest.approx(r_dev["u"][-1], rel=1e-9)
    assert top["ratios"]["device_absorbed"]["with_device"] == pytest.approx(r_dev["E_device"][-1], rel=1e-9)
    assert r_dev["t"][-1] == T and r_sup["t"][-1] == T
    lines = (out / "ratios.csv").read_text().splitlines()
    assert lines[0] == "quantity,with_device,supports_alone,ratio,what" and len(lines) == 1 + len(top["ratios"])
    # the report overlays both
    from reports.build import build_report
    paths = build_report(out, tmp_path / "rep")
    assert any("compare_" in p for p in map(str, paths["pngs"]))


def test_a_peak_on_the_last_sample_warns_in_the_summary_and_on_stderr(tmp_path, capsys):
    from nsd_cli.main import main
    out = tmp_path / "w"
    # 0.15 s of a 1 Hz input: the plate is still moving out when the window ends
    code = main(["seismic", "--ground", "harmonic:amplitude=1,frequency=1,duration=0.15", "--no-device",
                 "--out", str(out)])
    err = capsys.readouterr().err
    s = json.loads((out / "summary.json").read_text())
    assert code == 0 and "peak_displacement" in s["peaks_at_last_sample"]
    assert len(s["warnings"]) == 1 and "peak_displacement" in s["warnings"][0]
    assert len([line for line in err.splitlines() if "warning" in line]) == 1, err


@pytest.mark.slow
def test_a_run_the_rod_ends_keeps_its_series_on_both_in_house_paths():
    """RodReachError carries the samples before the event (compiled and scipy paths alike)."""
    from nsd_core.ground.motions import Pulse
    from nsd_core.structure.isolation import Structure
    from nsd_core.device.params import Params
    from nsd_core.structure.seismic import RodReachError, simulate_seismic
    soft = Structure(mass=3743.8, radius_of_gyration=0.40825, stiffness=2.0e5, damping=0.0, support_radius=0.5)
    kept = {}
    for backend in ("compiled", "scipy"):
        with pytest.raises(RodReachError) as info:
            simulate_seismic(Params(), soft, Pulse(1.2, 2.0, 2.0), duration=0.6, backend=backend)
        err = info.value
        assert err.partial["t"][-1] <= err.t_event < err.partial["t"][-1] + 1e-3
        kept[backend] = err.partial
    a, b = kept["compiled"], kept["scipy"]
    assert len(a["t"]) == len(b["t"]) > 200
    assert np.max(np.abs(a["u"] - b["u"])) < 1e-6 * np.max(a["u"])
