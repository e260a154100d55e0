"""The API's steady cycle and the one default of output samples per cycle."""
import numpy as np
import pytest

from nsd_core.api import cycle
from nsd_core.device.cycle import loop_area
from nsd_core.device.drive import SAMPLES_PER_CYCLE, Drive
from nsd_core.device.params import Params


def test_one_default_samples_per_cycle():
    from comparisons.config import load_cases
    from nsd_cli.cycle import drive_from_args
    from nsd_cli.main import build_parser
    assert SAMPLES_PER_CYCLE == 2000  # the gate's limits were derived at 2000 (comparisons/tolerances.toml)
    assert Drive(0.015, 1.0).samples_per_cycle == SAMPLES_PER_CYCLE
    cases = [c for c in load_cases() if hasattr(c, "drive")]
    assert {c.drive.samples_per_cycle for c in cases} == {SAMPLES_PER_CYCLE}
    args = build_parser().parse_args(["cycle", "--amplitude", "0.01", "--frequency", "1", "--out", "x"])
    assert drive_from_args(args).samples_per_cycle == SAMPLES_PER_CYCLE


def test_steady_is_the_cycle_the_summary_describes():
    drive = Drive(0.015, 10.0, cycles=2, samples_per_cycle=100)
    result, summary = cycle(Params(), drive)
    s = result.steady()
    assert len(s["t"]) == 101  # both end points: the loop closes
    assert s["t"][0] == pytest.approx(result["t"][-1] - 0.1, abs=1e-12)
    assert set(s.columns) == set(result.columns) and s.units == result.units
    assert np.array_equal(s["F"], result["F"][-101:])
    assert loop_area(s["u"], s["F"]) == summary["loop_area"]
    assert np.max(np.abs(s["F"])) == summary["peak_force"]


def test_steady_needs_a_frequency_when_the_result_has_none(tmp_path):
    from nsd_core.device.results import read_csv, write_csv
    result, _ = cycle(Params(), Drive(0.01, 10.0, cycles=2, samples_per_cycle=50))
    write_csv(tmp_path / "c.csv", result)
    back = read_csv(tmp_path / "c.csv")
    with pytest.raises(ValueError, match="frequency"):
        back.steady()
    assert len(back.steady(10.0)["t"]) == 51


def test_columns_are_written_as_ten_significant_digits_every_value(tmp_path):
    """The row-at-once formatting writes what formatting each value with .10g writes (special values too)."""
    import numpy as np
    from nsd_core.device.results import write_columns
    rng = np.random.default_rng(1)
    a = rng.standard_normal(50) * 10.0 ** rng.integers(-300, 300, 50)
    a[:6] = [np.nan, -0.0, np.inf, -np.inf, 5e-324, 1.0]
    b = np.arange(50)
    write_columns(tmp_path / "c.csv", {"x": a, "wire0_strain": b})   # units from nsd_core.device.columns
    lines = (tmp_path / "c.csv").read_text().splitlines()
    assert lines[0] == "x [m],wire0_strain [-]"
    assert lines[1:] == [f"{x:.10g},{y:.10g}" for x, y in zip(a, b)]
