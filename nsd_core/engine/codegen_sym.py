"""The code generator's algebra: scalar values that are either structural constants or names.

A value is a Python float (a structural constant: an exact 0 or 1 of the model, or one folded from
them) or a string (a Python expression of the generated source). The operations fold only what is
exact in floating point (x * 0 = 0, x * 1 = x, x + 0 = x, 0 - x = -x), and keep the order of the
generic kernels' sums, so the generated evaluation does the same arithmetic as the generic one
minus the terms that are structurally zero. ``Code`` collects the lines; ``Code.let`` gives a
non-trivial expression a name (LLVM removes the names nothing reads).
"""
from __future__ import annotations

import re

_NAME = re.compile(r"^[A-Za-z_][A-Za-z_0-9]*$")


def const(v) -> bool:
    return isinstance(v, float)


def mul(a, b):
    if const(a) and const(b):
        return a * b
    if (const(a) and a == 0.0) or (const(b) and b == 0.0):
        return 0.0
    if const(a) and a == 1.0:
        return b
    if const(b) and b == 1.0:
        return a
    if const(a) and a == -1.0:
        return neg(b)
    if const(b) and b == -1.0:
        return neg(a)
    return f"({a} * {b})"


def add(a, b):
    if const(a) and const(b):
        return a + b
    if const(a) and a == 0.0:
        return b
    if const(b) and b == 0.0:
        return a
    return f"({a} + {b})"


def sub(a, b):
    if const(a) and const(b):
        return a - b
    if const(b) and b == 0.0:
        return a
    if const(a) and a == 0.0:
        return neg(b)
    return f"({a} - {b})"


def neg(a):
    if const(a):
        return -a
    return f"(-{a})"


def div(a, b):
    if const(b) and b == 1.0:
        return a
    if const(a) and a == 0.0:
        return 0.0
    return f"({a} / {b})"


def dot(terms):
    """sum of a * b over the pairs, from 0.0, left to right (the generic kernels' acc += a * b)."""
    acc = 0.0
    for a, b in terms:
        acc = add(acc, mul(a, b))
    return acc


def acc_from(start, terms):
    """start + a * b over the pairs, left to right (acc = start; acc += a * b)."""
    acc = start
    for a, b in terms:
        acc = add(acc, mul(a, b))
    return acc


def cross(a, b):
    """The generic kernels' cross3: out_0 = a1 b2 - a2 b1, ..."""
    return [sub(mul(a[1], b[2]), mul(a[2], b[1])), sub(mul(a[2], b[0]), mul(a[0], b[2])),
            sub(mul(a[0], b[1]), mul(a[1], b[0]))]


class Code:
    """Lines of the generated function body, with indentation and fresh temporary names."""

    def __init__(self, counter=None, indent: int = 1):
        self.lines: list[str] = []
        self.ind = indent
        self.counter = counter if counter is not None else [0]

    def emit(self, *lines: str) -> None:
        self.lines.extend("    " * self.ind + line for line in lines)

    def let(self, v, prefix: str = "t"):
        """v itself when a constant or a plain name, else a fresh name assigned to it."""
        if const(v) or _NAME.match(v):
            return v
        self.counter[0] += 1
        name = f"{prefix}{self.counter[0]}"
        self.emit(f"{name} = {v}")
        return name

    def lets(self, vs):
        return [self.let(v) for v in vs]

    def bind(self, v, name: str):
        """Assign v to a fixed name (constants stay constants): the same name in every copy of a block."""
        if const(v):
            return v
        self.emit(f"{name} = {v}")
        return name

    def indent(self):
        code = self

        class _Block:
            def __enter__(self):
                code.ind += 1

            def __exit__(self, *exc):
                code.ind -= 1
        return _Block()

    def text(self) -> str:
        return "\n".join(self.lines)


def lu_factor(code: Code, a: list[list], tag: str, fail: str) -> tuple[list[list[str]], list[str]]:
    """Unrolled LU with partial pivoting on locals, the generic lu_factor step for step (LAPACK's
    getrf rule: the first largest pivot; whole rows swapped). ``a``: n x n values; emits ``fail``
    (a statement) where a pivot is exactly zero. Returns the factor's names and the pivot names."""
    n = len(a)
    names = [[f"{tag}{i}_{j}" for j in range(n)] for i in range(n)]
    for i in range(n):
        for j in range(n):
            code.emit(f"{names[i][j]} = {a[i][j]!s}")
    piv = [f"{tag}p{k}" for k in range(n)]
    for k in range(n):
        code.emit(f"{piv[k]} = {k}")
        code.emit(f"big = abs({names[k][k]})")
        for i in range(k + 1, n):
            code.emit(f"if abs({names[i][k]}) > big:")
            with code.indent():
                code.emit(f"{piv[k]} = {i}")
                code.emit(f"big = abs({names[i][k]})")
        code.emit("if big == 0.0:")
        with code.indent():
            code.emit(fail)
        for i in range(k + 1, n):
            code.emit(f"if {piv[k]} == {i}:")
            with code.indent():
                left = ", ".join(names[k] + names[i])
                right = ", ".join(names[i] + names[k])
                code.emit(f"{left} = {right}")
        for i in range(k + 1, n):
            code.emit(f"{names[i][k]} = {names[i][k]} / {names[k][k]}")
            for j in range(k + 1, n):
                code.emit(f"{names[i][j]} = {names[i][j]} - {names[i][k]} * {names[k][j]}")
    return names, piv


def lu_solve(code: Code, lu: list[list[str]], piv: list[str], b: list, tag: str) -> list[str]:
    """The generic lu_solve on locals: the row swaps in order, forward (unit L), backward."""
    n = len(lu)
    x = [f"{tag}{i}" for i in range(n)]
    for i in range(n):
        code.emit(f"{x[i]} = {b[i]!s}")
    for k in range(n):
        for i in range(k + 1, n):
            code.emit(f"if {piv[k]} == {i}:")
            with code.indent():
                code.emit(f"{x[k]}, {x[i]} = {x[i]}, {x[k]}")
    for i in range(n):
        for j in range(i):
            code.emit(f"{x[i]} = {x[i]} - {lu[i][j]} * {x[j]}")
    for i in range(n - 1, -1, -1):
        for j in range(i + 1, n):
            code.emit(f"{x[i]} = {x[i]} - {lu[i][j]} * {x[j]}")
        code.emit(f"{x[i]} = {x[i]} / {lu[i][i]}")
    return x
