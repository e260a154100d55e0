import dataclasses
import math
import tomllib

import pytest

from nsd_core.device.drive import Drive, DriveError
from nsd_core.device.params import FIELDS, ParameterError, Params, load_params, parse_set
from tests.conftest import ROOT

PAPER = tomllib.loads((ROOT / "references" / "paper-data.toml").read_text())

TABLE2 = {  # paper-data.toml key -> Params field
    "cap_diameter": "cap_diameter", "cap_mass": "cap_mass", "rod_length": "rod_length",
    "rod_mass": "rod_mass", "wall_diameter": "wall_diameter", "wall_mass": "wall_mass",
    "base_diameter": "base_diameter", "base_mass": "base_mass", "n_ropes": "n_ropes",
    "rope_upper_radius": "rope_upper_radius", "rope_lower_radius": "rope_lower_radius",
    "n_wires": "n_wires", "wire_diameter": "wire_diameter", "wire_upper_radius": "wire_upper_radius",
    "wire_lower_radius": "wire_lower_radius", "wire_first_azimuth_deg": "wire_first_azimuth_deg",
    "wire_inclination_deg": "wire_inclination_deg", "spring_length_precompressed": "spring_length",
}


def test_defaults_are_the_papers_table2():
    p = Params()
    for key, name in TABLE2.items():
        assert getattr(p, name) == pytest.approx(PAPER["table2"][key], rel=1e-12), name
    assert p.rope_stiffness == PAPER["ropes"]["stiffness"]
    assert p.precompression_force == PAPER["table6"]["precompression_force"][-1]


def test_every_field_has_unit_and_provenance():
    for f in dataclasses.fields(Params):
        assert f.metadata["unit"], f.name
        assert f.metadata["source"], f.name
    sources = {r["name"]: r["source"] for r in Params().describe()}
    assert sources["cap_mass"] == "Table 2"
    assert sources["wire_E"].startswith("assumed")
    assert Params(rope_stiffness=7e5).describe()[[r["name"] for r in Params().describe()].index("rope_stiffness")]["source"] == "override"


@pytest.mark.parametrize("name,value,fragment", [
    ("n_ropes", 2, "n_ropes = 2"),
    ("rod_length", -0.01, "rod_length = -0.01"),
    ("cap_mass", float("nan"), "cap_mass = nan"),
    ("wire_inclination_deg", 45.0, "[0, 45)"),
    ("wire_inclination_deg", -1.0, "[0, 45)"),
    ("precompression_force", 5.0, "carried"),
    ("n_wires", 2.5, "whole number"),
])
def test_validation_one_line_errors(name, value, fragment):
    with pytest.raises(ParameterError) as e:
        Params().replace(**{name: value})
    msg = str(e.value)
    assert fragment in msg and "\n" not in msg


def test_unknown_and_derived_keys_rejected():
    with pytest.raises(ParameterError, match="unknown parameter"):
        load_params(None, {"rope_stifness": 1})
    with pytest.raises(ParameterError, match="derived"):
        load_params(None, {"wire_lower_radius": 0.03})
    with pytest.raises(ParameterError, match="name=value"):
        parse_set(["rope_stiffness"])


def test_toml_then_overrides(tmp_path):
    f = tmp_path / "p.toml"
    f.write_text("[params]\nrope_stiffness = 7.0e5\nn_ropes = 6\n")
    p = load_params(f, parse_set(["n_ropes=8"]))
    assert p.rope_stiffness == 7e5 and p.n_ropes == 8 and isinstance(p.n_ropes, int)
    bad = tmp_path / "bad.toml"
    bad.write_text("rope_stiffness = [")
    with pytest.raises(ParameterError, match="not valid TOML"):
        load_params(bad)


def test_derived_geometry_matches_table2():
    p = Params()
    assert p.wire_lower_radius == pytest.approx(0.0265, abs=1e-12)
    assert math.degrees(math.atan((p.wire_lower_radius - p.wire_upper_radius) / p.wire_span)) == pytest.approx(12.8)
    # sweeping theta keeps h_w and R_w,u (docs/model.md); theta = 0 gives a vertical wire
    assert Params(wire_inclination_deg=0.0).wire_lower_radius == pytest.approx(p.wire_upper_radius)


def test_drive_validation():
    with pytest.raises(DriveError, match="cannot follow"):
        Drive(0.03, 1.0).check_followable(Params())
    Drive(0.0299, 1.0).check_followable(Params())
    for kw in ({"frequency": 0.0}, {"amplitude": -1e-3}, {"cycles": 0}):
        args = {"amplitude": 0.01, "frequency": 1.0, **kw}
        with pytest.raises(ParameterError):
            Drive(**args)
    assert set(FIELDS) >= set(TABLE2.values()) - {"wire_lower_radius"}
