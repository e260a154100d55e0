"""The field checks of a model description's reader (nsd_core.model.load): a TOML file read within its
limits, and each field's type, range and name checked, every mistake one ``ModelError`` line that
names the element, the field, the value and what is allowed."""
from __future__ import annotations

import math
import tomllib

import numpy as np

from nsd_core.common.errors import ParameterError
from nsd_core.model.description import GROUND
from nsd_core.model.errors import ModelError


def read_toml(path, flag: str) -> dict:
    """A TOML file as a dict; unreadable or not TOML is one ModelError line naming ``flag``."""
    from nsd_core.common.files import MAX_DESCRIPTION_BYTES, printable, read_input_text
    try:   # a regular file only, at most MAX_DESCRIPTION_BYTES, read within a time bound
        text = read_input_text(path, flag, MAX_DESCRIPTION_BYTES, "UTF-8 TOML")
    except ModelError:
        raise
    except ParameterError as e:
        raise ModelError(str(e)) from None
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise ModelError(f"{flag} {printable(path)}: not valid TOML ({e})") from None
    except RecursionError:
        raise ModelError(f"{flag} {printable(path)}: not valid TOML (nested too deeply)") from None



def _fields(where: str, table, allowed: set, required: tuple = ()) -> dict:
    if not isinstance(table, dict):
        raise ModelError(f"{where} = {table!r}: must be a table")
    for k in table:
        if k not in allowed:
            raise ModelError(f"{where}.{k}: unknown field; allowed: {', '.join(sorted(allowed))}")
    for k in required:
        if k not in table:
            raise ModelError(f"{where}.{k}: missing")
    return table



def number(where: str, v, low=-math.inf, high=math.inf, strict_low=False) -> float:
    """``v`` as a float when it is a finite number in range, else ModelError naming ``where``."""
    ok = not isinstance(v, bool) and isinstance(v, (int, float)) and math.isfinite(v)
    if ok and (v > low if strict_low else v >= low) and v <= high:
        return float(v)
    rng = f"> {low:g}" if strict_low else (f">= {low:g}" if low > -math.inf else "finite")
    raise ModelError(f"{where} = {v!r}: must be a number {rng}" + (f" and <= {high:g}" if high < math.inf else ""))



def _vec(where: str, v, nonzero=False) -> tuple:
    if not isinstance(v, list) or len(v) != 3:
        raise ModelError(f"{where} = {v!r}: must be a list of 3 numbers")
    out = tuple(number(where, x) for x in v)
    if nonzero and math.hypot(*out) < 1e-12:
        raise ModelError(f"{where} = {v!r}: must be a non-zero vector")
    return out



def _name(where: str, v) -> str:
    if not isinstance(v, str) or not v or not all(c.isalnum() or c in "_-." for c in v):
        raise ModelError(f"{where} = {v!r}: must be a name of letters, digits, '_', '-' or '.'")
    return v



def _inertia(where: str, v) -> np.ndarray:
    if not isinstance(v, list) or len(v) not in (3, 6):
        raise ModelError(f"{where} = {v!r}: must be 3 principal values [Ixx, Iyy, Izz] or 6 "
                         "[Ixx, Iyy, Izz, Ixy, Ixz, Iyz] [kg m^2]")
    x = [number(where, e) for e in v]
    J = np.diag(x[:3])
    if len(x) == 6:
        J[0, 1] = J[1, 0] = x[3]
        J[0, 2] = J[2, 0] = x[4]
        J[1, 2] = J[2, 1] = x[5]
    ev = np.linalg.eigvalsh(J)
    tol = 1e-12 * max(1.0, float(np.max(np.abs(ev))))
    if ev[0] < -tol or any(ev[i] + ev[j] < ev[k] - tol for i, j, k in ((0, 1, 2), (1, 2, 0), (0, 2, 1))):
        raise ModelError(f"{where} = {v!r}: not a physical inertia (principal values must be >= 0 and "
                         "obey the triangle inequality)")
    return J



def _list(where: str, v) -> list:
    if not isinstance(v, list):
        raise ModelError(f"[[{where}]] = {v!r}: must be an array of tables")
    return v



def _unique(where: str, items) -> None:
    seen = set()
    for it in items:
        if it.name in seen:
            raise ModelError(f"{where}.{it.name}: the name is used twice")
        seen.add(it.name)



def _is_name(v) -> bool:
    return isinstance(v, str) and bool(v) and all(c.isalnum() or c in "_-." for c in v) and v != GROUND



def _isnumber(v) -> bool:
    return not isinstance(v, bool) and isinstance(v, (int, float)) and math.isfinite(v)



def _body_ref(where: str, v, names) -> str:
    if v != GROUND and v not in names:
        raise ModelError(f"{where} = {v!r}: unknown body; allowed: ground, {', '.join(sorted(names))}")
    return v



def _where(kind: str, i: int, t) -> str:
    """How a message names the i-th table of ``kind``: by its name where it has a usable one."""
    given = t.get("name") if isinstance(t, dict) else None
    return f"{kind}.{given}" if _is_name(given) else f"{kind}[{i}]"
