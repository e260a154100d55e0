"""The shared force laws against closed forms and physical properties (Eqs. 16-18)."""
import math

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from scipy.integrate import solve_ivp

from nsd_core.device.forces import (SpringLaw, WireLaw, advance_spring_zeta, advance_wire_stress, bouc_wen_slope,
                             precompressed_spring, rope_tension, sma_wire, spring_push)
from nsd_core.device.geometry import device_geometry
from nsd_core.device.params import Params

G = device_geometry(Params())
WIRE: WireLaw = G.wire
SPRING: SpringLaw = G.spring


def test_rope_is_slack_in_compression_and_hookean_in_tension():
    L0, k = 0.1, 5e5
    assert rope_tension(0.099, L0, k) == 0.0
    assert rope_tension(L0, L0, k) == 0.0
    assert rope_tension(0.1002, L0, k) == pytest.approx(k * 0.0002)
    np.testing.assert_allclose(rope_tension(np.array([0.05, 0.11]), L0, k), [0.0, k * 0.01])


def _path(law_advance, xs, state):
    out = [state]
    for a, b in zip(xs[:-1], xs[1:]):
        state = float(law_advance(a, b, state))
        out.append(state)
    return np.array(out)


def test_bouc_wen_saturates_at_ksd_over_beta_plus_gamma():
    bound = SPRING.ksd / (SPRING.beta + SPRING.gamma)
    x = np.linspace(0.0, 0.05, 2001)  # 0.05 m is ~30 decay lengths 1/(beta+gamma)
    z = _path(lambda a, b, s: advance_spring_zeta(a, b, s, SPRING, 2), x, 0.0)
    assert z[-1] == pytest.approx(bound, rel=1e-6)
    # n_s = 1 closed form on monotonic loading from zeta = 0
    np.testing.assert_allclose(z, bound * (1 - np.exp(-(SPRING.beta + SPRING.gamma) * x)), rtol=1e-6, atol=1e-9)
    back = _path(lambda a, b, s: advance_spring_zeta(a, b, s, SPRING, 2), x[::-1], z[-1])
    assert back[-1] == pytest.approx(-bound, rel=2e-3)


def test_precompressed_spring_pushes_with_F_press():
    x, z0 = precompressed_spring(SPRING.kse, SPRING.ksd, SPRING.beta, SPRING.gamma, SPRING.n, 3800.0)
    assert SPRING.kse * x + z0 == pytest.approx(3800.0, rel=1e-12)
    b = SPRING.beta + SPRING.gamma
    assert z0 == pytest.approx(SPRING.ksd / b * (1 - math.exp(-b * x)), rel=1e-12)
    # the general-n branch (numerical in x) agrees with the closed form at n = 1 + tiny
    x2, z2 = precompressed_spring(SPRING.kse, SPRING.ksd, SPRING.beta, SPRING.gamma, 1.0 + 1e-9, 3800.0)
    assert x2 == pytest.approx(x, rel=1e-5)


def test_spring_push_is_push_only():
    push, rate, raw = spring_push(SPRING.free_length + 0.01, 0.0, 0.0, SPRING)
    assert push == 0.0 and raw < 0
    push, rate, raw = spring_push(SPRING.free_length - 0.01, -0.1, 100.0, SPRING)
    assert push == pytest.approx(SPRING.kse * 0.01 + 100.0)
    assert rate == pytest.approx(float(bouc_wen_slope(100.0, 1.0, SPRING)) * 0.1)


def sma_loop(eps_max, n=600, start=0.0):
    up = np.linspace(start, eps_max, n)
    s_up = _path(lambda a, b, s: advance_wire_stress(a, b, s, WIRE, 4), up, 0.0)
    dn = up[::-1]
    s_dn = _path(lambda a, b, s: advance_wire_stress(a, b, s, WIRE, 4), dn, s_up[-1])
    return up, s_up, dn, s_dn


def test_sma_flag_shaped_loop_returns_near_zero():
    up, s_up, dn, s_dn = sma_loop(0.06)
    load = np.interp([0.02, 0.04], up, s_up) / 1e6
    unload = np.interp([0.02, 0.04], dn[::-1], s_dn[::-1]) / 1e6
    # docs/model.md: plateaus near 420-470 MPa on loading and 170-200 MPa on unloading
    assert 400 < load[0] < 480 and 400 < load[1] < 480
    assert 150 < unload[0] < 215 and 150 < unload[1] < 215
    assert abs(s_dn[-1]) < 0.1 * s_up.max()  # superelastic: returns near zero stress
    # initial slope is the austenite modulus
    assert (s_up[1] - s_up[0]) / (up[1] - up[0]) == pytest.approx(WIRE.E, rel=0.02)


def test_sma_rate_form_matches_strain_form():
    """Eq. 17 integrated in time (rate form) equals the rate-independent strain form."""
    L0 = WIRE.natural_length
    f = 3.0
    amp = 0.05 * L0

    def rhs(t, y):
        L = L0 + amp * math.sin(2 * math.pi * f * t)
        Ld = amp * 2 * math.pi * f * math.cos(2 * math.pi * f * t)
        return [float(sma_wire(L, Ld, y[0], WIRE)[1])]

    t = np.linspace(0, 1 / (4 * f), 400)
    sol = solve_ivp(rhs, (0, t[-1]), [0.0], t_eval=t, rtol=1e-10, atol=1e-3, max_step=1e-4)
    eps = amp * np.sin(2 * math.pi * f * t) / L0
    s = _path(lambda a, b, st_: advance_wire_stress(a, b, st_, WIRE, 4), eps, 0.0)
    np.testing.assert_allclose(sol.y[0], s, rtol=1e-5, atol=1e3)


def test_vectorised_equals_elementwise():
    L = WIRE.natural_length * np.array([0.99, 1.0, 1.02, 1.05])
    Ld = np.array([-0.1, 0.0, 0.2, -0.3])
    sig = np.array([-1e7, 0.0, 2e8, 4e8])
    T, rate = sma_wire(L, Ld, sig, WIRE)
    for i in range(4):
        Ti, ri = sma_wire(L[i], Ld[i], sig[i], WIRE)
        assert T[i] == Ti and rate[i] == ri
    assert T[0] == 0.0  # Eq. 17a clips a compressive stress: a wire never pushes


def _sma_cycle_work(amp, mean):
    eps = mean + amp * np.sin(np.linspace(0, 4 * np.pi, 801))  # two cycles; take the second
    s = _path(lambda a, b, st_: advance_wire_stress(a, b, st_, WIRE, 2), eps, 0.0)
    e2, s2 = eps[400:], s[400:]
    return np.sum(0.5 * (s2[1:] + s2[:-1]) * np.diff(e2)), np.max(np.abs(s2))


@settings(max_examples=25, deadline=None)
@given(amp=st.floats(0.002, 0.06), extra=st.floats(0.0, 0.02))
def test_sma_dissipates_on_any_closed_tension_cycle(amp, extra):
    """Cycles that stay clear of the pinching zone (strain >= 2.5/a = 0.005) dissipate."""
    work, smax = _sma_cycle_work(amp, amp + 0.005 + extra)
    assert work >= -1e-6 * smax * amp


def test_sma_known_limitation_cycles_through_zero_strain():
    """With the assumed wire values (a = 500, f_T = 0.36) Eq. 17c's pinching term makes small
    tension-compression cycles through zero strain run the wrong way round: negative loop area.
    This pins the known behaviour of the law as written (documented in the README); small cycles
    that merely touch zero strain do it too."""
    assert _sma_cycle_work(0.0085, -0.0006)[0] < 0
    assert _sma_cycle_work(0.002, 0.002)[0] < 0


@settings(max_examples=25, deadline=None)
@given(amp=st.floats(1e-4, 0.02), z0=st.floats(-300, 300))
def test_bouc_wen_dissipates_on_any_closed_cycle(amp, z0):
    x = amp * np.sin(np.linspace(0, 4 * np.pi, 801))
    z = _path(lambda a, b, s: advance_spring_zeta(a, b, s, SPRING, 2), x, z0)
    x2, z2 = x[400:], z[400:]
    work = np.sum(0.5 * (z2[1:] + z2[:-1]) * np.diff(x2))  # the elastic part k_se x stores, never dissipates
    assert work >= -1e-9
