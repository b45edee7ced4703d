"""Named numeric columns of a CSV file with units in the header (private): the one style
``name [unit]`` that empact writes, the units it converts to SI when it reads a column
(`HEADER_UNITS`) and the reader of measured records (`empact.identification.records`, which
documents the format and re-exports these names), of the measured loss map
(`empact.variator.losses.load_loss_map`) and of speed traces (`empact.cycles`), in a module
without the identification's dependencies (a parameter file may name a loss map).

A header cell may carry a unit in brackets after the name (``time [s]``); the unit of every
column that is read is converted to SI (`HEADER_UNITS`), a unit empact does not know is
refused, never ignored.
"""
from __future__ import annotations

import csv
import re
from pathlib import Path
from typing import Mapping, Sequence

import numpy as np

from ._io import read_input_text
from .errors import DataError, ParameterError

__all__ = ["load_records", "column_name", "header_cell", "HEADER_UNITS", "column_unit",
           "si_factor"]

#: units a CSV header may give a column that is read -> (factor to SI, quantity); a column
#: without a unit is taken as SI
HEADER_UNITS: dict[str, tuple[float, str]] = {
    "s": (1.0, "time"), "ms": (1e-3, "time"), "us": (1e-6, "time"), "\u00b5s": (1e-6, "time"),
    "min": (60.0, "time"),
    "N m": (1.0, "torque"), "Nm": (1.0, "torque"), "N*m": (1.0, "torque"),
    "N\u00b7m": (1.0, "torque"),
    "rad": (1.0, "angle"), "rad/s": (1.0, "angular speed"),
    "rpm": (2.0 * np.pi / 60.0, "angular speed"), "1/min": (2.0 * np.pi / 60.0, "angular speed"),
    "-": (1.0, "dimensionless"), "1": (1.0, "dimensionless"), "N": (1.0, "force"),
    "m": (1.0, "length"), "m/s": (1.0, "speed"), "km/h": (1.0 / 3.6, "speed"),
    "mph": (0.44704, "speed"), "W": (1.0, "power"), "J": (1.0, "energy"),
    "1/s": (1.0, "rate"), "A": (1.0, "current"), "V": (1.0, "voltage"),
}


def header_cell(name: str, unit: str) -> str:
    """The one style of a CSV header cell that empact writes: ``"theta_mp [rad]"``
    (``"nu [-]"`` for a dimensionless quantity; `column_name` reads it back).

    Parameters
    ----------
    name : str
        The column (signal) name, e.g. ``"theta_mp"``.
    unit : str
        Its unit, e.g. ``"rad"``; ``"-"`` for a dimensionless quantity.

    Returns
    -------
    str
        ``"<name> [<unit>]"``.
    """
    return f"{name} [{unit}]"


def column_name(header: str) -> str:
    """A header cell without its unit: ``"theta_mp [rad]"`` -> ``"theta_mp"``.

    Parameters
    ----------
    header : str
        A CSV header cell, with or without a trailing unit in brackets.

    Returns
    -------
    str
        The name, stripped of surrounding white space and of the bracketed unit.
    """
    return re.sub(r"\s*\[[^\]]*\]\s*$", "", header.strip())


def column_unit(header: str) -> str | None:
    """The bracketed unit of a header cell (``"time [ms]"`` -> ``"ms"``), None without one.

    Parameters
    ----------
    header : str
        A CSV header cell.

    Returns
    -------
    str or None
        The unit, white space collapsed to single spaces.
    """
    m = re.search(r"\[([^\]]*)\]\s*$", header.strip())
    return " ".join(m.group(1).split()) if m else None


def si_factor(where: str | Path, name: str, unit: str | None, quantity: str | None,
              error: type[ParameterError] = DataError) -> float:
    """The factor from a column's header unit to SI; one line for a unit empact does not
    convert or one of another quantity than the column must have.

    Parameters
    ----------
    where : str or Path
        The file, for the message.
    name : str
        The column's name, for the message.
    unit : str or None
        Its header unit (`column_unit`); None: SI.
    quantity : str or None
        The quantity the column must be (``"time"``, ``"speed"``; the second entry of
        `HEADER_UNITS`), None for any.
    error : type
        The error raised (a `ParameterError`; default `DataError`).

    Returns
    -------
    float
        Multiply the column by it for SI [SI unit per header unit].

    Raises
    ------
    ParameterError
        (`error`) For a unit not in `HEADER_UNITS`, or one of another quantity than
        `quantity`: one line naming `where`, the column and the units it takes.
    """
    if unit is None:
        return 1.0
    if unit not in HEADER_UNITS:
        known = ", ".join(u for u, (_, k) in HEADER_UNITS.items()
                          if u.isascii() and quantity in (None, k))
        raise error(f"{where}: column {name!r} has unit [{unit}], which empact does not "
                    f"convert; give one of {known}" + (" (or no unit: SI)" if quantity
                                                       in (None, "time") else ""))
    factor, kind = HEADER_UNITS[unit]
    if quantity is not None and kind != quantity:
        units = ", ".join(u for u, (_, k) in HEADER_UNITS.items() if k == quantity
                          and u.isascii())
        raise error(f"{where}: column {name!r} has unit [{unit}], a unit of {kind}; the "
                    f"column is a {quantity} ({units})")
    return factor


def load_records(path: str | Path, columns: Sequence[str], *, min_rows: int = 16,
                 quantities: Mapping[str, str] | None = None) -> dict[str, np.ndarray]:
    """Read the named columns of a CSV file as float arrays, shape (n_t,) each.

    Parameters
    ----------
    path : str or Path
        A UTF-8 CSV file: optional ``#`` comment lines, a header row of column names (units
        in brackets allowed), one row per sample.
    columns : sequence of str
        Names of the columns to read (without units).
    min_rows : int
        Fewest data rows accepted.
    quantities : mapping str -> str, optional
        The quantity a column must be (``{"time": "time"}``): a header unit of another
        quantity is refused.

    Returns
    -------
    dict str -> ndarray
        Each of `columns` as a float array, shape (n_t,), in SI (a header unit of
        `HEADER_UNITS` converted; no unit: SI).

    Raises
    ------
    DataError
        One line naming the file, and the column, row and value that are wrong: a missing file
        or column, a column named twice, a non-numeric or non-finite entry, fewer than
        `min_rows` rows, a binary or non-UTF-8 file, a header unit empact does not
        convert (or of another quantity than `quantities` names).
    """
    path = Path(path)
    text = read_input_text(path, "data", error=DataError)
    lines = [ln for ln in text.splitlines() if ln.strip()]
    while lines and lines[0].lstrip().startswith("#"):
        lines.pop(0)
    reader = csv.reader(lines)
    cells = next(reader, [])
    header = [column_name(h) for h in cells]
    units = [column_unit(h) for h in cells]
    rows = [r for r in reader if r and any(c.strip() for c in r)]
    if not header:
        raise DataError(f"{path}: empty file (expected a header row of column names)")
    # a name given to two columns is ambiguous whichever of them is asked for
    for name in dict.fromkeys(header):
        where = [k + 1 for k, h in enumerate(header) if h == name]
        if len(where) > 1:
            raise DataError(f"{path}: column {name!r} appears {len(where)} times (columns "
                            f"{', '.join(map(str, where))}); name each column once")
    out: dict[str, np.ndarray] = {}
    for name in columns:
        if name not in header:
            raise DataError(f"{path}: no column {name!r} (columns: {', '.join(header)})")
        j = header.index(name)
        factor = si_factor(path, name, units[j], (quantities or {}).get(name))
        values = np.empty(len(rows))
        for i, row in enumerate(rows):
            cell = row[j].strip() if j < len(row) else ""
            try:
                values[i] = float(cell)
            except ValueError:
                raise DataError(f"{path}: column {name!r}, data row {i + 1}: {cell!r} is not a "
                                "number") from None
            if not np.isfinite(values[i]):
                raise DataError(f"{path}: column {name!r}, data row {i + 1}: {cell!r} is not "
                                "finite")
        out[name] = values * factor if factor != 1.0 else values
    if len(rows) < min_rows:
        raise DataError(f"{path}: {len(rows)} data rows; at least {min_rows} are needed")
    return out
