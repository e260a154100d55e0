"""``nsd compare --model``: bad input found before any engine runs: exit 2, one line on
stderr naming the field, nothing written into --out. A loop that cannot close, a rate the loops forbid
or a position that opens a loop is found once, by the shared initial state, not once per engine; a
dt_out that does not divide the duration is refused, not silently changed; a joint direction the joint
does not use is refused; an angle that looks like degrees is a warning, and the run goes on. A re-run
into the same --out removes the earlier model's per-run CSVs."""
from __future__ import annotations

import json
from pathlib import Path

import pytest

from nsd_cli.main import main

MODELS = Path(__file__).resolve().parents[1] / "models"
FOURBAR = (MODELS / "fourbar_spring.toml").read_text()
SHORT = FOURBAR.replace('name = "fourbar_2s"\nduration = 2.0\ndt_out = 0.01', 'name = "c"\nduration = 0.05\ndt_out = 0.01')
SLIDER = (MODELS / "slider_crank.toml").read_text().replace(
    'name = "slider_crank_2turns"\nduration = 0.4     # s: two turns\ndt_out = 0.002     # s\n'
    'reference = { file = "slider_crank_reference.csv", source = "closed form (references/model_references.py)" }',
    'name = "c"\nduration = 0.02\ndt_out = 0.002')
ROCKER_JOINT = 'joint = { type = "revolute", position = [0.3, 0.0, 0.0], axis = [0.0, 0.0, 1.0] }'


def sub(text: str, old: str, new: str) -> str:
    assert old in text, old
    return text.replace(old, new)


def nsd(capsys, *args) -> tuple[int, str, str]:
    """Exit code, stdout and stderr of ``nsd compare ARGS`` in this process (stderr without the one-off
    notice of a cold numba cache, nsd_core.engine.compile_once, which is not the command's output)."""
    code = main(["compare", *args])
    cap = capsys.readouterr()
    return code, cap.out, "".join(ln for ln in cap.err.splitlines(keepends=True) if not ln.startswith("nsd: compiling"))


BAD = {
    "loop-cannot-close": (SHORT, 'point_a = [0.25, 0.0, 0.0]\nbody_b = "rocker"', 'point_a = [2.0, 0.0, 0.0]\nbody_b = "rocker"',
                          "loops: cannot be closed from [initial].coordinates"),
    "rate-the-loops-forbid": (SHORT, 'free = ["crank"]', 'free = ["crank"]\nvelocities = { rocker = 1.0 }',
                              "[initial].velocities.rocker = 1.0 (coordinate 0): the loops require 0"),
    "position-opens-the-loop": (SHORT, ROCKER_JOINT, ROCKER_JOINT.replace("[0.3, 0.0, 0.0]", "[1e300, 0.0, 0.0]"),
                                "loops: cannot be closed"),
    "coordinate-1e300": (SHORT, "crank = 1.0471975511965976", "crank = 1e300",
                         "[initial].coordinates.crank = 1e+300: coordinate 0 must be within"),
    "prescribed-initial-value": (SLIDER, "coordinates = { slider = 0.45 }", "coordinates = { slider = 0.45, crank = 3.0 }",
                                 "[initial].coordinates.crank = 3.0: coordinate 0 is prescribed (motor), whose motion "
                                 "gives 0.0 at t = 0"),
    "dt-out-not-dividing": (FOURBAR, "dt_out = 0.01", "dt_out = 0.003",
                            "case.fourbar_2s.dt_out = 0.003: must divide the duration (2 s)"),
    "axis-on-spherical": (SHORT, ROCKER_JOINT, ROCKER_JOINT.replace('"revolute"', '"spherical"'),
                          "bodies.rocker.joint.axis: not a key of a spherical joint"),
    "axis2-on-revolute": (SHORT, ROCKER_JOINT, ROCKER_JOINT.replace(" }", ", axis2 = [0.0, 1.0, 0.0] }"),
                          "bodies.rocker.joint.axis2: not a key of a revolute joint (it uses axis)"),
    "normal-on-revolute": (SHORT, ROCKER_JOINT, ROCKER_JOINT.replace(" }", ", normal = [0.0, 0.0, 1.0] }"),
                           "bodies.rocker.joint.normal: not a key of a revolute joint"),
    "axis-on-planar": (SLIDER, 'type = "prismatic", position = [0.0, 0.0, 0.0], axis = [1.0, 0.0, 0.0]',
                       'type = "planar", position = [0.0, 0.0, 0.0], axis = [1.0, 0.0, 0.0]',
                       "bodies.slider.joint.axis: not a key of a planar joint (it uses normal)"),
    "body-named-not-indexed": (SHORT, 'name = "rocker"\n', 'name = "rocker"\ncolour = "red"\n',
                               "bodies.rocker.colour: unknown field"),
    "case-named-dot-dot": (SHORT, 'name = "c"', 'name = ".."', "case[0].name = '..': must be a name"),
}


@pytest.mark.parametrize("name", list(BAD))
def test_bad_input_is_exit_2_one_line_nothing_written(tmp_path, capsys, name):
    text, old, new, expected = BAD[name]
    model = tmp_path / "m.toml"
    model.write_text(sub(text, old, new))
    out = tmp_path / "out"
    code, stdout, stderr = nsd(capsys, "--model", str(model), "--out", str(out))
    lines = [ln for ln in stderr.splitlines() if ln.strip()]
    assert code == 2, stdout + stderr
    assert len(lines) == 1 and expected in lines[0], stderr
    assert "np.float64" not in stderr and "bodies[" not in stderr
    assert not out.exists()


@pytest.mark.parametrize("value", ["1e300", "0.02"])
def test_a_symbolic_regularisation_that_would_open_the_loops_is_exit_2(tmp_path, capsys, value):
    """Its estimate runs it at x10 (comparisons.estimate.FORMULATION_COMPANION): at most 0.01 of S's
    largest diagonal entry (1e300 dropped the loops' forces: a FAIL with its estimate blind to it)."""
    model = tmp_path / "m.toml"
    model.write_text(sub(SHORT, 'name = "c"', f'name = "c"\nsymbolic = {{ regularisation = {value} }}'))
    out = tmp_path / "out"
    code, stdout, stderr = nsd(capsys, "--model", str(model), "--engines", "semirecursive,symbolic", "--out", str(out))
    lines = [ln for ln in stderr.splitlines() if ln.strip()]
    assert code == 2 and len(lines) == 1, stdout + stderr
    assert f"symbolic.regularisation = {float(value)!r}: must be <= 0.01" in lines[0], stderr
    assert not out.exists()


def test_a_dt_out_that_divides_within_round_off_is_accepted(tmp_path):
    """0.1 s over 0.3 s is 2.9999999999999996 intervals in doubles: it divides (within 1e-9)."""
    from comparisons.model_cases import load_model_cases
    from nsd_core.model.load import load_model
    model = tmp_path / "m.toml"
    model.write_text(sub(SHORT, "duration = 0.05\ndt_out = 0.01", "duration = 0.3\ndt_out = 0.1"))
    case, = load_model_cases(load_model(model), None, ["semirecursive"])
    assert len(case.times()) == 4 and case.times()[-1] == 0.3


def test_angles_that_look_like_degrees_are_a_warning_and_the_run_goes_on(tmp_path, capsys):
    model = tmp_path / "m.toml"
    model.write_text(sub(SHORT, "crank = 1.0471975511965976", "crank = 63"))
    out = tmp_path / "out"
    code, stdout, stderr = nsd(capsys, "--model", str(model), "--engines", "semirecursive", "--out", str(out))
    assert code == 0, stdout + stderr
    lines = [ln for ln in stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and "[initial].coordinates.crank = 63: looks like degrees; angles are in rad" in lines[0]
    assert (out / "results.json").exists()


def test_prescribed_angles_that_look_like_degrees_are_warned():
    from nsd_core.model.load import angles_in_degrees, parse_model
    import tomllib
    raw = tomllib.loads(SLIDER)
    raw["prescribed"][0].update(motion="harmonic", centre=0.0, amplitude=90.0, frequency=1.0)
    raw["prescribed"][0].pop("speed")
    assert angles_in_degrees(parse_model(raw)) == [
        "prescribed.motor.amplitude = 90: looks like degrees; angles are in rad (90 deg = 1.5708 rad)"]
    raw["prescribed"][0].update(amplitude=1.0)
    raw["initial"]["coordinates"]["slider"] = 45.0   # a length: never degrees
    assert angles_in_degrees(parse_model(raw)) == []


def test_a_rerun_into_the_same_out_removes_the_earlier_models_csvs(tmp_path, capsys):
    """The second model's cases replace the first's: the earlier CASE/ENGINE.csv files and report pages
    go; a file this command never wrote stays (with its folder)."""
    out = tmp_path / "out"
    first = tmp_path / "first.toml"
    first.write_text(sub(SHORT, 'name = "c"', 'name = "first"'))
    code, stdout, stderr = nsd(capsys, "--model", str(first), "--engines", "semirecursive", "--out", str(out))
    assert code == 0, stdout + stderr
    assert (out / "first" / "semirecursive.csv").exists()
    (out / "report").mkdir()
    (out / "report" / "model_page9.png").write_bytes(b"old")
    (out / "notes.txt").write_text("mine")
    second = tmp_path / "second.toml"
    second.write_text(sub(SHORT, 'name = "c"', 'name = "second"') + '\n[[case]]\nname = "kept"\nduration = 0.02\n'
                      'dt_out = 0.01\n')
    code, stdout, stderr = nsd(capsys, "--model", str(second), "--engines", "semirecursive", "--out", str(out))
    assert code == 0, stdout + stderr
    assert not (out / "first").exists() and not (out / "report").exists()
    assert (out / "second" / "converged.csv").exists() and (out / "notes.txt").read_text() == "mine"
    assert set(json.loads((out / "results.json").read_text())["cases"]) == {"second", "kept"}
    # a third run with one case: "kept"'s folder goes, except for a file someone else put there
    (out / "kept" / "mine.txt").write_text("x")
    code, stdout, stderr = nsd(capsys, "--model", str(first), "--engines", "semirecursive", "--out", str(out))
    assert code == 0, stdout + stderr
    assert not (out / "second").exists() and sorted(p.name for p in (out / "kept").iterdir()) == ["mine.txt"]
    assert (out / "first" / "semirecursive.csv").exists()


def test_the_unresolved_reference_message_names_the_callers_rtol():
    """'the converged reference itself is not converged': the rtol said is the caller's (--model's
    converged reference runs at 1e-12; the device's gate at comparisons.reference's), not a fixed 1e-11."""
    from comparisons import model_compare, reference
    from comparisons.verdict import Rule, case_verdicts

    def text(**kw):
        _, v = case_verdicts("c", "drive", ["mujoco"], {"mujoco": {"max_dF_rel": 1e-2}}, {"mujoco": {"max_dF_rel": 1e-2}},
                             {"max_dF_rel": 2e-3}, {"max_dF_rel": (1.0, "N")}, {}, Rule(), **kw)
        return v["mujoco"]["text"]
    assert "its own error 0.002 at rtol 1e-12 > 0.001" in text(reference_rtol=model_compare.CONVERGED_SETTINGS["rtol"])
    assert f"at rtol {reference.CONVERGED_SETTINGS['rtol']:g} > 0.001" in text(reference_rtol=reference.CONVERGED_SETTINGS["rtol"])
    assert "at its rtol > 0.001" in text() and "1e-11" not in text()   # a caller that names none: no number
