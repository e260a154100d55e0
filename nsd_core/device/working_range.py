"""X_max, where the working range ends: the ropes go slack on monotonic loading from rest.

(The model document, "Working range".)
Two evaluations of the same quasi-static definition:

* ``path``: ``nsd_core.device.quasistatic.x_max``, which steps the whole quasi-static path (seconds per
  entry; its step adds an error of about 0.01 mm);
* ``slack`` (default): the same point found directly. Moving the wall's height z_w moves cap, rod
  and wall together, so the wires never enter the vertical equilibrium, and at the slack point the
  ropes pull nothing: the spring's push equals the carried weight W there. Along the monotonic
  path the spring only extends, so its hysteretic force is one ODE in the extension, integrated
  from the precompressed state to P = W; that fixes z_w, and the slack condition (longest rope at
  its natural length) then fixes u. Milliseconds per entry, which makes the calibration
  (``nsd_core.study.calibrate``) affordable; tests check it against ``path``.
"""
from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from nsd_core.device.forces import bouc_wen_slope
from nsd_core.device.geometry import device_geometry
from nsd_core.device.params import ParameterError, Params


class SlackPointError(ValueError):
    """The ropes never go slack before the rod lies flat: X_max does not exist for this design."""


def spring_extension_at_slack(p: Params, g=None) -> tuple[float, float]:
    """(compression x*, hysteretic force zeta*) where the extending spring's push falls to W.

    s is the extension from the precompressed state (the compression falls: Eq. 18b with
    dx_s < 0). For n_s = 1, dzeta/ds = -k_sd + c zeta with c = gamma - beta while zeta > 0 and
    c = -(beta + gamma) once zeta < 0: exponentials, solved in closed form; other n_s by an ODE.
    """
    g = g or device_geometry(p)
    sp, W = g.spring, p.carried_weight
    x0, z0 = g.spring_precompression, g.spring_zeta0
    if sp.n == 1.0:
        def piece(c, s_a, z_a):
            if abs(c) < 1e-12:
                return lambda s: z_a - sp.ksd * (s - s_a)
            return lambda s: sp.ksd / c + (z_a - sp.ksd / c) * math.exp(c * (s - s_a))
        c1, c2 = sp.gamma - sp.beta, -(sp.beta + sp.gamma)
        zeta_a = piece(c1, 0.0, z0)
        if z0 <= 0.0:
            s1 = 0.0
        elif abs(c1) < 1e-12:
            s1 = z0 / sp.ksd
        elif sp.ksd - c1 * z0 > 0.0:
            s1 = math.log(sp.ksd / (sp.ksd - c1 * z0)) / c1
        else:  # zeta grows without bound while it is positive: outside the law's validity
            raise SlackPointError("the spring's hysteretic force never reverses (k_sd <= (gamma - beta) zeta_0)")
        if sp.kse * (x0 - s1) - W <= 0.0:  # the push reaches W while zeta is still positive
            s = brentq(lambda s: sp.kse * (x0 - s) + zeta_a(s) - W, 0.0, s1, xtol=1e-16, rtol=1e-15)
            return x0 - s, zeta_a(s)
        zeta_b = piece(c2, s1, 0.0)
        hi = max(x0, s1) + W / sp.kse  # there the push is below W for sure (zeta_b < 0)
        s = brentq(lambda s: sp.kse * (x0 - s) + zeta_b(s) - W, s1, hi, xtol=1e-16, rtol=1e-15)
        return x0 - s, zeta_b(s)

    def rhs(s, y):
        return [-float(bouc_wen_slope(y[0], -1.0, sp))]

    def push_is_weight(s, y):
        return sp.kse * (x0 - s) + y[0] - W
    push_is_weight.terminal, push_is_weight.direction = True, -1
    sol = solve_ivp(rhs, (0.0, x0 + sp.free_length), [z0], method="DOP853", events=push_is_weight,
                    rtol=1e-11, atol=1e-9, max_step=x0 / 50.0)
    if not len(sol.t_events[0]):
        raise SlackPointError("the spring's push never falls to the carried weight")
    s = float(sol.t_events[0][0])
    return x0 - s, float(sol.y_events[0][0][0])


def x_max_at_slack(p: Params, direction_deg: float = 0.0) -> float:
    """X_max [m] by the direct slack-point construction (see the module docstring)."""
    g = device_geometry(p)
    x_star, _ = spring_extension_at_slack(p, g)
    z_w = g.spring.free_length - x_star
    e = np.array([math.cos(math.radians(direction_deg)), math.sin(math.radians(direction_deg)), 0.0])
    l_d = p.rod_length

    def stretch(u):  # longest rope's stretch with the wall at z_w and the plate at u (u: array)
        u = np.atleast_1d(u)
        cap = u[:, None] * e + np.column_stack([0 * u, 0 * u, z_w + np.sqrt(l_d ** 2 - u * u)])
        d = g.element_vectors(cap, z_w)[0]
        return np.max(np.linalg.norm(d, axis=2) - g.rope_natural_length[None], axis=1)

    us = np.linspace(0.0, 0.999 * l_d, 400)
    slack = np.flatnonzero(stretch(us) <= 0.0)
    if len(slack) == 0 or slack[0] == 0:
        raise SlackPointError(f"no slack point for rod_length = {l_d}")
    k = slack[0]
    return float(brentq(lambda u: float(stretch(u)[0]), us[k - 1], us[k], xtol=1e-13))


def model_x_max(p: Params, method: str = "slack", step: float = 2e-5) -> float:
    if method == "slack":
        return x_max_at_slack(p)
    if method == "path":
        from nsd_core.device.quasistatic import x_max
        return x_max(p, step=step)
    raise ParameterError(f"method = {method!r}: allowed: slack, path")
