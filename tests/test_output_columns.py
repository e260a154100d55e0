"""What the seismic outputs say: every column's unit (one table, nsd_core.device.columns), the
fixed-base run's base shear (story 1's, docs/building.md), and the warning for a building's peak on
the last sample. Real runs of the in-house engine, 0.1 s of a harmonic ground under a 2-story
building on the device with the restrainer (every column family at once)."""
from __future__ import annotations

import re

import numpy as np
import pytest

from nsd_core.structure.building import building_from
from nsd_core.device.columns import unit_of
from nsd_core.ground.motions import parse_ground_spec
from nsd_core.structure.isolation import default_structure
from nsd_core.device.params import Params
from nsd_core.structure.restrainer import with_restrainer
from nsd_core.device.results import column_units, read_csv, write_csv
from nsd_core.structure.seismic import seismic_summary, simulate_seismic

GROUND = "harmonic:amplitude=1.5,frequency=3,azimuth=30,duration=0.1"

# what each column is, written from docs/seismic.md and docs/building.md (not from the table)
EXPECTED = [
    (r"t", "s"), (r"[xyu]|[xy]_g|cap_z|wall_z|closure|restrainer_indentation", "m"),
    (r"floor\d+_[xy]|drift\d+_[xy]", "m"), (r"v[xy]|floor\d+_v[xy]", "m/s"),
    (r"a[xy]_g|a[xy]_abs|floor\d+_a[xy]_abs", "m/s^2"), (r"theta", "rad"), (r"support_torque", "N m"),
    (r"(support|device|restrainer)_F[xy]?|base_shear_[xy]|story_shear\d+_[xy]", "N"),
    (r"spring_push|spring_zeta|rope\d+_tension|wire\d+_tension", "N"),
    (r"wire\d+_strain", "-"), (r"wire\d+_stress", "Pa"), (r"E_\w+", "J"),
]


def expected_unit(name: str) -> str:
    units = [u for pattern, u in EXPECTED if re.fullmatch(pattern, name)]
    assert len(units) == 1, (name, units)
    return units[0]


@pytest.fixture(scope="module")
def runs():
    p = Params()
    st = default_structure(p)
    st = with_restrainer(st.with_building(building_from(st.mass, {"stories": 2})), p, True)
    ground = parse_ground_spec(GROUND)
    device = simulate_seismic(p, st, ground, duration=0.1, dt_out=0.002, device=True)
    fixed = simulate_seismic(p, st.with_restrainer(None), ground, duration=0.1, dt_out=0.002, device=False,
                             fixed_base=True)
    return device, fixed


def test_every_column_of_a_building_run_has_its_unit(runs, tmp_path):
    device, fixed = runs
    assert {"floor2_ax_abs", "drift1_x", "story_shear2_y", "restrainer_F", "wire3_stress"} <= set(device.columns)
    for r in (device, fixed):
        for name in r.columns:
            assert r.units[name] == expected_unit(name), name
    write_csv(tmp_path / "seismic.csv", device)
    header = (tmp_path / "seismic.csv").read_text().splitlines()[0].split(",")
    assert "floor1_x [m]" in header and "drift1_x [m]" in header and "floor1_ax_abs [m/s^2]" in header
    assert "story_shear1_x [N]" in header
    back = read_csv(tmp_path / "seismic.csv")
    assert back.units == {n: expected_unit(n) for n in device.columns}


def test_drive_columns_come_from_the_same_table():
    units = column_units(4, 6)
    assert units["u"] == "m" and units["F"] == "N" and units["wire5_strain"] == "-" and units["rope3_F"] == "N"
    assert all(unit_of(n) == u for n, u in units.items())


def test_a_column_without_a_unit_is_an_error_not_a_guess():
    with pytest.raises(KeyError):
        unit_of("floor1_jerk")


def test_fixed_base_base_shear_is_story_1_shear(runs):
    """docs/building.md: on a fixed base the base shear is story 1's shear (before: 0, the supports'
    and the device's force, both absent)."""
    _, fixed = runs
    assert np.max(np.abs(fixed["story_shear1_x"])) > 100.0
    assert np.array_equal(fixed["base_shear_x"], fixed["story_shear1_x"])
    assert np.array_equal(fixed["base_shear_y"], fixed["story_shear1_y"])
    s = seismic_summary(fixed)
    assert s["peak_base_shear"]["value"] == s["building"]["peak_story_shear"][0]["value"] > 100.0


def test_building_peaks_on_the_last_sample_are_warned(runs):
    """0.1 s of a growing harmonic: every floor still moves away at the end, so its peaks are on the
    last sample and the summary says so (nsd seismic prints them on stderr)."""
    device, _ = runs
    s = seismic_summary(device)
    at_end = s["peaks_at_last_sample"]
    assert "building.peak_drift_ratio[story 2]" in at_end and "building.peak_floor_acceleration[floor 1]" in at_end
    s["building"]["peak_drift_ratio"][1]["t"] = 0.05  # a peak inside the window is not listed
    from nsd_core.structure.seismic_summary import peaks_at_last_sample
    assert "building.peak_drift_ratio[story 2]" not in peaks_at_last_sample(s, float(device["t"][-1]))


def test_nsd_seismic_warns_of_the_building_s_peaks_on_the_last_sample(tmp_path):
    """stderr and summary.json's warnings name the building's peaks that fall on the last sample."""
    import json
    import subprocess
    import sys
    out = tmp_path / "run"
    p = subprocess.run([sys.executable, "-m", "nsd_cli.main", "seismic", "--ground", GROUND, "--dt-out", "0.002",
                        "--building", "stories=2", "--out", str(out)], capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stderr
    warning = [line for line in p.stderr.splitlines() if "at the last sample" in line]
    assert len(warning) == 1 and "building.peak_drift_ratio[story 2]" in warning[0], p.stderr
    s = json.loads((out / "summary.json").read_text())
    assert any("building.peak_floor_acceleration[floor 2]" in w for w in s["warnings"])
