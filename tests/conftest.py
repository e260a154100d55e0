import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

import os

import pytest

# The commands the tests run (in this process or as a child) start one local worker unless a test asks
# for more (--workers, or NSD_WORKERS set before pytest): pytest-xdist already keeps every core busy,
# so a command's own second worker only adds its start-up (spawn, imports, warm-up: ~3.5 CPU s a
# compare on a warm cache, measured on the short case file). Tests of the pools pass --workers.
os.environ.setdefault("NSD_WORKERS", "1")
# The study commands draw no PNGs into their folders (~1 s a figure on a 2-core machine) unless a test
# asks (the ``figures`` fixture, or NSD_FIGURES set before pytest): the tests that check the figures
# or the pages use the fixture; the rest check numbers, which are written either way.
os.environ.setdefault("NSD_FIGURES", "0")


@pytest.fixture
def figures(monkeypatch):
    """The study commands in this test (in this process or as a child) draw their PNGs."""
    monkeypatch.setenv("NSD_FIGURES", "1")


@pytest.fixture(autouse=True)
def _evaluator_choice_kept():
    """A test that sets NSD_EVALUATOR itself (a benchmark's ``main()`` calls prefer_generated) gets it
    put back after, so that no test depends on which ran before it (a study command run in-process puts
    it back itself: nsd_core.engine.codegen.preferring_generated)."""
    before = os.environ.get("NSD_EVALUATOR")
    yield
    if before is None:
        os.environ.pop("NSD_EVALUATOR", None)
    else:
        os.environ["NSD_EVALUATOR"] = before


@pytest.fixture(autouse=True)
def _numba_cache_folder_kept():
    """A test that points NUMBA_CACHE_DIR at its own folder (monkeypatch) gets the environment back,
    but numba read the folder into its configuration at the test's compilation and keeps it until its
    next compilation: a kernel module imported meanwhile in this worker (a lazy import, a generated
    module) would look for its machine code in the test's deleted folder and compile again. Numba
    reads the environment back after the test (monkeypatch's own teardown has run by then)."""
    yield
    config = sys.modules.get("numba.core.config")
    if config is not None:
        config.reload_config()


@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(config, items):
    """Under pytest-xdist (``--dist loadgroup``): the tests that share a module- or session-scoped
    fixture go to one worker together (the fixture is built once), every other test wherever a worker
    is free. First among the hooks: xdist's own reads the group markers in its hook of this name, and
    after it a marker added here is not seen (the fixture was then built on each worker)."""
    for item in items:
        info = getattr(item, "_fixtureinfo", None)
        if info is None:
            continue
        shared = any(defs and defs[-1].scope in ("module", "package", "session")
                     for name, defs in info.name2fixturedefs.items() if name in item.fixturenames)
        if shared:
            item.add_marker(pytest.mark.xdist_group(item.module.__name__))
