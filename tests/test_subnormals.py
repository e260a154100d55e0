"""Subnormal numbers flushed while a peer's step loop runs (comparisons.builders.subnormals)."""
import numpy as np
import pytest

from comparisons.builders.subnormals import ON_X86, control_register, flushed

TINY = np.finfo(float).tiny   # the smallest normal double, 2.2e-308
STATUS = 0x3F   # the register's exception flags: sticky, raised by any arithmetic (not settings)

pytestmark = pytest.mark.skipif(not ON_X86, reason="the flag is x86-64's MXCSR")


def _product() -> float:
    return float(np.float64(1e-300) * np.float64(1e-10))   # 1e-310: subnormal


def test_flushed_flushes_within_the_block_and_puts_the_register_back_also_on_an_error():
    before = control_register() & ~STATUS
    assert _product() == pytest.approx(1e-310, rel=1e-3)
    with flushed():
        assert _product() == 0.0
    assert control_register() & ~STATUS == before and _product() != 0.0
    with pytest.raises(RuntimeError):
        with flushed():
            raise RuntimeError("inside")
    assert control_register() & ~STATUS == before


def test_mujocos_axial_drive_carries_no_subnormal_numbers():
    """The gate's A15mm_f1Hz in MuJoCo: the out-of-plane force F_y is zero in exact arithmetic; MuJoCo's
    round-off went below 2.2e-308 in 1774 of its 4001 samples (1.4x the run's CPU time) before the step
    loop flushed them."""
    from comparisons.config import load_cases
    from comparisons.engines import run_engine
    case = next(c for c in load_cases() if c.name == "A15mm_f1Hz")
    r = run_engine("mujoco", case.params, case.drive, dict(case.settings.get("mujoco", {})))
    found = {k: int(np.count_nonzero((np.abs(v) > 0) & (np.abs(v) < TINY)))
             for k, v in r.columns.items() if np.asarray(v).dtype.kind == "f"}
    assert not {k: n for k, n in found.items() if n}, found
