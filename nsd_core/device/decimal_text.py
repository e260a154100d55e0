"""A table of numbers as the text Python's ``"%.10g" % value`` gives for each, and the values that text
reads back as, both compiled: what a results CSV holds (nsd_core.device.results.write_columns).

``table_text(data)`` returns the CSV body (rows joined by newlines, values by commas) and the
numbers ``float(text)`` gives for each entry, bit for bit what Python's formatter and a correctly
rounding reader (``float``, ``numpy.loadtxt``) give, for a fraction of their CPU (the gate's main
process writes ~11 million numbers a run beside its workers: benchmarks/bench_csv_text.py).

How it stays exact (docs/performance.md, "Writing the CSVs"): a value |v| is scaled to ten
digits, s = |v| * 10**(9 - k), by one product with the correctly rounded double of the power of
ten, so s is within 2.2e-6 of the exact |v| * 10**(9 - k) (two roundings of 2**-53 each, s < 1e10);
the ten digits N = round(s) are therefore the correctly rounded ones unless the exact value lies
within that distance of a half, and every value whose computed s lies within 1e-4 of a half (or
whose magnitude lies outside 1e-290..1e290) is handed to Python's own formatter instead.
The value read back, N * 10**(k - 9), is one correctly rounded product or quotient of two exact
doubles where |k - 9| <= 22 (Clinger's fast path), and Python's ``float`` of the text otherwise.
tests/test_decimal_text.py holds both to Python's formatter and to numpy.loadtxt on values chosen to
sit on every boundary (halves, powers of ten, the fixed/scientific switch, subnormals, signed zeros).
"""
from __future__ import annotations

import numpy as np
from numba import njit, types

from nsd_core.engine.compile_once import compile_once, unit

DIGITS = 10                # "%.10g": ten significant digits
_EXACT_POWERS = 22         # 10**k is a double exactly for 0 <= k <= 22
_LIMIT = 290               # decimal exponents handled here; beyond, Python's formatter
_HALF_WINDOW = 1e-4        # a scaled value this close to a half is left to Python (the error is <= 2.2e-6)
# how an entry is written: FIXED (its digits and exponent), ZERO, NAN, INF; PYTHON: Python's formatter decides
FIXED, PYTHON, ZERO, NAN, INF = 0, 1, 2, 3, 4
CHUNK_ROWS = 1 << 14        # rows formatted at a time
_SPAN = _LIMIT + DIGITS     # the powers a scaling or a read-back uses: 10**m for |m| <= 300
POWERS = np.array([float(f"1e{m}") for m in range(-_SPAN, _SPAN + 1)])   # correctly rounded 10**m


@njit(cache=True)
def _decimal_parts(values, powers):
    """Per value: the ten digits N (1e9 <= N < 1e10), the decimal exponent k (v = +-N * 10**(k - 9)
    rounded) and how it is written (FIXED ... INF; PYTHON where it is not decided here)."""
    n = values.size
    mant = np.zeros(n, np.int64)
    expo = np.zeros(n, np.int64)
    kind = np.zeros(n, np.int64)
    mid = (powers.size - 1) // 2
    for i in range(n):
        v = values[i]
        if v != v:
            kind[i] = NAN
            continue
        a = abs(v)
        if a == 0.0:
            kind[i] = ZERO
            continue
        if a == np.inf:
            kind[i] = INF
            continue
        k = int(np.floor(np.log10(a)))
        if k < -_LIMIT or k > _LIMIT:
            kind[i] = PYTHON
            continue
        s = a * powers[mid + 9 - k]
        if s < 1e9:      # log10 rounded up across a power of ten
            k -= 1
            s = a * powers[mid + 9 - k]
        elif s >= 1e10:
            k += 1
            s = a * powers[mid + 9 - k]
        whole = np.floor(s)
        if abs(s - whole - 0.5) < _HALF_WINDOW or s < 1e9 or s >= 1e10:
            kind[i] = PYTHON
            continue
        m = np.int64(whole) + (1 if s - whole > 0.5 else 0)
        if m == 10_000_000_000:   # rounded up to the next power of ten
            m = 1_000_000_000
            k += 1
        mant[i] = m
        expo[i] = k
    return mant, expo, kind


@njit(cache=True)
def _values_read(mant, expo, powers):
    """N * 10**(k - 9) correctly rounded where one exact operation gives it (NaN elsewhere: Python's)."""
    mid = (powers.size - 1) // 2
    out = np.empty(mant.size)
    for i in range(mant.size):
        j = expo[i] - 9
        if 0 <= j <= _EXACT_POWERS:
            out[i] = mant[i] * powers[mid + j]
        elif -_EXACT_POWERS <= j < 0:
            out[i] = mant[i] / powers[mid - j]
        else:
            out[i] = np.nan
    return out


@njit(cache=True)
def _render(mant, expo, kind, negative, columns):
    """The body's bytes: each row's values "%.10g" as Python writes them, joined by ',' and ending '\\n'."""
    out = np.empty(mant.size * 18 + mant.size // max(columns, 1) + 1, np.uint8)
    digits = np.empty(DIGITS, np.uint8)
    p = 0
    for i in range(mant.size):
        if negative[i] and kind[i] != NAN:
            out[p] = 45   # '-'
            p += 1
        c = kind[i]
        if c == ZERO:
            out[p] = 48
            p += 1
        elif c == NAN or c == INF:
            word = (110, 97, 110) if c == NAN else (105, 110, 102)
            for b in word:
                out[p] = b
                p += 1
        else:
            m, x = mant[i], expo[i]
            for d in range(DIGITS - 1, -1, -1):
                digits[d] = 48 + m % 10
                m //= 10
            last = DIGITS - 1
            while last > 0 and digits[last] == 48:
                last -= 1
            if -4 <= x < DIGITS:   # fixed point: the point after digit x
                if x < 0:
                    out[p] = 48
                    out[p + 1] = 46
                    p += 2
                    for _ in range(-x - 1):
                        out[p] = 48
                        p += 1
                    for d in range(last + 1):
                        out[p] = digits[d]
                        p += 1
                else:
                    for d in range(max(last, x) + 1):
                        if d == x + 1:
                            out[p] = 46
                            p += 1
                        out[p] = digits[d]
                        p += 1
            else:                  # d.ddde+XX
                out[p] = digits[0]
                p += 1
                if last > 0:
                    out[p] = 46
                    p += 1
                    for d in range(1, last + 1):
                        out[p] = digits[d]
                        p += 1
                out[p] = 101
                out[p + 1] = 45 if x < 0 else 43
                p += 2
                e = abs(x)
                width = 3 if e >= 100 else 2
                for w in range(width - 1, -1, -1):
                    out[p + w] = 48 + e % 10
                    e //= 10
                p += width
        out[p] = 10 if (i + 1) % columns == 0 else 44   # '\n' after a row's last value, else ','
        p += 1
    return out[:p]


def _python_parts(v: float) -> tuple[int, int]:
    """(N, k) of |v| from Python's own "%.9e" (the rounding "%.10g" makes)."""
    s = "%.9e" % abs(v)
    return int(s[0] + s[2:11]), int(s[12:])


def table_text(data: np.ndarray) -> tuple[bytes, np.ndarray]:
    """(the body's bytes, the values as read back) of a 2-D float table, row by row: each entry the
    text of ``"%.10g" % v``, and ``float`` of that text, in ``data``'s shape; ``CHUNK_ROWS`` rows at a
    time (the working arrays stay small whatever the table's length)."""
    data = np.asarray(data, dtype=float)
    table = data.reshape(-1, 1) if data.ndim == 1 else data
    read = np.empty(table.shape)
    compile_once(TEXT_UNIT)
    parts = []
    for a in range(0, table.shape[0], CHUNK_ROWS):
        body, values = _block_text(np.array(table[a:a + CHUNK_ROWS], order="C").ravel(), table.shape[1])
        parts.append(body)
        read[a:a + CHUNK_ROWS] = values.reshape(-1, table.shape[1])
    return b"".join(parts), read.reshape(data.shape)


def _block_text(flat: np.ndarray, columns: int) -> tuple[bytes, np.ndarray]:
    """``table_text`` of a block of whole rows, flattened (a writable copy: the one signature compiled)."""
    mant, expo, kind = _decimal_parts(flat, POWERS)
    for i in np.flatnonzero(kind == PYTHON):   # finite and non-zero: the others are decided above
        mant[i], expo[i] = _python_parts(float(flat[i]))
        kind[i] = FIXED
    body = _render(mant, expo, kind, np.signbit(flat), columns).tobytes()
    read = _values_read(mant, expo, POWERS)
    read[kind == ZERO] = 0.0
    read[kind == INF] = np.inf
    read[kind == NAN] = np.nan
    for i in np.flatnonzero(np.isnan(read) & (kind != NAN)):   # the text's decimal, correctly rounded
        read[i] = float(f"{mant[i]}e{expo[i] - 9}")
    return body, np.where(np.signbit(flat) & (kind != NAN), -read, read)


_F = types.Array(types.float64, 1, "C")
_I = types.Array(types.int64, 1, "C")
_B = types.Array(types.boolean, 1, "C")
TEXT_UNIT = unit("decimal_text", ((_decimal_parts, types.UniTuple(_I, 3)(_F, _F)),
                                  (_values_read, _F(_I, _I, _F)),
                                  (_render, types.Array(types.uint8, 1, "C")(_I, _I, _I, _B, types.int64))),
                 shared=False)
