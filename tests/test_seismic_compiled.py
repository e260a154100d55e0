"""The seismic mode on the compiled path (nsd_core.structure.compiled_seismic) against the scipy-driven
reference path, and the one ground-motion implementation both read."""
from __future__ import annotations

import math

import numpy as np
import pytest

from nsd_core.ground.motions import Harmonic, Pulse, ground_values
from nsd_core.structure.isolation import Structure
from nsd_core.device.params import Params
from nsd_core.structure.seismic import RodReachError, simulate_seismic

STRUCTURE = Structure(mass=3743.80, radius_of_gyration=0.40825, stiffness=147799.2, damping=2352.30,
                      support_radius=0.5)
TIGHT = dict(rtol=1e-9, atol=1e-12)


def _vec_rel(a, b, cx, cy):
    d = np.hypot(a[cx] - b[cx], a[cy] - b[cy])
    return float(np.max(d) / np.max(np.hypot(b[cx], b[cy])))


@pytest.mark.parametrize("ground", [Harmonic(0.8, 2.0, 30.0, duration=0.3),
                                    Pulse(0.12, 2.0, 2.0, phase_deg=30.0, azimuth_deg=20.0)],
                         ids=["harmonic", "pulse"])
def test_compiled_path_equals_the_scipy_path(ground):
    """Measured at rtol 1e-9 (the same DOP853 steps, 490-492 and 391; the laws in scalar compiled form
    against their numpy form): harmonic du 4.7e-11, dF 3.4e-9, da 2.9e-9; pulse du 2.1e-11,
    dF 6.2e-11, da 3.1e-11. The limit 1e-7 leaves room for another platform's round-off."""
    dur = 0.3
    c = simulate_seismic(Params(), STRUCTURE, ground, duration=dur, dt_out=2e-3, backend="compiled", **TIGHT)
    r = simulate_seismic(Params(), STRUCTURE, ground, duration=dur, dt_out=2e-3, backend="scipy", **TIGHT)
    assert list(c.columns) == list(r.columns) and c.stats["backend"] == "compiled"
    assert np.max(r["u"]) > 3e-3  # the device is worked
    du, dF = _vec_rel(c, r, "x", "y"), _vec_rel(c, r, "device_Fx", "device_Fy")
    da = _vec_rel(c, r, "ax_abs", "ay_abs")
    assert du < 1e-7 and dF < 1e-7 and da < 1e-7, (du, dF, da)
    for k in r.columns:
        if k in ("closure", "E_residual"):  # both at round-off
            continue
        scale = max(np.max(np.abs(r[k])), 1e-9)
        assert np.max(np.abs(c[k] - r[k])) < 1e-6 * scale, k
    assert np.max(c["closure"]) < 1e-13
    assert np.max(np.abs(c["E_residual"])) < 1e-6 * np.max(c["E_input"])


def test_supports_alone_on_the_compiled_path_equal_the_scipy_path():
    gm = Harmonic(1.0, 1.5, 30.0, duration=0.6)
    c = simulate_seismic(Params(), STRUCTURE, gm, device=False, backend="compiled")
    r = simulate_seismic(Params(), STRUCTURE, gm, device=False, backend="scipy")
    assert list(c.columns) == list(r.columns)
    assert _vec_rel(c, r, "x", "y") < 1e-9
    assert np.max(np.abs(c["base_shear_x"] + STRUCTURE.mass * c["ax_abs"])) < 1e-9 * np.max(np.abs(c["base_shear_x"]))
    assert np.max(np.abs(c["E_residual"])) < 1e-8 * np.max(c["E_input"])


def test_chunks_do_not_change_the_run_beyond_the_tolerance(monkeypatch):
    """The compiled path restarts its step loop every CHUNK model seconds: compare with one chunk."""
    from nsd_core.structure import compiled_seismic
    gm = Harmonic(0.8, 2.0, 0.0, duration=0.4)
    one = simulate_seismic(Params(), STRUCTURE, gm, dt_out=2e-3)
    monkeypatch.setattr(compiled_seismic, "CHUNK", 0.1)
    four = simulate_seismic(Params(), STRUCTURE, gm, dt_out=2e-3)
    assert _vec_rel(four, one, "x", "y") < 1e-6 and _vec_rel(four, one, "device_Fx", "device_Fy") < 1e-5


@pytest.mark.slow
def test_rod_reach_on_the_compiled_path_stops_with_the_time():
    soft = Structure(mass=STRUCTURE.mass, radius_of_gyration=0.40825, stiffness=2.0e5, damping=0.0,
                     support_radius=0.5)
    with pytest.raises(RodReachError, match=r"t = 0\.[0-9]+ s: \|u\| = 0.0[23]\d* m"):
        simulate_seismic(Params(), soft, Pulse(1.2, 2.0, 2.0), duration=0.6, backend="compiled")


def test_the_compiled_ground_is_the_python_ground_and_the_closed_forms():
    """ground_values on a block placed at an offset (as inside the seismic force parameters) gives
    what GroundMotion.__call__ gives, and the closed forms of the harmonic input."""
    A, f, psi = 2.0, 1.5, 30.0
    h = Harmonic(A, f, psi, duration=2.0)
    p = np.concatenate([np.full(5, 7.0), h.block()])
    w, e = 2 * math.pi * f, (math.cos(math.radians(psi)), math.sin(math.radians(psi)))
    for t in (-0.3, 0.0, 0.4, 1.0 / f, 1.99, 2.5):
        dx, dy, vx, vy, ax, ay = ground_values(t, p, 5)
        d, v, a = h(t)
        assert (dx, dy, vx, vy, ax, ay) == (d[0], d[1], v[0], v[1], a[0], a[1])
        tc = min(max(t, 0.0), 2.0)
        a_cf = A * math.sin(w * tc) if 0 <= t <= 2.0 else 0.0
        v_cf = A * (1 - math.cos(w * tc)) / w
        d_cf = A * (tc / w - math.sin(w * tc) / w ** 2) + v_cf * max(t - 2.0, 0.0)
        assert np.allclose([ax, vx, dx], np.multiply([a_cf, v_cf, d_cf], e[0]), rtol=1e-13, atol=1e-15)
