"""What a user waits for on ``nsd compare --model`` with a description of their own, the first time.

    python benchmarks/bench_model_first.py --out DIR [--models andrews,fourbar_spring,...]

On a snapshot of the committed source (``git archive HEAD``: edits in the working tree during the run
would change the compile cache's key) and one empty cache folder (``XDG_CACHE_HOME`` a new folder,
``NUMBA_CACHE_DIR`` unset):
1. ``nsd compare --model`` on the first description, nothing compiled yet (a user whose first command
   is their own mechanism);
2. ``nsd warm`` (every mode of the package compiled, as after the README's first command or CI);
3. for each description under models/: ``nsd compare --model`` the first time (the package compiled,
   the description new: its generated forces and evaluation compiled now), then again (warm).
Each row keeps the wall and CPU seconds (the process and its workers), the "nsd: compiling" notices,
the verdict's exit code and the load average before. Writes DIR/bench_model_first.json.
"""
from __future__ import annotations

import argparse
import io
import os
import shutil
import subprocess
import sys
import tarfile
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from benchmarks.bench_cold import timed  # noqa: E402
from nsd_core.common.files import atomic_write_json  # noqa: E402
from nsd_core.device.results import versions  # noqa: E402

MODELS = ("fourbar_spring", "andrews", "slider_crank", "iftomm_a01_pendulum", "iftomm_a04_bricard")


def snapshot(where: Path) -> Path:
    """The committed tree of HEAD, unpacked into ``where``."""
    tar = subprocess.run(["git", "archive", "HEAD"], cwd=ROOT, capture_output=True, check=True).stdout
    with tarfile.open(fileobj=io.BytesIO(tar)) as t:
        t.extractall(where, filter="data")
    return where


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--models", default=",".join(MODELS), help="descriptions under models/ (names, comma-separated)")
    ap.add_argument("--out", required=True)
    a = ap.parse_args(argv)
    names = [n for n in a.models.split(",") if n]
    bad = [n for n in names if not (ROOT / "models" / f"{n}.toml").is_file()]
    if bad or not names:
        print(f"bench_model_first: --models {a.models!r}: each must name a file models/NAME.toml", file=sys.stderr)
        return 2
    work = Path(tempfile.mkdtemp(prefix="model-first-"))
    root, rows = snapshot(work / "src"), []

    def run(phase: str, model: str | None, args: list[str], cache: Path, out: Path) -> None:
        r = {"phase": phase, "model": model, "command": "nsd " + " ".join(os.path.basename(a) for a in args),
             **timed(args, out, cache, root)}
        rows.append(r)
        print(f"{phase} {model or ''}: {r['wall_s']:.1f} s wall, {r['cpu_s']:.1f} s CPU, exit {r['exit_code']}",
              flush=True)

    def compare(model: str) -> list[str]:
        return ["compare", "--model", str(root / "models" / f"{model}.toml")]

    run("empty cache, first description", names[0], compare(names[0]), work / "cache-empty", work / "out-0")
    cache = work / "cache"
    run("nsd warm", None, ["warm"], cache, work / "out-warm")   # (no --out: the folder is not used)
    for k, m in enumerate(names, start=1):
        run("package compiled, new description", m, compare(m), cache, work / f"out-{k}")
        run("again (warm)", m, compare(m), cache, work / f"out-{100 + k}")
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    commit = subprocess.run(["git", "rev-parse", "HEAD"], cwd=ROOT, capture_output=True, text=True).stdout.strip()
    atomic_write_json(out / "bench_model_first.json", {"commit": commit, "rows": rows, "cpus": os.cpu_count(),
                                                       "versions": versions()})
    shutil.rmtree(work, ignore_errors=True)
    return 0 if all(r["exit_code"] in (0, 1) for r in rows) else 1


if __name__ == "__main__":
    raise SystemExit(main())
