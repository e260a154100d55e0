"""IFToMM A02 as the library states it (N = 40 four-bars, 20 s), written by references.iftomm_a02: the
committed description files are the generator's, and the three engines pass the gate's rule against
the exact reference over the first 5 s (four singular positions: 0.72, 1.24, 2.69 and 3.21 s). The
whole 20 s case is in models/iftomm_a02_fourbar_n40.toml's comments and docs/validation.md. Exudyn's
builder solves its ~1300 unknowns with Eigen's sparse LU (comparisons/builders/exudyn_solver.py:
dense took ~60-120 ms a step here, sparse ~2 ms)."""
from __future__ import annotations

from multiprocessing import get_context
from pathlib import Path

import pytest

from comparisons.model_cases import load_model_cases
from comparisons.model_compare import compare_model
from nsd_core.model.load import load_model
from references.iftomm_a02 import description

MODELS = Path(__file__).resolve().parents[1] / "models"
N40 = MODELS / "iftomm_a02_fourbar_n40.toml"


def test_the_committed_a02_files_are_the_generators():
    assert N40.read_text() == description(40)
    assert (MODELS / "iftomm_a02_fourbar.toml").read_text() == description(4)


def test_the_n40_description_has_the_librarys_size():
    model = load_model(N40)
    assert len(model.bodies) == 81 and len(model.loops) == 40
    case = load_model_cases(model, None, ("semirecursive",))[0]
    assert (case.duration, case.dt_out) == (20.0, 0.05)
    assert len(case.reference.index) == 401


# on the machines where the in-house reference cannot cross the singular position it crawled there at
# steps of ~1e-14 s for 20 to 40+ minutes before DOP853 gave up (the xfail's reason): the comparison runs
# in a child process, stopped after LIMIT_S, so the slow mark's time stays bounded (it passes in ~1-3 min
# where it passes)
LIMIT_S = 600


@pytest.mark.slow   # ~60 s on 2 loaded cores
@pytest.mark.xfail(strict=False, reason=(
    "on some machines (an Intel Xeon lent on 2026-11-28, at this session's base commit 9196674 as well; a v657 "
    "on 2026-11-30) the converged in-house reference (DOP853, rtol 1e-12) cannot cross A02's singular position: "
    "it crawls at t = 1.24402 s with steps of ~1e-14 s ('DOP853 failed at t = 1.24402 s: Required step size is "
    "less than spacing between numbers' after ~20 min there); Exudyn's run of the same 5 s is 2.25e-4 from the "
    "exact solution there. Open: the in-house engine at singular positions"))
def test_a02_n40_first_5s_passes_in_three_engines(tmp_path):
    ctx = get_context("spawn")
    parent, child = ctx.Pipe(duplex=False)
    p = ctx.Process(target=_first_5s, args=(str(tmp_path), child))
    p.start()
    child.close()
    finished = parent.poll(LIMIT_S)
    try:
        outcome = parent.recv() if finished else None
    except EOFError:   # the child ended without a word
        outcome = f"the comparison's process ended without a result (exit code {p.exitcode})"
    if p.is_alive():
        p.kill()
    p.join()
    if not finished:
        pytest.fail(f"the comparison did not finish within {LIMIT_S} s (stopped)")
    assert outcome == "passed", outcome


def _first_5s(folder: str, conn) -> None:
    """The first 5 s in three engines against the exact reference; sends "passed" or what failed."""
    try:
        model = load_model(N40)
        whole = load_model_cases(model, None, ("semirecursive", "mujoco", "exudyn"))[0]
        settings = "\n".join(f"{e} = {{ {', '.join(f'{k} = {v!r}' for k, v in s.items())} }}"
                             for e, s in whole.settings.items())
        cases = Path(folder) / "cases.toml"
        cases.write_text(f'[[case]]\nname = "a02_5s"\nduration = 5.0\ndt_out = 0.05\n{settings}\n'
                         f'reference = {{ file = "{MODELS / "iftomm_a02_n40_reference.csv"}", source = "exact" }}\n')
        engines = ["semirecursive", "mujoco", "exudyn"]
        s = compare_model(model, load_model_cases(model, str(cases), engines), engines, log=lambda *a: None)
        c = s["cases"]["a02_5s"]
        failed = [f"failures: {c['failures']}"] if c["failures"] else []
        failed += [f"{e}: {c['verdicts'][e]['text']}" for e in engines + ["converged"] if not c["verdicts"][e]["pass"]]
        if not s["passed"]:
            failed.append("not passed")
        conn.send("; ".join(failed) or "passed")
    except Exception as e:  # noqa: BLE001 (what failed goes back to the test, which fails with it)
        conn.send(f"{type(e).__name__}: {e}")
    finally:
        conn.close()
