"""The device's symmetries in the plane (nsd-model.md "Two-dimensional drive paths"):
with n_w = n_r = 4 (a square) a drive along 90 deg repeats the one along 0 deg and 180 deg mirrors
it; with 8, 45 deg repeats 0 deg; on a circle at constant speed the force's magnitude is constant
up to the pattern's residual anisotropy (only harmonics of order n over a turn). In-house, then a cheap check in MuJoCo and Exudyn."""
import math

import numpy as np
import pytest

from nsd_core.device.cycle import steady_cycle
from nsd_core.device.drive import Drive
from nsd_core.device.model import simulate
from nsd_core.device.params import Params

P4, P8 = Params(), Params().replace(n_wires=8, n_ropes=8)


def _rotate(F, deg):
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    return np.column_stack([c * F[:, 0] - s * F[:, 1], s * F[:, 0] + c * F[:, 1]])


def _F(r):
    return np.column_stack([r["F_x"], r["F_y"]])


def _check_rotation(run, params, psi, rel):
    """run(params, drive) along 0 and along psi: the force vector turns with the drive."""
    a = run(params, Drive(0.015, 10.0, 0.0, cycles=1, samples_per_cycle=200))
    b = run(params, Drive(0.015, 10.0, psi, cycles=1, samples_per_cycle=200))
    scale = np.max(np.abs(_F(a)))
    return np.max(np.abs(_F(b) - _rotate(_F(a), psi))) / scale


def _in_house(params, drive):
    return simulate(params, drive)


@pytest.mark.parametrize("params, psi", [(P4, 90.0), (P4, 180.0), (P4, 270.0), (P8, 45.0)])
def test_in_house_symmetries(params, psi):
    # the same equations in a rotated frame: equal to the integrator's tolerance (rtol 1e-7)
    assert _check_rotation(_in_house, params, psi, 0) < 1e-6


def test_in_house_four_fold_device_is_not_isotropic():
    """45 deg differs from 0 deg for the square pattern, so the tests above can fail (issue: 11 %)."""
    assert _check_rotation(_in_house, P4, 45.0, 0) > 0.05


# Residual anisotropy of |F| on a constant-speed circle (A = 15 mm, 10 Hz, steady third cycle), measured
# on the in-house model: (max - min)/mean |F| = 0.0706 for n = 8, 0.1155 for n = 4, 0.1439 for n = 3,
# 0.0816 for n = 6 (the same to 4e-3 at 1 Hz: it is the pattern, not inertia). It is the discrete
# wire pattern itself: its spectrum over one turn holds only harmonics of order n, 2n, ...
ANISOTROPY_8, MARGIN = 0.0706, 1.1


def _circle_magnitude(params):
    d = Drive(0.015, 10.0, cycles=3, samples_per_cycle=400, path="circle")
    r = simulate(params, d)
    return np.linalg.norm(_F(r)[steady_cycle(r, d.frequency)], axis=1)[:-1]  # one turn, end point dropped


def test_circle_force_magnitude_has_only_the_patterns_harmonics():
    for params, n in ((P8, 8), (P4, 4)):
        mag = _circle_magnitude(params)
        H = np.abs(np.fft.rfft(mag)) / len(mag) * 2
        order = np.arange(len(H))
        foreign = (order > 0) & (order % n != 0) & (order <= 40)
        assert np.max(H[foreign]) < 1e-3 * mag.mean()  # measured <= 0.2 N of ~1100 N
        if n == 8:
            assert (mag.max() - mag.min()) / mag.mean() <= MARGIN * ANISOTROPY_8
            assert H[8] > 0.01 * mag.mean()  # the 8-fold ripple is real, not numerical noise


def _mujoco(params, drive):
    from comparisons.engines.peers import MujocoEngine
    return MujocoEngine().run(params, drive)


def _exudyn(params, drive):
    from comparisons.engines.peers import ExudynEngine
    return ExudynEngine().run(params, drive, {"builder_forces": "compiled"})


@pytest.mark.parametrize("run, psi", [(_mujoco, 90.0), (_mujoco, 180.0), (_exudyn, 90.0)])
def test_other_engines_symmetries(run, psi):
    # each engine against itself: its step-size error is the same in a rotated frame, up to round-off.
    # Exudyn with its forces in every Newton iteration: its once-a-step "predicted" forces leave a one-sample
    # spike of the drive force at a turnaround along X (1.6e-5 of the peak at 5e-6 s; the states agree)
    assert _check_rotation(run, P4, psi, 0) < 1e-5
