"""``nsd compare --refine``: a peer that is not converged at its case settings runs once more at the
step its own estimate asks for, within a cost cap, and the verdict is taken again on that run; a peer
whose estimate is uncertain (observed order far below its method's), or whose agreement is undecided
(its companion run is within the bound its run exceeds, or its difference did not fall with the step),
runs once at half its step. A refined peer is marked on its case (``refined``): a difference that has
still not fallen at the refined pair (three steps: h/2, h, 2h) is a disagreement there, not undecided.

The step asked for is the one at which the estimated error falls to 0.8 x the engineering tolerance
(error ~ step^p, comparisons.estimate.step_needed). The cap: at most ``MAX_REFINE`` x the case's
steps (the step not below the case's step / MAX_REFINE); a step the cap stops is used at the cap and
the verdict says so. Only the refined runs (and their 2h companions) are new: every other run is read back
from the folder (the same inputs, the same kept runs).
"""
from __future__ import annotations

import dataclasses

from comparisons.reference import CONVERGED_SETTINGS

MAX_REFINE = 8.0


def refinements(cases, summary: dict) -> tuple[list, list[dict]]:
    """The case list with each not-converged peer's step set to what its estimate asks (capped),
    and one record per change: case, engine, setting, from, to, asked, capped."""
    changes, by_name = [], {c.name: c for c in cases}
    new = dict(by_name)
    for case_name, per in summary.get("verdicts", {}).items():
        for engine, v in per.items():
            needs, step = v.get("needs"), v.get("step")
            if v.get("consistent") is False or not step:
                continue
            if needs and not v.get("accurate"):
                (setting, asked), = needs.items()
            elif (v.get("uncertain") or {"companion", "stalled"} & set(v.get("undecided") or {})) and v.get("setting"):
                # check the estimate one halving further
                setting, asked = v["setting"], step / 2.0
            else:
                continue
            # a step: at most MAX_REFINE x the steps; the in-house rtol: not below the converged reference's
            to = max(asked, CONVERGED_SETTINGS["rtol"]) if setting == "rtol" else max(asked, step / MAX_REFINE)
            c = new[case_name]
            settings = {**c.settings, engine: {**c.settings.get(engine, {}), setting: to}}
            new[case_name] = dataclasses.replace(c, settings=settings, refined=(*c.refined, engine))
            changes.append({"case": case_name, "engine": engine, "setting": setting, "from": step, "to": to,
                            "asked": asked, "capped": to > asked})
    return [new[c.name] for c in cases], changes


def refine_text(changes: list[dict]) -> list[str]:
    def unit(r):
        return "" if r["setting"] == "rtol" else " s"
    return [f"refined {r['case']}: {r['engine']} {r['setting']} {r['from']:.3g} -> {r['to']:.3g}{unit(r)}"
            + (f" (asked {r['asked']:.3g}{unit(r)}; capped: " + ("the converged reference's rtol)" if r["setting"] == "rtol"
               else f"{MAX_REFINE:g}x the case's steps)") if r["capped"] else "")
            for r in changes]
