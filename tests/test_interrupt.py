"""Clean interrupts: Ctrl-C (SIGINT to the process group, as a terminal sends it) or SIGTERM
(to the parent alone, as `kill` sends it) stops nsd compare and nsd sweep within seconds with one line
"interrupted; N of M cases kept in DIR", exit 130 / 143, no traceback, no worker left behind, no
half-written file; a re-run resumes what was kept and completes."""
import glob
import os
import re
import signal
import subprocess
import sys
import time

import psutil
import pytest

pytestmark = pytest.mark.slow

CASES = """
[defaults]
cycles = 1
samples_per_cycle = 1000   # the energy balance is a trapezoid quadrature: ~7e-4 at 100 samples, ~2e-6 at 2000
[[case]]
name = "a"
amplitude = 0.015
frequency = 10.0
[[case]]
name = "b"
amplitude = 0.02
frequency = 10.0
[[case]]
name = "c"
amplitude = 0.015
frequency = 1.0
[[case]]
name = "d"
amplitude = 0.02
frequency = 1.0
[[case]]
name = "e"
amplitude = 0.01
frequency = 1.0
[[case]]
name = "f"
amplitude = 0.012
frequency = 1.0
"""
# the compiled engines run a case in well under a second: enough cases that some are still running
# when the first is kept


@pytest.fixture(scope="module", autouse=True)
def warm_compiled_code(tmp_path_factory):
    """Run each command once to the end first, so numba's on-disk cache is warm: a signal cannot
    interrupt a compilation in progress (it is handled when the compiler returns), and these tests
    are about interrupting work, not compilation (a fresh clone starts with a cold cache)."""
    d = tmp_path_factory.mktemp("warm")
    (d / "cases.toml").write_text(CASES.split("[[case]]")[0] + "[[case]]" + CASES.split("[[case]]")[1])
    for args in (["compare", "--cases", str(d / "cases.toml"), "--engines", "semirecursive,mujoco", "--workers", "2",
                  "--out", str(d / "compare")],
                 ["sweep", "--param", "rod_length", "--values", "0.03", "--frequency", "1", "--cycles", "1",
                  "--samples-per-cycle", "100", "--workers", "1", "--out", str(d / "sweep")]):
        r = subprocess.run([sys.executable, "-m", "nsd_cli.main", *args], capture_output=True, text=True, timeout=900)
        assert r.returncode == 0, r.stdout + r.stderr


def start(args):
    return subprocess.Popen([sys.executable, "-m", "nsd_cli.main", *args], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, start_new_session=True)


def interrupt_after_first_kept(p, pattern, signum, to_group):
    """Wait until a first result is kept, then signal; returns (stderr, seconds to stop, children)."""
    t0 = time.time()
    while not glob.glob(pattern):
        assert p.poll() is None, p.communicate()
        assert time.time() - t0 < 400, "nothing was kept in 400 s"
        time.sleep(0.2)
    children = psutil.Process(p.pid).children(recursive=True)
    sent = time.time()
    os.killpg(p.pid, signum) if to_group else p.send_signal(signum)
    out, err = p.communicate(timeout=60)
    return out, err, time.time() - sent, children


def check_stopped(p, err, seconds, children, signum, out_dir):
    assert p.returncode == 128 + signum, err
    assert "Traceback" not in err, err
    last = err.strip().splitlines()[-1]
    m = re.fullmatch(r"nsd: interrupted; (\d+) of (\d+) cases kept in (.+)", last)
    assert m and m.group(3) == str(out_dir), last
    assert 1 <= int(m.group(1)) < int(m.group(2))
    assert seconds < 10, f"took {seconds:.1f} s to stop"
    deadline = time.time() + 5
    while time.time() < deadline and any(c.is_running() and c.status() != psutil.STATUS_ZOMBIE for c in children):
        time.sleep(0.1)
    assert not [c.pid for c in children if c.is_running() and c.status() != psutil.STATUS_ZOMBIE]
    assert not glob.glob(str(out_dir / "**" / "*.tmp*"), recursive=True), "a half-written file was left"
    return int(m.group(1))


@pytest.mark.parametrize("signum,to_group", [(signal.SIGINT, True), (signal.SIGTERM, False)])
def test_compare_interrupted_then_resumed(tmp_path, signum, to_group):
    cases = tmp_path / "cases.toml"
    cases.write_text(CASES)
    out = tmp_path / "out"
    args = ["compare", "--cases", str(cases), "--engines", "semirecursive,mujoco", "--workers", "2", "--out", str(out)]
    p = start(args)
    _, err, seconds, children = interrupt_after_first_kept(p, str(out / "cycles" / "*.json"), signum, to_group)
    kept = check_stopped(p, err, seconds, children, signum, out)
    assert not (out / "results.json").exists()
    again = subprocess.run([sys.executable, "-m", "nsd_cli.main", *args], capture_output=True, text=True, timeout=600)
    assert again.returncode == 0, again.stdout + again.stderr
    assert again.stdout.count(" kept ") >= kept  # read back, not run again
    assert (out / "results.json").exists()


def test_sweep_interrupted_then_resumed(tmp_path):
    out = tmp_path / "sweep"
    # 40 designs x 10 cycles: ~0.3 s a design with the generated evaluation (8 designs x 2 cycles all
    # finished between two 0.2 s looks in CI), so several are still running when the first is kept
    values = ",".join(f"{0.026 + 0.0002 * i:.4f}" for i in range(40))
    args = ["sweep", "--param", "rod_length", "--values", values,
            "--frequency", "1", "--cycles", "10", "--samples-per-cycle", "100", "--workers", "2", "--out", str(out)]
    p = start(args)
    _, err, seconds, children = interrupt_after_first_kept(p, str(out / "designs" / "*" / "result.json"),
                                                           signal.SIGTERM, False)
    kept = check_stopped(p, err, seconds, children, signal.SIGTERM, out)
    again = subprocess.run([sys.executable, "-m", "nsd_cli.main", *args], capture_output=True, text=True, timeout=600)
    assert again.returncode == 0, again.stdout + again.stderr
    assert f"{kept} already stored" in again.stderr


HALF_SENT = '''
import gc, os, struct, time
from multiprocessing.queues import SimpleQueue

def half_sent(marker):
    """What a worker stopped while sending a large result leaves in the pipe: the length, a few bytes."""
    results = next(o for o in gc.get_objects() if isinstance(o, SimpleQueue))
    os.write(results._writer.fileno(), struct.pack("!i", 1 << 20) + b"x" * 10)
    open(marker, "w").close()
    time.sleep(60)
'''

STOP_AFTER_HALF_SENT = '''
import os, sys, time
from halfsent import half_sent
from nsd_core.engine.workers import worker_pool
marker = sys.argv[1]
try:
    with worker_pool(1) as pool:
        pool.submit(half_sent, marker)
        deadline = time.time() + 60
        while not os.path.exists(marker) and time.time() < deadline:
            time.sleep(0.01)
        time.sleep(0.2)  # the pool's manager thread reads the length, then waits for the rest
        raise KeyboardInterrupt
except KeyboardInterrupt:
    print("stopped", flush=True)
'''


def test_worker_stopped_mid_result_does_not_hang_the_exit(tmp_path):
    """A run's result (over 64 KiB) goes down the pipe in several writes: a worker stopped in between
    must not leave the pool's manager thread waiting for the rest, which the interpreter joins on exit
    (nsd printed "interrupted" and then never exited)."""
    (tmp_path / "halfsent.py").write_text(HALF_SENT)
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [str(tmp_path), os.environ.get("PYTHONPATH")]))}
    r = subprocess.run([sys.executable, "-c", STOP_AFTER_HALF_SENT, str(tmp_path / "sent")], env=env,
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 0 and r.stdout == "stopped\n", r.stdout + r.stderr
    assert "Traceback" not in r.stderr, r.stderr
