"""CSV header cells (private): the one style ``name [unit]`` that empact writes, and the units
it converts to SI when it reads a column (`HEADER_UNITS`), shared by every CSV reader
(measured records, `empact.identification.records`; speed traces, `empact.cycles`).  A unit
of a column that is read is converted when known and refused otherwise (one line naming the
file, the column and the units of its quantity), never ignored.
"""
from __future__ import annotations

import re

import numpy as np

from .errors import ParameterError

__all__ = ["HEADER_UNITS", "header_cell", "column_name", "column_unit", "si_factor"]

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


def si_factor(where: str, name: str, unit: str | None, quantity: str | None,
              error: type[ParameterError] = ParameterError) -> float:
    """The factor from a column's header unit to SI.

    Parameters
    ----------
    where : str
        The file, for the message.
    name : str
        The column's name, for the message.
    unit : str or None
        Its header unit (`column_unit`); None: SI.
    quantity : str or None
        The quantity the column must be (``"time"``, ``"speed"``; the second entry of
        `HEADER_UNITS`), None for any.
    error : type
        The error raised (a `ParameterError`).

    Returns
    -------
    float
        Multiply the column by it for SI [SI unit per header unit].

    Raises
    ------
    ParameterError
        (`error`) For a unit empact does not convert, or one of another quantity than
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
