"""The generated per-mechanism evaluation (nsd_core.engine.codegen) against the generic kernels, its
specification: on random states of the device (drive mode; seismic mode with and without the
building and the restrainer) and of Andrews' mechanism, and over whole drive and seismic runs."""
from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest

from nsd_core.structure import compiled_seismic as cs
from nsd_core.structure.building import building_from
from nsd_core.device.compiled import device_forces, device_motion
from nsd_core.device.drive import Drive
from nsd_core.ground.motions import Harmonic
from nsd_core.structure.isolation import default_structure
from nsd_core.device.model import simulate
from nsd_core.device.params import Params
from nsd_core.structure.restrainer import with_restrainer
from nsd_core.structure.seismic import simulate_seismic
from nsd_core.engine import codegen
from nsd_core.engine.callbacks import linear_springs, no_motion
from nsd_core.engine.codegen_main import generate_source
from nsd_core.engine.compiled_model import make_workspace
from nsd_core.common.errors import InputError
from tests.test_compiled import andrews_model, device_case

FIELDS = ("z", "zd", "zdd", "lam", "tau", "extra_rate", "Phi", "L", "Ld", "T", "r", "A", "Z", "N", "momentum")


def _rel(a, b):
    scale = np.max(np.abs(b)) if b.size else 0.0
    return float(np.max(np.abs(a - b)) / scale) if scale > 0 else float(np.max(np.abs(a - b), initial=0.0))


def _compare(model, z0, y, ts, forces, motion, seed, scale=1e-3):
    """Both evaluators from the same workspaces on perturbed states, three times in a row (the
    predictor and warm start carried along): the worst relative difference per field."""
    gen, ref = codegen.generated_evaluator(model), codegen.generic_evaluator()
    rng = np.random.default_rng(seed)
    worst = dict.fromkeys(FIELDS, 0.0)
    for trial in range(8):
        yy = y + rng.normal(scale=scale, size=len(y)) * np.maximum(np.abs(y), 1e-2)
        wg, wr = make_workspace(model, z0), make_workspace(model, z0)
        for t in ts:
            for reactions in (False, True):
                cr = ref(t, yy, model, wr, forces, motion, reactions)
                cg = gen(t, yy, model, wg, forces, motion, reactions)
                assert cg == cr
                assert cr == 0
            for f in FIELDS:
                worst[f] = max(worst[f], _rel(getattr(wg, f), getattr(wr, f)))
        assert np.array_equal(wg.counters, wr.counters)  # the same Newton iterations, the same branches
    return worst


def test_device_drive_generated_equals_generic():
    _, model, z, y, t = device_case()
    worst = _compare(model, z, y, (t, t + 2e-4, t + 5e-4), device_forces, device_motion, 1)
    assert max(worst.values()) <= 1e-12, worst


@pytest.mark.slow   # 39 s of a cold default run (its generated module compiled); the device's drive case above stays
def test_andrews_generated_equals_generic():
    _, model, z0, y0 = andrews_model()
    y = y0.copy()
    y[1] = 50.0
    worst = _compare(model, z0, y, (0.0, 1e-4, 3e-4), linear_springs, no_motion, 2, scale=1e-4)
    assert max(worst.values()) <= 1e-12, worst


def _seismic_case(monkeypatch, structure, device=True):
    """The model, start and a mid-run state of a short seismic run (cs.run's arguments captured)."""
    seen = {}
    original = cs.run

    def capture(model, z0, y0, t_eval, *args, **kw):
        res = original(model, z0, y0, t_eval, *args, **kw)
        seen.update(model=model, z0=z0, y=res["y"][-1].copy(), t=float(t_eval[-1]))
        return res
    monkeypatch.setattr(cs, "run", capture)
    simulate_seismic(Params(), structure, Harmonic(0.8, 2.0, 30.0, duration=0.05), duration=0.05, dt_out=1e-2,
                     device=device)
    return seen


# the building with its device: 31 s of the README's test command (a fresh clone, 2026-11-28), slow mark; the
# building without it and the device's own variants stay in the default run
@pytest.mark.parametrize("variant", ["device", "restrainer", pytest.param("building", marks=pytest.mark.slow),
                                     "building_no_device"])
def test_seismic_generated_equals_generic(monkeypatch, variant):
    structure = default_structure(Params())
    if variant == "restrainer":
        structure = with_restrainer(structure, Params(), True)
    if variant.startswith("building"):
        structure = structure.with_building(building_from(structure.mass, {"stories": 3}))
    c = _seismic_case(monkeypatch, structure, device=variant != "building_no_device")
    y = c["y"].copy()
    y[len(y) // 2:] += 1e-3 * np.max(np.abs(y))  # moving
    worst = _compare(c["model"], c["z0"], y, (c["t"], c["t"] + 1e-4), cs.seismic_forces, cs.seismic_motion, 3,
                     scale=1e-4)
    assert max(worst.values()) <= 1e-12, worst


def test_the_structure_not_the_numbers_selects_the_source():
    """A design with other numbers (masses, lengths, stiffnesses) shares the generated source, so a
    sweep compiles once; another partition or tree is another source."""
    _, model, _, _, _ = device_case()
    other = Params().replace(cap_mass=0.9, rod_length=0.034, rope_stiffness=4e5, base_mass=1.3)
    from nsd_core.device.compiled import compiled_model
    from nsd_core.device.model import device_system
    system, g = device_system(other, Drive(0.02, 1.0))
    model2 = compiled_model(system, g, Drive(0.02, 1.0), system.forces.elements)
    assert not np.array_equal(model.mass, model2.mass)
    assert generate_source(model) == generate_source(model2)
    assert codegen.structure_key(model) == codegen.structure_key(model2)  # the in-process memo's key
    andrews = andrews_model()[1]
    assert generate_source(andrews) != generate_source(model)
    assert codegen.structure_key(andrews) != codegen.structure_key(model)
    assert codegen.generated_evaluator(model2) is codegen.generated_evaluator(model)


def test_generated_source_is_in_the_cache_folder_named_by_its_hash():
    _, model, _, _, _ = device_case()
    ev = codegen.generated_evaluator(model)
    files = [p for p in codegen.source_folder().glob("nsd_eval_*.py") if p.read_text() == generate_source(model)]
    assert len(files) == 1 and ev is codegen.generated_evaluator(model)


def test_evaluator_choice(monkeypatch):
    _, model, _, _, _ = device_case()
    assert codegen.evaluator_for(model, "generic") is codegen.generic_evaluator()
    monkeypatch.setenv(codegen.ENV, "generic")
    assert codegen.evaluator_for(model) is codegen.generic_evaluator()
    monkeypatch.setenv(codegen.ENV, "fast")
    with pytest.raises(InputError, match="NSD_EVALUATOR = 'fast'"):
        codegen.evaluator_for(model)


def test_auto_uses_the_generated_evaluation_only_once_it_is_compiled(monkeypatch, tmp_path):
    """"auto" (the default): the generic kernels for a structure whose generated evaluation is not
    compiled (a short run would pay 12-25 s to save milliseconds), the generated one once its mark
    is on disk, which compiling it writes."""
    _, model, _, _, _ = device_case()
    monkeypatch.delenv(codegen.ENV, raising=False)
    codegen.generated_evaluator(model)
    _, name, _ = codegen._generated_source(model)
    assert (codegen.source_folder() / f"{name}.compiled").exists()
    assert codegen.evaluator_for(model) is codegen.generated_evaluator(model)
    monkeypatch.setattr(codegen, "_LOADED", {})            # a new process ...
    monkeypatch.setattr(codegen, "source_folder", lambda: tmp_path)   # ... on a cache without it
    assert not codegen.is_compiled(model)
    assert codegen.evaluator_for(model) is codegen.generic_evaluator()
    (tmp_path / f"{name}.compiled").touch()
    assert codegen.is_compiled(model)


def test_a_study_command_asks_for_the_generated_evaluation(monkeypatch):
    """Many runs of one structure (an IDA) ask for the generated evaluation; a single run does not, nor
    a sweep, whose designs change the structure (14 structures in --paper, ~0.1 s a run): compiling one
    generated evaluation per structure cost its cold run ~100 s wall (77.8 -> 31.0 s without)."""
    import contextlib
    from nsd_cli.main import main
    monkeypatch.delenv(codegen.ENV, raising=False)
    seen, real = [], codegen.preferring_generated

    @contextlib.contextmanager
    def watched():   # what the command's handler runs under
        with real():
            seen.append(os.environ.get(codegen.ENV))
            yield
    monkeypatch.setattr(codegen, "preferring_generated", watched)
    assert main(["cycle", "--amplitude", "-1", "--frequency", "1", "--out", "x"]) == 2
    assert main(["sweep", "--param", "rod_length", "--values", "abc", "--out", "x"]) == 2
    assert seen == [] and codegen.ENV not in os.environ
    assert main(["ida", "--record-set", "farfield", "--limit", "bogus", "--out", "x"]) == 2
    assert seen == ["generated"] and codegen.ENV not in os.environ   # asked for while it ran, then put back


def test_a_bad_evaluator_choice_is_one_line_and_exit_2(tmp_path):
    r = subprocess.run([sys.executable, "-m", "nsd_cli.main", "cycle", "--amplitude", "0.01", "--frequency", "1",
                        "--out", str(tmp_path / "o")], capture_output=True, text=True,
                       env={**os.environ, codegen.ENV: "fast"})
    assert r.returncode == 2 and r.stderr.count("\n") == 1, r.stderr
    assert "NSD_EVALUATOR = 'fast'" in r.stderr and "'auto'" in r.stderr
    assert not (tmp_path / "o").exists()


def _runs(monkeypatch, fn):
    out = {}
    for kind in ("generic", "generated"):
        monkeypatch.setenv(codegen.ENV, kind)
        out[kind] = fn()
    return out["generated"], out["generic"]


def test_whole_drive_run_equals_the_generic_one(monkeypatch):
    """The Figure 6 drive A = 15 mm at 1 Hz, one cycle at the default accuracy: the force on the plate
    from the generated evaluation against the generic one (bit-identical arithmetic: measured 0)."""
    g, r = _runs(monkeypatch, lambda: simulate(Params(), Drive(0.015, 1.0, cycles=1)))
    assert (g.stats["evaluation"], r.stats["evaluation"]) == ("generated", "generic")  # the cost page names it
    assert g.stats["steps"] == r.stats["steps"]
    for k in ("F", "F_rod", "F_ropes", "F_wires"):
        assert np.max(np.abs(g[k] - r[k])) <= 1e-9 * np.max(np.abs(r[k])), k


def test_whole_seismic_run_equals_the_generic_one(monkeypatch):
    structure = with_restrainer(default_structure(Params()), Params(), True)
    run = lambda: simulate_seismic(Params(), structure, Harmonic(0.8, 2.0, 30.0, duration=0.3), duration=0.3,  # noqa: E731
                                   dt_out=2e-3)
    g, r = _runs(monkeypatch, run)
    assert (g.stats["evaluation"], r.stats["evaluation"]) == ("generated", "generic")
    assert g.stats["steps"] == r.stats["steps"]
    for k in ("x", "y", "device_Fx", "device_Fy", "ax_abs"):
        assert np.max(np.abs(g[k] - r[k])) <= 1e-9 * np.max(np.abs(r[k])), k


def test_a_study_run_in_process_puts_the_evaluator_choice_back(monkeypatch, tmp_path):
    """A study command asks for the generated evaluation while it runs, and leaves the program's own
    environment as it found it (unset, or the user's choice), also when it fails."""
    import os
    from nsd_cli.main import main
    monkeypatch.delenv("NSD_EVALUATOR", raising=False)
    # a study whose input is refused inside its handler (after the choice is made): exit 2
    assert main(["polar", "--out", str(tmp_path / "p"), "--points", "1"]) == 2
    assert "NSD_EVALUATOR" not in os.environ
    monkeypatch.setenv("NSD_EVALUATOR", "generic")
    assert main(["polar", "--out", str(tmp_path / "p"), "--points", "1"]) == 2
    assert os.environ["NSD_EVALUATOR"] == "generic"
    from nsd_core.engine.codegen import preferring_generated
    monkeypatch.delenv("NSD_EVALUATOR")
    with preferring_generated():
        assert os.environ["NSD_EVALUATOR"] == "generated"
    assert "NSD_EVALUATOR" not in os.environ
