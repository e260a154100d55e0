"""Derived expressions as generated Python code, cached per description.

Two functions are generated from a ``Derivation`` (comparisons.builders.symbolic_derive), each one
straight-line block after common-subexpression elimination (``sympy.cse``) over all its quantities:

- ``dynamics(q, u, g) -> (M, F, Phi, Phi_q, gamma)``: the mass matrix and the forcing, with the
  constraints, in one call;
- ``points(q, u) -> (R, J, Jdu)``: every named point's position (k x 3), Jacobian (k x 3 x n) and,
  where an acceleration is asked, J' u (k x 3; zero elsewhere).

Numbers are printed as Python's repr of the double (exact round trip); the functions use ``math``
on floats and fill numpy arrays, so a call runs no sympy and no Python per expression term beyond
its own straight-line code.

The cache: a folder per key under ``$XDG_CACHE_HOME/nsd-harness/symbolic`` (``~/.cache`` when the
variable is unset, as nsd_core.compilation.numba_cache places numba's), the key a hash of what the derivation
reads from the description (bodies, joints, loops, law points, output points: ``derivation_input``),
sympy's version and the source of the symbolic builder's modules. A law's parameters, the drives,
the excitation and the cases do not enter the equations (they are applied numerically), so changing
them re-uses the derivation. The folder holds ``equations.py`` (the generated module) and
``meta.json`` (derivation and generation times, expression sizes).
"""
from __future__ import annotations

import hashlib
import importlib.util
import json
import os
import time
from pathlib import Path

import numpy as np
import sympy as sp
from sympy.printing.pycode import PythonCodePrinter

from nsd_core.model.description import Model

MODULES = ("symbolic.py", "symbolic_derive.py", "symbolic_codegen.py", "symbolic_forces.py", "symbolic_start.py")


class _Printer(PythonCodePrinter):
    def _print_Float(self, e):
        return repr(float(e))


def _print(e, printer) -> str:
    return printer.doprint(e)


def derivation_input(model: Model) -> dict:
    """Everything of the description the derivation reads, as plain data (the cache key's content)."""
    def tup(v):
        return [float(x) for x in np.asarray(v, dtype=float).ravel()]
    return {
        "bodies": [[b.name, b.parent, b.joint.type, tup(b.joint.position), tup(b.joint.axis), tup(b.joint.axis2),
                    float(b.mass), tup(b.com), tup(b.inertia)] for b in model.bodies],
        "loops": [[lp.type, lp.body_a, tup(lp.point_a), lp.body_b, tup(lp.point_b), tup(lp.axis_a), tup(lp.axis_b)]
                  for lp in model.loops],
        "law_points": [[f.body_a, tup(f.point_a), f.body_b, tup(f.point_b)] for f in model.forces
                       if f.law.acts_on == "points"],
        "outputs": [[o.kind, o.body, tup(o.point)] for o in model.outputs
                    if o.kind in ("point", "point_velocity", "point_acceleration")],
    }


def cache_key(model: Model) -> str:
    h = hashlib.sha256(json.dumps(derivation_input(model), sort_keys=True).encode())
    h.update(sp.__version__.encode())
    here = Path(__file__).parent
    for m in MODULES:
        h.update((here / m).read_bytes())
    return h.hexdigest()[:20]


def cache_root(environ=os.environ) -> Path:
    from nsd_core.common.files import cache_root
    return cache_root("symbolic", environ)


def _block(name: str, args: list, exprs: list, shapes: list, printer) -> list[str]:
    """One generated function: args unpacked, the cse'd subexpressions, then each output array filled."""
    flat = [e for m in exprs for e in m]
    subs, reduced = sp.cse(flat, symbols=sp.numbered_symbols("x"), order="none")
    lines = [f"def {name}({', '.join(a for a, _ in args)}):"]
    for a, syms in args:
        for k, s in enumerate(syms):
            lines.append(f"    {s} = {a}[{k}]")
    for s, e in subs:
        lines.append(f"    {s} = {_print(e, printer)}")
    outs, at = [], 0
    for k, shape in enumerate(shapes):
        size = int(np.prod(shape)) if len(shape) else 1
        lines.append(f"    o{k} = _zeros({shape!r})")
        for j in range(size):
            e = reduced[at + j]
            if e != 0:
                idx = np.unravel_index(j, shape) if len(shape) else ()
                lines.append(f"    o{k}[{', '.join(str(int(i)) for i in idx)}] = {_print(e, printer)}")
        at += size
        outs.append(f"o{k}")
    lines.append(f"    return {', '.join(outs)}")
    return lines


def generate(d) -> str:
    """The module source of ``dynamics`` and ``points`` for a Derivation."""
    printer = _Printer({"fully_qualified_modules": False, "standard": "python3"})
    n, k = d.n, len(d.points)
    dyn = _block("dynamics", [("q", d.q), ("u", d.u), ("g", d.g)],
                 [list(d.M), list(d.F), list(d.Phi), list(d.Phi_q), list(d.gamma)],
                 [(n, n), (n,), (d.Phi.shape[0],), (d.Phi.shape[0], n), (d.Phi.shape[0],)], printer)
    zero3 = [sp.S.Zero] * 3
    pts = _block("points", [("q", d.q), ("u", d.u)],
                 [[e for r in d.R for e in r], [e for j in d.J for e in j],
                  [e for a in d.Jdu for e in (a if a is not None else zero3)]],
                 [(k, 3), (k, 3, n), (k, 3)], printer)
    head = ['"""Generated by comparisons.builders.symbolic_codegen from a description\'s derivation: do not edit."""',
            "from math import *", "from numpy import zeros as _zeros", ""]
    return "\n".join(head + dyn + ["", ""] + pts) + "\n"


def _load(path: Path):
    spec = importlib.util.spec_from_file_location(f"nsd_symbolic_{path.parent.name}", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def equations(model: Model, root: Path | None = None):
    """(module with ``dynamics`` and ``points``, meta): from the cache, else derived, generated and
    stored. meta: ``cache`` ("hit" or "miss"), ``derive_time``, ``codegen_time`` [s] of this call (0 on
    a hit), the stored ones of the first (``derived_in``, ``generated_in``), ``operations``, ``lines``,
    the named points' order."""
    from comparisons.builders.symbolic_derive import derive, operations
    folder = (root or cache_root()) / cache_key(model)
    src, meta_file = folder / "equations.py", folder / "meta.json"
    begin = time.perf_counter()
    if src.is_file() and meta_file.is_file():
        try:
            meta = json.loads(meta_file.read_text())
            mod = _load(src)
            return mod, {**meta, "cache": "hit", "derive_time": 0.0, "codegen_time": 0.0,
                         "load_time": time.perf_counter() - begin}
        except (OSError, ValueError, SyntaxError):
            pass   # a damaged entry is derived again
    d = derive(model)
    t1 = time.perf_counter()
    text = generate(d)
    t2 = time.perf_counter()
    meta = {"derived_in": t1 - begin, "generated_in": t2 - t1, "operations": operations(d),
            "lines": text.count("\n"), "n": d.n, "constraints": int(d.Phi.shape[0]),
            "points": [[b, list(p)] for b, p in d.points], "sympy": sp.__version__}
    folder.mkdir(parents=True, exist_ok=True)
    for f, content in ((src, text), (meta_file, json.dumps(meta, indent=1))):
        tmp = f.with_suffix(f".tmp{os.getpid()}")
        tmp.write_text(content)
        os.replace(tmp, f)
    mod = _load(src)
    return mod, {**meta, "cache": "miss", "derive_time": t1 - begin, "codegen_time": t2 - t1,
                 "load_time": time.perf_counter() - t2}
