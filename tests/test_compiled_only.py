"""Functions compiled without numba's Python entry wrapper (a call from Python would crash the process):
the in-house engine's helpers in nsd_core.engine.compiled.COMPILED_ONLY and the private helpers of
Exudyn's generated force module stay out of reach of Python code."""
from __future__ import annotations

import ast
import re
from pathlib import Path

from comparisons.builders import exudyn_codegen
from nsd_core.engine import compiled

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("nsd_core", "comparisons", "nsd_cli", "benchmarks", "tests")


def _sources():
    for pkg in PACKAGES:
        yield from (p for p in (ROOT / pkg).rglob("*.py") if p.name != Path(__file__).name)


def test_the_in_house_helpers_without_a_python_entry_are_named_nowhere_else():
    assert compiled.COMPILED_ONLY
    home = Path(compiled.__file__).resolve()
    for name in compiled.COMPILED_ONLY:
        fn = getattr(compiled, name)
        assert fn.targetoptions.get("no_cpython_wrapper"), name
        used = (rf"from nsd_core\.engine\.compiled import[^\n]*\b{name}\b", rf"\b(compiled|C)\.{name}\b")
        for path in _sources():
            if path.resolve() != home:
                text = path.read_text()
                assert not any(re.search(u, text) for u in used), f"{path}: uses {name}"


def test_the_generated_module_s_helpers_are_private_and_its_users_call_only_entry_points():
    laws = exudyn_codegen.law_set([])
    text, _ = exudyn_codegen.source(laws)
    helpers, entries = set(), set()
    for node in ast.parse(text).body:
        if isinstance(node, ast.FunctionDef):
            wrapped = any(isinstance(d, ast.Call) and any(k.arg == "no_cpython_wrapper" for k in d.keywords)
                          for d in node.decorator_list)
            (helpers if wrapped else entries).add(node.name)
    assert {"_state", "_laws", "_evaluate", "_commit", "_force"} <= helpers
    assert all(n.startswith("_") for n in helpers) and not any(n.startswith("_") for n in entries)
    used = set()
    for path in _sources():
        used |= set(re.findall(r"\.gen\.(\w+)", path.read_text()))
    assert used and used <= entries, used - entries
