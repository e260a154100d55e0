"""``nsd params``: every parameter of the device and of the isolated structure, with its value, unit,
bounds and provenance (a table of Dai et al. 2024, or "assumed" with the place in docs/model.md).

``--format toml`` (the default with ``--out FILE``) writes a starting parameter file: every device
parameter under ``[params]`` with its unit, bounds and provenance as a comment; edit the values you
want, delete the rest, and pass it as ``--params FILE`` to cycle, compare, seismic, sweep or polar.
The isolated structure follows as comments: the one ``nsd seismic`` uses (the same function builds
it: ``nsd_cli.seismic_extras.isolated_structure``, the design basis's, the same for every device); it
is set with ``nsd seismic --structure NAME=VALUE`` or ``structure = {...}`` in a seismic case, not in a
parameter file. ``--params``/``--set`` show a variant (its rows say "override")."""
from __future__ import annotations

import argparse

from nsd_cli.options import add_param_arguments, base_params

HELP = "list every parameter (value, unit, bounds, provenance); write a starting parameter file"


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--format", choices=("table", "toml"), default=None,
                   help="table (default on the terminal) or toml (default with --out: a parameter file)")
    add_param_arguments(p, "parameter overrides to list instead of the defaults")
    p.add_argument("--resize", action="store_true",
                   help="list the isolated structure derived from the device (as nsd seismic --resize) instead of the "
                        "design basis's")
    p.add_argument("--out", default=None, metavar="FILE", help="write to FILE instead of printing")


DIGITS = 5  # the table's values: 5 significant digits (a parameter file, --format toml, holds every digit)


def _table(title: str, rows: list[dict]) -> str:
    cols = [("name", "name"), ("value", "value"), ("unit", "unit"), ("bounds", "bounds"),
            ("provenance", "provenance"), ("doc", "description")]
    cells = [[f"{r[k]:.{DIGITS}g}" if isinstance(r[k], float) else str(r[k]) for k, _ in cols] for r in rows]
    width = [max([len(h)] + [len(c[i]) for c in cells]) for i, (_, h) in enumerate(cols)]  # (no rows: headers)
    line = lambda vals: "  ".join(v.ljust(w) for v, w in zip(vals, width)).rstrip()  # noqa: E731
    return "\n".join([title, line([h for _, h in cols]), line(["-" * w for w in width]), *map(line, cells)])


def table_text(params_rows: list[dict], structure_rows: list[dict]) -> str:
    return (f"values to {DIGITS} significant digits; every digit: --format toml\n\n"
            + _table("device parameters (--params FILE, --set NAME=VALUE; a case's params = {...})", params_rows)
            + "\n\n" + _table("isolated structure of nsd seismic (the design basis's, the same for every device; "
                              "--structure NAME=VALUE; a seismic case's structure = {...})", structure_rows) + "\n")


def toml_text(params_rows: list[dict], structure_rows: list[dict]) -> str:
    from nsd_core.structure.listing import toml_value
    out = ["# Parameter file written by `nsd params --format toml`: every device parameter with its value.",
           "# Comment: description [unit]; allowed range; provenance. Pass it as --params FILE (nsd cycle,",
           "# compare, seismic, sweep, polar); keep only the lines you change if you like (the rest default).",
           "[params]"]
    for r in params_rows:
        out.append(f"# {r['doc']} [{r['unit']}]; {r['bounds']}; {r['provenance']}")
        out.append(f"{r['name']} = {toml_value(r['value'])}")
    out += ["", "# The isolated structure of nsd seismic is not part of a parameter file: set it with",
            "# `nsd seismic --structure NAME=VALUE` or `structure = { NAME = VALUE }` in a seismic case.",
            "# Its values (the design basis's, the same for every device: the structure nsd seismic uses;",
            "# nsd seismic --resize derives it from the device by the rules of docs/model.md instead):"]
    for r in structure_rows:
        out.append(f"#   {r['name']} = {toml_value(r['value'])}  # {r['doc']} [{r['unit']}]; {r['bounds']}; "
                   f"{r['provenance']}")
    return "\n".join(out) + "\n"


def run(args) -> int:
    from nsd_cli.seismic_extras import isolated_structure
    from nsd_core.structure.listing import param_rows, structure_rows
    from nsd_core.device.params import ParameterError
    from nsd_core.common.files import atomic_write_text
    from nsd_cli.options import check_out_file
    params = base_params(args)
    check_out_file("--out", args.out)
    fmt = args.format or ("toml" if args.out else "table")
    try:
        structure = isolated_structure(args, params)   # the structure nsd seismic uses (the same function)
    except ParameterError as e:  # --resize: a variant without negative stiffness has no derived structure
        structure, note = None, f"# no default isolated structure: {e}\n"
    rows_p = param_rows(params)
    rows_s = structure_rows(structure, params) if structure is not None else []
    text = (toml_text if fmt == "toml" else table_text)(rows_p, rows_s)
    if structure is None:
        text += note
    if args.out:
        atomic_write_text(args.out, text)
        print(f"wrote {args.out} ({len(rows_p)} device parameters, {len(rows_s)} structure fields)")
    else:
        print(text, end="")
    return 0
