"""The shared force laws against closed forms written here from the equations alone.

``nsd_core.forces`` is the one implementation every engine calls, so the engines cannot disagree
about it: a swapped or mis-signed constant there passes the cross-validation gate. These tests
check it by means that share no code with it:

- Bouc-Wen spring (Eq. 18b) with n_s = 1 is linear in zeta on each branch, so its exact solution is
  a piecewise exponential: on a branch where sgn(zeta dx) = s, d zeta/dx = k_sd - (gamma + s beta)
  |zeta| and zeta approaches k_sd/(gamma + s beta) (s = +1) or runs away from / towards the other
  fixed point (s = -1) exponentially. A load-unload-reload cycle visits both signs, so beta and
  gamma are told apart (swapped, the s = -1 branch has rate gamma - beta instead of beta - gamma).
- SMA wire (Eq. 17): three limits with closed forms: the elastic start (slope E at rest), the
  martensitic branch beyond eps_t (slope E_m), and the superelastic plateaus. On a monotonic
  branch away from eps = 0 and below eps_t, z = sigma - beta settles where dz/deps = 0:
  |z*| = Y (1 + alpha)^(-1/n), the plateau is sigma = (E alpha eps + z*)/(1 + alpha) on loading and
  sigma = (E alpha (eps + f_T) - z*)/(1 + alpha) on unloading (H(-eps deps) = 1, tanh(a eps) = 1),
  both with slope E alpha/(1 + alpha).
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from nsd_core.device.forces import SpringLaw, WireLaw, advance_spring_zeta, advance_wire_stress, sma_stress_slope
from nsd_core.device.params import Params

P = Params()
KSD, BETA, GAMMA = P.spring_ksd, P.spring_beta, P.spring_gamma


def exact_zeta(x_path: np.ndarray, zeta0: float, ksd=KSD, beta=BETA, gamma=GAMMA) -> np.ndarray:
    """Eq. 18b with n_s = 1, solved exactly along a piecewise-monotonic path x_path (compression).

    On a monotonic stretch with direction d = +-1, write y = d zeta (y >= 0 when zeta dx >= 0).
    Then dy/dX = k_sd - (gamma + beta) y for y >= 0 and dy/dX = k_sd - (beta - gamma) y for y < 0,
    X the distance travelled; both linear: y(X) = y_inf + (y0 - y_inf) exp(-r X), y_inf = k_sd/r.
    The branch changes where y crosses 0, at X = ln(1 - y0/y_inf)/r, found in closed form.
    """
    out = np.empty(len(x_path))
    zeta = zeta0
    out[0] = zeta
    for k in range(1, len(x_path)):
        dx = x_path[k] - x_path[k - 1]
        d = 1.0 if dx >= 0 else -1.0
        y, X = d * zeta, abs(dx)
        if y < 0:   # the s = -1 branch until y reaches 0 (it always grows: dy/dX >= k_sd there)
            r = beta - gamma
            y_inf = ksd / r
            X0 = math.log(1.0 - y / y_inf) / r if r != 0 else -y / ksd  # distance to y = 0
            if X < X0:
                y = y_inf + (y - y_inf) * math.exp(-r * X) if r != 0 else y + ksd * X
                X = 0.0
            else:
                y, X = 0.0, X - X0
        if X > 0:   # the s = +1 branch: exponential approach to k_sd/(beta + gamma)
            r = gamma + beta
            y = ksd / r + (y - ksd / r) * math.exp(-r * X)
        zeta = d * y
        out[k] = zeta
    return out


def spring_law(beta=BETA, gamma=GAMMA) -> SpringLaw:
    return SpringLaw(P.spring_kse, KSD, beta, gamma, 1.0, 0.0)


def _shared_zeta(x_path, zeta0, law):
    z = [zeta0]
    for a, b in zip(x_path[:-1], x_path[1:]):
        z.append(float(advance_spring_zeta(a, b, z[-1], law, substeps=4)))
    return np.array(z)


# load to 8 mm, unload to -6 mm, reload to 4 mm: both branches of both directions
CYCLE = np.concatenate([np.linspace(0, 8e-3, 801), np.linspace(8e-3, -6e-3, 1401)[1:],
                        np.linspace(-6e-3, 4e-3, 1001)[1:]])


def test_bouc_wen_matches_its_exact_piecewise_solution_on_a_load_unload_cycle():
    exact = exact_zeta(CYCLE, 0.0)
    shared = _shared_zeta(CYCLE, 0.0, spring_law())
    bound = KSD / (BETA + GAMMA)
    assert np.max(np.abs(shared - exact)) < 1e-6 * bound   # RK4 in 10 um steps: 2.8e-8 measured
    # the cycle really visits the s = -1 branch (zeta and dx of opposite signs) for a long stretch
    opposite = (exact[1:] * np.diff(CYCLE)) < 0
    assert opposite.sum() > 200


def test_bouc_wen_with_beta_and_gamma_swapped_is_told_apart():
    """The check above fails for a law with beta and gamma swapped (the error the gate cannot see)."""
    exact = exact_zeta(CYCLE, 0.0)
    swapped = _shared_zeta(CYCLE, 0.0, spring_law(beta=GAMMA, gamma=BETA))
    assert np.max(np.abs(swapped - exact)) > 1e-2 * KSD / (BETA + GAMMA)


def test_precompressed_rest_state_is_the_exact_monotonic_loading():
    from nsd_core.device.forces import precompressed_spring
    x_pre, zeta0 = precompressed_spring(P.spring_kse, KSD, BETA, GAMMA, 1.0, P.precompression_force)
    z = KSD / (BETA + GAMMA) * (1 - math.exp(-(BETA + GAMMA) * x_pre))   # loading from rest, s = +1
    assert zeta0 == pytest.approx(z, rel=1e-12)
    assert P.spring_kse * x_pre + zeta0 == pytest.approx(P.precompression_force, rel=1e-12)


# ------------------------------------------------------------------------------------ SMA wire
def wire_law(**kw) -> WireLaw:
    v = dict(E=P.wire_E, Y=P.wire_Y, alpha=P.wire_alpha, n=P.wire_n, fT=P.wire_fT, a=P.wire_a,
             Em=P.wire_Em, eps_t=P.wire_eps_t, c=P.wire_c, area=1.0, natural_length=1.0)
    v.update(kw)
    return WireLaw(**v)


def stress_path(eps_path, law, substeps=2):
    s = [0.0]
    for a, b in zip(eps_path[:-1], eps_path[1:]):
        s.append(float(advance_wire_stress(a, b, s[-1], law, substeps)))
    return np.array(s)


def plateaus(eps, law_values=P):
    """The closed-form superelastic plateaus (module docstring) at strain eps > 0, eps << eps_t."""
    E, Y, al, n, fT = law_values.wire_E, law_values.wire_Y, law_values.wire_alpha, law_values.wire_n, law_values.wire_fT
    z = Y * (1 + al) ** (-1 / n)
    return (E * al * eps + z) / (1 + al), (E * al * (eps + fT) - z) / (1 + al)


def test_sma_elastic_start_slope_is_E():
    law = wire_law()
    for d in (1.0, -1.0):
        assert float(sma_stress_slope(0.0, d, 0.0, law)) == pytest.approx(P.wire_E, rel=1e-9)
    # small strain from rest: sigma = E eps to first order; the first departure is (eps E/Y)^n
    s = stress_path(np.linspace(0, 1e-4, 11), law, 8)[-1]
    assert s == pytest.approx(P.wire_E * 1e-4, rel=1e-3)


def test_sma_martensitic_branch_beyond_eps_t_has_slope_Em():
    law = wire_law()
    eps = np.linspace(0, 0.12, 2401)
    s = stress_path(eps, law)
    k = np.gradient(s, eps)
    beyond = eps > P.wire_eps_t + 5 / P.wire_c   # s(eps) = (tanh(c(eps - eps_t)) + 1)/2 > 0.99995
    np.testing.assert_allclose(k[beyond][1:-1], P.wire_Em, rtol=1e-3)


def test_sma_superelastic_plateaus_match_their_closed_forms():
    """Load 0 -> 6 %, unload 6 % -> 1 %: the nominal constants give the flag-shaped loop."""
    law = wire_law()
    up = np.linspace(0.0, 0.06, 1201)
    down = np.linspace(0.06, 0.01, 1001)
    s_up = stress_path(up, law)
    s = [s_up[-1]]   # unload from the loaded state
    for a, b in zip(down[:-1], down[1:]):
        s.append(float(advance_wire_stress(a, b, s[-1], law, 2)))
    s_dn = np.array(s)
    for eps in (0.03, 0.045, 0.06):
        load, _ = plateaus(eps)
        assert np.interp(eps, up, s_up) == pytest.approx(load, rel=5e-4)   # 1.3e-4 measured
    for eps in (0.02, 0.03):
        _, unload = plateaus(eps)
        assert np.interp(eps, down[::-1], s_dn[::-1]) == pytest.approx(unload, rel=5e-3)
    # the nominal loop's plateaus at 6 %: about 472 MPa loading and 227 MPa unloading
    assert 4.6e8 < s_up[-1] < 4.8e8


@pytest.mark.parametrize("bad", [dict(fT=-P.wire_fT), dict(E=P.wire_Em, Em=P.wire_E),
                                 dict(alpha=2 * P.wire_alpha), dict(Y=0.8 * P.wire_Y)])
def test_sma_with_a_wrong_constant_misses_the_closed_forms(bad):
    """f_T sign flipped, E and E_m swapped, alpha or Y wrong: at least one closed form fails."""
    law = wire_law(**bad)
    up = np.linspace(0.0, 0.06, 1201)
    s = [0.0]
    for a, b in zip(up[:-1], up[1:]):
        s.append(float(advance_wire_stress(a, b, s[-1], law, 2)))
    down = np.linspace(0.06, 0.02, 801)
    for a, b in zip(down[:-1], down[1:]):
        s.append(float(advance_wire_stress(a, b, s[-1], law, 2)))
    load, unload = plateaus(0.06)[0], plateaus(0.02)[1]
    start = float(sma_stress_slope(0.0, 1.0, 0.0, law))
    misses = [abs(start / P.wire_E - 1) > 1e-3, abs(s[1200] / load - 1) > 2e-3, abs(s[-1] / unload - 1) > 5e-3]
    assert any(misses)
