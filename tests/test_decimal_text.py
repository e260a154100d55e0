"""The CSVs' numbers (nsd_core.device.decimal_text): each entry's text is Python's own "%.10g" and each
value read back is numpy.loadtxt's of that text, bit for bit, on values chosen to sit on every
boundary the compiled path decides, and on a run's real columns (write_csv against read_csv)."""
from __future__ import annotations

import io

import numpy as np
import pytest

from nsd_core.device import decimal_text
from nsd_core.device.decimal_text import table_text
from nsd_core.device.results import RunResult, read_csv, write_columns, write_csv


def python_text(x: np.ndarray) -> str:
    return "".join(",".join("%.10g" % v for v in row) + "\n" for row in x.tolist())


def assert_as_python(x: np.ndarray) -> None:
    body, read = table_text(x)
    text = python_text(x)
    assert body.decode() == text
    loaded = np.loadtxt(io.StringIO(text), delimiter=",", ndmin=2)
    same = (read.view(np.int64) == loaded.view(np.int64)) | (np.isnan(read) & np.isnan(loaded))
    assert same.all(), [(x.ravel()[i], read.ravel()[i], loaded.ravel()[i]) for i in np.flatnonzero(~same)[:5]]


def boundary_values() -> np.ndarray:
    """Halves at the eleventh digit, powers of ten and their neighbours, the fixed/scientific switch
    (1e-4 and 1e10 before and after rounding), signed zeros, subnormals, the largest double, NaN, inf."""
    out = [0.0, -0.0, np.nan, -np.nan, np.inf, -np.inf, 5e-324, -1e-310, 2.2250738585072014e-308,
           1.7976931348623157e308, 12345678905.0, 12345678915.0, 0.5, 1.5, 2.5, 9999999999.5, 9999999999.4,
           999999999.95, 999999999.94, 9.9999999995e-5, 9.9999999994e-5, 1e-4, 1e10, 9999999999.0,
           99999999995.0, 123456789.0, 0.1, 3800.0, -2.114048392e-11]
    for e in range(-320, 309):
        for text in ("1e{}", "9.9999999995e{}", "1.0000000005e{}", "1.2345678905e{}", "5.0000000005e{}"):
            v = float(text.format(e))
            out += [v, np.nextafter(v, 0.0), np.nextafter(v, np.inf), -v]
    return np.array(out)


def test_boundaries_as_python():
    x = boundary_values()
    assert_as_python(x[: x.size // 7 * 7].reshape(-1, 7))
    assert_as_python(x.reshape(-1, 1))   # one column: every value ends a row


def test_a_table_longer_than_a_chunk(monkeypatch):
    """Rows go through in blocks of CHUNK_ROWS: blocks of 5 rows, the last one short, give the same text."""
    monkeypatch.setattr(decimal_text, "CHUNK_ROWS", 5)
    x = boundary_values()[:3 * 1001].reshape(-1, 3)
    assert_as_python(x)
    body, read = table_text(x[:, 0])   # a 1-D column: one value a row, read back in its shape
    assert body.decode() == "".join("%.10g\n" % v for v in x[:, 0]) and read.shape == (1001,)


def test_random_doubles_as_python():
    rng = np.random.default_rng(2026)
    bits = rng.integers(0, 2**63, 60_000, dtype=np.int64).view(np.float64)   # every exponent, NaNs
    ties = np.array([float(f"{a}5e{e}") for a, e in zip(rng.integers(10**9, 10**10, 20_000),
                                                         rng.integers(-320, 300, 20_000))])
    physical = rng.standard_normal(60_000) * 10.0 ** rng.uniform(-18, 12, 60_000)
    x = np.concatenate([bits, -ties, np.nextafter(ties, 0.0), physical])
    assert_as_python(x[: x.size // 11 * 11].reshape(-1, 11))


def test_write_returns_what_read_csv_reads(tmp_path):
    rng = np.random.default_rng(5)
    t = np.linspace(0.0, 1.0, 2001)
    cols = {"t": t, "u": 0.0255 * np.sin(2 * np.pi * t), "F": rng.standard_normal(t.size) * 1e3,
            "F_y": rng.standard_normal(t.size) * 1e-15, "wire0_stress": rng.standard_normal(t.size) * 1e7}
    written = write_columns(tmp_path / "c.csv", cols)
    back = read_csv(tmp_path / "c.csv")
    assert list(written) == list(back.columns)
    for name in cols:
        assert written[name].tobytes() == back[name].tobytes(), name
    text = (tmp_path / "c.csv").read_text()
    assert text.splitlines()[0] == "t [s],u [m],F [N],F_y [N],wire0_stress [Pa]"
    assert text.splitlines()[2] == ",".join("%.10g" % cols[n][1] for n in cols)
    result = RunResult("mujoco", cols, {"t": "s", "u": "m", "F": "N", "F_y": "N", "wire0_stress": "Pa"})
    again = write_csv(tmp_path / "r.csv", result)
    assert again.engine == "mujoco" and again.units == result.units
    assert all(again[n].tobytes() == read_csv(tmp_path / "r.csv")[n].tobytes() for n in cols)


@pytest.mark.parametrize("rows", [0, 1])
def test_short_tables(tmp_path, rows):
    cols = {"t": np.arange(rows, dtype=float), "F": -np.arange(rows, dtype=float) - 0.5}
    written = write_columns(tmp_path / "s.csv", cols)
    assert (tmp_path / "s.csv").read_text() == "t [s],F [N]\n" + "".join(f"{i:.10g},{-i - 0.5:.10g}\n" for i in range(rows))
    assert all(written[n].tobytes() == cols[n].tobytes() for n in cols)
