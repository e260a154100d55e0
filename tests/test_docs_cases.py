"""docs/cases.md lists every key the case and tolerance parsers accept."""
import re
from pathlib import Path

import pytest

DOC = (Path(__file__).resolve().parents[1] / "docs" / "cases.md").read_text()
DOCUMENTED = set(re.findall(r"`([A-Za-z_][A-Za-z0-9_]*)`", DOC))


def keys():
    from comparisons import config
    from comparisons.engines import ENGINES, get_engine
    from comparisons.engines.base import SeismicSettings
    from comparisons.seismic import SYNTHETIC
    from nsd_core.structure.listing import structure_fields
    out = {("case", k) for k in config.CASE_KEYS | config.SEISMIC_KEYS | config.DEFAULT_KEYS}
    out |= {("convergence", k) for k in (*config.CONVERGENCE_KEYS, *config.SWEEP_KEYS)}
    out |= {("metric", k) for k in config.METRICS}
    out |= {("engine", e) for e in ENGINES}
    for e in ENGINES:
        eng = get_engine(e)
        out |= {(f"settings.{e}", k) for k in eng.default_settings}
        out |= {(f"seismic settings.{e}", k) for k in SeismicSettings(eng).default_settings}
    out |= {("structure", k) for k in structure_fields()}
    out |= {(f"ground {kind}", k) for kind, (_, ks) in SYNTHETIC.items() for k in ks}
    out |= {("kind", k) for k in SYNTHETIC}
    return sorted(out)


@pytest.mark.parametrize("where, key", keys())
def test_every_accepted_key_is_documented(where, key):
    assert key in DOCUMENTED, f"{where}: {key} is accepted by the parser but not documented in docs/cases.md"


def test_top_level_tables_and_defaults_match_the_parser():
    from comparisons.engines import ENGINES, get_engine
    from nsd_core.device.drive import SAMPLES_PER_CYCLE, Drive
    assert "`samples_per_cycle` | whole number | – | 2000 |" in DOC and SAMPLES_PER_CYCLE == 2000
    assert f"| `cycles` | whole number | – | 2 | 1–{Drive.CYCLES_MAX};" in DOC
    assert "| `frequency` | number | Hz | required | 0.05–100 |" in DOC and (Drive.F_MIN, Drive.F_MAX) == (0.05, 100.0)
    for e in ENGINES:  # each engine's drive defaults as documented
        for k, v in get_engine(e).default_settings.items():
            if isinstance(v, (int, float)) and not isinstance(v, bool) and v is not None:
                shown = re.search(rf"`{k}` = ([0-9.e+-]+(?: [0-9]{{3}})?)", DOC)
                assert shown, (e, k)
                assert float(shown.group(1).replace(" ", "")) == v, (e, k, shown.group(1), v)
