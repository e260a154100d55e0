"""``nsd seismic``: the displacement restrainer's options, a run the device's failure ends
(exit 4) still written, the run's warnings (nsd_core.structure.seismic_warnings), and ``--compare-supports``
(with the device and on the supports alone, both written, with their ratios). See docs/seismic.md.

Layout of ``--compare-supports --out DIR``:
    DIR/device/seismic.csv, DIR/device/summary.json      the run with the device (as nsd seismic writes it)
    DIR/supports/seismic.csv, DIR/supports/summary.json  the supports alone (the same structure and restrainer)
    DIR/summary.json     {"compare_supports": true, ground, structure, ratios, both runs' summaries}
    DIR/ratios.csv       quantity, with_device, supports_alone, ratio, what
"""
from __future__ import annotations

import sys

from nsd_core.device.params import ParameterError


def add_design_arguments(p) -> None:
    """--isolator, --resize, --design-level (docs/design.md): every seismic command's."""
    p.add_argument("--isolator", default="device", metavar="device|linear|bilinear|friction-pendulum",
                   help="what isolates the structure: the device (on the supports; default), or a baseline without "
                        "it: linear (the supports alone), bilinear (lead-rubber), friction-pendulum, sized for the "
                        "design displacement (docs/design.md); where a command runs with and without the device, "
                        "the run without it stands on this baseline")
    p.add_argument("--resize", action="store_true",
                   help="derive the isolated structure from the device (the model document's rule) instead of the "
                        "design basis, which holds it fixed for every device")
    p.add_argument("--design-level", action="store_true",
                   help="the design level: each record scaled so that its Sa(T_D) is the design spectrum's, and the "
                        "isolation level's supplemental damping of the design (docs/design.md)")


def add_arguments(p) -> None:
    p.add_argument("--restrainer", action="store_true",
                   help="add the displacement restrainer (Hunt-Crossley contact at |u| > u_gap, defaults in "
                        "docs/seismic.md); its constants also by --structure restrainer_gap=, restrainer_stiffness=, "
                        "restrainer_exponent=, restrainer_damping=")
    p.add_argument("--compare-supports", action="store_true",
                   help="run with the device and on the supports alone; write both (DIR/device, DIR/supports) "
                        "and their ratios (DIR/summary.json, DIR/ratios.csv)")


def isolated_structure(args, params):
    """The default structure with --structure overrides and the restrainer (--restrainer or any
    restrainer_* override): ParameterError, one line, on anything wrong."""
    from nsd_core.device.params import parse_set
    from nsd_core.structure.restrainer import split_overrides, with_restrainer
    from nsd_core.structure.isolation import designed_structure_with
    from nsd_core.structure.isolators import CHOICES, KINDS, sized
    kind = isolator_choice(args)
    own, restrainer = split_overrides(parse_set(getattr(args, "structure", None) or []))
    structure = designed_structure_with(params, own, resize=bool(getattr(args, "resize", False)),
                                        design_level=bool(getattr(args, "design_level", False)))
    if kind in KINDS:
        structure = structure.with_isolator(sized(kind, structure.mass))
    assert kind in CHOICES
    return with_restrainer(structure, params, bool(getattr(args, "restrainer", False)), restrainer)


def isolator_choice(args) -> str:
    """--isolator's value, checked (one line on anything else)."""
    from nsd_core.structure.isolators import CHOICES
    kind = getattr(args, "isolator", None)
    kind = "device" if kind is None else kind
    if kind not in CHOICES:
        raise ParameterError(f"--isolator {kind!r}: allowed {', '.join(CHOICES)}")
    if kind != "device" and getattr(args, "fixed_base", False):
        raise ParameterError(f"--isolator {kind}: --fixed-base holds the slab to the ground, so the run has no "
                             "isolator; leave one out")
    return kind


def design_scale(set_: str, rid, args, window=None) -> float:
    """--design-level: the record's scale so that its Sa(T_D) is the design spectrum's
    (nsd_core.study.intensity.design_level_scale), on the whole record (a window is a part of the same
    scaled record, so its Sa does not set the scale); --scale must be left at 1."""
    from nsd_core.study.intensity import design_level_scale
    from nsd_core.ground.records import SIMILITUDE_TIME_FACTOR, fema_record
    if float(args.scale) != 1.0:
        raise ParameterError(f"--scale {args.scale!r}: --design-level sets each record's scale; leave --scale out")
    tf = SIMILITUDE_TIME_FACTOR if args.time_factor is None else args.time_factor
    motion = fema_record(set_, rid, scale=1.0, time_factor=tf, window=None, rotate_deg=args.rotate,
                         normalised=not args.raw)
    return design_level_scale(motion)["scale"]


def check_compare(args, engines) -> None:
    if not getattr(args, "compare_supports", False):
        return
    if args.no_device:
        raise ParameterError("--compare-supports: runs the supports alone itself; leave out --no-device")
    if len(engines) > 1:
        raise ParameterError(f"--engines {args.engines!r}: --compare-supports runs the in-house engine only")


def warn(summary: dict, which: str = "") -> None:
    """summary["warnings"] (and "warning_kinds") by the warning rules of nsd_core.structure.seismic_warnings
    (stroke exhausted or nearly, beyond the device's stroke, restrainer impacts, peaks on the last
    sample), and one stderr line per warning."""
    from nsd_core.structure.seismic_warnings import apply_warnings
    for text in apply_warnings(summary):
        print(f"nsd seismic: warning: {which}{text}", file=sys.stderr)


def print_restrainer(summary: dict) -> None:
    """One line on the restrainer's work, when the structure has one."""
    r = summary.get("restrainer")
    if r:
        print(f"  restrainer: {r['engagements']} engagements, {r['engaged_time'] * 1e3:.1f} ms engaged, largest impact "
              f"energy {r['impact_energy_max']:.4g} J, dissipated {r['dissipated']:.4g} J, peak force "
              f"{summary['peak_restrainer_force']['value']:.4g} N")


def stopped_summary(err, head: dict) -> dict | None:
    """The summary of a run the device's failure ended, from its partial series (None: no samples)."""
    from nsd_core.structure.seismic import RodReachError, seismic_summary
    partial = getattr(err, "partial", None)
    if partial is None or len(partial["t"]) < 2:
        return None
    summary = {**head, **seismic_summary(partial), "solver": partial.stats}
    summary["stopped"] = {"kind": "rod_reach" if isinstance(err, RodReachError) else "outside_validity",
                          "reason": str(err), "t": getattr(err, "t_event", None),
                          "last_sample": float(partial["t"][-1])}
    summary["complete"] = False
    return summary


def write_stopped(err, out, head: dict) -> None:
    """Exit 4 keeps its series: seismic.csv up to the event and summary.json with the event."""
    from nsd_core.device.results import write_csv
    from nsd_core.common.files import atomic_write_json
    summary = stopped_summary(err, head)
    if summary is None:
        return
    warn(summary)
    write_csv(out / "seismic.csv", err.partial)  # (no last-sample warning: the event ends the series)
    atomic_write_json(out / "summary.json", summary)
    print(f"stopped at t = {summary['stopped']['t']:.6g} s ({summary['stopped']['kind']}); kept the series up to "
          f"t = {summary['stopped']['last_sample']:.6g} s: wrote {out / 'seismic.csv'} and {out / 'summary.json'}")


def run_compare(args, params, structure, motion, solver, out, head: dict) -> int:
    """--compare-supports: both runs, both written, the ratios; exit 4 if the device run was ended by
    the device's failure (both runs are still written), 0 otherwise."""
    from nsd_cli.options import Progress
    from nsd_cli.seismic_checks import for_run
    from nsd_core.device.results import versions, write_csv
    from nsd_core.common.files import atomic_write_json
    from nsd_core.study.with_without import ratio_rows, run_with_and_without
    both = run_with_and_without(params, structure, motion, duration=args.duration, dt_out=args.dt_out,
                                solver=solver, progress=Progress("nsd seismic"))
    summaries = {}
    for name in ("device", "supports"):
        run = both[name]
        if run["summary"] is None:
            continue
        summary = {**head, "device": name == "device", **run["summary"], "solver": run["result"].stats,
                   "complete": run["complete"], "versions": versions(), "params": params.describe()}
        for_run(summary, name == "device")
        warn(summary, f"{name}: ")
        (out / name).mkdir(parents=True, exist_ok=True)
        write_csv(out / name / "seismic.csv", run["result"])
        atomic_write_json(out / name / "summary.json", summary)
        summaries[name] = summary
    top = {**head, "compare_supports": True, "complete": both["complete"], "ratios": both["ratios"],
           "note": both.get("note"), "runs": {n: f"{n}/summary.json" for n in summaries},
           "stopped": both["device"]["stopped"], "versions": versions(), "params": params.describe()}
    _write_ratios(out / "ratios.csv", ratio_rows(both["ratios"]))
    atomic_write_json(out / "summary.json", top)
    for row in ratio_rows(both["ratios"]):
        ratio = f"{float(row['ratio']):.4g}" if row["ratio"] else "-"   # (ratios.csv keeps every digit)
        print(f"  {row['quantity']}: with the device {row['with_device']:.5g}, supports alone "
              f"{row['supports_alone']:.5g}, ratio {ratio}")
    if both["device"]["stopped"]:
        s = both["device"]["stopped"]
        print(f"  the device run stopped at t = {s['t']:.6g} s ({s['kind']}): {s['reason']}")
    print(f"wrote {out / 'device'}, {out / 'supports'}, {out / 'summary.json'} and {out / 'ratios.csv'}")
    return 4 if both["device"]["stopped"] else 0


def _write_ratios(path, rows) -> None:
    import csv
    import io
    from nsd_core.common.files import atomic_write_text
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=["quantity", "with_device", "supports_alone", "ratio", "what"],
                       lineterminator="\n")
    w.writeheader()
    for row in rows:
        w.writerow({**row, "with_device": repr(row["with_device"]), "supports_alone": repr(row["supports_alone"])})
    atomic_write_text(path, buf.getvalue())
