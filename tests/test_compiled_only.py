"""Functions compiled without numba's Python entry wrapper (a call from Python would crash the process):
the in-house engine's helpers (nsd_core.engine.compiled's ``compiled_only``), Exudyn's kernels that only its
generated force module calls, and that module's private helpers are used only inside compiled functions."""
from __future__ import annotations

import ast
import re
from pathlib import Path

from comparisons.builders import exudyn_codegen, exudyn_kernels, generated
from nsd_core.engine import compiled

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("nsd_core", "comparisons", "nsd_cli", "benchmarks", "tests")


def _sources():
    for pkg in PACKAGES:
        yield from (p for p in (ROOT / pkg).rglob("*.py") if p.name != Path(__file__).name)


def _jitted(tree: ast.Module) -> set[str]:
    """Names of the module's functions that numba compiles: decorated with njit or compiled_only, or
    passed to a call of njit(...) (``njit(sig)(f)``, ``njit(sig)(f.py_func)``)."""
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.FunctionDef) and any("njit" in ast.unparse(d) or "compiled_only" in ast.unparse(d)
                                                     for d in node.decorator_list):
            out.add(node.name)
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Call) and "njit" in ast.unparse(node.func.func):
            out |= {n.id for a in node.args for n in ast.walk(a) if isinstance(n, ast.Name)}
    return out


def _bindings(tree: ast.Module, module: str, name: str, home: bool) -> tuple[bool, set[str]]:
    """Whether the bare ``name`` in a module's code is ``module``'s (defined there, or imported from it),
    and the names the module binds to ``module`` itself."""
    direct, aliases = home, set()
    package, _, last = module.rpartition(".")
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module == module:
            direct |= any(a.name == name for a in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module == package:
            aliases |= {a.asname or a.name for a in node.names if a.name == last}
        elif isinstance(node, ast.Import):
            aliases |= {a.asname for a in node.names if a.name == module and a.asname}
    return direct, aliases


def _uses_outside_compiled(tree: ast.Module, module: str, name: str, home: bool) -> list[int]:
    """Lines where ``module``'s ``name`` is used (not imported) outside a compiled function."""
    jitted, bad = _jitted(tree), []
    direct, aliases = _bindings(tree, module, name, home)

    def visit(node, inside):
        for child in ast.iter_child_nodes(node):
            if isinstance(child, ast.FunctionDef):
                visit(child, inside or child.name in jitted)
            elif isinstance(child, (ast.Import, ast.ImportFrom)):
                continue
            else:
                hit = (direct and isinstance(child, ast.Name) and child.id == name) or (
                    isinstance(child, ast.Attribute) and child.attr == name and isinstance(child.value, ast.Name)
                    and child.value.id in aliases)
                if hit and not inside:
                    bad.append(child.lineno)
                visit(child, inside)
    visit(tree, False)
    return bad


def _wrapperless(module) -> list[str]:
    return [n for n, v in vars(module).items() if getattr(v, "targetoptions", {}).get("no_cpython_wrapper")]


def test_the_helpers_without_a_python_entry_are_used_only_in_compiled_code():
    assert {"_closure", "_factor_dependent_block", "_newton", "derivatives"} <= set(_wrapperless(compiled))
    assert {"arguments", "forces"} <= set(_wrapperless(exudyn_kernels))
    for module in (compiled, exudyn_kernels):
        for name in _wrapperless(module):
            for path in _sources():
                text = path.read_text()
                if name in text:
                    home = path.resolve() == Path(module.__file__).resolve()
                    assert not _uses_outside_compiled(ast.parse(text), module.__name__, name, home), \
                        f"{path}: {module.__name__}.{name} outside compiled code"


def test_the_generated_module_s_helpers_are_private_and_its_users_call_only_entry_points():
    laws = generated.law_set([])
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
