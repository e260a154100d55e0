import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

import os

import pytest


@pytest.fixture(autouse=True)
def _evaluator_choice_kept():
    """A study command run in-process (nsd_cli.main) sets NSD_EVALUATOR=generated for its workers
    (nsd_core.engine.codegen.prefer_generated); put it back after each test, so that no test depends on
    which ran before it."""
    before = os.environ.get("NSD_EVALUATOR")
    yield
    if before is None:
        os.environ.pop("NSD_EVALUATOR", None)
    else:
        os.environ["NSD_EVALUATOR"] = before
