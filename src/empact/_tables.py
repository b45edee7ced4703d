"""Reading tabulated curves ``y(x)`` at several ratios from CSV or TOML (one reader for the
traction tables and the thrust-ratio maps).

CSV: a header naming exactly the columns ``r_g``, `x`, `y` (any order; a UTF-8 BOM and ``#``
comment lines are allowed), one sample per row; rows with the same ``r_g`` form one curve, in
file order.  TOML: ``[[curve]]`` tables, each with ``r_g = <float>``, ``x = [...]``,
``y = [...]``.  Every problem is a one-line `ParameterError` naming the file, row and value.
"""
from __future__ import annotations

import csv
import os
import tomllib
from pathlib import Path

from .errors import ParameterError

__all__ = ["read_curves"]

Curves = dict[float, tuple[list[float], list[float]]]


def read_curves(path: str | os.PathLike[str], what: str, x: str, y: str) -> Curves:
    """The curves of a ``.csv`` or ``.toml`` table: ``{r_g: (x values, y values)}``.

    `what` names the table in messages (``"traction table"``); `x`, `y` are its columns.
    """
    p = Path(path)
    if not p.is_file():
        raise ParameterError(f"{p}: no such {what}")
    suffix = p.suffix.lower()
    if suffix == ".csv":
        return _read_csv(p, what, x, y)
    if suffix == ".toml":
        return _read_toml(p, x, y)
    raise ParameterError(f"{p}: {what} must be .csv or .toml, not {suffix or 'no suffix'!r}")


def _number(text: str, where: str) -> float:
    try:
        return float(text)
    except ValueError:
        raise ParameterError(f"{where}: {text!r} is not a number") from None


def _read_csv(p: Path, what: str, x: str, y: str) -> Curves:
    try:
        with open(p, newline="", encoding="utf-8-sig") as fh:
            rows = [row for row in csv.reader(fh) if row and not row[0].lstrip().startswith("#")]
    except UnicodeDecodeError:
        raise ParameterError(f"{p}: not a UTF-8 text file") from None
    if not rows:
        raise ParameterError(f"{p}: empty {what}")
    header = [h.strip() for h in rows[0]]
    names = ("r_g", x, y)
    if sorted(header) != sorted(names):
        raise ParameterError(f"{p}: header {','.join(header)!r} must name exactly the columns "
                             f"{', '.join(names)}")
    col = {name: header.index(name) for name in names}
    curves: Curves = {}
    for line, row in enumerate(rows[1:], start=2):
        if len(row) != 3:
            raise ParameterError(f"{p}, row {line}: {len(row)} fields, expected 3 "
                                 f"({', '.join(names)})")
        where = f"{p}, row {line}"
        r = _number(row[col["r_g"]], where)
        xs, ys = curves.setdefault(r, ([], []))
        xs.append(_number(row[col[x]], where))
        ys.append(_number(row[col[y]], where))
    if not curves:
        raise ParameterError(f"{p}: no data rows")
    return curves


def _read_toml(p: Path, x: str, y: str) -> Curves:
    try:
        data = tomllib.loads(p.read_text(encoding="utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise ParameterError(f"{p}: not valid TOML ({exc})") from None
    if set(data) != {"curve"} or not isinstance(data["curve"], list) or not data["curve"]:
        raise ParameterError(f"{p}: expected only [[curve]] tables with r_g, {x}, {y}")
    curves: Curves = {}
    for i, c in enumerate(data["curve"]):
        keys = set(c) if isinstance(c, dict) else set()
        if keys != {"r_g", x, y}:
            raise ParameterError(f"{p}: curve {i + 1} has keys {sorted(keys)}, expected r_g, "
                                 f"{x}, {y}")
        if isinstance(c["r_g"], bool) or not isinstance(c["r_g"], (int, float)):
            raise ParameterError(f"{p}: curve {i + 1}: r_g = {c['r_g']!r} must be a number")
        r = float(c["r_g"])
        if r in curves:
            raise ParameterError(f"{p}: curve {i + 1}: ratio r_g = {r:g} given twice")
        if not isinstance(c[x], list) or not isinstance(c[y], list):
            raise ParameterError(f"{p}: curve {i + 1}: {x} and {y} must be arrays")
        curves[r] = (c[x], c[y])
    return curves
