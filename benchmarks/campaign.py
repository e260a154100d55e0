"""The randomized differential campaign: N generated mechanisms (comparisons.campaign) through every
engine under the per-run rule, each non-PASS re-run with --refine and classified.

    python benchmarks/campaign.py --seeds 0-299 --out OUT [--workers 2] [--timeout 600]

Each mechanism runs in a forked child (the imports and compiled code of this process shared), at most
``--workers`` at once, each stopped after ``--timeout`` s (class ``timeout``). OUT holds each
mechanism's description (mechanism_SEED.toml) and record (SEED.json; a rerun skips the seeds that
have one) and ``campaign.json``: the records, the count of each class, the time. Reproducible: a seed
gives the same description on any machine (numpy's PCG64), and the same verdicts.
"""
from __future__ import annotations

import argparse
import collections
import json
import multiprocessing as mp
import os
import sys
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def seeds_of(text: str) -> list[int]:
    """'0-299' or '1,5,7-9' as the seeds; a malformed list raises ValueError naming the flag."""
    out = []
    for part in text.split(","):
        lo, _, hi = part.strip().partition("-")
        if not lo.isdigit() or not (hi or lo).isdigit() or int(hi or lo) < int(lo):
            raise ValueError(f"--seeds {text!r}: {part!r} is not a seed or a range LO-HI of whole numbers >= 0 "
                             "(e.g. 0-299 or 1,5,7-9)")
        out += list(range(int(lo), int(hi or lo) + 1))
    return out


def _child(seed: int, folder: str) -> None:
    from comparisons.campaign.run import run_seed
    try:
        rec = run_seed(seed, Path(folder))
    except Exception as e:  # noqa: BLE001 (the harness itself failed on this mechanism: kept as a class)
        rec = {"seed": seed, "cls": "harness_error", "reason": f"{type(e).__name__}: {e}"[:400]}
    tmp = Path(folder) / f"{seed}.json.tmp"
    tmp.write_text(json.dumps(rec, default=float))
    os.replace(tmp, Path(folder) / f"{seed}.json")


def run(seeds: list[int], folder: Path, workers: int, timeout: float, log=print) -> None:
    ctx = mp.get_context("fork")
    todo = [s for s in seeds if not (folder / f"{s}.json").exists()]
    lock, queue = threading.Lock(), list(todo)

    def worker():
        while True:
            with lock:
                if not queue:
                    return
                seed = queue.pop(0)
            start = time.perf_counter()
            p = ctx.Process(target=_child, args=(seed, str(folder)))
            p.start()
            p.join(timeout)
            if p.is_alive():
                p.kill()
                p.join()
                (folder / f"{seed}.json").write_text(json.dumps({"seed": seed, "cls": "timeout", "wall_time": timeout}))
            rec = json.loads((folder / f"{seed}.json").read_text()) if (folder / f"{seed}.json").exists() else \
                {"seed": seed, "cls": "harness_error", "reason": f"child exit {p.exitcode}"}
            if not (folder / f"{seed}.json").exists():
                (folder / f"{seed}.json").write_text(json.dumps(rec))
            log(f"seed {seed}: {rec['cls']} ({rec.get('family', '')}, {time.perf_counter() - start:.1f} s)", flush=True)
    threads = [threading.Thread(target=worker) for _ in range(workers)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()


def compact(r: dict) -> dict:
    """A record as kept in campaign.json: every mechanism's class, time and each engine's worst
    difference / bound and error / tolerance; a non-PASS's verdict texts and refinements whole."""
    out = {k: r[k] for k in ("seed", "family", "source", "cls", "wall_time", "reason") if k in r}
    for stage in ("first", "refined"):
        if stage in r:
            out[stage] = {case: {e: ({k: v[k] for k in ("pass", "uncertain")} | {
                "ratio": (v.get("worst") or {}).get("ratio"), "error_over_tolerance":
                (v.get("worst") or {}).get("error_over_tolerance")} if r["cls"] == "pass" else v)
                for e, v in per.items()} for case, per in r[stage].items()}
    if "refine_changes" in r:
        out["refine_changes"] = r["refine_changes"]
    if "referee" in r:   # the symbolic engine's side where a peer disagreed (comparisons.campaign.referee)
        out["referee"] = r["referee"]
    return out


def worst(records: list[dict]) -> dict:
    """engine -> the largest difference / bound and error / tolerance over every PASS verdict."""
    out = {}
    for r in records:
        for per in (r.get("refined") or r.get("first") or {}).values():
            for e, v in per.items():
                if not v.get("pass"):
                    continue
                w = out.setdefault(e, {"ratio": 0.0, "error_over_tolerance": 0.0, "uncertain": 0})
                ratio = v.get("ratio", (v.get("worst") or {}).get("ratio")) or 0.0
                err = v.get("error_over_tolerance", (v.get("worst") or {}).get("error_over_tolerance")) or 0.0
                w["ratio"], w["error_over_tolerance"] = max(w["ratio"], ratio), max(w["error_over_tolerance"], err)
                w["uncertain"] += bool(v.get("uncertain"))
    return out


def collect(seeds: list[int], folder: Path, wall: float) -> dict:
    records = [json.loads((folder / f"{s}.json").read_text()) for s in seeds if (folder / f"{s}.json").exists()]
    classes = collections.Counter(r["cls"] for r in records)
    families = collections.Counter(r.get("family", "?") for r in records)
    return {"n": len(records), "seeds": [min(seeds), max(seeds)], "classes": dict(classes), "families": dict(families),
            "wall_s": wall, "mechanism_wall_s": {"median": _median([r.get("wall_time", 0.0) for r in records]),
                                                  "max": max((r.get("wall_time", 0.0) for r in records), default=0.0)},
            "worst_pass": worst(records), "referee": referee_sides(records), "records": [compact(r) for r in records]}


def referee_sides(records: list[dict]) -> dict:
    """side -> how many (mechanism, case, disagreeing peer) the symbolic referee put there."""
    return dict(collections.Counter(f["side"] for r in records for per in (r.get("referee") or {}).values()
                                    for f in per.values()))


def _median(v):
    v = sorted(v)
    return v[len(v) // 2] if v else None


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--seeds", default="0-299")
    p.add_argument("--out", required=True)
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--timeout", type=float, default=600.0)
    p.add_argument("--engines", default="semirecursive,mujoco,exudyn",
                   help="the engines each mechanism runs in (symbolic: the symbolic engine as a 4th peer)")
    p.add_argument("--referee", choices=("symbolic", "none"), default="symbolic",
                   help="where a peer disagrees, run the symbolic engine and record whose side it takes")
    a = p.parse_args(argv)
    try:   # bad input: one line, exit 2, nothing written
        seeds = seeds_of(a.seeds)
        if a.workers < 1:
            raise ValueError(f"--workers {a.workers}: must be a whole number >= 1")
        if not 0 < a.timeout < float("inf"):
            raise ValueError(f"--timeout {a.timeout}: must be a number of seconds > 0")
        from comparisons.model_compare import BUILDERS, REFERENCE
        engines = [e.strip() for e in a.engines.split(",") if e.strip()]
        if REFERENCE not in engines or not set(engines) <= set(BUILDERS) or len(set(engines)) != len(engines):
            raise ValueError(f"--engines {a.engines!r}: each engine once, {REFERENCE} included; allowed: "
                             f"{', '.join(BUILDERS)}")
    except ValueError as e:
        print(f"campaign: {e}", file=sys.stderr)
        return 2
    folder = Path(a.out)
    folder.mkdir(parents=True, exist_ok=True)
    from comparisons.campaign import run as _warm   # (imports paid once, before the forks)
    _warm.ENGINES[:] = engines          # the forked children inherit the engines and the referee's switch
    _warm.REFEREE["on"] = a.referee == "symbolic"
    import comparisons.builders.exudyn, comparisons.builders.mujoco, nsd_core.model.semirecursive  # noqa: F401,E401
    import comparisons.builders.symbolic, comparisons.campaign.referee  # noqa: F401,E401
    start = time.perf_counter()
    run(seeds, folder, a.workers, a.timeout)
    summary = collect(seeds, folder, time.perf_counter() - start)
    (folder / "campaign.json").write_text(json.dumps(summary, indent=1, default=float))
    print(json.dumps(summary["classes"]), f"{summary['n']} mechanisms, {summary['wall_s']:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
