"""The seismic mode across engines: ground inputs of a case and the metrics on time histories (docs/seismic.md).

The engines' seismic runs are in the one registry (``comparisons.engines``: ``run_seismic_engine``,
``run_seismic_job``); every one returns the columns of ``nsd_core.structure.seismic`` it can measure
(at least t, x, y, theta, ax_abs, ay_abs, device_Fx, device_Fy, cap_z) on the same output times.
OpenSees (``comparisons.engines.opensees_peer``) runs the baseline isolators only (no device); its runs
are judged there by the gate's rule on these metrics, the isolator's force in the device force's place.
"""
from __future__ import annotations

import numpy as np

from nsd_core.device.params import ParameterError

def _synthetic() -> dict:
    from nsd_core.ground.motions import GROUND_SPECS
    return {kind: (cls, {k: spec[0] for k, spec in keys.items()}) for kind, (cls, keys, _) in GROUND_SPECS.items()}


# kind -> (class name in nsd_core.ground.motions, allowed keys -> constructor argument): derived from the
# one table of the closed-form inputs and their ranges (nsd_core.ground.motions.GROUND_SPECS)
SYNTHETIC = _synthetic()


def parse_ground(text, where: str = "--ground"):
    """A synthetic ground motion from ``KIND:K=V,...`` (nsd seismic --ground, a case's ground = "..."):
    nsd_core.ground.motions.parse_ground_spec, the one parser (keys, ranges, duplicates)."""
    from nsd_core.ground.motions import parse_ground_spec
    return parse_ground_spec(text, where)


def gate_metrics(ref, other) -> dict:
    """The gated seismic metrics of ``other`` against the reference ``ref`` (names of
    comparisons.config.METRICS): max_du_rel, max_dF_device_rel (device force vector), peak_u_rel, peak_a_rel."""
    m = seismic_metrics(ref, other)
    out = {"max_du_rel": m["du"], "max_dF_device_rel": m["dF"], "peak_u_rel": abs(m["peak_displacement"]),
           "peak_a_rel": abs(m["peak_absolute_acceleration"])}
    if "floor1_x" in ref.columns and "floor1_x" in other.columns:
        b = building_metrics(ref, other)
        out.update({"max_dfloor_rel": b["dfloor"], "max_ddrift_rel": b["ddrift"], "max_dfloor_a_rel": b["dfloor_a"]})
    return out


def building_metrics(ref, other) -> dict:
    """The building's differences (docs/building.md): per floor / story, max |o - r| / max |r| of the plan
    vectors of the displacement relative to the ground (dfloor), the drift (ddrift) and the absolute
    acceleration (dfloor_a), each list and its worst; max |r| is at least 1e-3 of the building's largest."""
    n = 0
    while f"floor{n + 1}_x" in ref.columns:
        n += 1
    out = {}
    for key, (cx, cy) in {"dfloor": ("floor{}_x", "floor{}_y"), "ddrift": ("drift{}_x", "drift{}_y"),
                          "dfloor_a": ("floor{}_ax_abs", "floor{}_ay_abs")}.items():
        refs = [np.column_stack([ref[cx.format(i)], ref[cy.format(i)]]) for i in range(1, n + 1)]
        peaks = [float(np.max(np.linalg.norm(r, axis=1))) for r in refs]
        # a floor or story whose own peak is near zero (a tall, stiff building early in a record) is measured
        # against 1e-3 of the building's largest peak of that quantity, not against its own round-off
        floor = max(1e-3 * max(peaks), 1e-300)
        per = []
        for i, (r, peak) in enumerate(zip(refs, peaks), start=1):
            o = np.column_stack([other[cx.format(i)], other[cy.format(i)]])
            per.append(float(np.max(np.linalg.norm(o - r, axis=1)) / max(peak, floor)))
        out[key], out[key + "_per_floor"] = max(per), per
    return out


def own_seismic_metrics(run) -> dict:
    """An engine's own checks on a seismic run: the energy balance in the frame of the ground,
    max |E_residual| / max |E_input| (every term from the engine's own state), and loop closure."""
    out = {}
    if "E_residual" in run.columns and "E_input" in run.columns:
        out["energy_residual_rel"] = float(np.max(np.abs(run["E_residual"])) / max(np.max(np.abs(run["E_input"])), 1e-300))
    if "closure" in run.columns:
        out["closure_max"] = float(np.max(np.abs(run["closure"])))
    return out


def seismic_metrics(ref, other) -> dict:
    """Differences of ``other`` against ``ref`` on the same output times:
    du = max|u_o - u_r| / max|u_r| (plan vectors), dF the same for the device force vector,
    da for the absolute acceleration vector, and the differences of the peaks (relative)."""
    if len(ref["t"]) != len(other["t"]) or np.max(np.abs(ref["t"] - other["t"])) > 1e-9:
        raise ValueError("seismic_metrics: the runs are not on the same output times")

    def vec(r, a, b):
        return np.column_stack([r[a], r[b]])

    def rel(a, b):
        return float(np.max(np.linalg.norm(a - b, axis=1)) / max(np.max(np.linalg.norm(b, axis=1)), 1e-300))

    u_r, u_o = vec(ref, "x", "y"), vec(other, "x", "y")
    F_r, F_o = vec(ref, "device_Fx", "device_Fy"), vec(other, "device_Fx", "device_Fy")
    a_r, a_o = vec(ref, "ax_abs", "ay_abs"), vec(other, "ax_abs", "ay_abs")

    def peak_diff(o, r):
        pr = np.max(np.linalg.norm(r, axis=1))
        return float((np.max(np.linalg.norm(o, axis=1)) - pr) / max(pr, 1e-300))

    return {"du": rel(u_o, u_r), "dF": rel(F_o, F_r), "da": rel(a_o, a_r),
            "peak_displacement": peak_diff(u_o, u_r), "peak_absolute_acceleration": peak_diff(a_o, a_r),
            "dtheta": float(np.max(np.abs(other["theta"] - ref["theta"])) / max(np.max(np.abs(ref["theta"])), 1e-300)),
            "dcap_z": float(np.max(np.abs(other["cap_z"] - ref["cap_z"])))}
