"""numba's cache is keyed by the source version (nsd_core.compilation.numba_cache): an edit anywhere in the
model or the engines starts a fresh cache folder, so no cached kernel runs a callee's old code."""
from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

from nsd_core.compilation.numba_cache import (_sources, cache_folder, compiled_sources, source_fingerprint,
                                              use_versioned_cache)


def _tree(root: Path, law: str) -> None:
    for pkg in ("nsd_core", "comparisons"):
        (root / pkg).mkdir(parents=True, exist_ok=True)
    (root / "nsd_core" / "forces.py").write_text(law)
    (root / "comparisons" / "mujoco_engine.py").write_text("x = 1\n")


def test_an_edit_to_any_callee_changes_the_folder(tmp_path):
    _tree(tmp_path, "def rope(L): return 2.0 * L\n")
    before = source_fingerprint(tmp_path)
    assert source_fingerprint(tmp_path) == before  # the same source, the same folder
    _tree(tmp_path, "def rope(L): return 3.0 * L\n")
    assert source_fingerprint(tmp_path) != before
    (tmp_path / "comparisons" / "mujoco_engine.py").write_text("x = 2\n")  # the engines' callbacks count too
    after = source_fingerprint(tmp_path)
    _tree(tmp_path, "def rope(L): return 3.0 * L\n")
    assert source_fingerprint(tmp_path) != after
    env = {"XDG_CACHE_HOME": str(tmp_path / "c")}
    assert cache_folder(tmp_path, env).parent == tmp_path / "c" / "nsd-harness" / "numba"


KERNEL = """from numba import njit
from nsd_core.constants import (SCALE,
    OFFSET)


@njit(cache=True)
def law(x):
    from nsd_core.lazy import helper
    return SCALE * x + OFFSET + helper(x)
"""


def test_the_folder_follows_only_what_compiled_code_can_depend_on(tmp_path):
    """An edit to a module the kernels import (a constant frozen at compile time, on a continued line, or a
    lazy import) starts a fresh folder; an edit to a module no kernel reaches (the verdict, the command
    line) keeps the compiled code's folder, while the full fingerprint (kept runs' keys) still changes."""
    for pkg in ("nsd_core", "comparisons"):
        (tmp_path / pkg).mkdir()
        (tmp_path / pkg / "__init__.py").write_text("")
    files = {"nsd_core/kernel.py": KERNEL, "nsd_core/constants.py": "SCALE = 2.0\nOFFSET = 0.0\n",
             "nsd_core/lazy.py": "from numba import njit\n\n@njit\ndef helper(x):\n    return x\n",
             "comparisons/verdict.py": "from nsd_core.kernel import law\nK = 3.0\n"}
    for name, text in files.items():
        (tmp_path / name).write_text(text)
    assert compiled_sources(_sources(tmp_path)) == {"nsd_core.kernel", "nsd_core.constants", "nsd_core.lazy"}
    folder, full = source_fingerprint(tmp_path, compiled_only=True), source_fingerprint(tmp_path)
    (tmp_path / "comparisons/verdict.py").write_text("from nsd_core.kernel import law\nK = 4.0\n")
    assert source_fingerprint(tmp_path, compiled_only=True) == folder and source_fingerprint(tmp_path) != full
    for name, edit in (("nsd_core/constants.py", "SCALE = 2.0\nOFFSET = 1.0\n"),
                       ("nsd_core/lazy.py", "from numba import njit\n\n@njit\ndef helper(x):\n    return 2 * x\n")):
        (tmp_path / name).write_text(edit)
        assert source_fingerprint(tmp_path, compiled_only=True) != folder
        folder = source_fingerprint(tmp_path, compiled_only=True)


def test_the_real_tree_keeps_the_engines_and_laws_and_leaves_the_verdict_out():
    found = compiled_sources(_sources(Path(__file__).resolve().parents[1]))
    assert {"nsd_core.engine.semirecursive", "nsd_core.device.laws", "nsd_core.model.laws",
            "comparisons.builders.mujoco_kernels"} <= found
    assert not {"comparisons.verdict", "comparisons.harness", "comparisons.model_compare"} & found


def test_a_users_own_cache_setting_is_kept():
    env = {"NUMBA_CACHE_DIR": "/somewhere/of/mine"}
    assert use_versioned_cache(env) is None
    assert env == {"NUMBA_CACHE_DIR": "/somewhere/of/mine"}


def test_numba_writes_its_cache_into_the_versioned_folder(tmp_path):
    mod = tmp_path / "tiny_kernel.py"
    mod.write_text("from numba import njit\n\n@njit(cache=True)\ndef twice(x):\n    return 2.0 * x\n")
    code = textwrap.dedent(f"""
        import sys
        sys.path.insert(0, {str(tmp_path)!r})
        import nsd_core
        import tiny_kernel
        assert tiny_kernel.twice(2.0) == 4.0
    """)
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    env["XDG_CACHE_HOME"] = str(tmp_path / "cache")
    subprocess.run([sys.executable, "-c", code], env=env, check=True, timeout=120)
    root = tmp_path / "cache" / "nsd-harness" / "numba"
    folders = list(root.iterdir())
    assert len(folders) == 1 and folders[0].name == source_fingerprint(Path(__file__).resolve().parents[1],
                                                                        compiled_only=True)
    assert any(p.suffix == ".nbi" for p in folders[0].rglob("*")), "numba cached nothing there"


UNCACHEABLE = """
import ctypes, ctypes.util, sys
sys.path.insert(0, {path!r})
{first}
from numba import njit
cos = ctypes.CDLL(ctypes.util.find_library("m")).cos
cos.restype, cos.argtypes = ctypes.c_double, (ctypes.c_double,)

@njit(cache=True)
def f(x):
    return cos(x)   # a ctypes pointer: a dynamic global, which numba cannot cache (as under NUMBA_OPT=0)

assert f(0.0) == 1.0
"""


def test_numbas_cannot_cache_warning_never_reaches_stderr(tmp_path):
    env = {k: v for k, v in os.environ.items() if k not in ("NUMBA_CACHE_DIR", "NSD_NUMBA_CACHE_WARNINGS")}
    env["XDG_CACHE_HOME"] = str(tmp_path / "cache")
    for first, shown in (("import nsd_core", False), ("", True)):   # without nsd_core numba does warn
        mod = tmp_path / f"k{int(shown)}.py"
        mod.write_text(UNCACHEABLE.format(path=str(Path(__file__).resolve().parents[1]), first=first))
        p = subprocess.run([sys.executable, str(mod)], env=env, capture_output=True, text=True, timeout=120)
        assert p.returncode == 0, p.stderr
        assert ("Cannot cache compiled function" in p.stderr) == shown, p.stderr


def test_the_cache_sub_folder_is_named_by_the_place_in_the_package_not_the_absolute_path(tmp_path):
    from nsd_core.compilation.numba_cache import ROOT, package_subfolder
    assert package_subfolder(str(ROOT / "nsd_core" / "engine" / "rk.py")) == "nsd_core_engine"
    assert package_subfolder(str(ROOT / "comparisons" / "engines" / "mujoco_native.py")) == "comparisons_engines"
    assert package_subfolder(str(tmp_path / "elsewhere.py")) is None   # numba's own naming


def _copy_of_the_packages(dest: Path) -> None:
    import shutil
    from nsd_core.compilation.numba_cache import ROOT
    for pkg in ("nsd_core", "comparisons"):
        shutil.copytree(ROOT / pkg, dest / pkg, ignore=shutil.ignore_patterns("__pycache__"))


def test_a_copy_of_the_same_version_elsewhere_loads_what_another_compiled(tmp_path):
    """Two installs of one version at two paths (two clones): the second compiles nothing."""
    code = textwrap.dedent("""
        import numpy as np
        from numba.core import event
        seen = []
        class L(event.Listener):
            def on_start(self, ev):
                seen.append(ev.data["dispatcher"].py_func.__qualname__)
            def on_end(self, ev):
                pass
        event.register("numba:compile", L())
        from nsd_core.device.forces import rope_tension_scalar
        print(rope_tension_scalar(0.1, 0.09, 1e5), len(seen))
    """)
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    env["XDG_CACHE_HOME"] = str(tmp_path / "cache")
    outs = []
    for place in ("one", "two"):
        _copy_of_the_packages(tmp_path / place)
        p = subprocess.run([sys.executable, "-c", code], cwd=tmp_path / place, env=env, capture_output=True,
                           text=True, timeout=300)
        assert p.returncode == 0, p.stderr
        outs.append(p.stdout.split())
    assert outs[0][0] == outs[1][0] and int(outs[0][1]) >= 1 and int(outs[1][1]) == 0, outs


def test_a_child_process_names_the_sub_folders_as_its_parent(tmp_path):
    """A pool's worker or a helper inherits the folder this package chose (NUMBA_CACHE_DIR and the mark
    NSD_VERSIONED_CACHE): it names the sub-folders by the place in the package, as its parent does,
    so each loads what the other compiled. A user's own NUMBA_CACHE_DIR keeps numba's naming."""
    from nsd_core.compilation.numba_cache import CHOSEN
    code = ("import nsd_core\nfrom numba.core import caching\n"
            "print(any(getattr(c, 'nsd_relocatable', False) for c in caching.CacheImpl._locator_classes))")
    folder = str(tmp_path / "chosen")
    base = {k: v for k, v in os.environ.items() if k not in ("NUMBA_CACHE_DIR", CHOSEN)}
    for extra, relocatable in (({"NUMBA_CACHE_DIR": folder, CHOSEN: folder}, "True"),
                               ({"NUMBA_CACHE_DIR": folder}, "False"),
                               ({"NUMBA_CACHE_DIR": folder, CHOSEN: str(tmp_path / "other")}, "False")):
        p = subprocess.run([sys.executable, "-c", code], env={**base, **extra}, capture_output=True, text=True,
                           timeout=120)
        assert p.returncode == 0 and p.stdout.strip() == relocatable, (extra, p.stdout, p.stderr)
