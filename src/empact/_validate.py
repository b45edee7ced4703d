"""Range and choice checks with the project's one message format (private).

Every check raises `~empact.errors.ParameterError` with one line::

    <where>: <name> = <value>: allowed range is [lo, hi] [unit]

where ``<where>`` (a file, a table) is optional.  Values are printed as a user wrote them
(``0.499``, not ``np.float64(0.499)``).
"""
from __future__ import annotations

import math
from typing import Any, Iterable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .errors import ParameterError

__all__ = ["fmt", "interval", "check_number", "check_values", "check_int", "check_choice",
           "check_bool"]


def fmt(value: Any) -> str:
    """A value as a user would write it: numbers with ``:g`` (ints whole), others ``repr``."""
    if isinstance(value, (bool, np.bool_)):
        return str(bool(value)).lower()
    if isinstance(value, (int, np.integer)):
        text = str(int(value))
        return text if len(text) <= 20 else f"{text[:8]}...({len(text)} digits)"
    if isinstance(value, (float, np.floating)):
        return f"{float(value):g}"
    if isinstance(value, str):
        return repr(value)
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def interval(lo: float = -math.inf, hi: float = math.inf, *, lo_open: bool = False,
             hi_open: bool = False) -> str:
    """``[lo, hi]`` with open ends as ``(`` / ``)``; infinite ends are always open."""
    left = "(" if lo_open or math.isinf(lo) else "["
    right = ")" if hi_open or math.isinf(hi) else "]"
    return f"{left}{lo:g}, {hi:g}{right}"


def _prefix(name: str, where: str) -> str:
    return f"{where}: {name}" if where else name


def _in(value: float, lo: float, hi: float, lo_open: bool, hi_open: bool) -> bool:
    above = value > lo if lo_open else value >= lo
    below = value < hi if hi_open else value <= hi
    return above and below


def check_number(name: str, value: Any, lo: float = -math.inf, hi: float = math.inf, *,
                 lo_open: bool = False, hi_open: bool = False, unit: str = "",
                 where: str = "", note: str = "") -> float:
    """`value` as a finite float inside the interval, else a one-line `ParameterError`.

    Parameters
    ----------
    name : the field or option as the user knows it (``"actuation.k_w"``, ``"--fmax"``)
    value : the value given (a bool, a string or a non-finite number is refused)
    lo, hi : interval ends; `lo_open`, `hi_open` make them exclusive
    unit : unit for the message (``"N/m"``)
    where : the file or table the value came from (prefixed to the message)
    note : why the range is what it is (appended in parentheses)
    """
    rng = interval(lo, hi, lo_open=lo_open, hi_open=hi_open)
    tail = (f" [{unit}]" if unit else "") + (f" ({note})" if note else "")
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer,
                                                                      np.floating)):
        raise ParameterError(f"{_prefix(name, where)} = {fmt(value)}: must be a number in "
                             f"{rng}{tail}")
    try:
        x = float(value)
    except OverflowError:
        raise ParameterError(f"{_prefix(name, where)} = {fmt(value)}: too large for a number; "
                             f"allowed range is {rng}{tail}") from None
    if not math.isfinite(x):
        raise ParameterError(f"{_prefix(name, where)} = {fmt(x)}: must be a finite number in "
                             f"{rng}{tail}")
    if not _in(x, lo, hi, lo_open, hi_open):
        raise ParameterError(f"{_prefix(name, where)} = {fmt(x)}: allowed range is {rng}{tail}")
    return x


def check_values(name: str, values: ArrayLike, lo: float = -math.inf, hi: float = math.inf, *,
                 lo_open: bool = False, hi_open: bool = False, unit: str = "",
                 where: str = "", note: str = "") -> NDArray[np.float64]:
    """Array version of `check_number`: the message names the first bad entry."""
    try:
        a = np.asarray(values, dtype=float)
    except (TypeError, ValueError, OverflowError):
        raise ParameterError(f"{_prefix(name, where)} = {fmt(values)}: must be numbers in "
                             f"{interval(lo, hi, lo_open=lo_open, hi_open=hi_open)}") from None
    above = a > lo if lo_open else a >= lo
    below = a < hi if hi_open else a <= hi
    bad = ~(np.isfinite(a) & above & below)
    if np.any(bad):
        check_number(name, float(a[bad].flat[0]), lo, hi, lo_open=lo_open, hi_open=hi_open,
                     unit=unit, where=where, note=note)
    return a


def check_int(name: str, value: Any, lo: int, hi: int | None = None, *, where: str = "") -> int:
    """`value` as an int in ``[lo, hi]`` (a whole float such as ``1e3`` is accepted)."""
    upper = math.inf if hi is None else hi
    if isinstance(value, (bool, np.bool_)):
        ok = False
    elif isinstance(value, (int, np.integer)):
        ok = True
    elif isinstance(value, (float, np.floating)):
        ok = math.isfinite(value) and float(value).is_integer()
    else:
        ok = False
    if not ok or not lo <= value <= upper:
        rng = f"[{lo}, {hi}]" if hi is not None else f"[{lo}, inf)"
        raise ParameterError(f"{_prefix(name, where)} = {fmt(value)}: must be a whole number "
                             f"in {rng}")
    return int(value)


def check_choice(name: str, value: Any, allowed: Iterable[str], *, where: str = "") -> str:
    """`value` if it is one of `allowed`, else a one-line `ParameterError` listing them."""
    allowed = tuple(allowed)
    if not isinstance(value, str) or value not in allowed:
        raise ParameterError(f"{_prefix(name, where)} = {fmt(value)}: must be one of "
                             f"{', '.join(allowed)}")
    return value


def check_bool(name: str, value: Any, *, where: str = "") -> bool:
    """`value` if it is a bool (TOML ``true`` / ``false``)."""
    if not isinstance(value, (bool, np.bool_)):
        raise ParameterError(f"{_prefix(name, where)} = {fmt(value)}: must be true or false")
    return bool(value)
