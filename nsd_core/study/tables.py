"""The paper's Tables 5 and 6 (maximum horizontal displacement X_max against the rod length and the
precompression force) next to the model, entry by entry.

X_max is where the ropes go slack on monotonic loading from rest (nsd-model.md, "Working range").
Two evaluations of the same quasi-static definition:

* ``path``: ``nsd_core.quasistatic.x_max``, which steps the whole quasi-static path (seconds per
  entry; its step adds an error of about 0.01 mm);
* ``slack`` (default): the same point found directly. Moving the wall's height z_w moves cap, rod
  and wall together, so the wires never enter the vertical equilibrium, and at the slack point the
  ropes pull nothing: the spring's push equals the carried weight W there. Along the monotonic
  path the spring only extends, so its hysteretic force is one ODE in the extension, integrated
  from the precompressed state to P = W; that fixes z_w, and the slack condition (longest rope at
  its natural length) then fixes u. Milliseconds per entry, which makes the calibration
  (``nsd_core.calibrate``) affordable; tests check it against ``path``.

theta_max = asin(X_max / l_d) is the rod's rotation from the vertical at X_max (Table 5's note:
x_max = l_d sin(theta_max) holds to 4 digits in every column).
"""
from __future__ import annotations

import math
from concurrent.futures import ProcessPoolExecutor

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from nsd_core.device.forces import bouc_wen_slope
from nsd_core.device.geometry import device_geometry
from nsd_core.device.params import ParameterError, Params
from nsd_core.device.results import atomic_write_text

# Transcribed from the paper (paper-data.toml [table5], [table6]); tests compare with that file.
TABLE5 = {"where": "Table 5", "parameter": "rod_length", "unit": "m",
          "values": [0.03, 0.04, 0.05, 0.06, 0.07, 0.08, 0.09, 0.10],
          "x_max": [0.0255, 0.0315, 0.0372, 0.0427, 0.0481, 0.0533, 0.0585, 0.0635],
          "theta_max_deg": [58.21, 52.04, 48.14, 45.40, 43.37, 41.79, 40.51, 39.44]}
TABLE6 = {"where": "Table 6", "parameter": "precompression_force", "unit": "N",
          "values": [2400.0, 2600.0, 2800.0, 3000.0, 3200.0, 3400.0, 3600.0, 3800.0],
          "x_max": [0.0208, 0.0216, 0.0224, 0.0231, 0.0238, 0.0244, 0.0249, 0.0255]}
TABLES = {"5": TABLE5, "6": TABLE6}
GOAL_MM = 0.3  # the target for every entry
CSV_HEADER = ("table,parameter,value,unit,paper_x_max [m],model_x_max [m],difference [mm],"
              "paper_theta_max [deg],model_theta_max [deg],theta_difference [deg],method")


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


def _entry(args):
    p, method, step = args
    return model_x_max(p, method, step)


def table_rows(base: Params | None = None, method: str = "slack", step: float = 2e-5,
               workers: int = 1, tables: tuple[str, ...] = ("5", "6")) -> list[dict]:
    """One row per entry of Tables 5 and 6: the paper's X_max, the model's and the difference."""
    base = base or Params()
    jobs, meta = [], []
    for t in tables:
        spec = TABLES[t]
        for i, v in enumerate(spec["values"]):
            jobs.append((base.replace(**{spec["parameter"]: v}), method, step))
            meta.append((t, spec, i, v))
    if workers > 1 and method == "path":  # the path method costs seconds per entry: spread them
        with ProcessPoolExecutor(max_workers=workers) as ex:
            xs = list(ex.map(_entry, jobs))
    else:
        xs = [_entry(j) for j in jobs]
    rows = []
    for (t, spec, i, v), (p, _, _), xm in zip(meta, jobs, xs):
        paper = spec["x_max"][i]
        row = {"table": t, "parameter": spec["parameter"], "value": v, "unit": spec["unit"],
               "paper_x_max": paper, "model_x_max": xm, "difference_mm": (xm - paper) * 1e3,
               "paper_theta_max_deg": None, "model_theta_max_deg": math.degrees(math.asin(xm / p.rod_length)),
               "theta_difference_deg": None, "method": method}
        if "theta_max_deg" in spec:
            row["paper_theta_max_deg"] = spec["theta_max_deg"][i]
            row["theta_difference_deg"] = row["model_theta_max_deg"] - row["paper_theta_max_deg"]
        rows.append(row)
    return rows


def rows_csv(rows: list[dict]) -> str:
    def f(v, fmt):
        return "" if v is None else format(v, fmt)
    lines = [CSV_HEADER]
    for r in rows:
        lines.append(",".join([f"Table {r['table']}", r["parameter"], f(r["value"], "g"), r["unit"],
                               f(r["paper_x_max"], ".4f"), f(r["model_x_max"], ".6f"),
                               f(r["difference_mm"], "+.4f"), f(r["paper_theta_max_deg"], ".2f"),
                               f(r["model_theta_max_deg"], ".3f"), f(r["theta_difference_deg"], "+.3f"),
                               r["method"]]))
    return "\n".join(lines) + "\n"


def write_csv(path, rows: list[dict]) -> None:
    atomic_write_text(path, rows_csv(rows))


def format_rows(rows: list[dict]) -> str:
    """The printed comparison, one line per entry, and the worst difference against the goal."""
    out = []
    for t in sorted({r["table"] for r in rows}):
        sub = [r for r in rows if r["table"] == t]
        unit = sub[0]["unit"]
        head = f"Table {t}: X_max against {sub[0]['parameter']} [{unit}] (method: {sub[0]['method']})"
        out.append(head)
        out.append(f"  {'value':>8}  {'paper [mm]':>10}  {'model [mm]':>10}  {'diff [mm]':>9}"
                   + ("  theta paper/model [deg]" if t == "5" else ""))
        for r in sub:
            line = (f"  {r['value']:>8g}  {r['paper_x_max'] * 1e3:>10.2f}  {r['model_x_max'] * 1e3:>10.3f}"
                    f"  {r['difference_mm']:>+9.3f}")
            if r["paper_theta_max_deg"] is not None:
                line += f"  {r['paper_theta_max_deg']:.2f} / {r['model_theta_max_deg']:.2f}"
            out.append(line)
    worst = max(rows, key=lambda r: abs(r["difference_mm"]))
    ok = abs(worst["difference_mm"]) <= GOAL_MM
    out.append(f"worst |difference| = {abs(worst['difference_mm']):.3f} mm (Table {worst['table']}, "
               f"{worst['parameter']} = {worst['value']:g}); goal {GOAL_MM} mm: {'met' if ok else 'NOT met'}")
    return "\n".join(out)
