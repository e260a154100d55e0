"""``nsd seismic --building NAME=VALUE``: a shear building on the slab (docs/building.md),
``--fixed-base`` (the building with its slab held to the ground) and ``--compare-building`` (the three
configurations under the same record, and their ratios).

Layout of ``--compare-building --out DIR``:
    DIR/fixed_base/, DIR/supports/, DIR/device/   seismic.csv and summary.json of each configuration
    DIR/summary.json      {"compare_building": true, ground, structure, ratios, complete, runs}
    DIR/building_ratios.csv   quantity, index, fixed_base, supports, device, the three ratios, what
"""
from __future__ import annotations

from nsd_core.device.params import ParameterError


def add_arguments(p) -> None:
    p.add_argument("--building", action="append", default=[], metavar="NAME=VALUE",
                   help="a shear building on the slab (docs/building.md): stories, mass, stiffness, height "
                        "(one value or one per story, comma-separated), damping_ratio (Rayleigh on the first two "
                        "fixed-base modes) or damping (per-story c_i), period (fixed-base, sets a uniform "
                        "stiffness); --building stories=3 gives the default building")
    p.add_argument("--fixed-base", action="store_true", help="the building with its slab held to the ground")
    p.add_argument("--compare-building", action="store_true",
                   help="the building fixed-base, isolated on the supports alone and with the device; writes the "
                        "three runs and their ratios (DIR/building_ratios.csv)")


def building_overrides(args) -> dict | None:
    """The building's overrides: the --params file's [building] table, then --building (None: no building)."""
    from nsd_core.device.params import parse_set, read_toml
    table = None
    if getattr(args, "params", None):
        table = read_toml(args.params, "--params").get("building")
        if table is not None and not isinstance(table, dict):
            raise ParameterError(f"--params {args.params}: building = {table!r}: must be a table of name = value")
        for k, v in (table or {}).items():   # TOML numbers: a string here is a type mistake
            if any(isinstance(x, str) for x in (v if isinstance(v, list) else [v])):
                raise ParameterError(f"--params {args.params}: building.{k} = {v!r}: must be a number or an array "
                                     "of numbers, not a string")
    items = getattr(args, "building", None) or []
    if table is None and not items:
        return None
    from nsd_core.device.params import parse_set
    return {**(table or {}), **parse_set(items, "--building")}


def with_building(args, structure):
    """``structure`` with the building the options describe (and the checks of --fixed-base and
    --compare-building against the other options)."""
    from nsd_core.structure.building import building_from
    overrides = building_overrides(args)
    if overrides is None:
        for flag in ("fixed_base", "compare_building"):
            if getattr(args, flag, False):
                raise ParameterError(f"--{flag.replace('_', '-')}: needs a building (--building stories=N)")
        return structure
    if getattr(args, "fixed_base", False) and getattr(args, "compare_building", False):
        raise ParameterError("--fixed-base: --compare-building runs the fixed base itself")
    if getattr(args, "compare_building", False) and (args.no_device or getattr(args, "compare_supports", False)):
        raise ParameterError("--compare-building: runs all three configurations; leave out --no-device and "
                             "--compare-supports")
    return structure.with_building(building_from(structure.mass, overrides))


def run_compare(args, params, structure, motion, solver, out, head: dict) -> int:
    """--compare-building: the three runs written, the ratios; exit 4 if the device run was ended by
    the device's failure (the runs are still written), 0 otherwise."""
    from nsd_cli.options import Progress
    from nsd_cli.seismic_checks import for_run
    from nsd_cli.seismic_extras import warn
    from nsd_core.device.results import versions, write_csv
    from nsd_core.common.files import atomic_write_json
    from nsd_core.study.building_compare import CONFIGURATIONS, run_three
    runs = run_three(params, structure, motion, duration=args.duration, dt_out=args.dt_out, solver=solver,
                     progress=Progress("nsd seismic"))
    written = {}
    for name in CONFIGURATIONS:
        run = runs[name]
        if run["summary"] is None:
            continue
        summary = {**head, "device": name == "device", "fixed_base": name == "fixed_base", **run["summary"],
                   "solver": run["result"].stats, "complete": run["complete"], "versions": versions(),
                   "params": params.describe()}
        if name == "fixed_base":   # no isolation level: the restoring-force check is the isolated runs'
            summary.pop("restoring_force", None)
        for_run(summary, name == "device")
        warn(summary, f"{name}: ")
        (out / name).mkdir(parents=True, exist_ok=True)
        write_csv(out / name / "seismic.csv", run["result"])
        atomic_write_json(out / name / "summary.json", summary)
        written[name] = f"{name}/summary.json"
    stopped = runs["device"]["stopped"]
    top = {**head, "compare_building": True, "complete": runs["complete"], "ratios": runs["ratios"],
           "runs": written, "stopped": stopped, "versions": versions(), "params": params.describe()}
    _write_rows(out / "building_ratios.csv", runs["ratios"] or [])
    atomic_write_json(out / "summary.json", top)
    for row in runs["ratios"] or []:
        where = f" {row['index']}" if row["index"] else ""
        print(f"  {row['quantity']}{where}: fixed {row['fixed_base']:.5g}, supports {row['supports']:.5g}, "
              f"device {row['device']:.5g}; device/fixed {_fmt(row['device_over_fixed'])}, "
              f"supports/fixed {_fmt(row['supports_over_fixed'])}")
    if stopped:
        print(f"  the device run stopped at t = {stopped['t']:.6g} s ({stopped['kind']}): {stopped['reason']}")
    print(f"wrote {', '.join(str(out / n) for n in written)}, {out / 'summary.json'} and {out / 'building_ratios.csv'}")
    return 4 if stopped else 0


def _fmt(v) -> str:
    return "-" if v is None else f"{v:.4g}"


def _write_rows(path, rows) -> None:
    import csv
    import io
    from nsd_core.common.files import atomic_write_text
    fields = ["quantity", "index", "fixed_base", "supports", "device", "supports_over_fixed", "device_over_fixed",
              "device_over_supports", "what"]
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=fields, lineterminator="\n")
    w.writeheader()
    for row in rows:
        w.writerow({k: ("" if row[k] is None else repr(row[k]) if isinstance(row[k], float) else row[k])
                    for k in fields})
    atomic_write_text(path, buf.getvalue())


def print_building(summary: dict) -> None:
    """One line per story: peak drift ratio and peak floor acceleration."""
    b = summary.get("building")
    if not b:
        return
    for i, (d, a) in enumerate(zip(b["peak_drift_ratio"], b["peak_floor_acceleration"])):
        print(f"  story {i + 1}: peak drift ratio {d['value']:.4e} at t = {d['t']:.3f} s; floor {i + 1} peak "
              f"|a_abs| = {a['value']:.4f} m/s^2 at t = {a['t']:.3f} s")
