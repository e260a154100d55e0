"""Warm pool workers: ``worker_pool(n, warm=...)`` runs the warm-up once in each
worker before its first job, reports its cost apart (``pool.startup``), and the warm-ups the
commands build touch exactly the kernels their jobs then use (a job's ``compile_time`` is 0)."""
from __future__ import annotations

import os
import time
from functools import partial

import pytest

from nsd_core.engine.workers import worker_pool

WARM_CALLS = 0
WARM_SLEEP = 0.4


def _slow_warm() -> None:
    global WARM_CALLS
    WARM_CALLS += 1
    time.sleep(WARM_SLEEP)


def _failing_warm() -> None:
    raise RuntimeError("no such kernel")


def _job(_):
    t0 = time.perf_counter()
    return os.getpid(), WARM_CALLS, time.perf_counter() - t0


def test_warm_runs_once_per_worker_before_its_first_job_and_is_reported_apart():
    t0 = time.perf_counter()
    with worker_pool(2, warm=_slow_warm) as pool:
        out = list(pool.map(_job, range(8)))
        startup = pool.startup.summary()
    assert time.perf_counter() - t0 >= WARM_SLEEP
    assert {calls for _, calls, _ in out} == {1}          # every job, first or not, after exactly one warm-up
    pids = {pid for pid, _, _ in out}
    assert startup["workers"] == len(startup["per_worker"]) >= len(pids)
    assert pids <= {w["pid"] for w in startup["per_worker"]}
    for w in startup["per_worker"]:
        assert WARM_SLEEP <= w["warm_s"] < WARM_SLEEP + 5 and w["warm_error"] is None
        assert 0 < w["spawn_s"] < 120 and w["ready_s"] == pytest.approx(w["spawn_s"] + w["warm_s"])
    assert startup["warm_s"] == max(w["warm_s"] for w in startup["per_worker"])
    assert max(t for _, _, t in out) < WARM_SLEEP           # the jobs' own times hold none of it


def test_a_failing_warm_up_is_reported_and_the_jobs_still_run():
    with worker_pool(1, warm=_failing_warm) as pool:
        out = list(pool.map(_job, range(2)))
        startup = pool.startup.summary()
    assert len(out) == 2
    assert startup["per_worker"][0]["warm_error"] == "RuntimeError: no such kernel"


def _seismic_job(settings):
    from nsd_core.ground.records import fema_record
    from nsd_core.structure.isolation import default_structure
    from nsd_core.device.params import Params
    from nsd_core.structure.seismic import simulate_seismic
    motion = fema_record("farfield", 2, window=(0.0, 0.2))
    r = simulate_seismic(Params(), default_structure(Params()), motion, duration=0.05, **settings)
    return r.stats["compile_time"]


def _peer_job(engine):
    from comparisons.engines import run_job
    from nsd_core.device.drive import Drive
    from nsd_core.device.params import Params
    job = run_job(engine, Params(), Drive(0.002, 10.0, cycles=1, samples_per_cycle=20), {})
    return job["status"], job["result"].stats["compile_time"] if job["status"] == "ok" else job["message"]


def test_record_set_warm_up_touches_the_kernels_its_runs_use():
    """A record set's warm-up (in-house seismic kernels of the runs' settings, the set's files):
    the worker's first run then compiles nothing and reads no file (its compile_time is 0)."""
    from nsd_core.structure.isolation import default_structure
    from nsd_core.device.params import Params
    from nsd_core.study.seismic_set import RecordRun, set_warmup
    settings = {"method": "RK45"}
    run = RecordRun(set="farfield", record=2, device=True, ground={"window": [0.0, 0.2]}, params=Params().to_dict(),
                    structure=default_structure(Params()).to_dict(), duration=0.05, dt_out=1e-3, settings=settings)
    with worker_pool(1, warm=set_warmup([run])) as pool:
        assert pool.submit(_seismic_job, settings).result() == 0.0
        # a setting the warm-up did not name still warms on its own, inside the job, timed apart (the
        # default DOP853 too: a worker compiles what its warm-up names, not every mode, nsd_core.compilation.warm_all)
        assert pool.submit(_seismic_job, {"method": "DOP853"}).result() > 0.0
        startup = pool.startup.summary()
    assert startup["per_worker"][0]["warm_error"] is None and startup["warm_s"] > 0


def test_compare_warm_up_touches_the_peers_callbacks():
    """MuJoCo's import and compiled callbacks, and the in-house drive kernels, before the first job."""
    from comparisons.warmup import job_warmup, spec
    from nsd_core.device.drive import Drive
    warm = job_warmup([spec("mujoco", False, Drive(0.015, 1.0), {}), spec("semirecursive", False, Drive(0.015, 1.0))])
    with worker_pool(1, warm=warm) as pool:
        assert pool.submit(_peer_job, "mujoco").result() == ("ok", 0.0)
        assert pool.submit(_peer_job, "semirecursive").result() == ("ok", 0.0)


def test_warm_kind_matches_the_runs_key():
    from nsd_core.compilation.worker_warmup import kind
    assert kind("drive", None, "figure8") == ("drive", "DOP853", "auto", "figure8")
    assert kind("drive", {"method": "RK45", "rtol": 1e-3}, "/some/table.csv") == ("drive", "RK45", "auto", "line")
    assert kind("seismic", {"backend": "scipy"}) == ("seismic", "DOP853", "scipy", "line")


def test_warm_ups_pickle():
    """Spawned workers get the warm-up pickled: every command's warm-up must survive it."""
    import pickle
    from comparisons.warmup import job_warmup, spec
    from nsd_core.device.drive import Drive
    from nsd_core.study.designs import Design  # noqa: F401 (the sweep's items)
    from nsd_core.study.sweep import sweep_warmup
    warm = job_warmup([spec("exudyn", True, None, {"step_size": 1e-4}), spec("mujoco", False, Drive(0.01, 1.0, path="circle"))])
    assert pickle.loads(pickle.dumps(warm)).args[2][0].args[0] == "exudyn"
    assert pickle.loads(pickle.dumps(sweep_warmup([]))).args == ((), (), ())
    assert pickle.loads(pickle.dumps(partial(_slow_warm)))


def test_a_peers_warm_up_runs_at_its_named_choices_not_at_the_cases_step():
    """What compiles depends on the named choices (MuJoCo's integrator); a case's own fine step
    (Exudyn at 6.25e-6 s for A25.5mm_f1Hz) made each worker's tiny run cost 2.5 s."""
    from comparisons.warmup import job_warmup, spec
    from nsd_core.device.drive import Drive
    warm = job_warmup([spec("exudyn", False, Drive(0.0255, 1.0), {"step_size": 6.25e-6}),
                       spec("mujoco", False, Drive(0.0255, 1.0), {"integrator": "RK4", "timestep": 2.5e-5})])
    assert [c.args[0] for c in warm.args[2]] == ["exudyn", "mujoco"]
    assert [c.args[3] for c in warm.args[2]] == [{"min_steps_per_cycle": 100}, {"integrator": "RK4"}]
