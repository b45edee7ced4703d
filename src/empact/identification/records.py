"""Measured records from CSV: named numeric columns with a header row.

A record file has one header line of column names and one row per sample, for example::

    time,T_ms,theta_ms,nu
    0.000,0.12,0.0,0.010
    0.001,0.10,1.3e-4,0.011

Lines before the header that start with ``#`` are comments; a unit in brackets after a name
(``time [s]``) is not part of the name, so ``empact simulate``'s CSV reads as well as ``empact
rig``'s.  The unit of every column that is read is converted to SI (`HEADER_UNITS`: ``[ms]``,
``[us]``, ``[min]`` to s, ``[rpm]`` to rad/s, ...); a unit empact does not know is refused,
never ignored.  A UTF-8 byte-order mark (as spreadsheets write) is skipped.  The sample
rate is given (``fs``) or follows from a time column, which must then be uniform.
"""
from __future__ import annotations

import csv
from pathlib import Path
from typing import Mapping, Sequence

import numpy as np

from .._csv_header import HEADER_UNITS, column_name, column_unit, header_cell, si_factor
from .._io import read_input_text
from ..errors import DataError

__all__ = ["load_records", "sample_rate", "column_name", "header_cell", "HEADER_UNITS",
           "column_unit"]


def _si_factor(path: Path, name: str, unit: str | None, quantity: str | None) -> float:
    return si_factor(str(path), name, unit, quantity, DataError)


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
        factor = _si_factor(path, name, units[j], (quantities or {}).get(name))
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


def sample_rate(t: np.ndarray, name: str = "time", rtol: float = 1e-6) -> float:
    """Sample rate [Hz] of a uniform, increasing time vector; a one-line error otherwise.

    Parameters
    ----------
    t : ndarray, shape (n_t,)
        Sample times [s], n_t >= 2.
    name : str
        The time column's name, for the messages.
    rtol : float
        Largest allowed deviation of any step from the mean step, relative to the mean [-].

    Returns
    -------
    float
        ``1 / mean(diff(t))`` [Hz].

    Raises
    ------
    DataError
        When `t` does not increase strictly or is not uniformly sampled within `rtol`.
    """
    dt = np.diff(t)
    if np.any(dt <= 0):
        i = int(np.argmax(dt <= 0))
        raise DataError(f"column {name!r} must increase: data row {i + 2} has "
                        f"{float(t[i + 1]):.10g} after {float(t[i]):.10g}")
    mean = (t[-1] - t[0]) / (len(t) - 1)
    dev = np.abs(dt - mean).max() / mean
    if dev > rtol:
        raise DataError(f"column {name!r} is not uniformly sampled (spacing varies by "
                         f"{100 * dev:.3g} %, allowed {100 * rtol:g} %)")
    return 1.0 / mean
