"""The import graph, read from the source: layers depend one way, no circles, and the generic
layers (the engine, the model description) know nothing of the device or the structure
(docs/architecture.md). Function-level (lazy) imports count too."""
from __future__ import annotations

import ast
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("nsd_core", "comparisons", "reports", "nsd_cli")
# lowest first; a module may import its own layer or any below it
LAYERS = [("nsd_core.common",), ("nsd_core.engine", "nsd_core.ground"), ("nsd_core.model",), ("nsd_core.device",),
          ("nsd_core.structure",), ("nsd_core.compilation", "nsd_core"), ("nsd_core.study", "nsd_core.api"),
          ("comparisons",), ("reports",), ("nsd_cli",)]
UPWARD: set = set()   # edges allowed to run upward: none (docs/architecture.md)
ENGINE_MAY_IMPORT = {"numpy", "scipy", "numba"}


def module_name(path: Path) -> str:
    parts = path.relative_to(ROOT).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def imports_of(path: Path) -> set[str]:
    """Absolute names of every module ``path`` imports (relative imports resolved)."""
    tree = ast.parse(path.read_text(), str(path))
    me = module_name(path)
    pkg = me if path.name == "__init__.py" else me.rpartition(".")[0]
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = pkg.split(".")[: len(pkg.split(".")) - (node.level - 1)]
                mod = ".".join(base + ([node.module] if node.module else []))
            else:
                mod = node.module
            out.add(mod)
            out.update(f"{mod}.{a.name}" for a in node.names)  # "from pkg import submodule"
    return out


def project_modules() -> dict[str, Path]:
    return {module_name(p): p for pkg in PACKAGES for p in (ROOT / pkg).rglob("*.py")}


MODULES = project_modules()


def layer(mod: str) -> int:
    best = None
    for i, prefixes in enumerate(LAYERS):
        for pre in prefixes:
            if mod == pre or mod.startswith(pre + "."):
                if best is None or len(pre) > best[1]:
                    best = (i, len(pre))
    assert best is not None, mod
    return best[0]


def project_imports(mod: str) -> set[str]:
    """The project modules ``mod`` imports (a name that is an attribute resolves to its module)."""
    out = set()
    for name in imports_of(MODULES[mod]):
        while name and name not in MODULES:
            name = name.rpartition(".")[0]
        if name and name != mod and name.split(".")[0] in PACKAGES:
            out.add(name)
    return out


def test_the_graph_covers_every_package():
    assert {m.split(".")[0] for m in MODULES} == set(PACKAGES)
    assert "nsd_core.engine.semirecursive" in MODULES and "nsd_cli.main" in MODULES


@pytest.mark.parametrize("mod", sorted(MODULES))
def test_no_module_imports_a_layer_above_its_own(mod):
    above = [m for m in project_imports(mod) if layer(m) > layer(mod) and not (mod + ".").startswith(m + ".")
             and (mod, m) not in UPWARD]
    assert not above, f"{mod} (layer {layer(mod)}) imports {above}"


def test_the_engine_imports_only_numpy_scipy_numba_and_itself():
    stdlib = set(sys.stdlib_module_names)
    for mod, path in MODULES.items():
        if not mod.startswith("nsd_core.engine"):
            continue
        for name in imports_of(path):
            top = name.split(".")[0]
            if name.startswith(("nsd_core.engine", "nsd_core.common")) or top in ENGINE_MAY_IMPORT or top in stdlib \
                    or top == "__future__":
                continue
            if name.rpartition(".")[0] in ("nsd_core",) and name.startswith("nsd_core.engine"):
                continue
            pytest.fail(f"{mod} imports {name}")


def test_no_engine_specific_import_in_the_library():
    for mod, path in MODULES.items():
        if mod.startswith("nsd_core"):
            tops = {n.split(".")[0] for n in imports_of(path)}
            assert not tops & {"mujoco", "exudyn"}, mod


def test_no_import_circles():
    graph = {m: project_imports(m) for m in MODULES}
    # a package imports its own submodules through __init__ legitimately; drop parent->child edges
    graph = {m: {d for d in deps if not d.startswith(m + ".") and not m.startswith(d + ".")} for m, deps in graph.items()}
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(m):
        state[m] = 1
        stack.append(m)
        for d in graph[m]:
            if state.get(d) == 1:
                pytest.fail("import circle: " + " -> ".join(stack[stack.index(d):] + [d]))
            if d not in state:
                visit(d)
        stack.pop()
        state[m] = 2

    for m in sorted(graph):
        if m not in state:
            visit(m)


def test_the_reader_sees_lazy_imports_and_orders_layers():
    """The checker is not blind: a function-level import is read, and layers order as documented."""
    assert "comparisons.engines" in project_imports("nsd_cli.sweep")  # imported inside run()
    assert layer("nsd_core.model.load") < layer("nsd_core.device.laws") < layer("nsd_core.structure.isolator_laws")
    assert layer("nsd_core.engine.closure") < layer("nsd_core.device.model") < layer("nsd_core.study.sweep") \
        < layer("comparisons.harness") < layer("reports.build") < layer("nsd_cli.main")


@pytest.mark.parametrize("layer_name", ["nsd_core.model", "nsd_core.engine", "nsd_core.ground", "nsd_core.common"])
def test_a_generic_layer_imports_nothing_of_the_device_or_the_structure(layer_name):
    """A user's four-bar loads without the NSD's rope law: the generic layers never name the device."""
    bad = {mod: sorted(m for m in project_imports(mod) if m.startswith(("nsd_core.device", "nsd_core.structure",
                                                                          "nsd_core.compilation", "nsd_core.study")))
           for mod in MODULES if mod.startswith(layer_name)}
    assert {k: v for k, v in bad.items() if v} == {}


def test_a_description_loads_without_the_device(tmp_path):
    """In a fresh process, loading Andrews' mechanism imports nothing of the device or the structure, and
    the device's laws join the registry when nsd_core.device is imported."""
    import subprocess
    code = ("import sys; from nsd_core.model.load import load_model; load_model('models/andrews.toml'); "
            "print(sorted(m for m in sys.modules if m.startswith(('nsd_core.device', 'nsd_core.structure')))); "
            "from nsd_core.model.laws import LAWS; print('rope' in LAWS); import nsd_core.device; print('rope' in LAWS)")
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, check=True).stdout
    assert out.split("\n")[:3] == ["[]", "False", "True"]
