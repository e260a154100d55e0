"""OpenSees against the in-house engine on the baseline isolators (docs/seismic.md, "OpenSees as a peer"):
the gate's rule on each record (OpenSees at its step and at half of it, the in-house converged reference
and its check), and what each by-construction difference of OpenSees's other elements moves:

- the lead-rubber bearing as elastomericBearingPlasticity (bilinear plasticity: n -> infinity) against
  the Bouc-Wen bearing with the project's n = 10;
- the friction pendulum as singleFPBearing (Coulomb friction with an elastic pre-slip, the sphere's
  geometry and the axial force's shear component) against the Bouc-Wen bearing with the project's n = 2;
- the building's damping as OpenSees's ``rayleigh`` (mass part on velocities relative to the ground)
  against the project's form (floor-slab dampers), on the lead-rubber bearing.

    python benchmarks/bench_opensees.py --out benchmarks/results/bench_opensees.json
"""
from __future__ import annotations

import argparse
import importlib.metadata
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from comparisons.engines.opensees_peer import gate_values, judge, run_opensees  # noqa: E402
from nsd_core.ground.records import fema_record  # noqa: E402
from nsd_core.structure.isolation import designed_structure  # noqa: E402
from nsd_core.structure.isolators import sized  # noqa: E402
from nsd_core.device.params import Params  # noqa: E402
from nsd_core.device.results import versions
from nsd_core.common.files import atomic_write_json  # noqa: E402

# (set, id, scale, window in record seconds, used by a test?)
RECORDS = [("nearfield-pulse", 1, 0.6, (2.0, 5.0), "tests/test_isolators.py, tests/test_opensees.py"),
           ("farfield", 17, 1.0, (3.0, 9.0), "tests/test_opensees.py"),
           ("farfield", 12, 1.0, (10.0, 18.0), "none")]
KINDS = ("bilinear", "friction-pendulum")
ALTERNATIVE = {"bilinear": "plasticity", "friction-pendulum": "single-fp"}


def _peak(run, cx: str, cy: str) -> float:
    return float(np.max(np.hypot(run[cx], run[cy])))


def _differences(ref, other) -> dict:
    """The response's differences: peaks in %, max-norm differences of u and the isolator's force."""
    v = gate_values(ref, other)
    out = {"peak_u_pct": 100 * (_peak(other, "x", "y") / _peak(ref, "x", "y") - 1),
           "peak_F_pct": 100 * (_peak(other, "support_Fx", "support_Fy") / _peak(ref, "support_Fx", "support_Fy") - 1),
           "peak_a_pct": 100 * (_peak(other, "ax_abs", "ay_abs") / _peak(ref, "ax_abs", "ay_abs") - 1),
           "max_du_rel": v["max_du_rel"], "max_dF_rel": v["max_dF_device_rel"]}
    if "max_ddrift_rel" in v:
        out.update({"max_ddrift_rel": v["max_ddrift_rel"], "max_dfloor_a_rel": v["max_dfloor_a_rel"],
                    "peak_drift1_pct": 100 * (_peak(other, "drift1_x", "drift1_y") / _peak(ref, "drift1_x", "drift1_y") - 1)})
    return out


def one(set_: str, rid: int, scale: float, window, kind: str, building: bool = False) -> dict:
    st = designed_structure(True)
    st = st.with_isolator(sized(kind, st.mass))
    if building:
        from nsd_core.structure.building import building_from
        st = st.with_building(building_from(st.mass, {"stories": 3}))
    g = fema_record(set_, rid, scale=scale, window=window)
    j = judge(Params(), st, g)
    ref, h = j["runs"]["converged"], j["runs"]["h"]
    v = j["verdict"]
    iso = st.isolator
    out = {"record": f"{set_}:{rid}", "scale": scale, "window": list(window), "isolator": kind, "building": building,
           "constants": {"k_d_N_m": iso.stiffness, "Q_N": iso.q_fast, "D_y_m": iso.yield_displacement, "n": iso.exponent,
                         "M_kg": st.mass},
           "peak_u_m": _peak(ref, "x", "y"), "element": h.stats["element"], "step_s": h.stats["step"],
           "verdict": {k: v[k] for k in ("pass", "consistent", "accurate", "text")},
           "against_converged": j["values"], "estimates": j["estimates"], "reference_error": j["reference_error"],
           "observed_order": j["evidence"]["observed_order"],
           "wall_s": {k: r.stats.get("wall_time") for k, r in j["runs"].items()}}
    alt = run_opensees(st, g, settings={"element": ALTERNATIVE[kind], "step": h.stats["step"] / 2})
    out["alternative"] = {"element": alt.stats["element"], "step_s": alt.stats["step"], **_differences(ref, alt)}
    if building:
        ray = run_opensees(st, g, settings={"building_damping": "rayleigh"})
        out["rayleigh_damping"] = _differences(ref, ray)
    return out


def main(argv=None) -> None:
    import datetime as dt
    import os
    import platform
    import time
    from benchmarks.docs_common import loaded
    from benchmarks.measure import _git_commit
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--out", required=True)
    a = p.parse_args(argv)
    commit, load0, t0 = _git_commit(), os.getloadavg(), time.perf_counter()
    rows = []
    for set_, rid, scale, window, used in RECORDS:
        for kind in KINDS:
            r = one(set_, rid, scale, window, kind)
            r["used_by_tests"] = used
            rows.append(r)
            print(f"{r['record']} {kind}: peak |u| {r['peak_u_m'] * 1e3:.3f} mm, du {r['against_converged']['max_du_rel']:.2e} "
                  f"(estimate {r['estimates']['max_du_rel']:.2e}), dF {r['against_converged']['max_dF_device_rel']:.2e}: "
                  f"{r['verdict']['text']}; {r['alternative']['element']}: peak u {r['alternative']['peak_u_pct']:+.2f} %",
                  flush=True)
    b = one("nearfield-pulse", 1, 0.6, (2.0, 5.0), "bilinear", building=True)
    print(f"building: {b['verdict']['text']}; rayleigh: {b['rayleigh_damping']}", flush=True)
    measured = {"date_utc": dt.datetime.now(dt.timezone.utc).strftime("%Y-%m-%d %H:%M"),
                "machine": platform.platform(), "processor": platform.machine(), "cpus": os.cpu_count() or 1,
                "load_average_before": [round(x, 2) for x in load0],
                "load_average_after": [round(x, 2) for x in os.getloadavg()],
                "wall_s": time.perf_counter() - t0, "git_commit": commit,
                "versions": {**versions(), "openseespy": importlib.metadata.version("openseespy")}}
    measured["loaded"] = loaded(measured)
    atomic_write_json(a.out, {"name": "bench_opensees", "command": "python benchmarks/bench_opensees.py --out "
                              "benchmarks/results/bench_opensees.json", "measured": measured,
                              "data": {"runs": rows, "building": b}})


if __name__ == "__main__":
    main()
