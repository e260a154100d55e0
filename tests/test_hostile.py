"""Hostile input: every malformed flag or file of every subcommand gets exit code 2, exactly
one line on stderr naming the field/value/what is allowed, no traceback, nothing written, in seconds.

Table-driven and run in-process through ``nsd_cli.main.main(argv)`` (fast); a few go through a real
subprocess at the end. ``{d}`` in an argument is the test's folder, ``{out}`` an output folder
inside it that must not appear. Files are given as {name: text or bytes}.
"""
import json
import os
import subprocess
import sys
import time

import pytest

from nsd_cli.main import main

CASE = '[[case]]\nname = "q"\namplitude = 0.015\nfrequency = 10.0\n'
CONV = '\n[convergence]\ncase = "q"\n[convergence.sweep]\nmujoco = { setting = "timestep", values = [1e-5] }\n'
OK_RESULTS = {"verdict": "PASS", "exit_code": 0, "failures": [], "engines": ["semirecursive"],
              "cases": [{"name": "q", "amplitude": 0.015, "frequency": 10.0}], "metrics": [], "tolerances": {},
              "runs": {"q": {"semirecursive": {"status": "ok", "csv": "cycles/q__semirecursive.csv"}}}}


def case_file(extra="", case=CASE):
    return {"c.toml": case + extra}


def with_case_key(line):
    """A case file whose one case has ``line`` (replacing the line of the same key, if any)."""
    key = line.split("=")[0].strip()
    kept = [x for x in CASE.splitlines() if x.split("=")[0].strip() != key]
    return {"c.toml": "\n".join(kept + [line]) + "\n"}


CYCLE = ["cycle", "--amplitude", "0.015", "--frequency", "10", "--out", "{out}"]


def cycle(*extra, drop=()):
    args = list(CYCLE)
    for flag in drop:
        i = args.index(flag)
        del args[i:i + 2]
    return args + list(extra)


def cyc_with(flag, value):
    """nsd cycle with one flag replaced by ``value``."""
    args = list(CYCLE)
    if flag in args:
        args[args.index(flag) + 1] = value
    else:
        args += [flag, value]
    return args


COMPARE = ["compare", "--engines", "semirecursive,mujoco", "--out", "{out}"]
SWEEP = ["sweep", "--param", "rod_length", "--values", "0.03", "--out", "{out}"]

# (id, argv, files, fragment that the one stderr line must contain)
CASES = []


def add(id_, argv, files=None, fragment=""):
    CASES.append(pytest.param(argv, files or {}, fragment, id=id_))


# ---- top level and argparse-level errors
add("no-subcommand", [], fragment="required")
add("unknown-subcommand", ["simulate"], fragment="invalid choice")
add("unknown-flag", cycle("--bogus", "1"), fragment="--bogus")
add("cycle-no-out", cycle(drop=("--out",)), fragment="--out")
for v in ("x", "", "1,2", "0x"):
    add(f"cycle-amplitude-{v or 'empty'}", cyc_with("--amplitude", v), fragment="--amplitude")
# ---- nsd cycle: the drive
for v in ("nan", "inf", "-inf", "-0.001"):
    add(f"cycle-amplitude-{v}", cyc_with("--amplitude", v), fragment="amplitude")
for v in ("0", "-1", "nan", "inf", "1e-6", "0.01", "101", "1e9", "x"):
    add(f"cycle-frequency-{v}", cyc_with("--frequency", v), fragment="frequency")
for v in ("nan", "inf", "1e9", "-400"):
    add(f"cycle-direction-{v}", cyc_with("--direction", v), fragment="direction")
for v in ("0", "-1", "1.5", "1001", "x"):
    add(f"cycle-cycles-{v}", cyc_with("--cycles", v), fragment="cycles")
for v in ("0", "15", "1.5", "10000000"):
    add(f"cycle-samples-{v}", cyc_with("--samples-per-cycle", v), fragment="samples")
add("cycle-too-many-samples", cycle("--cycles", "1000", "--samples-per-cycle", "100000"), fragment="samples")
# ---- solver flags (cycle and sweep share them)
for flag, vals in (("--rtol", ("0", "-1", "nan", "inf", "1", "1e-20")), ("--atol", ("0", "-1", "nan", "2")),
                   ("--max-step", ("0", "-1", "nan", "1e-12", "inf")), ("--method", ("bogus", "", "rk45"))):
    for v in vals:
        add(f"cycle{flag}-{v or 'empty'}", cyc_with(flag, v), fragment=flag.lstrip("-").split("-")[0])
# ---- parameters: --set
for item, frag in (("n_ropes", "name=value"), ("=3", "name=value"), ("bogus=1", "bogus"), ("n_ropes=2", "n_ropes"),
                   ("n_ropes=4.5", "n_ropes"), ("n_ropes=x", "n_ropes"), ("n_ropes=65", "n_ropes"),
                   ("n_wires=-1", "n_wires"), ("rope_stiffness=1e15", "rope_stiffness"),
                   ("rope_stiffness=-1", "rope_stiffness"), ("rope_stiffness=nan", "rope_stiffness"),
                   ("rope_stiffness=inf", "rope_stiffness"), ("rod_length=1e308", "rod_length"),
                   ("wire_inclination_deg=45", "wire_inclination_deg"), ("wire_lower_radius=0.03", "derived"),
                   ("gravity=inf", "gravity"), ("precompression_force=1", "precompression_force"),
                   ("cap_mass=0", "cap_mass"), ("wire_eps_t=1.5", "wire_eps_t"), ("rod_length=", "rod_length")):
    add(f"set-{item}", cycle("--set", item), fragment=frag)
# ---- parameters: --params files
PARAMS_FILES = {
    "missing": (None, "not found"), "folder": ("DIR", "folder"), "binary": (b"\x00\xff\xfe" * 50, "text"),
    "invalid-toml": ("rod_length = = 1", "TOML"), "unknown-param": ("bogus = 1", "bogus"),
    "n_ropes-2": ("n_ropes = 2", "n_ropes"), "n_ropes-float": ("n_ropes = 4.0", "whole number"),
    "string-value": ('rod_length = "abc"', "rod_length"), "bool-value": ("rod_length = true", "rod_length"),
    "list-value": ("rod_length = [0.03]", "rod_length"), "beside-params": ("n_ropes = 2\n[params]\nrod_length = 0.03", "beside"),
    "unknown-table": ("[extra]\nrod_length = 0.03", "extra"), "params-number": ("params = 3", "params"),
    "nested-unknown": ("[params]\nrod_length = 0.03\n[params.sub]\nx = 1", "sub"),
    "nan-value": ("rod_length = nan", "rod_length"), "huge-value": ("rope_stiffness = 1e300", "rope_stiffness"),
}
for name, (content, frag) in PARAMS_FILES.items():
    files = {} if content is None else ({"p.toml/": ""} if content == "DIR" else {"p.toml": content})
    add(f"params-{name}", cycle("--params", "{d}/p.toml"), files, frag)
add("params-empty-name", cycle("--params", ""), fragment="--params")
# ---- output paths
add("out-empty", cyc_with("--out", ""), fragment="--out")
add("out-is-file", cyc_with("--out", "{d}/f.txt"), {"f.txt": "x"}, "not a folder")
add("out-under-file", cyc_with("--out", "{d}/f.txt/sub"), {"f.txt": "x"}, "not a folder")
add("drive-beyond-rod-before-out", cycle("--set", "rod_length=0.01"), fragment="")  # exit 4, see below
CASES.pop()  # (kept out: that is exit 4 by design, tested in test_cli)

# ---- nsd compare: flags
for v, frag in (("bullet", "unknown engine"), ("", "engine"), (",", "engine"),
                ("semirecursive,semirecursive", "once"), ("mujoco,exudyn", "reference"), ("mujoco", "reference")):
    add(f"compare-engines-{v or 'empty'}", ["compare", "--engines", v, "--out", "{out}"], fragment=frag)
for v in ("0", "-1", "100000", "x"):
    add(f"compare-workers-{v}", COMPARE + ["--workers", v], fragment="workers")
add("compare-junit-folder", COMPARE + ["--junit", "{d}"], fragment="--junit")
add("compare-junit-empty", COMPARE + ["--junit", ""], fragment="--junit")
add("compare-junit-under-file", COMPARE + ["--junit", "{d}/f.txt/j.xml"], {"f.txt": "x"}, "--junit")
add("compare-junit-name-250", COMPARE + ["--junit", "{d}/" + "j" * 250], fragment="too long")
add("compare-junit-name-300", COMPARE + ["--junit", "{d}/" + "j" * 300], fragment="too long")
add("compare-junit-link-loop", COMPARE + ["--junit", "{d}/loop/j.xml"], {"loop": ("link", "loop")}, "loop")
add("compare-out-is-file", ["compare", "--out", "{d}/f.txt"], {"f.txt": "x"}, "not a folder")
add("compare-convergence-without-table", COMPARE + ["--cases", "{d}/c.toml", "--convergence"], case_file(), "convergence")
add("compare-set-bad", COMPARE + ["--set", "n_ropes=2"], fragment="n_ropes")
# ---- case files
CASEFILES = {
    "missing": (None, "not found"), "folder": ("DIR", "folder"), "binary": (b"\x89PNG\x00\x00" * 30, "text"),
    "invalid-toml": ("[[case]\nname=", "TOML"), "unknown-table": (CASE + "[extra]\nx = 1\n", "extra"),
    "case-as-table": ('[case]\nname = "q"\namplitude = 0.015\nfrequency = 10.0\n', "array"),
    "case-number": ("case = 3", "case"), "no-cases": ("[defaults]\ncycles = 1\n", "no [[case]]"),
    "case-list-of-numbers": ("case = [1, 2]", "case[0]"), "empty": ("", "no [[case]]"),
    "defaults-number": ("defaults = 3\n" + CASE, "defaults"), "defaults-unknown": ("[defaults]\nbogus = 1\n" + CASE, "bogus"),
    "defaults-name": ('[defaults]\nname = "x"\n' + CASE, "name"),
    "defaults-params-number": ("[defaults]\nparams = 3\n" + CASE, "defaults.params"),
    "defaults-settings-bullet": ("[defaults.settings.bullet]\nx = 1\n" + CASE, "bullet"),
    "defaults-cycles-float": ("[defaults]\ncycles = 1.5\n" + CASE, "cycles"),
    "duplicate-names": (CASE + CASE, "duplicate"),
    "missing-amplitude": ('[[case]]\nname = "q"\nfrequency = 10.0\n', "amplitude"),
    "missing-frequency": ('[[case]]\nname = "q"\namplitude = 0.015\n', "frequency"),
    "too-many-cases": ("".join(f'[[case]]\nname = "c{i}"\namplitude = 0.01\nfrequency = 10.0\n' for i in range(201)),
                       "at most"),
}
for name, (content, frag) in CASEFILES.items():
    files = {} if content is None else ({"c.toml/": ""} if content == "DIR" else {"c.toml": content})
    add(f"cases-{name}", COMPARE + ["--cases", "{d}/c.toml"], files, frag)
CASE_KEYS = {
    "unknown-key": ("frequncy = 3", "frequncy"), "name-dotdot": ('name = "../../x"', "plain file name"),
    "name-slash": ('name = "a/b"', "plain file name"), "name-empty": ('name = ""', "plain file name"),
    "name-number": ("name = 5", "name"), "name-dots": ('name = ".."', "plain file name"),
    "name-long": (f'name = "{"a" * 65}"', "plain file name"), "name-space": ('name = "a b"', "plain file name"),
    "amplitude-string": ('amplitude = "x"', "amplitude"), "amplitude-nan": ("amplitude = nan", "amplitude"),
    "amplitude-negative": ("amplitude = -1.0", "amplitude"), "amplitude-bool": ("amplitude = true", "amplitude"),
    "frequency-zero": ("frequency = 0.0", "frequency"), "frequency-huge": ("frequency = 1e9", "frequency"),
    "frequency-inf": ("frequency = inf", "frequency"), "frequency-tiny": ("frequency = 1e-6", "frequency"),
    "cycles-float": ("cycles = 1.5", "cycles"), "cycles-zero": ("cycles = 0", "cycles"),
    "cycles-string": ('cycles = "2"', "cycles"), "cycles-huge": ("cycles = 100000", "cycles"),
    "samples-small": ("samples_per_cycle = 10", "samples_per_cycle"),
    "samples-float": ("samples_per_cycle = 100.0", "samples_per_cycle"),
    "direction-string": ('direction_deg = "x"', "direction_deg"), "direction-huge": ("direction_deg = 1e6", "direction"),
    "params-number": ("params = 3", "params"), "params-unknown": ("params = { bogus = 1 }", "bogus"),
    "params-n_ropes": ("params = { n_ropes = 2 }", "n_ropes"), "params-n_ropes-float": ("params = { n_ropes = 4.0 }", "n_ropes"),
    "settings-number": ("settings = 3", "settings"), "settings-bullet": ("settings.bullet = { x = 1 }", "bullet"),
    "settings-engine-number": ("settings.semirecursive = 3", "settings.semirecursive"),
    "sr-unknown": ("settings.semirecursive = { bogus = 1 }", "bogus"),
    "sr-rtol-zero": ("settings.semirecursive = { rtol = 0.0 }", "rtol"),
    "sr-rtol-string": ('settings.semirecursive = { rtol = "x" }', "rtol"),
    "sr-rtol-bool": ("settings.semirecursive = { rtol = true }", "rtol"),
    "sr-atol-negative": ("settings.semirecursive = { atol = -1.0 }", "atol"),
    "sr-max-step-tiny": ("settings.semirecursive = { max_step = 1e-12 }", "max_step"),
    "sr-method": ('settings.semirecursive = { method = "bogus" }', "method"),
    "sr-method-number": ("settings.semirecursive = { method = 3 }", "method"),
    "ex-step-zero": ("settings.exudyn = { step_size = 0.0 }", "step_size"),
    "ex-step-string": ('settings.exudyn = { step_size = "x" }', "step_size"),
    "ex-step-tiny": ("settings.exudyn = { step_size = 1e-12 }", "step_size"),
    "ex-solver": ('settings.exudyn = { solver = "bogus" }', "solver"),
    "ex-rho": ('settings.exudyn = { spectral_radius = 2.0 }', "spectral_radius"),
    "ex-min-steps-float": ("settings.exudyn = { min_steps_per_cycle = 1.5 }", "min_steps_per_cycle"),
    "ex-min-steps-zero": ("settings.exudyn = { min_steps_per_cycle = 0 }", "min_steps_per_cycle"),
    "ex-unknown": ("settings.exudyn = { bogus = 1 }", "bogus"),
    "ex-newton-nan": ('settings.exudyn = { newton_rel_tol = nan }', "newton_rel_tol"),
    "mj-timestep-neg": ("settings.mujoco = { timestep = -1.0 }", "timestep"),
    "mj-integrator": ('settings.mujoco = { integrator = "bogus" }', "integrator"),
    "mj-solimp": ('settings.mujoco = { solimp = [1.0, 2.0] }', "solimp"),
    "mj-commit-zero": ('settings.mujoco = { commit_every = 0 }', "commit_every"),
    "mj-solref-small": ("settings.mujoco = { solref_factor = 1.0 }", "solref_factor"),
    "mj-passive": ('settings.mujoco = { passive = "bogus" }', "passive"),
    "mj-model-adapter": ('settings.mujoco = { model = "adapter" }', "model"),
    "ex-linear-solver": ('settings.exudyn = { linear_solver = "bogus" }', "linear_solver"),
    "mj-adapter-key-described": ('settings.mujoco = { step_loop = "python" }', "step_loop"),
    "ex-adapter-key-described": ('settings.exudyn = { model = "described", forces = "per_step" }', "forces"),
    "ex-builder-forces": ('settings.exudyn = { builder_forces = "fast" }', "builder_forces"),
    "engine-params-bullet": ("engine_params.bullet = { rope_stiffness = 1.0 }", "bullet"),
    "engine-params-number": ("engine_params.mujoco = 3", "engine_params.mujoco"),
    "engine-params-unknown": ("engine_params.mujoco = { bogus = 1 }", "bogus"),
    "engine-params-bad": ("engine_params.mujoco = { n_ropes = 2 }", "n_ropes"),
}
for name, (line, frag) in CASE_KEYS.items():
    add(f"case-{name}", COMPARE + ["--cases", "{d}/c.toml"], with_case_key(line), frag)
# ---- tolerance files
TOLS = {
    "missing": (None, "not found"), "folder": ("DIR", "folder"), "empty": ("", "no limits"),
    "empty-limits": ("[limits]\n", "no limits"), "binary": (b"\xff\x00" * 40, "text"),
    "invalid-toml": ("[limits\n", "TOML"), "unknown-metric": ("[limits]\nmax_dF = 1e-3\n", "unknown metric"),
    "zero": ("[limits]\nmax_dF_rel = 0.0\n", "max_dF_rel"), "negative": ("[limits]\nmax_dF_rel = -1.0\n", "max_dF_rel"),
    "nan": ("[limits]\nmax_dF_rel = nan\n", "max_dF_rel"), "inf": ("[limits]\nmax_dF_rel = inf\n", "max_dF_rel"),
    "string": ('[limits]\nmax_dF_rel = "x"\n', "max_dF_rel"), "bool": ("[limits]\nmax_dF_rel = true\n", "max_dF_rel"),
    "limits-number": ("limits = 5\n", "limits"), "beside-limits": ("[limits]\nmax_dF_rel = 1e-3\n[other]\nx = 1\n", "other"),
    "nested": ("[limits.max_dF_rel]\nx = 1\n", "max_dF_rel"),
}
for name, (content, frag) in TOLS.items():
    files = {} if content is None else ({"t.toml/": ""} if content == "DIR" else {"t.toml": content})
    add(f"tolerances-{name}", COMPARE + ["--tolerances", "{d}/t.toml"], files, frag)
# ---- convergence tables
CONVS = {
    "unknown-key": (CONV + "bogus = 1\n", "bogus"), "case-unknown": (CONV.replace('case = "q"', 'case = "z"'), "convergence.case"),
    "cycles-float": (CONV.replace('case = "q"', 'case = "q"\ncycles = 1.5'), "cycles"),
    "cycles-zero": (CONV.replace('case = "q"', 'case = "q"\ncycles = 0'), "cycles"),
    "reference-number": (CONV.replace('case = "q"', 'case = "q"\nreference = 3'), "reference"),
    "reference-unknown": (CONV.replace('case = "q"', 'case = "q"\nreference = { bogus = 1 }'), "bogus"),
    "reference-rtol": (CONV.replace('case = "q"', 'case = "q"\nreference = { rtol = 0.0 }'), "rtol"),
    "sweep-empty": ('\n[convergence]\ncase = "q"\n[convergence.sweep]\n', "sweep"),
    "sweep-bullet": (CONV.replace("mujoco = {", "bullet = {"), "bullet"),
    "sweep-number": (CONV.replace('mujoco = { setting = "timestep", values = [1e-5] }', "mujoco = 3"), "mujoco"),
    "no-setting": (CONV.replace('setting = "timestep", ', ""), "setting"),
    "setting-unknown": (CONV.replace('"timestep"', '"bogus"'), "bogus"),
    "values-empty": (CONV.replace("[1e-5]", "[]"), "values"), "values-string": (CONV.replace("[1e-5]", '["x"]'), "values"),
    "values-zero": (CONV.replace("[1e-5]", "[0.0]"), "values"), "values-nan": (CONV.replace("[1e-5]", "[nan]"), "values"),
    "values-number": (CONV.replace("[1e-5]", "1e-5"), "values"),
    "values-tiny-step": (CONV.replace("[1e-5]", "[1e-12]"), "timestep"),
    "spec-unknown-key": (CONV.replace("values = [1e-5]", "values = [1e-5], bogus = 1"), "bogus"),
    "spec-settings-unknown": (CONV.replace("values = [1e-5]", "values = [1e-5], settings = { bogus = 1 }"), "bogus"),
    "convergence-number": ("\nconvergence = 3\n", "convergence"),
}
for name, (extra, frag) in CONVS.items():
    add(f"convergence-{name}", COMPARE + ["--cases", "{d}/c.toml", "--convergence"], case_file(extra), frag)
# ---- seismic cases of nsd compare (mode = "seismic")
SEIS = '[[case]]\nname = "s"\nmode = "seismic"\nrecord = "nearfield-pulse:1"\nwindow = [4.8, 4.9]\n'
SEISMIC = {
    "mode-bogus": (SEIS.replace('"seismic"', '"quake"'), "mode"),
    "unknown-key": (SEIS + "cycles = 2\n", "cycles"),
    "both-inputs": (SEIS + 'ground = "pulse:velocity=0.3,frequency=1"\n', "exactly one"),
    "no-input": (SEIS.replace('record = "nearfield-pulse:1"\n', "").replace("window = [4.8, 4.9]\n", ""), "exactly one"),
    "record-no-colon": (SEIS.replace("nearfield-pulse:1", "nearfield-pulse"), "record"),
    "record-number": (SEIS.replace('"nearfield-pulse:1"', "1"), "record"),
    "record-set": (SEIS.replace("nearfield-pulse:1", "midfield:1"), "midfield"),
    "record-id": (SEIS.replace("nearfield-pulse:1", "nearfield-pulse:99"), "99"),
    "scale-zero": (SEIS + "scale = 0\n", "scale"),
    "scale-string": (SEIS + 'scale = "big"\n', "scale"),
    "scale-nan": (SEIS + "scale = nan\n", "scale"),
    "rotate-string": (SEIS + 'rotate_deg = "east"\n', "rotate_deg"),
    "window-outside": (SEIS.replace("[4.8, 4.9]", "[10.0, 90.0]"), "window"),
    "window-one": (SEIS.replace("[4.8, 4.9]", "[4.8]"), "window"),
    "window-string": (SEIS.replace("[4.8, 4.9]", '"4.8,4.9"'), "window"),
    "duration-negative": (SEIS + "duration = -1.0\n", "duration"),
    "duration-huge": (SEIS + "duration = 1e6\n", "duration"),
    "dt-out-zero": (SEIS + "dt_out = 0\n", "dt_out"),
    "dt-out-longer": (SEIS + "dt_out = 5.0\n", "dt_out"),
    "dt-out-tiny": (SEIS + "dt_out = 1e-12\n", "dt_out"),
    "device-string": (SEIS + 'device = "yes"\n', "device"),
    "device-false-with-peers": (SEIS + "device = false\n", "in-house engine only"),
    "structure-unknown": (SEIS + "structure = { height = 3.0 }\n", "height"),
    "structure-mass-zero": (SEIS + "structure = { mass = 0 }\n", "mass"),
    "scale-with-ground": ('[[case]]\nname = "s"\nmode = "seismic"\nground = "pulse:velocity=0.3,frequency=1"\n'
                          "scale = 2\n", "record"),
    "ground-kind": ('[[case]]\nname = "s"\nmode = "seismic"\nground = "quake:velocity=1"\n', "quake"),
    "ground-key": ('[[case]]\nname = "s"\nmode = "seismic"\nground = "pulse:speed=1,frequency=1"\n', "speed"),
    "ground-missing": ('[[case]]\nname = "s"\nmode = "seismic"\nground = "pulse:velocity=0.3"\n', "frequency"),
    "ground-number": ('[[case]]\nname = "s"\nmode = "seismic"\nground = 3\n', "ground"),
    "ground-gamma": ('[[case]]\nname = "s"\nmode = "seismic"\nground = "pulse:velocity=0.3,frequency=1,gamma=0.5"\n',
                     "gamma"),
    "setting-drive-only": (SEIS + "settings.exudyn = { min_steps_per_cycle = 10 }\n", "min_steps_per_cycle"),
    "setting-step-tiny": (SEIS + "settings.exudyn = { step_size = 1e-12 }\n", "step_size"),
    "setting-engine": (SEIS + "settings.opensees = { dt = 1e-3 }\n", "opensees"),
    "perturb-unknown": (SEIS + 'settings.mujoco = { perturb = { what = "plate_colour" } }\n', "plate_colour"),
    "param-unknown": (SEIS + "params = { bogus = 1 }\n", "bogus"),
    "duplicate-name": (SEIS + SEIS, "duplicate"),
}
for name, (text, frag) in SEISMIC.items():
    add(f"seismic-case-{name}", COMPARE + ["--cases", "{d}/c.toml"], {"c.toml": text}, frag)
# an injected modelling error (engines/perturb.py) out of its bounds, found before anything runs
for name, perturbation, frag in (
        ("rope-index-range", 'what = "rope_stiffness", index = 9, by = 0.01', "settings.exudyn.perturb.index = 9"),
        ("point-index-range", 'what = "rope_cap_point", index = 7, by = 2e-4', "perturb.index = 7"),
        ("index-negative", 'what = "rope_stiffness", index = -1, by = 0.01', "perturb.index = -1"),
        ("index-fraction", 'what = "rope_stiffness", index = 0.5, by = 0.01', "perturb.index = 0.5"),
        ("index-bool", 'what = "rope_stiffness", index = true, by = 0.01', "perturb.index"),
        ("stiffness-negative", 'what = "rope_stiffness", index = 0, by = -1.5', "perturb.by = -1.5"),
        ("mass-zero", 'what = "cap_mass", by = -1.0', "perturb.by = -1.0"),
        ("factor-huge", 'what = "spring_kse", by = 1e300', "perturb.by"),
        ("shift-huge", 'what = "wire_wall_point", by = 0.5', "a length in m")):
    add(f"perturb-{name}", COMPARE + ["--cases", "{d}/c.toml"],
        {"c.toml": CASE + f"settings.exudyn = {{ perturb = {{ {perturbation} }} }}\n"}, frag)
# ---- nsd sweep
for argv, frag in ((["sweep", "--out", "{out}"], "--param"), (SWEEP + ["--paper"], "exactly one"),
                   (["sweep", "--param", "bogus", "--values", "1", "--out", "{out}"], "bogus"),
                   (["sweep", "--param", "rod_length", "--out", "{out}"], "--values"),
                   (["sweep", "--paper", "--values", "1", "--out", "{out}"], "--values")):
    add(f"sweep-{'-'.join(a for a in argv[1:4] if a.startswith('--'))}", argv, fragment=frag)
for v, frag in (("a", "not a number"), ("1,nan", "finite"), ("1e308", "rod_length"), ("", "--values"),
                (",".join(["0.03"] * 201), "at most"), ("0.03,,", "not a number"), ("-0.03", "rod_length")):
    add(f"sweep-values-{v[:12] or 'empty'}", ["sweep", "--param", "rod_length", "--values", v, "--out", "{out}"],
        fragment=frag)
for v, frag in (("2.5", "n_ropes"), ("2", "n_ropes")):
    add(f"sweep-n_ropes-{v}", ["sweep", "--param", "n_ropes", "--values", v, "--out", "{out}"], fragment=frag)
for flag, v, frag in (("--amplitude", "0.5", "rod_length"), ("--amplitude", "-1", "amplitude"),
                      ("--amplitude", "nan", "amplitude"), ("--frequency", "0", "frequency"),
                      ("--frequency", "1e9", "frequency"), ("--cycles", "0", "cycles"),
                      ("--samples-per-cycle", "8", "samples"), ("--engines", "bogus", "unknown engine"),
                      ("--workers", "0", "workers"), ("--workers", "100000", "workers"),
                      ("--scheduler", "not an address", "scheduler"), ("--scheduler", "tcp://127.0.0.1:1", "nothing answers"),
                      ("--method", "bogus", "method"), ("--rtol", "0", "rtol"), ("--max-step", "1e-12", "max-step"),
                      ("--direction", "nan", "direction"), ("--out", "{d}/f.txt", "not a folder")):
    add(f"sweep{flag}-{v[:16]}", SWEEP + [flag, v], {"f.txt": "x"} if "f.txt" in v else None, frag)
# ---- nsd report
REPORTS = {
    "from-missing": ([], "no such folder"), "from-file": ([("r", "x")], "no such folder"),
    "no-results": ([("r/", "")], "results.json"), "results-invalid": ([("r/results.json", "{")], "results.json"),
    "results-list": ([("r/results.json", "[]")], "malformed"),
    "results-missing-keys": ([("r/results.json", json.dumps({"verdict": "PASS"}))], "malformed"),
    "results-wrong-type": ([("r/results.json", json.dumps({**OK_RESULTS, "runs": []}))], "malformed"),
    "csv-missing": ([("r/results.json", json.dumps(OK_RESULTS))], "missing"),
    "csv-outside": ([("r/results.json", json.dumps({**OK_RESULTS, "runs": {"q": {"semirecursive": {
        "status": "ok", "csv": "../../etc/passwd"}}}}))], "outside"),
    "all-failed": ([("r/results.json", json.dumps({**OK_RESULTS, "runs": {"q": {"semirecursive": {
        "status": "error", "message": "boom"}}}}))], "nothing to report"),
    "csv-garbage": ([("r/results.json", json.dumps(OK_RESULTS)), ("r/cycles/q__semirecursive.csv", "a,b\nx,y\n")],
                    "cycle CSV"),
}
for name, (files, frag) in REPORTS.items():
    add(f"report-{name}", ["report", "--from", "{d}/r", "--out", "{out}"], dict(files), frag)
add("report-from-empty", ["report", "--from", "", "--out", "{out}"], fragment="--from")
# ---- nsd tables, calibrate, benchmark
for flag, v, frag in (("--method", "bogus", "method"), ("--step", "0", "step"), ("--step", "nan", "step"),
                      ("--step", "1", "step"), ("--workers", "0", "workers"), ("--out", "{d}/f.txt", "not a folder"),
                      ("--set", "n_ropes=2", "n_ropes"), ("--params", "{d}/missing.toml", "not found")):
    add(f"tables{flag}-{v[:10]}", ["tables", flag, v], {"f.txt": "x"} if "f.txt" in v else None, frag)
for v, frag in (("bogus", "bogus"), ("n_ropes", "n_ropes"), ("", "--fit"), ("rod_length", "rod_length"),
                ("spring_kse,spring_kse", "once")):
    add(f"calibrate-fit-{v or 'empty'}", ["calibrate", "--fit", v], fragment=frag)
add("calibrate-out-file", ["calibrate", "--out", "{d}/f.txt"], {"f.txt": "x"}, "not a folder")
add("calibrate-set", ["calibrate", "--set", "rope_stiffness=-1"], fragment="rope_stiffness")
for v, frag in (("0", "repeats"), ("-1", "repeats"), ("x", "repeats"), ("21", "repeats")):
    add(f"benchmark-repeats-{v}", ["benchmark", "--repeats", v, "--out", "{out}"], fragment=frag)
add("benchmark-out-file", ["benchmark", "--out", "{d}/f.txt"], {"f.txt": "x"}, "not a folder")
add("benchmark-out-empty", ["benchmark", "--out", ""], fragment="--out")

# ---- round two: the newer commands, odd files and output paths
SEIS_G = ["seismic", "--ground", "harmonic:amplitude=1,frequency=2,duration=1", "--out", "{out}"]
SEIS_R = ["seismic", "--record", "farfield:1", "--window", "5,6", "--out", "{out}"]
SET_R = ["seismic", "--record-set", "farfield", "--records", "1", "--window", "5,6", "--out", "{out}"]
for v in ("1e6", "1e-9", "0", "-1", "nan", "inf", "x", "101"):
    add(f"seismic-time-factor-{v}", SEIS_R + ["--time-factor", v], fragment="time-factor")
    add(f"seismic-set-time-factor-{v}", SET_R + ["--time-factor", v], fragment="time-factor")
add("seismic-time-factor-with-ground", SEIS_G + ["--time-factor", "1"], fragment="time-factor")
for v in ("1e6", "3000", "301", "0", "-1", "nan", "inf"):
    add(f"seismic-duration-{v}", SEIS_G + ["--duration", v], fragment="duration")
    add(f"seismic-set-duration-{v}", SET_R + ["--duration", v], fragment="duration")
add("seismic-duration-steps-named", SEIS_G + ["--duration", "3000"], fragment="solver steps")
for v in ("1e-9", "0", "-1", "nan", "inf", "2"):
    add(f"seismic-dt-out-{v}", SEIS_G + ["--dt-out", v], fragment="dt-out")
add("seismic-dt-out-over-duration", SEIS_G + ["--duration", "0.5", "--dt-out", "0.9"], fragment="dt-out")
add("seismic-too-many-samples", SEIS_G + ["--duration", "10", "--dt-out", "1e-6"], fragment="samples")
add("seismic-own-duration-too-many-samples", ["seismic", "--record", "farfield:1", "--window", "5,15", "--time-factor",
                                              "10", "--dt-out", "1e-5", "--out", "{out}"], fragment="samples")
add("seismic-set-own-duration-too-long", ["seismic", "--record-set", "farfield", "--records", "1", "--time-factor", "100",
                                          "--out", "{out}"], fragment="duration")
for v in ("1e9", "0", "-1", "nan", "x"):
    add(f"seismic-scale-{v}", SEIS_R + ["--scale", v], fragment="scale")
for v in ("1e9", "nan", "x"):
    add(f"seismic-rotate-{v}", SEIS_R + ["--rotate", v], fragment="rotate")
add("seismic-scheduler-timeout-single", SEIS_G + ["--scheduler-timeout", "5"], fragment="scheduler-timeout")
for v in ("0", "-1", "nan", "1e9"):
    add(f"seismic-set-scheduler-timeout-{v}", SET_R + ["--scheduler", "{silent}", "--scheduler-timeout", v],
        fragment="scheduler-timeout")
add("seismic-set-scheduler-timeout-alone", SET_R + ["--scheduler-timeout", "5"], fragment="--scheduler")
add("seismic-set-scheduler-silent", SET_R + ["--scheduler", "{silent}", "--scheduler-timeout", "1"],
    fragment="handshake")
add("sweep-scheduler-silent", SWEEP + ["--scheduler", "{silent}", "--scheduler-timeout", "1"], fragment="{silent}")
add("sweep-scheduler-closes", SWEEP + ["--scheduler", "{closing}", "--scheduler-timeout", "1"], fragment="closed")
add("sweep-scheduler-timeout-nan", SWEEP + ["--scheduler", "{silent}", "--scheduler-timeout", "nan"],
    fragment="scheduler-timeout")
GROUNDS = {
    "duplicate-key": ("pulse:velocity=0.3,frequency=1,velocity=0.5", "twice"),
    "duplicate-key-spaced": ("pulse:velocity=0.3, frequency=1, frequency = 2", "twice"),
    "unknown-key": ("pulse:velocity=0.3,frequency=1,damping=2", "damping"),
    "empty-value": ("pulse:velocity=,frequency=1", "velocity"),
    "no-equals": ("pulse:velocity,frequency=1", "velocity"),
    "semicolon": ("pulse:velocity=0.3;frequency=1", "velocity"),
    "kind-case": ("PULSE:velocity=0.3,frequency=1", "PULSE"),
    "kind-only": ("harmonic:", "amplitude"),
    "no-kind": ("velocity=0.3,frequency=1", "kind"),
    "gamma-huge": ("pulse:velocity=0.3,frequency=1,gamma=1e9", "gamma"),
    "gamma-one": ("pulse:velocity=0.3,frequency=1,gamma=1", "gamma"),
    "gamma-nan": ("pulse:velocity=0.3,frequency=1,gamma=nan", "gamma"),
    "pulse-too-long": ("pulse:velocity=0.3,frequency=0.05,gamma=20", "lasts"),
    "frequency-zero": ("pulse:velocity=0.3,frequency=0", "frequency"),
    "frequency-huge": ("pulse:velocity=0.3,frequency=1e9", "frequency"),
    "frequency-inf": ("harmonic:amplitude=1,frequency=inf", "frequency"),
    "velocity-huge": ("pulse:velocity=1e9,frequency=1", "velocity"),
    "velocity-nan": ("pulse:velocity=nan,frequency=1", "velocity"),
    "phase-huge": ("pulse:velocity=0.3,frequency=1,phase=1e9", "phase"),
    "azimuth-nan": ("harmonic:amplitude=1,frequency=1,azimuth=nan", "azimuth"),
    "amplitude-huge": ("harmonic:amplitude=1e9,frequency=1", "amplitude"),
    "duration-huge": ("harmonic:amplitude=1,frequency=1,duration=1e6", "duration"),
    "duration-zero": ("harmonic:amplitude=1,frequency=1,duration=0", "duration"),
}
for name, (spec, frag) in GROUNDS.items():
    add(f"seismic-ground-{name}", ["seismic", "--ground", spec, "--out", "{out}"], fragment=frag)
    add(f"seismic-case-ground-{name}", COMPARE + ["--cases", "{d}/c.toml"],
        {"c.toml": f'[[case]]\nname = "s"\nmode = "seismic"\nground = "{spec}"\n'}, frag)
for v, frag in (("mass=1e308", "mass"), ("mass=1e-9", "mass"), ("stiffness=1e12", "stiffness"),
                ("damping=1e300", "damping"), ("radius_of_gyration=1e9", "radius_of_gyration"),
                ("support_radius=0", "support_radius"), ("stiffness=1e10", "Hz"), ("mass=1e-3", "Hz")):
    add(f"seismic-structure-{v}", SEIS_G + ["--structure", v], fragment=frag)
    add(f"seismic-case-structure-{v}", COMPARE + ["--cases", "{d}/c.toml"],
        {"c.toml": '[[case]]\nname = "s"\nmode = "seismic"\nground = "pulse:velocity=0.3,frequency=1"\n'
                   f'structure = {{ {v.replace("=", " = ")} }}\n'}, frag)
# nsd polar
for flag, v, frag in (("--step", "1e-7", "step"), ("--step", "0.01", "step"), ("--step", "0", "step"),
                      ("--step", "-15", "step"), ("--step", "nan", "step"), ("--step", "7", "divide"),
                      ("--step", "100", "step"), ("--points-per-cycle", "16", "points-per-cycle"),
                      ("--points-per-cycle", "63", "points-per-cycle"), ("--points-per-cycle", "0", "points-per-cycle"),
                      ("--points-per-cycle", "100000", "points-per-cycle"), ("--wires", "", "wires"),
                      ("--wires", ",", "wires"), ("--wires", "2", "wires"), ("--wires", "3,3", "once"),
                      ("--wires", "65", "wires"), ("--wires", "x", "wires"), ("--wires", "4.5", "wires"),
                      ("--wires", ",".join(str(n) for n in range(3, 20)), "wires"), ("--amplitude", "0", "amplitude"),
                      ("--amplitude", "nan", "amplitude"), ("--amplitude", "1", "amplitude"),
                      ("--workers", "0", "workers"), ("--workers", "1000", "workers"),
                      ("--set", "n_ropes=2", "n_ropes"), ("--set", "rope_stiffness=-1", "rope_stiffness")):
    add(f"polar{flag}-{v[:12] or 'empty'}", ["polar", flag, v, "--out", "{out}"], fragment=frag)
add("polar-work-cap", ["polar", "--step", "0.1", "--points-per-cycle", "10000", "--out", "{out}"],
    fragment="quasi-static points")
# drive tables
TABLE = "t,x,y\n0,0,0\n0.5,0.005,0\n1,0.01,0.002\n1.5,0.005,0\n2,0,0\n"
TAB = ["cycle", "--path", "{d}/p.csv", "--frequency", "1", "--out", "{out}"]
for name, (files, extra, frag) in {
    "minor": ({"p.csv": TABLE}, ["--minor", "0.01"], "--minor"),
    "direction": ({"p.csv": TABLE}, ["--direction", "30"], "--direction"),
    "direction-zero": ({"p.csv": TABLE}, ["--direction", "0"], "--direction"),
    "amplitude": ({"p.csv": TABLE}, ["--amplitude", "0.01"], "--amplitude"),
    "fifo": ({"p.csv": ("fifo",)}, [], "FIFO"),
    "device": ({}, ["--path", "/dev/null"], "device"),
    "folder": ({"p.csv/": ""}, [], "folder"),
    "dangling-link": ({"p.csv": ("link", "nowhere.csv")}, [], "not found"),
    "link-loop": ({"p.csv": ("link", "p.csv")}, [], "p.csv"),
    "nan": ({"p.csv": TABLE.replace("0.01,0.002", "nan,0")}, [], "finite"),
    "not-increasing": ({"p.csv": TABLE.replace("1.5,", "0.9,")}, [], "increasing"),
    "rows-too-close": ({"p.csv": TABLE.replace("0.5,", "1e-9,")}, [], "apart"),
    "not-from-zero": ({"p.csv": TABLE.replace("0,0,0\n0.5", "0.1,0,0\n0.5", 1)}, [], "t = 0"),
    "far-away": ({"p.csv": TABLE.replace("0.01,0.002", "5,0")}, [], "centre"),
    "too-short": ({"p.csv": TABLE}, ["--cycles", "5"], "ends"),
    "binary": ({"p.csv": b"\xff\xfe\x00" * 30}, [], "text"),
}.items():
    add(f"cycle-table-{name}", TAB + extra, files, frag)
# work estimated before it starts
add("cycle-work-long", cycle("--frequency", "0.05", "--cycles", "1000"), fragment="solver steps")
add("cycle-work-max-step", cycle("--frequency", "1", "--cycles", "100", "--max-step", "1e-6"), fragment="solver steps")
add("sweep-work", ["sweep", "--param", "rod_length", "--values", "0.03", "--frequency", "0.05", "--cycles", "1000",
                   "--out", "{out}"], fragment="solver steps")
# odd input files: FIFOs, devices, folders, never blocking
for flag, argv in (("--params", cycle("--params", "{d}/x")), ("--cases", COMPARE + ["--cases", "{d}/x"]),
                   ("--tolerances", COMPARE + ["--tolerances", "{d}/x"]),
                   ("seismic-params", SEIS_G + ["--params", "{d}/x"]), ("polar-params", ["polar", "--params", "{d}/x",
                                                                                     "--out", "{out}"])):
    add(f"fifo{flag}", argv, {"x": ("fifo",)}, "FIFO")
    add(f"device{flag}", [a.replace("{d}/x", "/dev/zero") for a in argv], {}, "device")
add("report-results-fifo", ["report", "--from", "{d}/r", "--out", "{out}"], {"r/results.json": ("fifo",)}, "FIFO")
add("report-seismic-summary-fifo", ["report", "--from", "{d}/r", "--out", "{out}"],
    {"r/seismic.csv": ("fifo",), "r/set.json": ("fifo",)}, "FIFO")  # named: the folder is read as regular files
# a damaged field in a compare folder
GOOD_CSV = "t [s],u [m],F [N],closure [m]\n0,0,0,0\n0.05,0.001,10,0\n0.1,0,0,0\n"
for name, change in (("metric-value-string", {"metrics": [{"case": "q", "engine": "semirecursive", "reference": None,
                                                           "metric": "x", "value": "big", "limit": 1.0, "gated": True,
                                                           "pass": True}]}),
                     ("case-amplitude-string", {"cases": [{"name": "q", "amplitude": "x", "frequency": 10.0}]})):
    add(f"report-damaged-{name}", ["report", "--from", "{d}/r", "--out", "{out}"],
        {"r/results.json": json.dumps({**OK_RESULTS, **change}), "r/cycles/q__semirecursive.csv": GOOD_CSV},
        "malformed")
# output paths: symbolic link loops, dangling links, names too long, files on the way
OUTS = {
    "link-loop": ({"loop": ("link", "loop")}, "{d}/loop", "loop"),
    "under-link-loop": ({"loop": ("link", "loop")}, "{d}/loop/sub", "loop"),
    "dangling-link": ({"dangle": ("link", "nowhere")}, "{d}/dangle", "nothing"),
    "under-dangling-link": ({"dangle": ("link", "nowhere")}, "{d}/dangle/sub", "nothing"),
    "name-300": ({}, "{d}/" + "n" * 300, "too long"),
    "path-5000": ({}, "{d}/" + "/".join(["p" * 200] * 25), "too long"),
    "path-4000": ({}, "{d}/" + "/".join(["p" * 200] * 19), "too long"),
    "under-file": ({"f.txt": "x"}, "{d}/f.txt/a/b", "not a folder"),
    "device": ({}, "/dev/null", "not a folder"),
}
for name, (files, out, frag) in OUTS.items():
    add(f"out-{name}", cyc_with("--out", out), files, frag)
    add(f"seismic-out-{name}", SEIS_G[:-1] + [out], files, frag)
    add(f"polar-out-{name}", ["polar", "--out", out], files, frag)
# names with control characters: one line, escaped
for name, argv, files, frag in (
        ("params", cycle("--params", "{d}/a\nb.toml"), {}, "a\\nb.toml"),
        ("cases", COMPARE + ["--cases", "{d}/a\x1b[2Jb.toml"], {}, "\\x1b"),
        ("path", TAB[:2] + ["{d}/x\ny.csv"] + TAB[3:], {}, "x\\ny.csv"),
        ("out-under-file", cyc_with("--out", "{d}/f.txt/a\nb"), {"f.txt": "x"}, "a\\nb"),
        ("out-loop", cyc_with("--out", "{d}/lo\rop/x"), {"lo\rop": ("link", "lo\rop")}, "lo\\rop"),
        ("record", ["seismic", "--record", "far\nfield:1", "--out", "{out}"], {}, "far\\nfield"),
        ("ground", ["seismic", "--ground", "pulse:velocity=0.3,frequency=1,spe\ned=1", "--out", "{out}"], {}, "spe\\ned"),
        ("power-case", COMPARE + ["--power", "--power-cases", "a\nb"], {}, "a\\nb"),
        ("argparse", cycle("--frequency", "1\n2"), {}, "1\\n2")):
    add(f"control-chars-{name}", argv, files, frag)
# --power-cases
for v, frag in ((",", "empty"), ("", "empty"), ("A15mm_f1Hz,,A15mm_f10Hz", "empty"),
                ("A15mm_f1Hz,A15mm_f1Hz", "twice"), ("bogus", "unknown case")):
    add(f"compare-power-cases-{v[:20] or 'empty'}", COMPARE + ["--power", "--power-cases", v], fragment=frag)
add("compare-power-cases-without-power", COMPARE + ["--power-cases", "A15mm_f1Hz"], fragment="--power")


def snapshot(root):
    out = {}
    for dirpath, dirs, files in os.walk(root):
        for n in dirs + files:
            p = os.path.join(dirpath, n)
            out[p] = os.lstat(p).st_mtime_ns if n in files else None  # lstat: links that loop are inputs here
    return out


def materialise(d, files):
    """{name: text | bytes | ("fifo",) | ("link", target)}; a name ending in / is a folder."""
    for name, content in files.items():
        path = d / name.rstrip("/")
        if name.endswith("/"):
            path.mkdir(parents=True, exist_ok=True)
            continue
        path.parent.mkdir(parents=True, exist_ok=True)
        if content == ("fifo",):
            os.mkfifo(path)
        elif isinstance(content, tuple):
            os.symlink(content[1], path)
        else:
            path.write_bytes(content) if isinstance(content, bytes) else path.write_text(content)


@pytest.fixture(scope="module")
def listeners():
    """Addresses of two listeners that are not Dask schedulers: one accepts and never speaks, one
    accepts and closes at once."""
    import socket
    import threading
    socks, conns, stop = [], [], threading.Event()

    def serve(sock, close):
        sock.settimeout(0.2)
        while not stop.is_set():
            try:
                c, _ = sock.accept()
            except OSError:
                continue
            c.close() if close else conns.append(c)

    addresses = {}
    for name, close in (("silent", False), ("closing", True)):
        s = socket.socket()
        s.bind(("127.0.0.1", 0))
        s.listen(8)
        socks.append(s)
        threading.Thread(target=serve, args=(s, close), daemon=True).start()
        addresses[name] = f"tcp://127.0.0.1:{s.getsockname()[1]}"
    yield addresses
    stop.set()
    for c in conns + socks:
        c.close()


TIMES = []


def test_there_are_at_least_150_hostile_inputs():
    assert len(CASES) >= 150, len(CASES)


@pytest.mark.parametrize("argv,files,fragment", CASES)
def test_hostile_input(tmp_path, capsys, listeners, argv, files, fragment):
    d = tmp_path / "w"
    d.mkdir()
    materialise(d, files)

    def fill(a):
        for name, address in listeners.items():
            a = a.replace("{" + name + "}", address)
        return a.replace("{d}", str(d)).replace("{out}", str(d / "out"))
    argv, fragment = [fill(a) for a in argv], fill(fragment)
    before = snapshot(tmp_path)
    start = time.perf_counter()
    try:
        code = main(argv)
    except SystemExit as e:  # argparse
        code = e.code
    elapsed = time.perf_counter() - start
    TIMES.append(elapsed)
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    assert code == 2, err
    assert len(lines) == 1, err
    assert "Traceback" not in err
    assert fragment.lower() in lines[0].lower(), lines[0]
    assert snapshot(tmp_path) == before, "something was written"
    assert elapsed < 30.0, f"{elapsed:.1f} s"  # the first case to import the engines pays that once


def nsd(*args, **kw):
    return subprocess.run([sys.executable, "-m", "nsd_cli.main", *args], capture_output=True, text=True,
                          timeout=120, **kw)


@pytest.mark.parametrize("args", [
    ["compare", "--engines", "mujoco,exudyn"],
    ["cycle", "--amplitude", "0.015", "--frequency", "1e9"],
    ["sweep", "--param", "rod_length", "--values", "1e308"],
    ["report", "--from", "/nonexistent"],
])
def test_hostile_input_in_a_real_process(tmp_path, args):
    out = tmp_path / "out"
    start = time.perf_counter()
    p = nsd(*args, "--out", str(out), cwd=tmp_path)
    assert p.returncode == 2, p.stderr
    assert len(p.stderr.strip().splitlines()) == 1 and "Traceback" not in p.stderr, p.stderr
    assert p.stdout == "" and list(tmp_path.iterdir()) == []
    assert time.perf_counter() - start < 60
