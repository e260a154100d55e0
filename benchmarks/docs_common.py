"""What every generated table of the docs shares (benchmarks.docs): numbers to 3 digits, the JSON's
loading and its provenance line, a markdown table."""
from __future__ import annotations

import json
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results"


def g(v, digits: int = 3) -> str:
    """A number to ``digits`` significant digits (the JSON keeps every digit)."""
    if v is None:
        return "–"
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, int):
        return str(v)
    return f"{v:.{digits}g}"


def plain(v, digits: int = 3) -> str:
    """As ``g`` but without an exponent (1180, not 1.18e+03) for numbers a table reads as plain."""
    return f"{float(f'{v:.{digits}g}'):g}"


def load(name: str) -> dict:
    return json.loads((RESULTS / f"{name}.json").read_text())


def loaded(m: dict) -> bool:
    """Other work shared the CPUs: the load average before the command above the CPU count, or after it
    above the CPU count + 1 (the load after counts the command's own processes, up to 2 workers)."""
    return m["load_average_before"][0] > m["cpus"] or m["load_average_after"][0] > m["cpus"] + 1


def provenance(rec: dict) -> str:
    m = rec["measured"]
    v = m["versions"]
    vers = ", ".join(f"{k} {v[k]}" for k in ("python", "numpy", "scipy", "numba", "mujoco", "exudyn") if k in v)
    load_text = (f"load average {m['load_average_before'][0]:g} before, {m['load_average_after'][0]:g} after"
                 + (" (**loaded**: other jobs shared the CPUs, so times are longer than on a quiet machine)"
                    if loaded(m) else ""))
    return (f"*Measured {m['date_utc']} UTC by `{rec['command']}` (exit {rec['exit_code']}, {m['wall_s']:.0f} s), "
            f"`python -m benchmarks.measure {rec['name']}`; {m['machine']}, {m['cpus']} CPUs, {load_text}; "
            f"{vers}; commit {m['git_commit'][:12]}{m['git_commit'][40:]}.*\n")


def table(head: list[str], rows: list[list[str]]) -> str:
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    lines += ["| " + " | ".join(r) + " |" for r in rows]
    return "\n".join(lines) + "\n"
