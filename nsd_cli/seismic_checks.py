"""``nsd seismic --design-displacement D``: the building codes' restoring-force check of the isolation
level (``nsd_core.device.restoring_force``; docs/seismic.md, "The restoring-force check"), computed
before the run, in summary.json as ``restoring_force`` and printed in one line."""
from __future__ import annotations


def add_arguments(p) -> None:
    p.add_argument("--design-displacement", default=None, metavar="D",
                   help="the isolation level's design displacement [m] for the restoring-force check "
                        "(F(D) - F(D/2) >= 0.025 W, ASCE/SEI 7-16 17.2.4.4); default: the device's working "
                        "range X_max (25.46 mm for the nominal device); in [1e-06, 0.999 rod length]")


def restoring_force(args, params, structure) -> dict | None:
    """The check for this run's isolation level (None on a fixed base: no isolation level);
    ParameterError, one line, for a bad --design-displacement (before anything is written)."""
    from nsd_core.device.restoring_force import NoDefaultError, check_design_displacement, restoring_force_check
    given = getattr(args, "design_displacement", None)
    if given is not None:
        check_design_displacement(given, params.rod_length)
    if getattr(args, "fixed_base", False):
        return None
    device = not args.no_device or getattr(args, "compare_supports", False) or getattr(args, "compare_building", False)
    try:
        return restoring_force_check(params, structure, given, device=device)
    except NoDefaultError as e:   # a device variant without a working range still runs: the check says why not
        return {"pass": None, "skipped": str(e)}
    except (ValueError, RuntimeError, ArithmeticError) as e:   # a variant the quasi-static path cannot follow
        return {"pass": None, "skipped": "the device's quasi-static force could not be followed to D: "
                                         + " ".join(str(e).split())[:200]}


def print_restoring_force(check: dict | None) -> None:
    if check is not None and "skipped" in check:
        print(f"restoring force: not checked ({check['skipped']})")
    elif check is not None:
        from nsd_core.device.restoring_force import describe
        print(describe(check))
