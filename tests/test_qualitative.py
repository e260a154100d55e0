"""The paper's qualitative findings (paper-data.toml [qualitative]) as checks on the model's output.

Each finding is a pure check function (data in, (ok, message) out), applied to quasi-static cycles
(u = A sin, the hysteresis carried along the path; A = 0.024 m as in Section 4.3) and, for
Figure 7, also to a short dynamic run at 10 Hz. ``test_checks_can_fail`` feeds the checks the
reversed findings to show that they can fail. A finding the model does not reproduce is an xfail
that states the measured numbers.
"""
from __future__ import annotations

import functools

import numpy as np
import pytest

from nsd_core.device.cycle import loop_area
from nsd_core.device.params import Params
from nsd_core.device.quasistatic import quasi_static_cycle

A = 0.024


@functools.lru_cache(maxsize=None)
def qs(amplitude: float = A, **overrides) -> dict:
    return quasi_static_cycle(Params(**overrides), amplitude)


def qs_(amplitude: float = A, **overrides) -> dict:
    return qs(amplitude, **dict(sorted(overrides.items())))


def energy(c: dict) -> float:
    return loop_area(c["u"], c["F_device"])


# ---------------------------------------------------------------- the checks
def check_figure7(u, k, amplitude) -> tuple[bool, str]:
    """Positive at the origin, a wide nearly constant negative plateau, positive again before A."""
    msg = f"k(0) = {k[0]:.3g} N/m, min k = {k.min():.3g} N/m"
    if not k[0] > 0:
        return False, "stiffness at the origin not positive: " + msg
    neg = np.flatnonzero(k < 0)
    if len(neg) == 0:
        return False, "no negative-stiffness region: " + msg
    plateau = u[k <= 0.8 * k.min()]  # within 20 % of the most negative value
    width = plateau.max() - plateau.min()
    if width < 0.2 * amplitude:
        return False, f"negative region has no plateau (width {width * 1e3:.2f} mm): " + msg
    if not (k[neg[-1] + 1:] > 0).any() or u[neg[-1]] >= amplitude:
        return False, "stiffness does not turn positive again before the amplitude: " + msg
    return True, msg + f", plateau {width * 1e3:.1f} mm wide, positive again from {u[neg[-1] + 1] * 1e3:.1f} mm"


def check_initial_stiffness_sign(rod_lengths, k0) -> tuple[bool, str]:
    """Section 4.3: the initial stiffness is negative exactly for l_d > 0.05 m."""
    msg = ", ".join(f"l_d={l:g}: {k / 1e3:+.1f} kN/m" for l, k in zip(rod_lengths, k0))
    ok = all((k < 0) == (l > 0.05 + 1e-12) for l, k in zip(rod_lengths, k0))
    return ok, msg


def cycle_change(F_a, F_b) -> float:
    """rms difference of two cycles on the same u(t), relative to the rms of the second."""
    return float(np.sqrt(np.mean((F_a - F_b) ** 2)) / np.sqrt(np.mean(F_b ** 2)))


def check_saturation(changes: dict[tuple[float, float], float]) -> tuple[bool, str]:
    """Figure 10: above 7e5 N/m the cycle hardly changes (< 10 %) and much less than at low k_r."""
    items = sorted(changes.items())
    low, high = items[0][1], items[-1][1]
    msg = ", ".join(f"{a:.0e}->{b:.0e}: {100 * c:.1f} %" for (a, b), c in items)
    return high < 0.10 and high < 0.5 * low, msg


def check_increasing(xs, ys) -> tuple[bool, str]:
    msg = ", ".join(f"{x:g}: {y:.3f}" for x, y in zip(xs, ys))
    return bool(np.all(np.diff(ys) > 0)), msg


def check_odd_asymmetric(asym: dict[int, float]) -> tuple[bool, str]:
    """Figure 14: odd n_w breaks the cycle's point symmetry F(-u) = -F(u); even n_w keeps it."""
    msg = ", ".join(f"n_w={n}: {a:.2e}" for n, a in sorted(asym.items()))
    ok = all((a > 0.02) if n % 2 else (a < 1e-6) for n, a in asym.items())
    return ok, msg


def asymmetry(c: dict) -> float:
    """max |F(s) + F(s + 1/2)| / max |F|: zero for a loop symmetric under u -> -u."""
    F = c["F_device"]
    h = (len(F) - 1) // 2
    return float(np.max(np.abs(F[:h] + F[h:2 * h])) / np.max(np.abs(F)))


def check_vertical_wire(max_strain, f_origin, f_origin_nominal) -> tuple[bool, str]:
    """Figure 18: theta = 0 wires never stretch and the cycle pinches at the origin."""
    msg = f"max wire strain {max_strain:.2e}, |F(u=0)| {f_origin:.2e} N (nominal device {f_origin_nominal:.2f} N)"
    return max_strain <= 1e-9 and f_origin < 1e-3 * f_origin_nominal, msg


def check_inclination(e: dict[float, float]) -> tuple[bool, str]:
    """Figure 20: dissipation grows markedly from 6.4 to 16 deg, modestly (>= 0, < 1/3 of it) above."""
    marked, modest = e[16.0] - e[6.4], e[22.4] - e[16.0]
    msg = f"E(6.4) = {e[6.4]:.3f} J, E(16) = {e[16.0]:.3f} J, E(22.4) = {e[22.4]:.3f} J"
    return marked > 0.3 * e[6.4] and 0 <= modest < marked / 3, msg


# ---------------------------------------------------------------- the findings
def test_figure7_regions_quasi_static():
    c = qs_()
    ok, msg = check_figure7(c["loading_u"], c["loading_stiffness"], A)
    assert ok, msg


def test_figure7_regions_dynamic_10hz():
    from nsd_core.device.cycle import loading_quarter
    from nsd_core.device.model import simulate
    from nsd_core.device.drive import Drive
    r = simulate(Params(), Drive(A, 10.0, cycles=2, samples_per_cycle=160), rtol=1e-6, atol=1e-9)
    q = loading_quarter(r, 10.0)
    u, F = r["u"][q], r["F"][q]
    ok, msg = check_figure7(u, np.gradient(F, u), A)
    assert ok, msg


LD_VALUES = [0.04, 0.05, 0.06, 0.08]
# today's initial stiffness [N/m] at those rod lengths (quasi-static, A = 0.01 m, nominal constants)
LD_K0_TODAY = [72150.5, 68754.0, 64268.6, 55835.0]


def test_initial_stiffness_versus_rod_length_is_pinned():
    """Today's numbers, so that a change of the wire law or the geometry shows (1 N/m)."""
    k0 = [qs_(0.01, rod_length=l)["loading_stiffness"][0] for l in LD_VALUES]
    np.testing.assert_allclose(k0, LD_K0_TODAY, atol=1.0)


@pytest.mark.xfail(strict=True, raises=AssertionError,
                   reason="not reproduced by this model: the initial stiffness stays positive for every rod "
                          "length (+72, +69, +64, +56 kN/m at 0.04 ... 0.08 m); with h_wu fixed the wire angle "
                          "falls only to ~6 deg at 0.08 m. Strict: the day it is reproduced this test says so.")
def test_initial_stiffness_negative_above_0p05():
    k0 = [qs_(0.01, rod_length=l)["loading_stiffness"][0] for l in LD_VALUES]
    ok, msg = check_initial_stiffness_sign(LD_VALUES, k0)
    assert ok, msg


def test_rope_stiffness_saturates_above_7e5():
    F = {k: qs_(rope_stiffness=k)["F_device"] for k in (3e5, 5e5, 7e5, 9e5)}
    changes = {(3e5, 5e5): cycle_change(F[5e5], F[3e5]), (7e5, 9e5): cycle_change(F[9e5], F[7e5])}
    ok, msg = check_saturation(changes)
    assert ok, msg


def test_thicker_wires_dissipate_more():
    ds = [0.0012, 0.0016, 0.0020, 0.0024]
    ok, msg = check_increasing(ds, [energy(qs_(wire_diameter=d)) for d in ds])
    assert ok, msg


def test_odd_wire_count_breaks_symmetry():
    ok, msg = check_odd_asymmetric({n: asymmetry(qs_(n_wires=n)) for n in (3, 4, 5, 6)})
    assert ok, msg


def test_vertical_wire_does_not_stretch_and_pinches():
    c, nom = qs_(wire_inclination_deg=0.0), qs_()
    at_origin = np.abs(c["u"]) < 1e-12

    def f0(cc):
        return float(np.max(np.abs(cc["F_device"][np.abs(cc["u"]) < 1e-12])))
    assert at_origin.sum() >= 2  # both branches cross u = 0
    ok, msg = check_vertical_wire(float(np.max(c["wire_strain"])), f0(c), f0(nom))
    assert ok, msg


def test_dissipation_against_inclination():
    ok, msg = check_inclination({t: energy(qs_(wire_inclination_deg=t)) for t in (6.4, 16.0, 22.4)})
    assert ok, msg


# ---------------------------------------------------------------- the checks can fail
def test_checks_can_fail():
    # thicker wires dissipating *less*: the reversed ordering must be rejected
    ds = [0.0012, 0.0016, 0.0020, 0.0024]
    e = [energy(qs_(wire_diameter=d)) for d in ds]
    assert check_increasing(ds, e)[0] and not check_increasing(ds, e[::-1])[0]
    # even counts asymmetric, odd symmetric
    asym = {n: asymmetry(qs_(n_wires=n)) for n in (3, 4)}
    assert not check_odd_asymmetric({3: asym[4], 4: asym[3]})[0]
    # dissipation growing modestly to 16 deg and markedly above
    th = {t: energy(qs_(wire_inclination_deg=t)) for t in (6.4, 16.0, 22.4)}
    assert not check_inclination({6.4: th[6.4], 16.0: th[6.4] + (th[22.4] - th[16.0]), 22.4: th[22.4]})[0]
    # no saturation: the cycle changing as much at high k_r as at low k_r
    assert not check_saturation({(3e5, 5e5): 0.16, (7e5, 9e5): 0.15})[0]
    # Figure 7 on a device without wires (theta = 0): no positive stiffness at the origin
    c = qs_(wire_inclination_deg=0.0)
    assert not check_figure7(c["loading_u"], c["loading_stiffness"], A)[0]
    # a stretched, unpinched wire
    assert not check_vertical_wire(0.01, 16.0, 16.0)[0]
    # initial stiffness: the expected pattern passes the check
    assert check_initial_stiffness_sign([0.04, 0.06], [1e4, -1e4])[0]
