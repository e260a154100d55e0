"""``nsd params`` lists every field a parameter file accepts, with bounds that are validate()'s own."""
import dataclasses
import math
import tomllib

import pytest

from nsd_core.structure.isolation import Structure, default_structure
from nsd_core.structure.listing import bounds, param_rows, restrainer_fields, structure_fields, structure_rows
from nsd_core.device.params import FIELDS, ParameterError, Params, load_params


def run_nsd(*args):
    from nsd_cli.main import main
    return main(["params", *args])


def test_every_parameter_is_listed_and_the_written_file_reads_back(tmp_path, capsys):
    assert [r["name"] for r in param_rows()] == list(FIELDS)
    f = tmp_path / "p.toml"
    assert run_nsd("--out", str(f)) == 0
    data = tomllib.loads(f.read_text())
    assert list(data["params"]) == list(FIELDS)  # every field a parameter file accepts
    assert load_params(f) == Params()
    # a variant: the file holds the variant's values exactly
    assert run_nsd("--set", "n_wires=6", "--set", "rope_stiffness=612345.678", "--out", str(f)) == 0
    assert load_params(f) == Params().replace(n_wires=6, rope_stiffness=612345.678)


def test_table_names_every_parameter_and_structure_field(capsys):
    assert run_nsd() == 0
    text = capsys.readouterr().out
    for name in [*FIELDS, *structure_fields(), *restrainer_fields()]:
        assert f"\n{name} " in text, name
    assert "Table 2" in text and "assumed: docs/model.md" in text


def _probe(name, value):
    """validate() on Params with one field set (and room for the weight when masses are large)."""
    base = Params().to_dict()
    if name != "precompression_force":
        base["precompression_force"] = 1e8
    base[name] = value
    Params(**base)


@pytest.mark.parametrize("name", list(FIELDS))
def test_stated_bounds_are_the_ones_validate_enforces(name):
    p = Params() if name == "precompression_force" else Params().replace(precompression_force=1e8)
    b = bounds(name, p)
    is_int = FIELDS[name].metadata["kind"] is int
    for edge, is_open, outward in ((b["min"], b["min_open"], -1), (b["max"], b["max_open"], +1)):
        step = 1 if is_int else max(abs(edge), 1.0) * 1e-9
        inside = edge + (-outward * step if is_open else 0)
        outside = edge + (outward * step if not is_open else 0)
        if is_int:
            inside, outside = int(inside), int(outside)
        _probe(name, inside)
        with pytest.raises(ParameterError, match=name if name != "spring_gamma" else "spring_"):
            _probe(name, outside)


def test_structure_fields_listed_with_units_and_bounds():
    from nsd_core.structure.isolation import STRUCTURE_BOUNDS
    from nsd_core.structure.restrainer import with_restrainer
    # the tables and the baseline isolator (--isolator, sized by the design basis) are no --structure numbers
    names = [f.name for f in dataclasses.fields(Structure)
             if f.name not in ("provenance", "restrainer", "building", "isolator")]
    with pytest.raises(ParameterError, match="isolator: unknown"):
        default_structure().replace(isolator=1.0)
    rows = structure_rows()
    assert [r["name"] for r in rows][:len(names)] == names == structure_fields()
    assert [r["name"] for r in rows][len(names):] == restrainer_fields()
    st = default_structure()
    p = Params()
    for r in rows:
        assert r["unit"] != "?" and r["doc"] and r["provenance"], r
        name = r["name"]
        if name == "restrainer":
            assert r["value"] is False and r["bounds"] == "true or false"
            continue
        if name.startswith("restrainer_"):  # probed through --structure restrainer_*=VALUE
            on = with_restrainer(st, p, True, {name: r["value"]})
            assert getattr(on.restrainer, name[len("restrainer_"):]) == r["value"]
            lo_closed = r["bounds"].startswith("[")
            low = float(r["bounds"][1:].split(",")[0])
            if lo_closed:
                with_restrainer(st, p, True, {name: low})
            else:
                with pytest.raises(ParameterError):
                    with_restrainer(st, p, True, {name: low})
            with pytest.raises(ParameterError):
                with_restrainer(st, p, True, {name: low - 1.0})
            if name == "restrainer_gap":
                with pytest.raises(ParameterError):
                    with_restrainer(st, p, True, {name: p.rod_length})
            continue
        assert r["value"] == getattr(st, name)
        if name in STRUCTURE_BOUNDS:  # a stated finite interval: both ends accepted, beyond refused
            lo, hi, _ = STRUCTURE_BOUNDS[name]
            assert r["bounds"].startswith(f"[{lo:g}, {hi:g}]")
            for v in (lo * 0.5 if lo > 0 else -1.0, hi * 2.0):
                with pytest.raises(ParameterError):
                    _replace_alone(st, name, v)
        else:
            st.replace(**{name: 1.0})
            if r["bounds"].startswith("["):
                st.replace(**{name: 0.0})
            else:
                with pytest.raises(ParameterError):
                    st.replace(**{name: 0.0})
            with pytest.raises(ParameterError):
                st.replace(**{name: -1.0})
            assert r["bounds"].endswith("inf)") and not math.isinf(r["value"])


def _replace_alone(st, name, value):
    """st with one field changed; the supports' frequency cap is kept out of the way by scaling the
    stiffness with the mass, so only the field's own bound can refuse it."""
    if name == "mass":
        return st.replace(mass=value, stiffness=st.stiffness * value / st.mass)
    return st.replace(**{name: value})


@pytest.mark.parametrize("args, words", [
    (["--set", "n_ropes=2"], "n_ropes = 2: must be >= 3"),
    (["--set", "no_such=1"], "no_such: unknown parameter"),
    (["--params", "missing.toml"], "not found"),
])
def test_bad_input_exit_2_one_line_nothing_written(tmp_path, capsys, args, words):
    out = tmp_path / "p.toml"
    assert run_nsd(*args, "--out", str(out)) == 2
    err = capsys.readouterr().err
    assert words in err and len(err.strip().splitlines()) == 1, err
    assert not out.exists()


def test_out_must_be_a_file(tmp_path, capsys):
    assert run_nsd("--out", str(tmp_path)) == 2
    assert "must name a file" in capsys.readouterr().err
