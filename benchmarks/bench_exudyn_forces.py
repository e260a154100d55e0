"""Exudyn's compiled force path (comparisons/builders/exudyn_compiled.py), revision against revision
(docs/performance.md): the generated module's evaluation and pre-step call alone, and whole Exudyn
runs that spend them, each revision from its own source tree and its own empty compile cache.

    python benchmarks/bench_exudyn_forces.py --revisions 984438c,HEAD [--repeats 3] --out DIR

Each revision is exported with ``git archive`` (its committed files only) and measured in fresh
processes, the revisions alternating repeat by repeat; the median of the repeats is reported. A
process measures, on the device's drive (A25.5mm_f1Hz's description):
- ``evaluate`` (the generalized forces at one state) and ``advance`` (the pre-step's call: the laws'
  commit, then the forces at the Taylor-predicted state), each called 200 000 times from a compiled
  loop (numba's dispatch from Python excluded: the compiled work alone, microseconds a call);
- three whole runs, their ``wall_time`` (the stepping, start-up excluded): the gate's A25.5mm_f10Hz
  (forces "predicted", at its gate step) and the isolator's description (models/nsd_seismic.toml,
  2 s at 1e-4 s) with forces "compiled" (implicit: the force function in every Newton iteration and
  its compiled Jacobian) and "predicted";
- a SHA-256 of every output of those runs: equal across revisions when the numbers are the same bit
  for bit.
"""
from __future__ import annotations

import argparse
import hashlib
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
CALLS = 200_000
RUNS = (("A25.5mm_f10Hz (gate)", None), ("nsd_seismic compiled", "compiled"), ("nsd_seismic predicted", "predicted"))


def _digest(columns: dict) -> str:
    h = hashlib.sha256()
    for name in sorted(columns):
        h.update(name.encode())
        h.update(np.ascontiguousarray(columns[name], dtype=float).tobytes())
    return h.hexdigest()


def child() -> dict:
    """The measurements of one process, in the source tree it runs in (the module's docstring)."""
    import tomllib

    import numpy as np
    from numba import njit

    from comparisons.builders import exudyn as ex
    from comparisons.builders.exudyn_solver import check_settings
    from comparisons.config import load_cases
    from comparisons.engines import run_engine
    from comparisons.engines.described import builder_settings, described_model
    from nsd_core.model.load import parse_model

    cases = {c.name: c for c in load_cases()}
    c = cases["A25.5mm_f1Hz"]
    model, _ = described_model(c.params, c.drive)
    s = check_settings(builder_settings("exudyn", c.settings.get("exudyn"), c.drive.frequency), model)
    h = float(c.settings["exudyn"]["step_size"])
    b = ex.Build(model, s, h)
    b.mbs.Assemble()
    cf, sd = b.compiled, b.mbs.systemData
    q, qt, qtt = (np.asarray(v()) for v in (sd.GetODE2Coordinates, sd.GetODE2Coordinates_t, sd.GetODE2Coordinates_tt))
    ix = cf.node_index(b.mbs)
    evaluate, advance = cf.gen.evaluate, cf.gen.advance

    @njit
    def loop_evaluate(n, q, q_t, F, I, W, f):
        for _ in range(n):
            evaluate(q, q_t, F, I, W, f)
        return 0

    @njit
    def loop_advance(n, q, q_t, q_tt, ix, h, F, I, W, f):
        for _ in range(n):
            advance(q, q_t, q_tt, ix, h, True, F, I, W, f)
        return 0

    W = cf.W.copy()
    out = {}
    qi, qti = q[ix], qt[ix]
    loop_evaluate(10, qi, qti, cf.F, cf.I, W, cf.f)
    t = time.perf_counter()
    loop_evaluate(CALLS, qi, qti, cf.F, cf.I, W, cf.f)
    out["evaluate_us"] = (time.perf_counter() - t) / CALLS * 1e6
    loop_advance(10, q, qt, qtt, ix, h, cf.F, cf.I, W, cf.f)
    t = time.perf_counter()
    loop_advance(CALLS, q, qt, qtt, ix, h, cf.F, cf.I, W, cf.f)
    out["advance_us"] = (time.perf_counter() - t) / CALLS * 1e6
    gate = cases["A25.5mm_f10Hz"]
    seismic = parse_model(tomllib.loads((Path("models") / "nsd_seismic.toml").read_text()), "nsd_seismic")
    runs, digests = {}, {}
    for label, forces in RUNS:
        for warm in (True, False):   # a short run first: the machine code loaded, not in the timed run
            if forces is None:
                r = run_engine("exudyn", gate.params_for("exudyn"), gate.drive, gate.settings.get("exudyn"))
                cols = r.columns
            else:
                r = ex.simulate(seismic, 0.05 if warm else 2.0, 0.01, {"step_size": 1e-4, "forces": forces})
                cols = r.outputs
        runs[label] = float(r.stats["wall_time"])
        digests[label] = _digest(cols)
    out["runs_s"], out["digests"] = runs, digests
    return out


def _tree(rev: str, where: Path) -> tuple[Path, str]:
    sha = subprocess.run(["git", "rev-parse", "--short=12", rev], cwd=ROOT, capture_output=True, text=True,
                         check=True).stdout.strip()
    tree = where / sha
    tree.mkdir()
    archive = subprocess.run(["git", "archive", sha], cwd=ROOT, capture_output=True, check=True).stdout
    subprocess.run(["tar", "-x", "-C", str(tree)], input=archive, check=True)
    return tree, sha


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--revisions", default="984438c,HEAD", help="two git revisions, comma-separated")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--out", required=False)
    ap.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    a = ap.parse_args(argv)
    if a.child:
        print(json.dumps(child()))
        return 0
    if not a.out:
        ap.error("--out is required")
    revs = [r.strip() for r in a.revisions.split(",") if r.strip()]
    if len(revs) != 2:
        print(f"--revisions = {a.revisions!r}: two git revisions, comma-separated", file=sys.stderr)
        return 2
    for r in revs:
        if subprocess.run(["git", "rev-parse", "--verify", "--quiet", f"{r}^{{commit}}"], cwd=ROOT,
                          capture_output=True).returncode != 0:
            print(f"--revisions: {r!r} is not a commit of this repository", file=sys.stderr)
            return 2
    if a.repeats < 1:
        print(f"--repeats = {a.repeats}: must be >= 1", file=sys.stderr)
        return 2
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        trees = [_tree(r, Path(tmp)) for r in revs]
        for k in range(a.repeats + 1):   # repeat 0: each tree compiles its module on its own empty cache
            for (tree, sha), rev in zip(trees, revs):
                env = {**os.environ, "PYTHONPATH": str(tree), "XDG_CACHE_HOME": str(Path(tmp) / f"cache-{sha}")}
                env.pop("NUMBA_CACHE_DIR", None)
                load = os.getloadavg()[0]
                p = subprocess.run([sys.executable, str(Path(__file__).resolve()), "--child"], cwd=tree, env=env,
                                   capture_output=True, text=True)
                if p.returncode != 0:
                    print(p.stderr[-2000:], file=sys.stderr)
                    return 1
                if k > 0:
                    rows.append({"revision": rev, "commit": sha, "repeat": k, "load_before": load,
                                 **json.loads(p.stdout.strip().splitlines()[-1])})
    summary = []
    for rev in revs:
        mine = [r for r in rows if r["revision"] == rev]
        summary.append({"revision": rev, "commit": mine[0]["commit"],
                        "evaluate_us": statistics.median(r["evaluate_us"] for r in mine),
                        "advance_us": statistics.median(r["advance_us"] for r in mine),
                        "runs_s": {lab: statistics.median(r["runs_s"][lab] for r in mine) for lab, _ in RUNS},
                        "digests": mine[0]["digests"],
                        "digests_stable": all(r["digests"] == mine[0]["digests"] for r in mine)})
    same = {lab: summary[0]["digests"][lab] == summary[1]["digests"][lab] for lab, _ in RUNS}
    from nsd_core.common.files import atomic_write_json
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    atomic_write_json(out / "bench_exudyn_forces.json", {"repeats": a.repeats, "calls": CALLS, "rows": rows,
                                                         "summary": summary, "same_numbers": same})
    for s in summary:
        print(f"{s['revision']:>10} ({s['commit']}): evaluate {s['evaluate_us']:.2f} us, advance "
              f"{s['advance_us']:.2f} us, runs " + ", ".join(f"{k} {v:.2f} s" for k, v in s["runs_s"].items()))
    print("same numbers bit for bit:", same)
    return 0


if __name__ == "__main__":
    sys.exit(main())
