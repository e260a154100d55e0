"""What ``nsd ida``'s cross-check prints and counts (nsd_cli.ida_check writes the entries): the checked
records' entries, one line each, and the runs this call did with their wall seconds."""
from __future__ import annotations


def entries(check: dict) -> list[tuple[str, dict]]:
    """(configuration, entry) of every checked record: the median's, then the others (--cross-check all)."""
    out = [(n, check[n]) for n in ("device", "nodevice") if isinstance(check.get(n), dict)]
    for n, lst in (check.get("records") or {}).items():
        out += [(n, e) for e in lst if isinstance(e, dict)]
    return out


def describe_entry(name: str, c: dict) -> str:
    """One printed line: the record, the level, each engine's difference and wall time."""
    if "engines" not in c:
        return f"cross-check {name}: {c.get('skipped') or c.get('error')}"
    def when(m):
        t = m.get("wall_time")
        return "" if not isinstance(t, (int, float)) else f" ({t:.1f} s" + ("" if m.get("run_now") else ", stored") + ")"
    def est(m):
        d = (m.get("estimates") or {}).get("du")
        if d is None:
            return ""
        need = "".join(f"; not converged: needs {k} <= {v:.2g} s" for k, v in (m.get("step_needed") or {}).items())
        r = m.get("refined")
        if r:   # the first pair's verdict, then the step it ran again at
            (k, a), (_, b) = next(iter(r["from"].items())), next(iter(r["to"].items()))
            f = m.get("first") or {}
            was = (f.get("estimates") or {}).get("du")
            need += (f"; refined: {k} {a:.3g} -> {b:.3g} s, where its first pair said {f.get('verdict')}"
                     + (f" (du estimate {was['estimate']:.1e})" if was else ""))
        return f" (estimate {d['estimate']:.1e}, {m['verdict']}{need})"
    parts = [(f"{e} du {m['du']:.2e}" + est(m) if "du" in m else f"{e} {m.get('status')}") + when(m)
             for e, m in c["engines"].items()]
    own = (c.get("wall_time") or {}).get("semirecursive")
    if isinstance(own, (int, float)):
        stored = "" if (c.get("run_now") or {}).get("semirecursive") else ", stored"
        err = c.get("in_house_error") or {}
        mine = f"; its own error du {err['du']:.1e}, dF {err['dF']:.1e}" if "du" in err and "dF" in err else ""
        parts.append(f"in-house re-run ({own:.1f} s{stored}{mine})")
    return f"cross-check {name}: record {c['record']} at {c['level']:.4g} m/s^2: " + ", ".join(parts)


def cost(check: dict) -> dict:
    """The cross-check's runs done in this call: count and wall seconds per engine (stored runs excluded)."""
    per = {}
    for _, c in entries(check):
        timed = [("semirecursive", (c.get("wall_time") or {}).get(k), (c.get("run_now") or {}).get(k))
                 for k in ("semirecursive", "converged")]   # the re-run and, with the device, its converged one
        timed += [(e, mm.get(w), mm.get(n)) for e, m in (c.get("engines") or {}).items() if e != "exact"
                  for mm in (m, m.get("first") or {})   # a refined peer: its first pair too
                  for w, n in (("wall_time", "run_now"), ("check_wall_time", "check_run_now"))]
        for e, t, now in timed:
            if now and isinstance(t, (int, float)):
                n, s = per.get(e, (0, 0.0))
                per[e] = (n + 1, s + t)
    return {e: {"runs": n, "wall_s": s} for e, (n, s) in per.items()}
