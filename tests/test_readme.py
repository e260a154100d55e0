"""Every command in README.md runs as written (issue 25): the quick start is the CI's own, every
``nsd`` command parses, the short ones run to exit 0 in a fresh folder (the long ones: their --help),
and the Python example runs."""
from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text(encoding="utf-8")
CI = (ROOT / ".ci" / "run").read_text()
NSD = Path(sys.executable).with_name("nsd")
# long runs (minutes on 2 cores): checked by parsing their options and running their --help
LONG = ("nsd compare", "nsd sweep --paper", "nsd seismic --record-set", "nsd report", "nsd ida",
        "nsd seismic --record nearfield-pulse:1 --scale 0.4 --restrainer",
        "nsd sweep --param rope_stiffness --values 4e5,6e5 --scheduler")  # needs its scheduler: run apart


def blocks(lang: str) -> list[str]:
    return re.findall(rf"```{lang}\n(.*?)```", README, re.S)


def shell_commands() -> list[str]:
    """Every command of the README's sh blocks, in order, split at '&&'."""
    out = []
    for block in blocks("sh"):
        for line in block.splitlines():
            if line.strip() and not line.lstrip().startswith("#"):
                out += [c.strip() for c in line.split("&&")]
    return out


def nsd_commands() -> list[list[str]]:
    return [shlex.split(c)[1:] for c in shell_commands() if c.startswith(".venv/bin/nsd ")]


def test_readme_is_short():
    assert len(README.encode()) <= 14 * 1024


def test_every_command_is_known():
    allowed = re.compile(r"(python3 -m venv \.venv|\.venv/bin/pip install -q -c constraints\.txt -e "
                         r"(\.|'\.\[test\]'|'\.\[dask\]')|\.venv/bin/python -m pytest -q|\.venv/bin/nsd .+"
                         r"|\.venv/bin/dask (scheduler|worker) .+ &)")
    cmds = shell_commands()
    assert len(cmds) >= 12
    for c in cmds:
        assert allowed.fullmatch(c), c


def test_quick_start_is_what_ci_runs():
    """.ci/run runs the README's test command verbatim, in a fresh clone (set -e: any failure fails CI)."""
    test_line = next(line for b in blocks("sh") for line in b.splitlines() if "pytest" in line)
    assert test_line.strip() in CI
    install = next(line for b in blocks("sh") for line in b.splitlines() if "nsd compare --convergence" in line)
    assert install.replace("-e . &&", "-e '.[test]' &&").split(" && .venv/bin/nsd")[0] in CI


@pytest.mark.parametrize("argv", nsd_commands(), ids=" ".join)
def test_every_nsd_command_parses(argv):
    from nsd_cli.main import build_parser
    args = build_parser().parse_args(argv)  # an unknown option or a bad type exits 2 here
    assert args.handler is not None


def _run(argv, cwd, timeout=900):
    env = {**os.environ, "MPLBACKEND": "Agg"}
    return subprocess.run([str(NSD), *argv], cwd=cwd, capture_output=True, text=True, timeout=timeout, env=env)


@pytest.mark.slow
def test_readme_commands_run(tmp_path):
    """In a fresh folder, in the README's order: the short ones to exit 0, the long ones' --help."""
    ran = 0
    for argv in nsd_commands():
        line = "nsd " + " ".join(argv)
        if line.startswith(LONG):
            p = _run([argv[0], "--help"], tmp_path)
            assert p.returncode == 0 and "usage: nsd" in p.stdout, (line, p.stderr)
            continue
        p = _run(argv, tmp_path)
        assert p.returncode == 0, (line, p.stdout[-1500:], p.stderr[-1500:])
        ran += 1
    assert ran >= 6
    for run in ("", "device", "supports"):  # --compare-supports: both runs and the ratios
        assert (tmp_path / "out" / "nf1" / run / "summary.json").is_file(), run
    assert (tmp_path / "out" / "nf1" / "ratios.csv").is_file()
    assert (tmp_path / "out" / "my-device.toml").is_file()


@pytest.mark.slow
def test_readme_python_example_runs(tmp_path):
    drive, quake = blocks("python")
    p = subprocess.run([sys.executable, "-c", drive], cwd=tmp_path, capture_output=True, text=True, timeout=900)
    assert p.returncode == 0, p.stderr[-2000:]
    assert len(p.stdout.split()) == 4


def test_readme_seismic_api_example_runs(tmp_path):
    """The seismic API as the README shows it: the peaks it prints are the run's (0.38 model s twice)."""
    _, quake = blocks("python")
    p = subprocess.run([sys.executable, "-c", quake], cwd=tmp_path, capture_output=True, text=True, timeout=900)
    assert p.returncode == 0, p.stderr[-2000:]
    first, second = p.stdout.splitlines()
    peak, x_max = (float(v) for v in first.split()[:2])
    assert 0.005 < peak < 0.03 and 0 < x_max <= peak           # mm-scale stroke within the 30 mm rod
    drift, top = (float(v) for v in second.split())
    assert 0 < drift < 0.01 and top > 0


def _free_port() -> int:
    import socket
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.mark.slow
def test_readme_dask_commands_run(tmp_path):
    """The Dask lines as written (the port moved to a free one): the scheduler and its workers start
    from the venv's `dask`, and the sweep runs on them to exit 0."""
    (block,) = [b for b in blocks("sh") if "dask scheduler" in b]
    port = str(_free_port())
    lines = [line.replace("8786", port) for line in block.splitlines() if line.strip()]
    assert lines[0].startswith(".venv/bin/pip install") and "'.[dask]'" in lines[0]
    procs = []
    bin_dir = Path(sys.executable).parent
    try:
        for line in lines[1:3]:
            argv = shlex.split(line.rstrip("& "))
            procs.append(subprocess.Popen([str(bin_dir / Path(argv[0]).name), *argv[1:]], cwd=tmp_path,
                                          stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        argv = shlex.split(lines[3])[1:]
        for _ in range(60):  # the scheduler answers within seconds
            p = _run(argv, tmp_path)
            if "nothing answers there" not in p.stderr:
                break
            import time
            time.sleep(1)
        assert p.returncode == 0, (p.stdout[-1500:], p.stderr[-1500:])
        assert (tmp_path / "out" / "sweep-dask").is_dir()
    finally:
        for proc in procs[::-1]:
            proc.terminate()
            proc.wait(timeout=30)


def test_readme_counts_the_default_cases_right():
    from comparisons.config import SeismicCase, load_cases
    words = {1: "one", 2: "two", 3: "three", 4: "four", 5: "five", 6: "six", 7: "seven", 8: "eight", 9: "nine"}
    cases = load_cases()
    n_seismic = sum(isinstance(c, SeismicCase) for c in cases)
    text = README.lower()
    assert f"{words[len(cases) - n_seismic]} drive cases" in text
    assert f"{words[n_seismic]} seismic window" in text
