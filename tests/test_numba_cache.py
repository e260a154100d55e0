"""numba's cache is keyed by the source version (nsd_core.compilation.numba_cache): an edit anywhere in the
model or the engines starts a fresh cache folder, so no cached kernel runs a callee's old code."""
from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

from nsd_core.compilation.numba_cache import cache_folder, source_fingerprint, use_versioned_cache


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
    assert len(folders) == 1 and folders[0].name == source_fingerprint(Path(__file__).resolve().parents[1])
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
