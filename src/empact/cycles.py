"""Drive cycles: the shipped standard speed traces and a user's trace.

The shipped cycles are data files (``empact/data/cycles/*.csv``), each with a provenance header
(source, package and version, table, licence, how it was built):

``wltc3b``
    WLTC class 3b (UN GTR 15), from the JRC ``wltp`` package 0.1.2a0 on PyPI: 1801 samples
    at 1 Hz (t = 0..1800 s), phases Low, Medium, High, Extra-high.
``nedc``
    NEDC (UNECE R83), from the same package: 1180 samples (t = 0..1179 s: the table starts at
    t = 0 and has no t = 1180 s sample), phases ECE (four ECE-15) and EUDC.
``ftp75``
    FTP-75 (40 CFR 86), built from the UDDS of NREL's ``fastsim`` package 2.1.5 on PyPI: the
    UDDS, then its first 505 s repeated, the 10-minute soak omitted (1875 samples, 1874 s);
    phases cold-transient, stabilized, hot-transient.

A file (shipped or a user's) is CSV: ``#`` comment lines, one header row with ``time [s]``
and ``speed [km/h]`` or ``speed [m/s]`` (and optionally ``phase``, a name per sample of at
most 40 characters), then one row per sample.  Header units are converted as every CSV
reader of empact converts them (`empact._columns`: ``time [ms]``, ``[min]``, ``speed
[mph]``, ...) and refused when unknown; the speed must have one.  The time must increase
strictly and the speed be finite and not negative; every bad row is named (one line per
error, at most ten).

The distance is the trapezoid of the speed over time; on the standard cycles, which start
and end at rest at 1 Hz, it equals the sum of the samples times 1 s (WLTC 3b: 83 758.6 km/h
s = 23.266 km).
"""
from __future__ import annotations

import csv
import io
import os
from dataclasses import dataclass
from importlib import resources
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ._columns import column_name, column_unit, si_factor
from ._io import read_input_text
from ._results import Result, plain
from ._validate import check_choice
from .errors import ParameterError

__all__ = ["CYCLES", "Cycle", "load_cycle", "read_trace", "parse_trace"]

#: the shipped cycles: name -> file in ``empact/data/cycles``
CYCLES = {"wltc3b": "wltc3b.csv", "nedc": "nedc.csv", "ftp75": "ftp75.csv"}
#: most errors listed for a bad trace
_MAX_ERRORS = 10
#: longest phase name [characters] (it heads a column of the text and a key of the JSON)
_MAX_PHASE = 40


@dataclass(frozen=True, eq=False)
class Cycle(Result):
    """A speed trace.

    Attributes
    ----------
    name : str
        The cycle's name (a shipped one's key, or the file's name).
    t : array, shape (N,)
        Time [s], strictly increasing.
    v : array, shape (N,)
        Vehicle speed [m/s], >= 0.
    phase : tuple of str, length N
        Each sample's phase (``"all"`` for a trace without phases).
    header : tuple of str
        The file's comment lines (the provenance of a shipped cycle).
    """

    name: str
    t: NDArray[np.float64]
    v: NDArray[np.float64]
    phase: tuple[str, ...]
    header: tuple[str, ...] = ()

    @property
    def phases(self) -> tuple[str, ...]:
        """The phase names in the order they first occur."""
        return tuple(dict.fromkeys(self.phase))

    @property
    def duration(self) -> float:
        """``t[-1] - t[0]`` [s]."""
        return float(self.t[-1] - self.t[0])

    @property
    def distance(self) -> float:
        """The trapezoid of the speed over time [m]."""
        return float(np.trapezoid(self.v, self.t))

    def acceleration(self) -> NDArray[np.float64]:
        """The trace's acceleration at its samples [m/s^2]: second-order central
        differences (one-sided at the ends, `numpy.gradient`).

        Returns
        -------
        array, shape (N,)
        """
        return np.asarray(np.gradient(self.v, self.t), float)

    def to_dict(self) -> dict[str, Any]:
        """``name``, ``t`` [s], ``v`` [m/s], ``phase``, ``duration_s``, ``distance_m``.

        Returns
        -------
        dict
        """
        return plain({"name": self.name, "t": self.t, "v": self.v, "phase": list(self.phase),
                      "duration_s": self.duration, "distance_m": self.distance})


def parse_trace(text: str, name: str) -> Cycle:
    """A trace from CSV text (module notes).

    Parameters
    ----------
    text : str
        The file's text.
    name : str
        What the messages call it (the file) and the cycle's name.

    Returns
    -------
    Cycle

    Raises
    ------
    ParameterError
        One line per error (at most ten), each naming the file, the row and the value.
    """
    lines = text.splitlines()
    header = tuple(x[1:].strip() for x in lines if x.startswith("#"))
    body = [x for x in lines if x.strip() and not x.startswith("#")]
    if not body:
        raise ParameterError(f"{name}: no header row (need 'time [s]' and 'speed [km/h]' or "
                             "'speed [m/s]')")
    rows = list(csv.reader(io.StringIO("\n".join(body))))
    cols = [c.strip() for c in rows[0]]
    names = [column_name(c) for c in cols]
    if names.count("time") != 1 or names.count("speed") != 1 or names.count("phase") > 1:
        raise ParameterError(f"{name}: header {','.join(cols)!r}: need the columns 'time [s]' "
                             "and 'speed [km/h]' (or 'speed [m/s]'), once each")
    i_t, i_v = names.index("time"), names.index("speed")
    i_p = names.index("phase") if "phase" in names else None
    t_unit, v_unit = column_unit(cols[i_t]), column_unit(cols[i_v])
    if v_unit is None:
        raise ParameterError(f"{name}: column 'speed' has no unit; give 'speed [km/h]' or "
                             "'speed [m/s]'")
    t_scale = si_factor(name, "time", t_unit, "time", ParameterError)
    scale = si_factor(name, "speed", v_unit, "speed", ParameterError)
    t_unit, v_unit = t_unit or "s", v_unit
    errors: list[str] = []
    t: list[float] = []
    v: list[float] = []
    phase: list[str] = []
    for k, row in enumerate(rows[1:], start=2):
        where = f"{name}: data row {k - 1}"
        if len(row) != len(cols):
            errors.append(f"{where}: {len(row)} fields, the header has {len(cols)}")
            continue
        try:
            tk, vk = float(row[i_t]) * t_scale, float(row[i_v])
        except ValueError:
            errors.append(f"{where}: {row[i_t].strip()!r}, {row[i_v].strip()!r}: not numbers")
            continue
        if not np.isfinite(tk):
            errors.append(f"{where}: time = {row[i_t].strip()}: must be finite [{t_unit}]")
        elif t and not tk > t[-1]:
            errors.append(f"{where}: time = {tk:g} s: must increase (previous {t[-1]:g} s)")
        if not (np.isfinite(vk) and vk >= 0):
            errors.append(f"{where}: speed = {row[i_v].strip()}: must be finite and >= 0 "
                          f"[{v_unit}]")
        label = row[i_p].strip() if i_p is not None else "all"
        if len(label) > _MAX_PHASE:
            errors.append(f"{where}: phase {label[:20]!r}... ({len(label)} characters): a "
                          f"phase name holds at most {_MAX_PHASE}")
        t.append(tk)
        v.append(vk * scale)
        phase.append(label)
    if not errors and len(t) < 2:
        errors.append(f"{name}: {len(t)} samples: a trace needs at least 2")
    if errors:
        more = len(errors) - _MAX_ERRORS
        shown = errors[:_MAX_ERRORS] + ([f"{name}: ... and {more} more"] if more > 0 else [])
        raise ParameterError("\n".join(shown))
    return Cycle(name=name, t=np.asarray(t, float), v=np.asarray(v, float),
                 phase=tuple(phase), header=header)


def read_trace(path: str | os.PathLike[str]) -> Cycle:
    """A user's trace from a CSV file (module notes), read through `empact._io`.

    Parameters
    ----------
    path : str or path-like
        The CSV file.

    Returns
    -------
    Cycle
        Named by the file's name.

    Raises
    ------
    ParameterError
        For a missing, unreadable or bad file (one line per error).
    """
    text = read_input_text(path, "trace")
    return parse_trace(text, os.fspath(path))


def load_cycle(name: str) -> Cycle:
    """A shipped cycle (`CYCLES`).

    Parameters
    ----------
    name : {"wltc3b", "nedc", "ftp75"}

    Returns
    -------
    Cycle

    Examples
    --------
    >>> from empact.cycles import load_cycle
    >>> c = load_cycle("wltc3b")
    >>> len(c.t), round(c.distance / 1e3, 3), c.phases
    (1801, 23.266, ('Low', 'Medium', 'High', 'Extra-high'))
    """
    check_choice("cycle", name, tuple(CYCLES))
    text = resources.files("empact.data").joinpath("cycles", CYCLES[name]).read_text()
    c = parse_trace(text, name)
    return c
