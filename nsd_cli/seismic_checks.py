"""``nsd seismic --design-displacement D``: the building codes' restoring-force check of the isolation
level run (``nsd_core.structure.restoring_force``; docs/seismic.md, "The restoring-force check"), computed
before the run, in summary.json as ``restoring_force`` and printed in one line per configuration (a
command that also runs without the device has the baseline's check under ``baseline``)."""
from __future__ import annotations


def add_arguments(p) -> None:
    p.add_argument("--design-displacement", default=None, metavar="D",
                   help="the isolation level's design displacement [m] for the restoring-force check "
                        "(F(D) - F(D/2) >= 0.025 W, ASCE/SEI 7-16 17.2.4.4); default: the design basis's maximum "
                        "displacement D_M (19.64 mm at model scale); in [1e-06, 0.999 rod length]")


def check_arguments(args, params) -> None:
    """ParameterError, one line, for a bad --design-displacement: called before --out is made, the check
    itself (seconds of quasi-static paths) after, so that a bad --out is refused at once."""
    from nsd_core.structure.restoring_force import check_design_displacement
    given = getattr(args, "design_displacement", None)
    if given is not None:
        check_design_displacement(given, params.rod_length)


def restoring_force(args, params, structure) -> dict | None:
    """The check for this run's configuration (None on a fixed base: no isolation level), with the
    baseline's under "baseline" where the command also runs without the device; ParameterError, one
    line, for a bad --design-displacement (``check_arguments``)."""
    check_arguments(args, params)
    given = getattr(args, "design_displacement", None)
    if getattr(args, "fixed_base", False):
        return None
    both = getattr(args, "compare_supports", False) or getattr(args, "compare_building", False) \
        or getattr(args, "record_set", None) is not None
    check = _one(params, structure, given, device=not args.no_device)
    if both and not args.no_device:
        check["baseline"] = _one(params, structure, given, device=False)
    return check


def _one(params, structure, given, device: bool) -> dict:
    """One configuration's check, kept on disk for these inputs and this source
    (nsd_core.compilation.result_cache: seconds of quasi-static paths, the same for every run of a device
    and structure)."""
    from nsd_core.compilation.result_cache import cached_json
    from nsd_core.structure.restoring_force import configuration_of, restoring_force_check
    inputs = {"params": params.to_dict(), "structure": structure.to_dict(), "D": given, "device": device}
    try:
        return cached_json("restoring_force", inputs,
                           lambda: restoring_force_check(params, structure, given, device=device))
    except (ValueError, RuntimeError, ArithmeticError) as e:   # a variant the quasi-static path cannot follow
        return {"pass": None, "configuration": configuration_of(structure, device),
                "skipped": "the device's quasi-static force could not be followed to D: " + " ".join(str(e).split())[:200]}


def print_restoring_force(check: dict | None) -> None:
    from nsd_core.structure.restoring_force import describe
    for c in ([] if check is None else [check] + ([check["baseline"]] if check.get("baseline") else [])):
        if "skipped" in c:
            print(f"restoring force ({c.get('configuration')}): not checked ({c['skipped']})")
        else:
            print(describe(c))


def for_run(summary: dict, device: bool) -> None:
    """A run without the device in a command that runs both: its summary's check is the baseline's."""
    check = summary.get("restoring_force")
    if not device and isinstance(check, dict) and isinstance(check.get("baseline"), dict):
        summary["restoring_force"] = check["baseline"]
