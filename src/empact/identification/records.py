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

import numpy as np

from .._columns import HEADER_UNITS, column_name, column_unit, header_cell, load_records
from ..errors import DataError

__all__ = ["load_records", "sample_rate", "column_name", "header_cell", "HEADER_UNITS",
           "column_unit"]


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
