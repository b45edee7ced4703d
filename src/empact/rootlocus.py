"""Root loci over any scalar parameter of a linear model, with continuous branches.

python-control draws a root locus over a feedback gain only.  Here the parameter may enter the
system matrix in any way: `root_locus` takes a function ``A_of_p(p) -> A`` (shape (n, n)) and
follows the n eigenvalues from ``p_start`` to ``p_stop``:

* steps are uniform in ``p`` (``spacing="linear"``) or in ``log(p)`` (``"log"``, for parameters
  spanning decades, such as a damping constant); the step is halved while any pole moves more
  than ``max_move`` times its own magnitude plus an absolute floor, and grown again when the
  poles move little, so that fast regions (break-away points) are resolved and slow ones are
  not over-sampled;
* between steps the eigenvalues are matched to the previous ones by a minimum-cost assignment
  (`scipy.optimize.linear_sum_assignment` on ``|lambda_new - lambda_old|``), so column ``j`` of
  `RootLocus.poles` is one continuous branch.

`track_branches` applies the same matching to eigenvalues already computed on a grid (e.g. a
batched sweep).  End points at ``p = 0`` or ``p -> inf`` usually need a separate, exact
computation (see `empact.slip.belt_root_locus`).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import linear_sum_assignment

__all__ = ["RootLocus", "root_locus", "match_branches", "track_branches"]

Spacing = Literal["linear", "log"]


@dataclass(frozen=True)
class RootLocus:
    """Eigenvalues of ``A(p)`` along a parameter, one continuous branch per column.

    Attributes
    ----------
    parameter : parameter values, shape (n_steps,), monotone from ``p_start`` to ``p_stop``
    poles : eigenvalues [rad/s], shape (n_steps, n); column ``j`` is branch ``j``
    name : parameter name (with unit, for display)
    """

    parameter: NDArray[np.float64]
    poles: NDArray[np.complex128]
    name: str = "p"

    @property
    def start(self) -> NDArray[np.complex128]:
        """Poles at the first parameter value, shape (n,)."""
        return self.poles[0]

    @property
    def stop(self) -> NDArray[np.complex128]:
        """Poles at the last parameter value, shape (n,)."""
        return self.poles[-1]


def match_branches(previous: ArrayLike, current: ArrayLike) -> NDArray[np.complex128]:
    """Reorder `current` eigenvalues so that entry j continues ``previous[j]`` (shape (n,)).

    Minimum total distance ``sum |current[perm[j]] - previous[j]|`` (Hungarian algorithm).
    """
    prev = np.asarray(previous, complex)
    cur = np.asarray(current, complex)
    if prev.shape != cur.shape or prev.ndim != 1:
        raise ValueError(f"eigenvalue vectors of shapes {prev.shape} and {cur.shape}: need two "
                         "equal 1-d shapes")
    cost = np.abs(prev[:, None] - cur[None, :])
    rows, cols = linear_sum_assignment(cost)
    out = np.empty_like(cur)
    out[rows] = cur[cols]
    return out


def track_branches(eigs: ArrayLike) -> NDArray[np.complex128]:
    """Match eigenvalues along the first axis (shape (n_steps, n)) into continuous branches."""
    e = np.array(eigs, dtype=complex)
    if e.ndim != 2:
        raise ValueError(f"eigenvalues of shape {e.shape}: need (n_steps, n)")
    for k in range(1, len(e)):
        e[k] = match_branches(e[k - 1], e[k])
    return e


def root_locus(A_of_p: Callable[[float], ArrayLike], p_start: float, p_stop: float, *,
               spacing: Spacing = "linear", n_initial: int = 60, max_move: float = 0.05,
               abs_floor: float | None = None, min_step_fraction: float = 1e-6,
               max_points: int = 20000, name: str = "p") -> RootLocus:
    """Eigenvalues of ``A_of_p(p)`` from `p_start` to `p_stop`, tracked branch by branch.

    Parameters
    ----------
    A_of_p : callable
        ``p -> A``, a square real or complex matrix, shape (n, n), for a scalar parameter.
    p_start, p_stop : float
        Ends of the parameter range (either order).  With ``spacing="log"`` both must be
        positive (map an end point at 0 or infinity separately).
    spacing : {"linear", "log"}
        Steps uniform in ``p`` or in ``log(p)``.
    n_initial : int
        The largest step is ``1 / n_initial`` of the range (in the spacing's variable), so the
        locus has at least ``n_initial + 1`` points.
    max_move : float
        A step is accepted when every pole moves at most ``max_move * |lambda| + abs_floor``.
    abs_floor : float, optional
        Absolute part of the tolerance [units of the eigenvalues]; default 1 % of the median
        nonzero eigenvalue magnitude at `p_start` (so that poles near 0 do not force tiny steps).
    min_step_fraction : float
        Smallest step, as a fraction of the largest; a step this small is accepted anyway (at a
        break-away point the poles move like a square root of the parameter).
    max_points : int
        Hard limit on the number of points.
    name : str
        Parameter name for the result.

    Returns
    -------
    RootLocus
        ``parameter`` shape (n_steps,), ``poles`` shape (n_steps, n).

    Examples
    --------
    A mass on a spring with damping c: poles ``(-c +- sqrt(c^2 - 4)) / 2``.

    >>> loc = root_locus(lambda c: [[0, 1], [-1, -c]], 0.0, 4.0)
    >>> bool(np.allclose(sorted(loc.stop.real), [-2 - 3**0.5, -2 + 3**0.5]))
    True
    """
    if spacing not in ("linear", "log"):
        raise ValueError(f"spacing = {spacing!r}: choose 'linear' or 'log'")
    for label, v in (("p_start", p_start), ("p_stop", p_stop)):
        if not math.isfinite(v):
            raise ValueError(f"{label} = {v!r}: must be finite (map an infinite end point "
                             "separately)")
        if spacing == "log" and v <= 0:
            raise ValueError(f"{label} = {v!r}: must be > 0 with spacing='log'")
    if p_start == p_stop:
        raise ValueError(f"p_start = p_stop = {p_start!r}: the range is empty")
    if n_initial < 2:
        raise ValueError(f"n_initial = {n_initial}: must be >= 2")
    if not 0 < max_move < 1:
        raise ValueError(f"max_move = {max_move!r}: allowed range is (0, 1)")

    to_t = np.log if spacing == "log" else (lambda x: x)
    to_p = np.exp if spacing == "log" else (lambda x: x)
    t0, t1 = float(to_t(p_start)), float(to_t(p_stop))
    h_max = (t1 - t0) / n_initial  # signed
    h_min = abs(h_max) * min_step_fraction

    def eig(t: float) -> NDArray[np.complex128]:
        return np.linalg.eigvals(np.asarray(A_of_p(float(to_p(t)))))

    prev = eig(t0)
    if abs_floor is None:
        mags = np.abs(prev)
        nz = mags[mags > 1e-9 * max(mags.max(), 1e-300)]
        abs_floor = 0.01 * float(np.median(nz)) if nz.size else 1e-6
    params, poles = [float(to_p(t0))], [prev]
    t, h = t0, h_max
    while (t1 - t) * np.sign(h_max) > 0:
        if len(params) >= max_points:
            raise RuntimeError(f"root_locus: more than max_points = {max_points} points; "
                               "increase max_move or max_points")
        t_try = t + h
        if (t1 - t_try) * np.sign(h_max) < 0:
            t_try = t1
        cur = match_branches(prev, eig(t_try))
        ratio = float(np.max(np.abs(cur - prev) / (max_move * np.abs(prev) + abs_floor)))
        if ratio > 1 and abs(h) > h_min:
            h = np.sign(h_max) * max(abs(h) / 2, h_min)
            continue
        t, prev = t_try, cur
        params.append(float(to_p(t)))
        poles.append(cur)
        if ratio < 0.3:
            h = np.sign(h_max) * min(abs(h) * 1.5, abs(h_max))
    params[-1] = float(p_stop)
    return RootLocus(parameter=np.array(params), poles=np.array(poles), name=name)
