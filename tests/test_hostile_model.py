"""Hostile input to the newer commands, by class: every bad input is exit 2 with one line on stderr
naming the option or field, the value and what is allowed, and nothing is written into --out.

- a FIFO, a device or a folder where a file is expected (the description, its --cases file, a case's
  reference CSV): refused at once, never waited on;
- a description's work beyond its bounds (nsd_core/model/bounds.py: bodies, outputs, cases, output
  samples, the in-house engine's least step count), refused before any engine runs;
- a loop that cannot close at the start, a position that opens a loop;
- messages that name the option typed (p695 --collapse, not ida's --limit), tables named by name;
- option values accepted without a rule before: --isolator '', a baseline isolator with --fixed-base,
  a repeated --quality rating, a case file's building values given as strings, --model '';
and SIGTERM stops a run on a large model inside its first compilation, its lock released.
"""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from nsd_cli.main import main
from nsd_core.model.bounds import MAX_BODIES, MAX_CASES, MAX_INHOUSE_STEPS, MAX_OUTPUTS

MODELS = Path(__file__).resolve().parents[1] / "models"
FOURBAR = (MODELS / "fourbar_spring.toml").read_text()
CASE = FOURBAR[FOURBAR.index("[[case]]"):]
GROUND = "harmonic:amplitude=1,frequency=1,duration=1"


def sub(text: str, old: str, new: str) -> str:
    assert old in text, old
    return text.replace(old, new, 1)


def chain(n: int, case: str = '[[case]]\nname = "c"\nduration = 0.1\ndt_out = 0.01\n') -> str:
    """A chain of n revolute links under gravity (a description of n bodies)."""
    out = ['[model]\nname = "chain"\ngravity = [0.0, -9.81, 0.0]\n']
    for i in range(n):
        parent = f'parent = "b{i - 1}"\n' if i else ""
        out.append(f'[[bodies]]\nname = "b{i}"\n{parent}joint = {{ type = "revolute", position = '
                   f'[{0.1 if i else 0.0}, 0.0, 0.0], axis = [0.0, 0.0, 1.0] }}\nmass = 0.1\n'
                   'com = [0.05, 0.0, 0.0]\ninertia = [1e-5, 1e-4, 1e-4]\n')
    return "".join(out) + '[[outputs]]\nname = "a0"\nkind = "coordinate"\njoint = "b0"\n' + case


def files(tmp: Path) -> dict[str, str]:
    """The hostile files of the cases below, written into tmp."""
    os.mkfifo(tmp / "fifo.toml")
    os.mkfifo(tmp / "fifo.csv")
    (tmp / "folder").mkdir()
    ref = 'exudyn = { step_size = 5e-4 }     # s: 1e-3 gives 2.0e-3 of the crank angle, 5e-4 5.1e-4'
    written = {
        "ref_fifo.toml": sub(FOURBAR, ref, ref + '\nreference = { file = "fifo.csv" }'),
        "ref_folder.toml": sub(FOURBAR, ref, ref + '\nreference = { file = "folder" }'),
        "ref_empty.toml": sub(FOURBAR, ref, ref + '\nreference = { file = "empty.csv" }'),
        "empty.csv": "",
        "bodies.toml": chain(MAX_BODIES + 1),
        "outputs.toml": sub(FOURBAR, "[[case]]", "".join(
            f'[[outputs]]\nname = "o{i}"\nkind = "coordinate"\njoint = "crank"\n\n' for i in range(MAX_OUTPUTS)) + "[[case]]"),
        "cases.toml": "".join(f'[[case]]\nname = "c{i}"\nduration = 0.1\ndt_out = 0.01\n' for i in range(MAX_CASES + 1)),
        "long.toml": sub(sub(FOURBAR, "duration = 2.0", "duration = 1e9"), "dt_out = 0.01", "dt_out = 1000.0"),
        "max_step.toml": sub(FOURBAR, "exudyn = { step_size = 5e-4 }", "exudyn = { step_size = 5e-4 }\n"
                             "semirecursive = { max_step = 1e-7 }"),
        "samples.toml": sub(FOURBAR, "dt_out = 0.01", "dt_out = 1e-7"),
        "dt_out.toml": sub(FOURBAR, "dt_out = 0.01", "dt_out = 0.03"),
        "no_close.toml": sub(FOURBAR, 'point_a = [0.25, 0.0, 0.0]', 'point_a = [2.5, 0.0, 0.0]'),
        "far.toml": sub(FOURBAR, "crank = 1.0471975511965976, coupler = -0.9, rocker = 1.6", "crank = 1e300"),
        "unknown.toml": sub(FOURBAR, 'law = "linear_spring_damper"', 'law = "linear_spring_damper"\ncolour = "red"'),
        "building.toml": ('[[case]]\nname = "b"\nmode = "seismic"\nground = "harmonic:amplitude=1,frequency=1,'
                          'duration=0.2"\ndt_out = 1e-3\nbuilding = { stories = 2, mass = ["1.0", "2.0"] }\n'),
    }
    for name, text in written.items():
        (tmp / name).write_text(text)
    return written


FOURBAR_FILE = str(MODELS / "fourbar_spring.toml")
CASES = {   # name: (arguments without --out, what the one line must hold)
    "model-fifo": (["compare", "--model", "fifo.toml"], "--model fifo.toml: is a FIFO"),
    "model-device": (["compare", "--model", "/dev/zero"], "is a character device"),
    "model-folder": (["compare", "--model", "folder"], "--model folder: is a folder"),
    "model-empty-name": (["compare", "--model", ""], "--model '': name a file"),
    "cases-fifo": (["compare", "--model", FOURBAR_FILE, "--cases", "fifo.toml"], "--cases fifo.toml: is a FIFO"),
    "reference-fifo": (["compare", "--model", "ref_fifo.toml"], "reference.file fifo.csv: is a FIFO"),
    "reference-folder": (["compare", "--model", "ref_folder.toml"], "reference.file folder: is a folder"),
    "reference-empty": (["compare", "--model", "ref_empty.toml"], "'empty.csv': empty"),
    "bodies": (["compare", "--model", "bodies.toml"], f"[[bodies]]: {MAX_BODIES + 1} tables; at most {MAX_BODIES}"),
    "outputs": (["compare", "--model", "outputs.toml"], f"[[outputs]]: {MAX_OUTPUTS + 4} tables; at most {MAX_OUTPUTS}"),
    "cases": (["compare", "--model", FOURBAR_FILE, "--cases", "cases.toml"],
              f"{MAX_CASES + 1} [[case]] tables; at most {MAX_CASES}"),
    "in-house-steps": (["compare", "--model", "long.toml"], f"1e+11 in-house steps (max_step 0.01 s); at most {MAX_INHOUSE_STEPS:.3g}"),
    "in-house-max-step": (["compare", "--model", "max_step.toml"], "2e+07 in-house steps (max_step 1e-07 s)"),
    "samples": (["compare", "--model", "samples.toml"], "output samples"),
    "dt-out-divides": (["compare", "--model", "dt_out.toml"], "must divide the duration"),
    "loop-cannot-close": (["compare", "--model", "no_close.toml"], "loops: cannot be closed"),
    "position-opens-loop": (["compare", "--model", "far.toml"], "[initial].coordinates.crank = 1e+300"),
    "unknown-field-by-name": (["compare", "--model", "unknown.toml"], "forces.spring.colour: unknown field"),
    "building-strings": (["compare", "--cases", "building.toml"],
                         "case b.building.mass = ['1.0', '2.0']: must be a number or an array of numbers"),
    "p695-collapse-drift": (["p695", "--collapse", "drift=2"], "--collapse 'drift=2': drift needs a value"),
    "p695-collapse-impact": (["p695", "--collapse", "impact=nan"], "--collapse 'impact=nan': impact needs a value"),
    "p695-quality-twice": (["p695", "--quality", "DR=A,DR=D"], "--quality 'DR=A,DR=D': DR is given 2 times"),
    "isolator-empty": (["seismic", "--ground", GROUND, "--isolator", ""], "--isolator '': allowed device"),
    "isolator-fixed-base": (["seismic", "--ground", GROUND, "--isolator", "bilinear", "--fixed-base", "--building",
                             "stories=2"], "--isolator bilinear: --fixed-base holds the slab to the ground"),
}


@pytest.mark.parametrize("name", sorted(CASES))
def test_bad_input_exit_2_one_line_nothing_written(tmp_path, capsys, monkeypatch, name):
    files(tmp_path)
    monkeypatch.chdir(tmp_path)
    args, expected = CASES[name]
    out = tmp_path / "out"
    started = time.monotonic()
    code = main([*args, "--out", str(out)])
    err = [ln for ln in capsys.readouterr().err.splitlines() if ln.strip() and not ln.startswith("nsd: compiling")]
    assert code == 2, err
    assert len(err) == 1 and expected in err[0], err
    assert "--limit" not in err[0]
    assert not out.exists()
    assert time.monotonic() - started < 30


def _chain_run(tmp_path: Path, cache: Path) -> subprocess.Popen:
    (tmp_path / "chain.toml").write_text(chain(MAX_BODIES, '[[case]]\nname = "c"\nduration = 1.0\ndt_out = 0.01\n'))
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache)}   # a cold cache: the signal arrives inside the compiler
    return subprocess.Popen([sys.executable, "-m", "nsd_cli.main", "compare", "--model", str(tmp_path / "chain.toml"),
                             "--engines", "semirecursive", "--out", str(tmp_path / "out")], env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True)


@pytest.mark.slow
@pytest.mark.parametrize("delay", [2.0, 6.0])
def test_sigterm_stops_a_large_model_and_releases_its_lock(tmp_path, delay):
    """SIGTERM a few seconds into a 200-body description's first run (numba compiling its evaluation
    on a cold cache): the run ends within seconds, exit 143, one line, its .nsd.lock gone."""
    p = _chain_run(tmp_path, tmp_path / "cache")
    time.sleep(delay)
    assert p.poll() is None, p.communicate()
    sent = time.monotonic()
    p.send_signal(signal.SIGTERM)
    try:
        _, err = p.communicate(timeout=30)
    except subprocess.TimeoutExpired:
        os.killpg(p.pid, signal.SIGKILL)
        raise AssertionError("still running 30 s after SIGTERM") from None
    stopped = time.monotonic() - sent
    lines = [ln for ln in err.splitlines() if ln.strip() and not ln.startswith("nsd: compiling")]
    assert p.returncode == 143, err
    assert lines == ["nsd: interrupted; nothing kept"], err
    assert stopped < 10.0
    assert not (tmp_path / "out" / ".nsd.lock").exists()
