"""What a new user reads: the docs and every command's --help carry no internal words (issue numbers,
rounds, branches of the project's history), and the message for a Dask scheduler that is not there
names a command that exists here."""
from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
USER_DOCS = [ROOT / "README.md"] + sorted((ROOT / "docs").glob("*.md"))
INTERNAL = re.compile(r"\bissues? \d+\w*|\banother branch\b|\b(this|current|second|third|fourth|earlier|last) round\b"
                      r"|\(items? \d+[^)]*\)|\b(the )?lead engineer\b|\bhelper session\b|\bhidden battery\b",
                      re.I)


def internal_words(text: str) -> list[str]:
    return [m.group(0) for m in INTERNAL.finditer(text)]


def test_the_pattern_catches_what_users_cannot_follow():
    assert internal_words("`nsd ida` (issue 23b, another branch) does not") == ["issue 23b", "another branch"]
    assert internal_words("## Cross-check (item 5)") == ["(item 5)"]
    assert internal_words("what issue 26 (second round) took off") == ["issue 26", "second round"]
    assert internal_words("the paper's Table 5 and the IFToMM A01 benchmark, round trip") == []


@pytest.mark.parametrize("path", USER_DOCS, ids=lambda p: p.name)
def test_user_docs_carry_no_internal_words(path):
    found = internal_words(path.read_text(encoding="utf-8"))
    assert not found, f"{path.name}: {found}"


def test_help_texts_carry_no_internal_words():
    from nsd_cli.main import build_parser
    parser = build_parser()
    texts = {"nsd": parser.format_help()}
    for action in parser._subparsers._group_actions:  # noqa: SLF001 (argparse keeps them there)
        texts.update({f"nsd {name}": p.format_help() for name, p in action.choices.items()})
    assert len(texts) > 10
    found = {name: internal_words(text) for name, text in texts.items() if internal_words(text)}
    assert not found, found


def test_no_scheduler_message_names_a_command_that_exists(tmp_path):
    """Nothing answers at the address: the line names the venv's `dask scheduler` (or the extra to
    install), and that command runs here."""
    p = subprocess.run([sys.executable, "-m", "nsd_cli.main", "sweep", "--param", "rope_stiffness", "--values",
                        "4e5", "--scheduler", "tcp://127.0.0.1:1", "--scheduler-timeout", "1",
                        "--out", str(tmp_path / "s")], capture_output=True, text=True, timeout=120)
    assert p.returncode == 2 and len(p.stderr.strip().splitlines()) == 1, p.stderr
    commands = re.findall(r"`([^`]+ scheduler)`", p.stderr)
    assert commands, p.stderr
    exe = commands[0].split()[0]
    assert Path(exe).is_file(), exe
    q = subprocess.run([exe, "scheduler", "--help"], capture_output=True, text=True, timeout=120)
    assert q.returncode == 0 and "scheduler" in q.stdout.lower()
    assert not (tmp_path / "s").exists()


def test_no_scheduler_message_without_dask_names_the_extra(monkeypatch):
    import importlib.util

    from nsd_cli.sweep import start_scheduler_hint
    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec", lambda name, *a: None if name == "distributed" else real(name, *a))
    hint = start_scheduler_hint()
    assert "'.[dask]'" in hint and "pip install" in hint
