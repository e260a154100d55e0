"""The baseline isolators' hysteretic force law, written once and called by every engine.

A lead-rubber bearing (bilinear) and a friction pendulum are both a linear spring k_d in parallel
with a hysteretic force of strength Q acting along a dimensionless vector z (|z| <= 1):

    F_on_plate = -(k_d u + c u' + Q(|u'|) z)
    D_y z' = u' - H(z . u') |z|^(n - 2) (z . u') z        (bidirectional; Park, Wen and Ang 1986)

with H the unit step. Why this form: unloading (z . u' < 0) is exactly elastic (z' = u'/D_y, the
initial stiffness Q/D_y), loading saturates |z| -> 1 smoothly, so an adaptive step-size controller
sees a force with a continuous slope; as n grows the loop tends to the ideal bilinear one (n = 2 is
Park-Wen's beta = gamma = 1/2; the default n is in nsd_core.structure.isolators). In one direction the
loading branch is z' = u'(1 - |z|^n) / D_y.

* bilinear (lead-rubber): Q = Q_d, D_y the yield displacement, k_d the post-yield stiffness;
* friction pendulum: k_d = W / R (the spherical surface's restoring stiffness), Q = mu W with a
  small D_y (the sliding interface's elastic pre-slip) and, optionally, Constantinou et al.'s (1990)
  velocity dependence mu(v) = mu_fast - (mu_fast - mu_slow) exp(-a |v|) (a = 0: constant mu).

The in-house engine integrates z with the motion (two extra states); a peer that steps explicitly
advances z along each step's displacement change with ``advance_hysteresis`` (the law is rate
independent: z depends on the path of u, not on its speed).
"""
from __future__ import annotations

import math

from numba import njit

from nsd_core.model.laws import PLANE, Law, LawParameter, StateSpec, register


@njit(cache=True, _nrt=False)
def hysteretic_force_scalar(vx, vy, zx, zy, q_fast, q_slow, rate, yield_disp, exponent):
    """The hysteretic part at velocity (vx, vy) [m/s] and state (zx, zy) [-].

    Returns (F_x, F_y, z_x', z_y', power): (F_x, F_y) = Q z [N], the plate's push on the isolator
    (the isolator's force on the plate is its negative); z' [1/s] by the law above; power = Q z . v
    [W], the work rate of the hysteretic part (stored in its elastic range, dissipated beyond)."""
    q = q_fast - (q_fast - q_slow) * math.exp(-rate * math.hypot(vx, vy))
    zv = zx * vx + zy * vy
    dzx, dzy = vx, vy
    if zv > 0.0:
        s = (zx * zx + zy * zy) ** (0.5 * exponent - 1.0) * zv
        dzx -= s * zx
        dzy -= s * zy
    return q * zx, q * zy, dzx / yield_disp, dzy / yield_disp, q * zv


@njit(cache=True, _nrt=False)
def advance_hysteresis(dux, duy, zx, zy, yield_disp, exponent, substeps):
    """z after the displacement change (dux, duy) [m], by the midpoint rule in ``substeps`` equal
    parts of it (the law is rate independent: the change itself plays the velocity's part)."""
    hx, hy = dux / substeps, duy / substeps
    for _ in range(substeps):
        _, _, ax, ay, _ = hysteretic_force_scalar(hx, hy, zx, zy, 0.0, 0.0, 0.0, yield_disp, exponent)
        mx, my = zx + 0.5 * ax, zy + 0.5 * ay
        _, _, bx, by, _ = hysteretic_force_scalar(hx, hy, mx, my, 0.0, 0.0, 0.0, yield_disp, exponent)
        zx, zy = zx + bx, zy + by
    return zx, zy


# ---- the registry's plane law (nsd_core.model.laws): the hysteresis above on two slide coordinates -------
# p: strength, strength_at_rest, rate, yield_displacement, exponent, initial_zx, initial_zy

@njit(cache=True, _nrt=False)
def bidirectional_hysteresis_force(x, y, xd, yd, sx, sy, p):
    """(Q_x, Q_y) = -Q(|u'|) z [N]: the hysteretic part of a lead-rubber bearing or a friction pendulum
    on the displacement u = (x, y), z = (s_x, s_y) its state (hysteretic_force_scalar)."""
    fx, fy, _, _, _ = hysteretic_force_scalar(xd, yd, sx, sy, p[0], p[1], p[2], p[3], p[4])
    return -fx, -fy


@njit(cache=True, _nrt=False)
def bidirectional_hysteresis_rate(x, y, xd, yd, sx, sy, p):
    """z' = (u' - H(z . u') |z|^(n - 2) (z . u') z) / D_y [1/s] (Park, Wen and Ang 1986)."""
    _, _, dzx, dzy, _ = hysteretic_force_scalar(xd, yd, sx, sy, p[0], p[1], p[2], p[3], p[4])
    return dzx, dzy


register(Law("bidirectional_hysteresis", PLANE, (
    LawParameter("strength", "N", 0.0, doc="Q at high velocity (Q_d; mu_fast W)"),
    LawParameter("strength_at_rest", "N", 0.0, doc="Q at rest (= strength for a bilinear bearing; mu_slow W)"),
    LawParameter("rate", "s/m", 0.0, default=0.0, doc="a of mu(v) = mu_fast - (mu_fast - mu_slow) exp(-a |v|)"),
    LawParameter("yield_displacement", "m", 1e-12, doc="D_y"),
    LawParameter("exponent", "-", 2.0, 50.0, doc="n"),
    LawParameter("initial_zx", "-", -1.0, 1.0, default=0.0), LawParameter("initial_zy", "-", -1.0, 1.0, default=0.0)),
    bidirectional_hysteresis_force,
    "The baseline isolators' hysteretic part (a lead-rubber bearing: Q = Q_d; a friction pendulum: Q = mu W; "
    "Park, Wen and Ang 1986, evaluated by hysteretic_force_scalar of this module): on the "
    "planar displacement u = (x, y) [m], (Q_x, Q_y) = -Q(|u'|) z [N], D_y z' = u' - H(z . u') |z|^(n-2) "
    "(z . u') z [1/s], Q(v) = Q_fast - (Q_fast - Q_rest) exp(-a v) [N] (a [s/m]; a = 0: Q = Q_rest). A plane "
    "law because z couples the two directions (z_x' depends on z_y and y'): two scalar joint laws cannot "
    "express it",
    StateSpec("z", "-", "initial_zx,initial_zy"), bidirectional_hysteresis_rate))
