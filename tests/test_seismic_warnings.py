"""The seismic warnings (nsd_core.structure.seismic_warnings, docs/seismic.md "Warnings") on real
runs: short harmonic inputs on the default structure, in summary.json, on stderr and on the report's
warnings page."""
from __future__ import annotations

import json

import pytest

from nsd_cli.main import main

NEAR = "harmonic:amplitude=0.62,frequency=1,duration=0.6"    # peak |u| 29.07 mm at t = 0.518 s, no stop
STOP = "harmonic:amplitude=1,frequency=1,duration=0.5"       # |u| reaches the rod's length at t = 0.365 s


def _warned(capsys) -> list[str]:
    return [ln for ln in capsys.readouterr().err.splitlines() if "warning" in ln]


def _pages(folder, tmp_path):
    from reports.build import build_report
    return build_report(folder, tmp_path / f"rep_{folder.name}")["pages"]


def test_stroke_nearly_exhausted_warns_in_the_summary_on_stderr_and_the_report(tmp_path, capsys):
    out = tmp_path / "near"
    assert main(["seismic", "--ground", NEAR, "--out", str(out)]) == 0
    s = json.loads((out / "summary.json").read_text())
    assert s["peak_displacement"]["value"] >= 0.95 * 0.03 and "stroke_nearly_exhausted" in s["warning_kinds"]
    text = s["warnings"][s["warning_kinds"].index("stroke_nearly_exhausted")]
    assert "peak |u| = 29.07 mm" in text and "96.9% of the rod's length 30 mm" in text
    assert any("stroke nearly exhausted" in ln for ln in _warned(capsys))
    assert any(name.startswith("warnings_") for name in _pages(out, tmp_path))
    from page_checks import figure_problems
    assert figure_problems(out, ("warnings_harmonic",)) == {}


def test_a_run_stopped_at_the_rods_reach_warns_of_stroke_exhaustion(tmp_path, capsys):
    out = tmp_path / "stop"
    assert main(["seismic", "--ground", STOP, "--out", str(out)]) == 4
    s = json.loads((out / "summary.json").read_text())
    # no last-sample warning: the event ends it; the device fails the restoring-force check at D_M (45 deg)
    assert s["warning_kinds"] == ["stroke_exhausted", "restoring_force_fails"]
    assert "stroke exhausted: the run stopped at t = 0.3647" in s["warnings"][0]
    assert len(_warned(capsys)) == 2


def test_restrainer_impacts_warn_with_their_count_energy_and_force(tmp_path, capsys):
    out = tmp_path / "hit"
    assert main(["seismic", "--ground", NEAR, "--restrainer", "--out", str(out)]) == 0
    s = json.loads((out / "summary.json").read_text())
    n = s["restrainer"]["engagements"]
    assert n >= 1 and "restrainer_impacts" in s["warning_kinds"]
    text = s["warnings"][s["warning_kinds"].index("restrainer_impacts")]
    assert f"restrainer impacts: {n} contact(s)" in text
    assert f"largest impact energy {s['restrainer']['impact_energy_max']:.4g} J" in text
    assert f"peak contact force {s['peak_restrainer_force']['value']:.4g} N" in text
    assert any("restrainer impacts" in ln for ln in _warned(capsys))


def test_compare_supports_warns_per_run_and_draws_the_warnings_page(tmp_path, capsys):
    """The device run stops at the rod's reach; the supports alone (no stroke limit in the model) go
    past the rod's length: both are said, each run in its own summary."""
    out = tmp_path / "cmp"
    assert main(["seismic", "--ground", "harmonic:amplitude=2.5,frequency=1,duration=0.5", "--compare-supports",
                 "--out", str(out)]) == 4
    dev = json.loads((out / "device" / "summary.json").read_text())
    sup = json.loads((out / "supports" / "summary.json").read_text())
    assert dev["warning_kinds"] == ["stroke_exhausted", "restoring_force_fails"]   # the device fails at D_M (45 deg)
    assert sup["peak_displacement"]["value"] > 0.03 and "beyond_stroke" in sup["warning_kinds"]
    assert "restoring_force_fails" not in sup["warning_kinds"]   # the linear supports pass at D_M (+533 N)
    err = _warned(capsys)
    assert any(ln.startswith("nsd seismic: warning: device: stroke exhausted") for ln in err)
    assert any(ln.startswith("nsd seismic: warning: supports: beyond the device's stroke") for ln in err)
    assert "warnings_with_and_without_the_device" in _pages(out, tmp_path)


def test_warnings_page_keeps_its_text_on_the_page():
    """Many long warnings: wrapped, cut with a count, never off the page or on each other."""
    from page_checks import text_problems
    from reports.warnings_page import warnings_figure
    fig = warnings_figure("many", [f"record {k}: " + "a long warning text " * 30 for k in range(40)], "set.json")
    assert text_problems(fig) == []
    assert any("more warning(s)" in t.get_text() for t in fig.texts)


@pytest.mark.slow   # the set's worker process: 7.5 s warm, 150 s when it first compiles the engine
def test_a_record_set_warns_per_record_in_set_json_on_stderr_and_on_its_warnings_page(tmp_path, capsys):
    """Near-field pulse 1, record seconds 2-3 at scale 16: the device run stops at the rod's reach, the
    supports alone pass the rod's length."""
    out = tmp_path / "set"
    assert main(["seismic", "--record-set", "nearfield-pulse", "--records", "1", "--window", "2,3", "--scale", "16",
                 "--dt-out", "0.002", "--workers", "1", "--out", str(out)]) == 4
    index = json.loads((out / "set.json").read_text())
    assert index["restoring_force"]["pass"] is False and index["restoring_force"]["D_source"].startswith("default")  # D_M, 45 deg
    entry = index["entries"][0]
    assert entry["warnings"][0].startswith("device: stroke exhausted: the run stopped at t = ")
    assert any(w.startswith("nodevice: beyond the device's stroke") for w in entry["warnings"])
    alone = json.loads((out / "records" / "nearfield-pulse_1_nodevice" / "summary.json").read_text())
    assert "beyond_stroke" in alone["warning_kinds"]
    err = _warned(capsys)
    assert any(ln.startswith("nsd seismic: warning: nearfield-pulse:1 device: stroke exhausted") for ln in err)
    assert "warnings_record_set_nearfield-pulse" in _pages(out, tmp_path)


def test_compare_building_warns_per_configuration_and_checks_only_the_isolated_runs(tmp_path, capsys):
    """0.3 s of a 1 Hz input: every configuration's peaks fall on the last sample; the fixed base has no
    isolation level, so no restoring-force check in its summary (the top and the isolated runs have it)."""
    out = tmp_path / "cb"
    assert main(["seismic", "--ground", "harmonic:amplitude=0.5,frequency=1,duration=0.3", "--building", "stories=3",
                 "--compare-building", "--design-displacement", "0.02", "--out", str(out)]) == 0
    kinds = {c: json.loads((out / c / "summary.json").read_text()) for c in ("fixed_base", "supports", "device")}
    assert "restoring_force" not in kinds["fixed_base"]
    assert kinds["device"]["restoring_force"]["W"] == pytest.approx(2 * kinds["device"]["structure"]["mass"] * 9.80665)
    assert json.loads((out / "summary.json").read_text())["restoring_force"]["pass"] is False   # 934 N < 1836 N
    for c in ("supports", "device"):   # at D = 20 mm both isolated configurations fail (W doubled by the floors)
        assert kinds[c]["warning_kinds"] == ["peaks_at_last_sample", "restoring_force_fails"]
    assert "restoring_force_fails" not in kinds["fixed_base"]["warning_kinds"]
    err = _warned(capsys)
    assert any(ln.startswith("nsd seismic: warning: device: ") for ln in err)
    assert "warnings_the_building_fixed-base_and_isolated" in _pages(out, tmp_path)
