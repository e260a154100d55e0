"""The geometry every engine builds, recomputed from its attachment points, against Table 2 directly.

The expected values are read from references/paper-data.toml (the paper transcribed by hand), never
from nsd_core.params, so a wrong default or a mistake in nsd_core.geometry shows here. MuJoCo's
compiled model is read back too: its masses are those of its own MJCF, not of the parameter object.
"""
from __future__ import annotations

import math
import tomllib
from pathlib import Path

import numpy as np
import pytest

from nsd_core.device.drive import Drive
from nsd_core.device.geometry import device_geometry
from nsd_core.device.params import Params

TABLE2 = tomllib.loads((Path(__file__).resolve().parents[1] / "references" / "paper-data.toml").read_text())["table2"]
G = device_geometry(Params())


def _radii(points):
    return np.hypot(points[:, 0], points[:, 1])


def test_counts_and_radii_of_the_attachment_points():
    assert G.n_ropes == TABLE2["n_ropes"] and G.n_wires == TABLE2["n_wires"]
    np.testing.assert_allclose(_radii(G.rope_base_points), TABLE2["rope_lower_radius"], rtol=1e-12)
    np.testing.assert_allclose(_radii(G.rope_cap_points), TABLE2["rope_upper_radius"], rtol=1e-12)
    np.testing.assert_allclose(_radii(G.wire_cap_points), TABLE2["wire_upper_radius"], rtol=1e-12)
    np.testing.assert_allclose(_radii(G.wire_wall_points), TABLE2["wire_lower_radius"], rtol=1e-12)
    # the first wire lies along +X (delta_0), the others evenly around
    az = np.degrees(np.arctan2(G.wire_wall_points[:, 1], G.wire_wall_points[:, 0])) % 360
    np.testing.assert_allclose(az, TABLE2["wire_first_azimuth_deg"] + 360 / TABLE2["n_wires"] * np.arange(G.n_wires),
                               atol=1e-9)


def test_wire_inclination_from_the_points_is_theta():
    """theta from the vertical, recomputed from the rest positions of both ends of every wire."""
    upper = G.wire_cap_points + [0.0, 0.0, G.cap_rest_z]
    lower = G.wire_wall_points + [0.0, 0.0, G.wall_rest_z]
    v = upper - lower
    theta = np.degrees(np.arctan2(np.hypot(v[:, 0], v[:, 1]), v[:, 2]))
    np.testing.assert_allclose(theta, TABLE2["wire_inclination_deg"], atol=1e-9)
    # the upper end is inside the lower one (the wire leans inwards going up), as in Figure 2
    assert np.all(_radii(G.wire_cap_points) < _radii(G.wire_wall_points))
    np.testing.assert_allclose(np.linalg.norm(v, axis=1), G.wire.natural_length, rtol=1e-12)  # not pretensioned
    assert G.wire.area == pytest.approx(math.pi * TABLE2["wire_diameter"] ** 2 / 4, rel=1e-12)


def test_heights_rod_and_spring_lengths():
    assert G.wall_rest_z == pytest.approx(TABLE2["spring_length_precompressed"], abs=1e-15)
    assert G.cap_rest_z - G.wall_rest_z == pytest.approx(TABLE2["rod_length"], abs=1e-15)


def test_masses_in_the_shared_geometry():
    for body in ("cap", "wall", "base", "rod"):
        assert getattr(G, body).mass == TABLE2[f"{body}_mass"]


def test_masses_and_loop_of_the_compiled_mujoco_model():
    """What MuJoCo integrates: body masses read back from the mjModel its builder compiles from the
    device's description, the rod's length and the wall's height at the initial state."""
    import mujoco

    from comparisons.builders.mujoco import _compile, merged_settings
    from comparisons.engines.described import described_model
    from nsd_core.model.assemble import initial_state
    model, _ = described_model(Params(), Drive(0.01, 1.0))
    m, d, _ = _compile(model, merged_settings({}), 1e-5, initial_state(model))
    for body in ("cap", "wall", "rod"):
        assert m.body(body).mass[0] == pytest.approx(TABLE2[f"{body}_mass"], rel=1e-12)
    mujoco.mj_forward(m, d)
    tip = d.site_xpos[m.site("cap_rod:b").id]
    assert tip[2] - d.xpos[m.body("wall").id][2] == pytest.approx(TABLE2["rod_length"], abs=1e-12)
    assert d.xpos[m.body("wall").id][2] == pytest.approx(TABLE2["spring_length_precompressed"], abs=1e-12)
    assert m.opt.gravity[2] < 0
