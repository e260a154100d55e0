"""The tables of docs/validation.md and docs/performance.md are what benchmarks/results/*.json give,
byte for byte: no hand-typed figure."""
import json
import re
import shutil
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from benchmarks import docs, docs_common  # noqa: E402


def test_committed_tables_regenerate_byte_identical():
    assert docs.stale() == [], "run: python -m benchmarks.docs"


def test_every_block_has_a_renderer_and_every_renderer_a_block():
    names = [m.group("name") for p in docs.DOCS for m in docs.BLOCK.finditer(p.read_text())]
    assert sorted(names) == sorted(docs.RENDER)
    for p in docs.DOCS:  # every opening marker is closed (an unclosed one would be left alone silently)
        text = p.read_text()
        assert len(re.findall(r"<!-- generated: ", text)) == len(re.findall(r"<!-- end generated: ", text))


def test_each_result_says_where_and_when_it_was_measured():
    for f in sorted(docs_common.RESULTS.glob("*.json")):
        rec = json.loads(f.read_text())
        m = rec["measured"]
        assert rec["command"] and rec["name"] == f.stem
        for key in ("date_utc", "machine", "cpus", "load_average_before", "load_average_after", "loaded", "versions",
                    "git_commit", "wall_s"):
            assert key in m, (f.name, key)
        for pkg in ("numpy", "mujoco", "exudyn"):
            assert pkg in m["versions"]


def test_a_changed_number_makes_the_tables_stale(tmp_path, monkeypatch):
    results = tmp_path / "results"
    shutil.copytree(docs_common.RESULTS, results)
    rec = json.loads((results / "bench_cycle.json").read_text())
    rec["data"]["cases"][0]["median_s_per_cycle"] *= 2
    (results / "bench_cycle.json").write_text(json.dumps(rec))
    monkeypatch.setattr(docs_common, "RESULTS", results)
    assert docs.stale() == ["docs/performance.md"]
