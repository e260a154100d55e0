"""Help texts say what the commands do: checked against the files and code they describe."""
import re

import pytest

from nsd_cli.main import main


def help_text(capsys, *cmd) -> str:
    with pytest.raises(SystemExit) as e:
        main([*cmd, "--help"])
    assert e.value.code == 0
    return " ".join(capsys.readouterr().out.split())  # argparse wraps lines; compare words


def test_compare_help_names_the_default_cases_from_the_file(capsys):
    from comparisons.config import SeismicCase, load_cases
    text = help_text(capsys, "compare")
    cases = load_cases()
    seismic = [c.name for c in cases if isinstance(c, SeismicCase)]
    drives = [c.name for c in cases if not isinstance(c, SeismicCase)]
    assert f"{len(drives)} drive cases ({', '.join(drives)})" in text
    assert f"{len(seismic)} seismic ({', '.join(seismic)})" in text
    assert "Figure 6" not in text


def test_compare_default_engines_are_the_registry(capsys):
    from comparisons.engines import ENGINES
    from nsd_cli.main import build_parser
    sub = next(a for a in build_parser()._actions if a.dest == "command").choices["compare"]
    engines = next(a for a in sub._actions if a.dest == "engines").default
    assert engines.split(",") == list(ENGINES)


def test_cycle_help_gives_the_samples_default(capsys):
    from nsd_core.device.drive import SAMPLES_PER_CYCLE
    m = re.search(r"output samples per cycle \(default (\d+)", help_text(capsys, "cycle"))
    assert m and int(m.group(1)) == SAMPLES_PER_CYCLE


def test_seismic_help_record_ids_are_the_sets(capsys):
    from nsd_core.ground.records import SETS
    text = help_text(capsys, "seismic")
    found = dict((s, (int(a), int(b))) for s, a, b in re.findall(r"([a-z-]+):(\d+)\.\.(\d+)", text))
    assert found == {s: (ids[0], ids[-1]) for s, (_, ids, _) in SETS.items()}
    assert "--record-set SET" in text
    assert "NAME=VALUE|SET" not in text  # --set is a parameter override only


@pytest.mark.parametrize("cmd", ["cycle", "compare", "seismic", "sweep", "polar", "params"])
def test_set_help_points_to_the_parameter_list(capsys, cmd):
    text = help_text(capsys, cmd)
    assert "--set NAME=VALUE override one parameter (every name, unit and bound: nsd params)" in text


def test_sweep_help_gives_its_samples_default(capsys):
    import dataclasses
    from nsd_cli.main import build_parser
    from nsd_core.study.designs import Design
    m = re.search(r"output samples per cycle \(default (\d+), the parametric study's own", help_text(capsys, "sweep"))
    sub = next(a for a in build_parser()._actions if a.dest == "command").choices["sweep"]
    default = next(a for a in sub._actions if a.dest == "samples_per_cycle").default
    design_default = {f.name: f.default for f in dataclasses.fields(Design)}["samples_per_cycle"]
    assert m and int(m.group(1)) == default == design_default
