"""Tabulated curves ``y(x)`` at several ratios, read from CSV or TOML and checked (one reader
for the traction tables and the thrust-ratio maps).

CSV: a header naming exactly the columns ``r_g``, `x`, `y` (any order; a UTF-8 BOM and ``#``
comment lines are allowed), one sample per row; rows with the same ``r_g`` form one curve, in
file order.  TOML: ``[[curve]]`` tables, each with ``r_g = <float>``, ``x = [...]``,
``y = [...]``.  Every problem is a one-line `ParameterError` naming the file, row and value.
"""
from __future__ import annotations

import csv
import os
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._io import check_input, parse_toml, read_input_text
from ..errors import ParameterError
from . import _laws

__all__ = ["check_curve", "read_curves", "encode_curves", "interp_knots", "knot_segments",
           "interpolate_curves"]

Curves = dict[float, tuple[list[float], list[float]]]


def read_curves(path: str | os.PathLike[str], what: str, x: str, y: str) -> Curves:
    """The curves of a ``.csv`` or ``.toml`` table: ``{r_g: (x values, y values)}``.

    `what` names the table in messages (``"traction table"``); `x`, `y` are its columns.
    """
    p = check_input(path, what)
    suffix = p.suffix.lower()
    if suffix == ".csv":
        return _read_csv(p, what, x, y)
    if suffix == ".toml":
        return _read_toml(p, x, y)
    raise ParameterError(f"{p}: {what} must be .csv or .toml, not {suffix or 'no suffix'!r}")


def encode_curves(ratios, xs, ys) -> NDArray[np.float64]:
    """Flat encoding of curves ``y(x)`` at several ratios for the compiled model, appended to
    its parameter vector (`empact.variator._laws.table_at` reads it)::

        [n_r, ln r_1 .. ln r_n, start_1 .. start_n,
         (n_x, x_1 .. x_nx, y_1 .. y_nx) per curve]

    with each curve's start as an offset from the beginning of the table; the kernel
    interpolates linearly in x along each curve and in ln r_g between curves, held constant
    outside."""
    n_r = len(ratios)
    head = [float(n_r), *np.log(np.asarray(ratios, float))]
    starts: list[float] = []
    body: list[float] = []
    for x, y in zip(xs, ys):
        starts.append(float(1 + 2 * n_r + len(body)))
        body += [float(len(x)), *np.asarray(x, float), *np.asarray(y, float)]
    return np.array(head + starts + body, dtype=float)


def interp_knots(x: ArrayLike, knots: ArrayLike, values: ArrayLike,
                 segments: tuple[NDArray[np.intp], NDArray[np.intp]] | None = None
                 ) -> NDArray[np.float64]:
    """The piecewise-linear function through ``(knots[j], values[j])`` at `x`, held constant
    outside the knots, a knot counting to the segment on its left: the rule of the compiled
    law `empact.variator._laws.knots_at`, on arrays, with the same line (`_laws.lerp`), so
    the same numbers.

    Parameters
    ----------
    x : array_like
        Where to evaluate, any shape.
    knots : array_like, shape (n,)
        Strictly increasing abscissae.
    values : array_like, shape (n,) or (n,) + x.shape
        The ordinates, one per knot (per point of `x` when they vary with it).
    segments : (ndarray, ndarray), optional
        `knot_segments` of `x` and `knots`, when several functions share them.

    Returns
    -------
    ndarray
        The values, the shape of `x`.
    """
    xa = np.asarray(x, float)
    k = np.asarray(knots, float)
    v = np.asarray(values, float)
    zero = 0.0 * xa
    if len(k) == 1:
        return v[0] + zero
    i, j = knot_segments(xa, k) if segments is None else segments
    if v.ndim == 1:
        lo, hi = v[j], v[j + 1]
    else:
        lo = np.take_along_axis(v, j[None], 0)[0]
        hi = np.take_along_axis(v, (j + 1)[None], 0)[0]
    with np.errstate(invalid="ignore", over="ignore"):
        inside = _laws.lerp(xa, k[j], k[j + 1], lo, hi)
    return np.where(i == 0, v[0] + zero, np.where(i == len(k), v[-1] + zero, inside))


def knot_segments(x: ArrayLike, knots: ArrayLike) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
    """``(i, j)`` for `interp_knots`: ``knots[i - 1] < x <= knots[i]`` and the segment ``j``
    (``i - 1`` held to the first and last), each the shape of `x`."""
    k = np.asarray(knots, float)
    i = np.searchsorted(k, np.asarray(x, float), side="left")
    return i, np.clip(i - 1, 0, max(len(k) - 2, 0))


def interpolate_curves(ratios, xs, ys, x: ArrayLike, r_g: ArrayLike) -> NDArray[np.float64]:
    """The interpolation `encode_curves` gives the kernel (`empact.variator._laws.table_at`)
    on arrays: linear in x along each curve (held constant outside its samples), linear in
    ln r_g between the curves (held constant outside), at points `x`, `r_g` (broadcast);
    `interp_knots` along both, so the kernel's numbers."""
    x, r = np.broadcast_arrays(np.asarray(x, float), np.asarray(r_g, float))
    vals = np.stack([interp_knots(x, xc, yc) for xc, yc in zip(xs, ys)])
    return interp_knots(np.log(r), np.log(np.asarray(ratios, float)), vals)


def check_curve(where: str, x: ArrayLike, y: ArrayLike, names: tuple[str, str],
                min_points: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """One curve as float arrays: lists of numbers of equal length, at least `min_points`,
    finite, `x` strictly increasing; otherwise a one-line `ParameterError` from `where`
    naming the entry (`names` are the columns' names).  Ranges are the caller's to check."""
    xn, yn = names
    try:
        xa = np.asarray(x, float).ravel()
        ya = np.asarray(y, float).ravel()
    except (TypeError, ValueError):
        raise ParameterError(f"{where}: {xn} and {yn} must be lists of numbers") from None
    if xa.size != ya.size:
        raise ParameterError(f"{where}: {xa.size} {xn} values but {ya.size} {yn} values")
    if xa.size < min_points:
        raise ParameterError(f"{where}: {xa.size} points, need at least {min_points}")
    for name, arr in ((xn, xa), (yn, ya)):
        bad = np.flatnonzero(~np.isfinite(arr))
        if bad.size:
            i = int(bad[0])
            raise ParameterError(f"{where}: {name}[{i}] = {float(arr[i])!r}: must be a finite "
                                 "number")
    step = np.flatnonzero(np.diff(xa) <= 0)
    if step.size:
        i = int(step[0]) + 1
        raise ParameterError(f"{where}: {xn} must increase strictly, but {xn}[{i}] = "
                             f"{xa[i]:g} follows {xn}[{i - 1}] = {xa[i - 1]:g}")
    return xa, ya


def _number(text: str, where: str) -> float:
    try:
        return float(text)
    except ValueError:
        raise ParameterError(f"{where}: {text!r} is not a number") from None


def _read_csv(p: Path, what: str, x: str, y: str) -> Curves:
    text = read_input_text(p, what)
    rows = [row for row in csv.reader(text.splitlines())
            if row and not row[0].lstrip().startswith("#")]
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
    data = parse_toml(p, "curve table")
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
