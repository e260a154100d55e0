"""OpenSees as a peer of the in-house engine on the baseline isolators (a lead-rubber bearing, a friction
pendulum) and the building above them: ``nsd seismic --isolator bilinear|friction-pendulum --engines
semirecursive,opensees``. The model is built by comparisons.builders.opensees from the structure
(Structure, Isolator, Building) the in-house run integrates; the columns are the in-house run's names.

Judged by the gate's per-run rule (comparisons.verdict): OpenSees runs at its step h and at h/2 (its
own Richardson estimate, order 1: the bearing's hysteretic state is advanced by backward Euler), the
in-house engine at the gate's converged settings (the reference) and at its check settings (the
reference's own error); "consistent" when OpenSees's difference from the reference is within k x
(its estimate + the reference's error), "accurate enough" when that error is within the engineering
tolerance (comparisons/tolerances.toml).
"""
from __future__ import annotations

import numpy as np

from nsd_core.device.columns import units_of
from nsd_core.device.params import ParameterError
from nsd_core.device.results import RunResult
from nsd_core.structure.seismic import output_times

NAME = "opensees"
ORDER = 1.0   # the bearing's backward-Euler state: first order in the step (measured: docs/seismic.md)
# the step per isolator [s]: its estimated error is below the engineering tolerance on the records measured
# (docs/seismic.md); a friction pendulum's pre-slip D_y is 13x smaller than the lead-rubber bearing's
DEFAULT_STEP = {"bilinear": 1e-4, "friction-pendulum": 1e-5}
# the isolator's metrics (comparisons.engines.described_isolator.isolator_metrics) -> the gate's names
GATE_NAMES = {"du": "max_du_rel", "dF": "max_dF_device_rel", "da": "max_da_rel"}


def settings_for(structure, settings: dict | None) -> dict:
    """``settings`` over the isolator's default step."""
    from comparisons.builders.opensees import merged_settings
    iso = structure.isolator
    s = {"step": DEFAULT_STEP.get(iso.kind, 1e-4) if iso is not None else 1e-4, **(settings or {})}
    return merged_settings(s)


def run_opensees(structure, ground, duration: float | None = None, dt_out: float = 1e-3,
                 settings: dict | None = None) -> RunResult:
    """The run without the device on ``structure.isolator`` (and its building) in OpenSees, on the
    in-house run's output times."""
    from comparisons.builders.opensees import simulate
    duration = ground.duration if duration is None else float(duration)
    t_out = output_times(duration, dt_out)
    s = settings_for(structure, settings)
    rows, stats = simulate(structure, ground, t_out, s)
    _, _, a_g = ground(t_out)
    cols = {"t": t_out, "x": rows[:, 0], "y": rows[:, 1], "theta": rows[:, 2], "vx": rows[:, 3], "vy": rows[:, 4],
            "ax_abs": rows[:, 5] + a_g[:, 0], "ay_abs": rows[:, 6] + a_g[:, 1],
            "support_Fx": rows[:, 7], "support_Fy": rows[:, 8]}
    if not np.isnan(rows[0, 9]):
        cols.update({"isolator_zx": rows[:, 9], "isolator_zy": rows[:, 10]})
    zero = np.zeros_like(t_out)   # no device: its force is zero, as in the in-house run without it
    cols.update({"device_Fx": zero, "device_Fy": zero, "u": np.hypot(cols["x"], cols["y"]),
                 "base_shear_x": rows[:, 7], "base_shear_y": rows[:, 8]})
    b = structure.building
    if b is not None:
        cols.update(_floors(b, rows, a_g, cols))
    stats.update({"mode": "seismic", "device": False, "isolator": structure.isolator.kind, "model_time": duration})
    return RunResult(NAME, cols, units_of(cols), stats)


def _floors(b, rows: np.ndarray, a_g: np.ndarray, plate: dict) -> dict:
    """The building's columns (docs/building.md): floors relative to the ground, drifts, story shears."""
    out, below, acc = {}, (plate["x"], plate["y"]), []
    for i in range(b.stories):
        c = rows[:, 11 + 6 * i: 17 + 6 * i]
        n = i + 1
        out.update({f"floor{n}_x": c[:, 0], f"floor{n}_y": c[:, 1], f"floor{n}_vx": c[:, 2], f"floor{n}_vy": c[:, 3],
                    f"floor{n}_ax_abs": c[:, 4] + a_g[:, 0], f"floor{n}_ay_abs": c[:, 5] + a_g[:, 1],
                    f"drift{n}_x": c[:, 0] - below[0], f"drift{n}_y": c[:, 1] - below[1]})
        below = (c[:, 0], c[:, 1])
        acc.append((b.masses[i] * out[f"floor{n}_ax_abs"], b.masses[i] * out[f"floor{n}_ay_abs"]))
    for i in range(b.stories):   # the force the floors above story i take from below it: -sum m_j a_abs,j
        out[f"story_shear{i + 1}_x"] = -sum(a[0] for a in acc[i:])
        out[f"story_shear{i + 1}_y"] = -sum(a[1] for a in acc[i:])
    return out


def gate_values(ref, other) -> dict:
    """The gate's seismic metrics of ``other`` against ``ref`` for a run on a baseline isolator: the
    isolator's force in the device force's place (max_dF_device_rel), and the building's when there is one."""
    from comparisons.engines.described_isolator import isolator_metrics
    from comparisons.seismic import building_metrics
    m = isolator_metrics(ref, other)
    out = {GATE_NAMES[k]: m[k] for k in GATE_NAMES}
    out.update({"peak_u_rel": abs(m["peak_displacement"]), "peak_a_rel": abs(m["peak_absolute_acceleration"])})
    if "floor1_x" in ref.columns and "floor1_x" in other.columns:
        b = building_metrics(ref, other)
        out.update({"max_dfloor_rel": b["dfloor"], "max_ddrift_rel": b["ddrift"], "max_dfloor_a_rel": b["dfloor_a"]})
    return out


def _scales(ref) -> dict:
    from comparisons.verdict import seismic_scales
    out = seismic_scales(ref)
    out["max_dF_device_rel"] = (float(np.max(np.hypot(ref["support_Fx"], ref["support_Fy"]))), "N")
    return out


def reference_runs(params, structure, ground, duration=None, dt_out=1e-3) -> tuple:
    """The in-house engine's converged run and its check (comparisons.reference's settings)."""
    from comparisons.reference import CHECK_SETTINGS, CONVERGED_SETTINGS
    from nsd_core.structure.seismic import simulate_seismic
    return tuple(simulate_seismic(params, structure, ground, duration=duration, dt_out=dt_out, device=False, **s)
                 for s in (CONVERGED_SETTINGS, CHECK_SETTINGS))


def judge(params, structure, ground, duration=None, dt_out: float = 1e-3, settings: dict | None = None,
          runs: dict | None = None) -> dict:
    """OpenSees on this run judged by the gate's rule: its runs at h and h/2, the in-house converged
    reference and its check (each computed unless given in ``runs``: keys h, h2, converged, check).
    Returns the differences, the estimates, the verdict (comparisons.verdict) and the runs."""
    from comparisons.tolerance_file import load_tolerances
    from comparisons.estimate import observed_order, richardson_factor, step_ratio
    from comparisons.verdict import case_verdicts, estimate_from_pair
    runs = dict(runs or {})
    s = settings_for(structure, settings)
    if "h" not in runs:
        runs["h"] = run_opensees(structure, ground, duration, dt_out, s)
    if "h2" not in runs:
        runs["h2"] = run_opensees(structure, ground, duration, dt_out, {**s, "step": s["step"] / 2})
    if "converged" not in runs or "check" not in runs:
        runs["converged"], runs["check"] = reference_runs(params, structure, ground, duration, dt_out)
    ref, h, h2 = runs["converged"], runs["h"], runs["h2"]
    rule = load_tolerances().rule
    values, values_h2 = gate_values(ref, h), gate_values(ref, h2)
    ratio = step_ratio(h.stats, h2.stats)
    factor = richardson_factor(ORDER, ratio)
    estimates = estimate_from_pair(gate_values(h2, h), factor, rule.beta)
    ref_error = gate_values(runs["check"], ref)
    evidence = {"order": ORDER, "ratio": ratio, "factor": factor, "setting": "step", "step": h.stats["step"],
                "observed_order": observed_order(values["max_du_rel"], values_h2["max_du_rel"], ratio),
                "primary_error": values["max_du_rel"]}
    rows, verdicts = case_verdicts("run", "seismic", [NAME], {NAME: values}, {NAME: estimates}, ref_error,
                                   _scales(ref), {NAME: evidence}, rule)
    return {"values": values, "estimates": estimates, "reference_error": ref_error, "evidence": evidence,
            "verdict": verdicts[NAME], "rows": rows, "runs": runs}


def check_request(structure, device: bool) -> None:
    """One line when OpenSees cannot run this request (exit 2): it builds the baseline isolators only."""
    if device or structure.isolator is None:
        raise ParameterError("--engines opensees: OpenSees builds the structure on a baseline isolator only "
                             "(--isolator bilinear or friction-pendulum), not the negative-stiffness device")
    if structure.restrainer is not None:
        raise ParameterError("--engines opensees: the displacement restrainer is not built in OpenSees; leave out "
                             "--restrainer")


def judged_entry(params, structure, ground, result, duration=None, dt_out: float = 1e-3,
                 settings: dict | None = None) -> tuple:
    """(OpenSees's run at its step, its summary entry) for ``nsd seismic --engines ...,opensees``: the
    differences from the in-house run ``result`` (as the other peers'), and the verdict of the gate's rule
    against the in-house converged reference (``judge``)."""
    from comparisons.engines.described_isolator import isolator_metrics
    from comparisons.seismic import building_metrics
    j = judge(params, structure, ground, duration, dt_out, settings)
    run = j["runs"]["h"]
    v = j["verdict"]
    entry = {**isolator_metrics(result, run), "wall_time": run.stats["wall_time"],
             "check_wall_time": j["runs"]["h2"].stats["wall_time"], "element": run.stats["element"],
             "step": run.stats["step"], "order": ORDER,
             "verdict": {k: v.get(k) for k in ("pass", "consistent", "accurate", "text", "needs", "uncertain")},
             "against_converged": j["values"], "estimates": j["estimates"], "reference_error": j["reference_error"],
             "observed_order": j["evidence"]["observed_order"]}
    if "floor1_x" in result.columns:
        entry["building"] = building_metrics(result, run)
    return _with_ground_columns(run, ground), entry


def _with_ground_columns(run: RunResult, ground) -> RunResult:
    from comparisons.engines import _with_ground
    return _with_ground(run, ground)
