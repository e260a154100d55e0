"""Where an interrupt waits: only inside the compiler packages, where raising it would be swallowed."""
import importlib.util
import sys

from nsd_cli.main import _in_compiler


def test_an_interrupt_is_deferred_only_inside_the_compiler_packages(tmp_path):
    """Deferred inside numba's own code; not inside a generated module whose cache folder is named numba."""
    numba_dir = importlib.util.find_spec("numba").submodule_search_locations[0]
    inside = compile("import sys\nframe = sys._getframe()", f"{numba_dir}/core/fake.py", "exec")
    scope: dict = {}
    exec(inside, scope)
    assert _in_compiler(scope["frame"])
    cache = tmp_path / "nsd-harness" / "numba" / "generated"
    outside = compile("import sys\nframe = sys._getframe()", str(cache / "nsd_eval_x.py"), "exec")
    exec(outside, scope)
    assert not _in_compiler(scope["frame"])
    assert not _in_compiler(sys._getframe())
