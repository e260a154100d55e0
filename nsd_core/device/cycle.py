"""Cycle analysis, engine-independent: steady cycle, loop area, tangent stiffness, working regions
(Figure 7), X_max and the run's events (ropes slack, spring lifted off its seat); for any path in
the plane the force vector's peak, the work per cycle and each component's loop."""
from __future__ import annotations

import numpy as np

from nsd_core.device.results import RunResult, last_cycle


def steady_cycle(result: RunResult, frequency: float) -> np.ndarray:
    """Boolean mask of the last full cycle (both end points included, so the loop closes)."""
    return last_cycle(result["t"], frequency)


def loop_area(u: np.ndarray, F: np.ndarray) -> float:
    """Dissipated energy per cycle: the closed integral of F du (trapezoids) [J]."""
    return float(np.sum(0.5 * (F[1:] + F[:-1]) * np.diff(u)))


def loading_quarter(result: RunResult, frequency: float) -> np.ndarray:
    """Mask of the steady cycle's first quarter: u rising from 0 to +A (the Figure 7 branch)."""
    t = result["t"]
    t0 = t[-1] - 1.0 / frequency
    return (t >= t0 - 1e-9 / frequency) & (t <= t0 + 0.25 / frequency + 1e-9 / frequency)


def unloading_quarter(result: RunResult, frequency: float) -> np.ndarray:
    """Mask of the steady cycle's second quarter: u falling from +A back to 0 (the unloading branch)."""
    t = result["t"]
    t0 = t[-1] - 1.0 / frequency
    return (t >= t0 + 0.25 / frequency - 1e-9 / frequency) & (t <= t0 + 0.5 / frequency + 1e-9 / frequency)


def tangent_stiffness(u: np.ndarray, F: np.ndarray) -> np.ndarray:
    """dF/du along a monotonic branch [N/m]."""
    return np.gradient(F, u)


def stiffness_regions(u: np.ndarray, k: np.ndarray, min_width: float) -> list[dict]:
    """Regions of one sign of the tangent stiffness k along an ascending u: runs of constant sign,
    runs narrower than min_width (numerical noise) merged, the narrowest first, into its wider
    neighbour. Each region's
    ``mean_stiffness`` is k's mean over u in it (trapezoids; a sample where u does not advance, as at a
    turning point, weighs nothing) and its ``sign`` is that mean's: after a merge the region is
    labelled by its mean and neighbours of one sign are joined, until no region is narrower than
    min_width (or one is left). Sign and mean therefore always agree ("+" for a mean >= 0)."""
    u, k = np.asarray(u, float), np.asarray(k, float)
    sign = np.where(k >= 0, 1, -1)
    runs = []
    start = 0
    for i in range(1, len(sign) + 1):
        if i == len(sign) or sign[i] != sign[start]:
            runs.append([start, i - 1, int(sign[start])])
            start = i
    while True:
        while True:  # label by the mean, join neighbours of one sign, until no two neighbours share one
            for r in runs:
                r[2] = 1 if _mean_over_u(u, k, r[0], r[1]) >= 0 else -1
            out = [runs[0]]
            for r in runs[1:]:
                if r[2] == out[-1][2]:
                    out[-1][1] = r[1]
                else:
                    out.append(r)
            if len(out) == len(runs):
                break
            runs = out
        slivers = [j for j, (a, b, _) in enumerate(runs) if u[b] - u[a] < min_width]
        if not slivers or len(runs) == 1:
            break
        widths = [u[b] - u[a] for a, b, _ in runs]
        j = min(slivers, key=lambda i: widths[i])  # the narrowest sliver into its wider neighbour
        into = max((i for i in (j - 1, j + 1) if 0 <= i < len(runs)), key=lambda i: widths[i])
        runs[into][0], runs[into][1] = min(runs[into][0], runs[j][0]), max(runs[into][1], runs[j][1])
        del runs[j]
    return [{"from": float(u[a]), "to": float(u[b]), "sign": "+" if s > 0 else "-",
             "mean_stiffness": _mean_over_u(u, k, a, b)} for a, b, s in runs]


def _mean_over_u(u: np.ndarray, k: np.ndarray, a: int, b: int) -> float:
    """The mean of k over u in samples a..b (trapezoids over the finite samples; a region of one
    point, or where u does not advance: the samples' mean)."""
    uu, kk = u[a:b + 1], k[a:b + 1]
    ok = np.isfinite(kk)
    uu, kk = uu[ok], kk[ok]
    if len(kk) == 0:
        return 0.0
    width = uu[-1] - uu[0]
    if len(kk) < 2 or not width > 0:
        return float(np.mean(kk))
    return float(np.sum(0.5 * (kk[1:] + kk[:-1]) * np.diff(uu)) / width)


def events(result: RunResult) -> list[dict]:
    """Intervals where every rope is slack (precompression lost) or the spring left its seat."""
    t = result["t"]
    ropes = result.stack("rope")
    out = []
    flags = {"ropes_slack": (ropes <= 0.0).all(axis=1) if ropes.shape[1] else np.zeros(len(t), bool),
             "spring_lifted": result["spring_push"] <= 0.0}
    for kind, on in flags.items():
        edges = np.flatnonzero(np.diff(on.astype(int)))
        starts = list(edges[~on[edges]] + 1) if len(edges) else []
        ends = list(edges[on[edges]]) if len(edges) else []
        if on[0]:
            starts = [0] + starts
        if on[-1]:
            ends = ends + [len(t) - 1]
        for a, b in zip(starts, ends):
            out.append({"kind": kind, "start": float(t[a]), "end": float(t[b]),
                        "duration": float(t[b] - t[a]), "u_start": float(result["u"][a]),
                        "resolution": float(t[1] - t[0])})
    return sorted(out, key=lambda e: e["start"])


def x_max_from_run(result: RunResult) -> float | None:
    """First |u| at which every rope is slack, interpolated between samples; None if never."""
    ropes = result.stack("rope")
    if ropes.shape[1] == 0:
        return None
    total = ropes.sum(axis=1)
    idx = np.flatnonzero(total <= 0.0)
    if len(idx) == 0 or idx[0] == 0:
        return None
    k = idx[0]
    u0, u1 = abs(result["u"][k - 1]), abs(result["u"][k])
    f0 = total[k - 1]
    # the tension falls linearly with u near the edge: use the sample before and the crossing
    if k >= 2 and total[k - 2] > f0:
        slope = (f0 - total[k - 2]) / (u0 - abs(result["u"][k - 2]) or 1.0)
        est = u0 - f0 / slope if slope < 0 else u1
        return float(min(max(est, u0), u1))
    return float(u1)


def vector_summary(result: RunResult, frequency: float) -> dict:
    """The force as a vector over the steady cycle (any path in the plane): peak |F|, the work the
    drive does per cycle (the closed integral of F . dp, the energy dissipated), the loop of each
    component (closed integrals of F_x dx and F_y dy, summing to the work)."""
    cyc = steady_cycle(result, frequency)
    x, y, Fx, Fy = (result[k][cyc] for k in ("x", "y", "F_x", "F_y"))
    loop_x, loop_y = loop_area(x, Fx), loop_area(y, Fy)
    mag = np.hypot(Fx, Fy)
    k = int(np.argmax(mag))
    return {"peak_force_magnitude": float(mag[k]), "peak_force_at": [float(x[k]), float(y[k])],
            "min_force_magnitude": float(np.min(mag)), "work_per_cycle": loop_x + loop_y,
            "loop_area_x": loop_x, "loop_area_y": loop_y}


def analyse(result: RunResult, amplitude: float, frequency: float, path: str = "line") -> dict:
    """The summary every engine's run gets.

    Line: peak force, loop area, stiffness regions, X_max, events (the paper's quantities), plus the
    vector summary. Any other path: the vector summary, with peak_force = peak |F| and loop_area =
    the work per cycle, events and loop closure.
    """
    if path != "line":
        vec = vector_summary(result, frequency)
        ev = events(result)
        return {"peak_force": vec["peak_force_magnitude"], "loop_area": vec["work_per_cycle"], **vec,
                "outside_working_range": any(e["kind"] == "ropes_slack" for e in ev), "events": ev,
                "closure_max": float(np.max(np.abs(result["closure"])))}
    cyc = steady_cycle(result, frequency)
    u, F = result["u"][cyc], result["F"][cyc]
    q = loading_quarter(result, frequency)
    uq, Fq = result["u"][q], result["F"][q]
    k = tangent_stiffness(uq, Fq)
    ev = events(result)
    xm = x_max_from_run(result)
    return {
        "peak_force": float(np.max(np.abs(F))),
        "force_at_plus_A": float(np.interp(amplitude, uq, Fq)),
        "loop_area": loop_area(u, F),
        "initial_stiffness": float(k[0]),
        "stiffness_regions": stiffness_regions(uq, k, min_width=0.02 * amplitude),
        "stiffness_regions_unloading": _unloading_regions(result, amplitude, frequency),
        "x_max": xm,
        "outside_working_range": any(e["kind"] == "ropes_slack" for e in ev),
        "events": ev,
        "closure_max": float(np.max(np.abs(result["closure"]))),
        **(vector_summary(result, frequency) if "F_x" in result.columns else {}),
    }


def _unloading_regions(result: RunResult, amplitude: float, frequency: float) -> list[dict]:
    """Stiffness regions on the unloading branch, listed from u = 0 outwards like the loading ones."""
    m = unloading_quarter(result, frequency)
    u, F = result["u"][m][::-1], result["F"][m][::-1]  # ascending u
    keep = np.concatenate([[True], np.diff(u) > 0])
    return stiffness_regions(u[keep], tangent_stiffness(u[keep], F[keep]), min_width=0.02 * amplitude)


def phase_resample(result: RunResult, frequency: float, column: str, n: int = 2000) -> np.ndarray:
    """The steady cycle of ``column`` on the phase grid 0 .. 1 (n + 1 points)."""
    cyc = steady_cycle(result, frequency)
    t = result["t"][cyc]
    phase = (t - t[0]) * frequency
    return np.interp(np.linspace(0.0, 1.0, n + 1), phase, result[column][cyc])

