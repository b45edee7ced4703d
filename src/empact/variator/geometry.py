"""Variator geometry of a pushbelt CVT (paper eqs. 4-6).

Conventions (SI): running radii ``R_p`` (primary) and ``R_s`` (secondary) [m], geometric ratio
``r_g = R_p / R_s`` (``r_g > 1`` is overdrive), centre distance ``a`` [m], wedge angle ``beta``
[rad], wrapped-angle term ``phi = arcsin((R_p - R_s) / a)`` [rad] (eq. 4), belt length
``L = 2 a cos(phi) + (pi + 2 phi) R_p + (pi - 2 phi) R_s`` (eq. 6), sheave translations
``x = (R - R0) tan(beta)`` with ``R0 = R_min``, and ``Delta_x = x_p - x_s = a sin(phi) tan(beta)``
(eq. 5).  Exact identity used throughout: ``dL/dR_p = pi + 2 phi``, ``dL/dR_s = pi - 2 phi``.

All functions accept arrays and broadcast.  The root finds are Newton iterations on the exact
derivatives above (vectorised over ratios; bracketed for the range): no scipy import, which
keeps ``empact params`` fast (see ``bench/bench_geometry.py`` for the comparison with
``scipy.optimize``).  Eqs. 4 and 6 and the Newton step on them are written once, in
`empact.variator._laws` (`wrap_angle`, `belt_geometry`, `belt_newton_step`): the functions
here evaluate them on arrays, and the compiled kernel and the sampled loop law call their
compiled twins (`empact.variator._compiled`).

The functions take plain numbers (`wrap_angle`, `belt_length`, `radii`, `stretched_radii`) or
the variator's own parameter block `VariatorParams` (``[variator]`` of a parameter file).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache
from typing import Callable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._lazy import lazy_module
from .._results import Result
from .._section import Section, param
from .._validate import check_values
from ..errors import ParameterError
from . import _laws

#: the compiled laws (numba), loaded on first use (`secondary_radius`)
_compiled = lazy_module("empact.variator._compiled")

__all__ = ["VariatorParams", "wrap_angle", "belt_length", "radii", "stretched_radii",
           "ratio_range", "VariatorState", "variator_state", "check_ratio",
           "primary_radius_per_ratio"]


@dataclass(frozen=True)
class VariatorParams(Section):
    """Pushbelt variator geometry (paper eqs. 4-6).

    Attributes
    ----------
    a : float
        Centre distance between the pulley shafts [m].
    beta : float
        Pulley wedge angle (half the V angle; pushbelts: about 11 deg) [rad].
    L_belt : float
        Belt length (running circumference) [m].
    R_min : float
        Smallest running radius [m]; also ``R0``, the radius at zero sheave translation.
    R_max : float
        Largest running radius [m], above `R_min`.
    """

    _name = "variator"
    a: float = param("m", "centre distance between the pulley shafts", 0.02, 1.0)
    beta: float = param("rad", "pulley wedge angle (half the V angle; pushbelts: about 11 deg)",
                     math.radians(1), math.radians(30), lo_open=False)
    L_belt: float = param("m", "belt length (running circumference)", 0.1, 5.0)
    R_min: float = param("m", "smallest running radius; also R0, the radius at zero sheave "
                           "translation", 0.002, 0.5)
    R_max: float = param("m", "largest running radius", 0.002, 0.5)

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.R_max <= self.R_min:
            raise ParameterError(
                f"variator.R_max = {self.R_max!r}: must exceed variator.R_min = {self.R_min!r} [m]")
        # The belt must fit: at r_g = 1 both radii are (L - 2a) / (2 pi).
        R_med = (self.L_belt - 2 * self.a) / (2 * math.pi)
        if not self.R_min < R_med < self.R_max:
            raise ParameterError(
                f"variator.L_belt = {self.L_belt!r}: gives the medium-ratio radius {R_med:.4g} m, "
                f"which must lie in (R_min, R_max) = ({self.R_min:g}, {self.R_max:g}) m")


def wrap_angle(R_p: ArrayLike, R_s: ArrayLike, a: float) -> NDArray[np.float64]:
    """Wrapped-angle term ``phi = arcsin((R_p - R_s) / a)`` [rad] (eq. 4).

    Parameters
    ----------
    R_p, R_s : array_like
        Primary and secondary running radii [m], broadcast together.
    a : float
        Centre distance [m].

    Returns
    -------
    ndarray
        The wrapped-angle term ``phi`` [rad], the broadcast shape of `R_p` and `R_s` (NaN
        where ``|R_p - R_s| > a``).
    """
    return _laws.wrap_angle(np.asarray(R_p, float), np.asarray(R_s, float), a)


def belt_length(R_p: ArrayLike, R_s: ArrayLike, a: float) -> NDArray[np.float64]:
    """Belt length ``L = 2 a cos(phi) + (pi + 2 phi) R_p + (pi - 2 phi) R_s`` [m] (eq. 6).

    The law `empact.variator._laws.belt_geometry` (the compiled code calls its twin).

    Parameters
    ----------
    R_p, R_s : array_like
        Running radii [m] on the primary and the secondary, broadcast together.
    a : float
        Centre distance between the pulley shafts [m].

    Returns
    -------
    ndarray
        The belt length [m], the broadcast shape of `R_p` and `R_s`.
    """
    return _laws.belt_geometry(np.asarray(R_p, float), np.asarray(R_s, float), a)[1]


def radii(r_g: ArrayLike, L_belt: float, a: float, *, tol: float = 1e-13,
          max_iter: int = 50) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Running radii ``(R_p, R_s)`` [m] for ratio(s) `r_g` at belt length `L_belt` [m].

    Solves ``L(r_g R_s, R_s) = L_belt`` for ``R_s`` by Newton's method (vectorised), with the
    exact derivative ``dL/dR_s = r_g (pi + 2 phi) + (pi - 2 phi)``, from the exact solution
    for ``phi = 0``.

    Parameters
    ----------
    r_g : array_like
        Geometric ratio(s) ``R_p / R_s`` [-], > 0, any shape.
    L_belt : float
        Belt length [m].
    a : float
        Centre distance [m].
    tol : float
        Convergence tolerance of the Newton step, relative to `L_belt` [-].
    max_iter : int
        Largest number of Newton iterations.

    Returns
    -------
    R_p, R_s : ndarray
        Primary and secondary running radii [m], the shape of `r_g`.

    Raises
    ------
    ParameterError
        If `r_g` is not positive or the iteration does not converge (belt cannot span the
        pulleys at that ratio).
    """
    r = check_values("r_g", r_g, 0.0, lo_open=True)
    R_s = _laws.radius_at_zero_wrap(r, L_belt, a)
    # each point stops on its own convergence, so its radius does not depend on the others
    # (a sweep's chunks give bitwise the same result)
    active = np.ones(np.shape(R_s), dtype=bool)
    with np.errstate(invalid="ignore"):
        for _ in range(max_iter):
            step = np.where(active, _laws.belt_newton_step(R_s, r, L_belt, a), 0.0)
            R_s = R_s - step
            active = active & ~(np.abs(step) <= tol * L_belt)
            if not active.any():
                break
        else:
            R_s = np.full_like(R_s, np.nan)
    if np.any(~np.isfinite(R_s)):
        bad = r[~np.isfinite(R_s)].flat[0] if r.ndim else float(r)
        raise ParameterError(f"r_g = {bad:g}: no belt geometry at this ratio "
                             f"(L_belt = {L_belt:g} m, a = {a:g} m)")
    return r * R_s, R_s


def secondary_radius(r_g: float, L_belt: float, a: float, guess: float | None = None,
                     tol: float = 1e-13) -> float:
    """`radii`'s ``R_s`` [m] for one ratio in plain floats (a sampled controller calls it at
    every sample): the same Newton steps, compiled
    (`empact.variator._laws.secondary_radius`), started at `guess` (the last sample's
    radius) or at the exact solution for ``phi = 0``."""
    R_s = _compiled.secondary_radius(float(r_g), float(L_belt), float(a),
                                     math.nan if guess is None else float(guess), float(tol))
    if R_s != R_s:
        raise ParameterError(f"r_g = {r_g:g}: no belt geometry at this ratio")
    return float(R_s)


def stretched_radii(r_g: ArrayLike, F: ArrayLike, L_belt: float, a: float, beta: float,
                    k_belt: float, *, tol: float = 1e-15, max_iter: int = 30
                    ) -> tuple[NDArray[np.float64], ...]:
    """Running radii of an elastic belt stretched by the secondary axial force `F` [N] at
    ratio(s) `r_g` (arrays broadcast).

    The belt element of the nonlinear model (`empact.nonlinear.model`) pulls with ``N = k_belt
    e`` on a length ``L(R_p, R_s) = L_belt + e`` (eq. 6 on the current radii), and pushes the
    secondary sheave apart with ``F = N (pi - 2 phi) / tan(beta)`` (virtual work).  Solves
    ``L(r_g R_s, R_s) - L_belt - F tan(beta) / (k_belt (pi - 2 phi)) = 0`` for ``R_s`` by
    Newton's method from the unstretched radii, each point stopping on its own convergence
    (so a point's result does not depend on the others in the array).

    Parameters
    ----------
    r_g : array_like
        Geometric ratio(s) ``R_p / R_s`` [-] of the unstretched belt, broadcast with `F`.
    F : array_like
        Secondary axial (clamping) force [N].
    L_belt : float
        Unstretched belt length [m].
    a : float
        Centre distance [m].
    beta : float
        Pulley wedge angle [rad].
    k_belt : float
        Longitudinal belt stiffness [N/m].
    tol : float
        Convergence tolerance of the Newton step, relative to ``R_s`` [-].
    max_iter : int
        Largest number of Newton iterations.

    Returns
    -------
    R_p, R_s, phi, e : arrays
        Radii [m], wrap-angle term [rad] (eq. 4) and belt stretch ``e`` [m]; NaN where the
        iteration did not converge (no belt geometry carries `F` at that ratio).
    """
    r = np.asarray(r_g, float)
    F = np.asarray(F, float)
    r, F = np.broadcast_arrays(r, F)
    tb = math.tan(beta)
    _, R_s = radii(r, L_belt, a)
    R_s = np.array(R_s, float)
    active = np.ones(R_s.shape, dtype=bool)
    with np.errstate(invalid="ignore"):
        for _ in range(max_iter):
            phi = wrap_angle(r * R_s, R_s, a)
            g = np.pi - 2 * phi
            f = belt_length(r * R_s, R_s, a) - L_belt - F * tb / (k_belt * g)
            dphi = (r - 1) / (a * np.cos(phi))
            df = r * (np.pi + 2 * phi) + g - F * tb / k_belt * 2 * dphi / g**2
            step = np.where(active, f / df, 0.0)
            R_s = R_s - step
            active &= np.abs(step) > tol * R_s
            if not active.any():
                break
        R_s = np.where(active, np.nan, R_s)
        phi = wrap_angle(r * R_s, R_s, a)
    return r * R_s, R_s, phi, F * tb / (k_belt * (np.pi - 2 * phi))


def _bracketed_newton(f: Callable[[float], float], df: Callable[[float], float], lo: float,
                      hi: float, tol: float) -> float:
    """Root of `f` in ``[lo, hi]`` (``f(lo) < 0 < f(hi)``): Newton steps, bisection whenever a
    step would leave the bracket."""
    x = 0.5 * (lo + hi)
    for _ in range(200):
        fx = f(x)
        if fx < 0:
            lo = x
        else:
            hi = x
        d = df(x)
        x_new = x - fx / d if d > 0 else 0.5 * (lo + hi)
        if not lo < x_new < hi:
            x_new = 0.5 * (lo + hi)
        if abs(x_new - x) <= tol or hi - lo <= tol:
            return x_new
        x = x_new
    return x


@lru_cache(maxsize=64)
def ratio_range(variator: VariatorParams) -> tuple[float, float]:
    """Geometric ratio range ``(r_min, r_max)`` allowed by ``R_min <= R_p, R_s <= R_max``.

    At the largest ratio either ``R_s = R_min`` or ``R_p = R_max``, whichever binds first; the
    smallest ratio is the mirror image (eq. 6 is symmetric under exchanging the pulleys).
    """
    v = variator
    R_med = (v.L_belt - 2 * v.a) / (2 * np.pi)
    tol = 1e-15 * v.L_belt
    candidates = []
    # R_s = R_min: dL/dR_p = pi + 2 phi
    upper = v.R_min + v.a * (1 - 1e-12)  # arcsin domain of eq. 4
    f = lambda x: float(belt_length(x, v.R_min, v.a)) - v.L_belt  # noqa: E731
    if f(R_med) < 0 < f(upper):
        R_p = _bracketed_newton(f, lambda x: np.pi + 2 * float(wrap_angle(x, v.R_min, v.a)),
                                R_med, upper, tol)
        candidates.append(R_p / v.R_min)
    # R_p = R_max: dL/dR_s = pi - 2 phi; L decreases as R_s falls, so solve -L
    lower = max(0.0, v.R_max - v.a * (1 - 1e-12))
    g = lambda x: float(belt_length(v.R_max, x, v.a)) - v.L_belt  # noqa: E731
    if g(lower) < 0 < g(R_med):
        R_s = _bracketed_newton(g, lambda x: np.pi - 2 * float(wrap_angle(v.R_max, x, v.a)),
                                lower, R_med, tol)
        candidates.append(v.R_max / R_s)
    if not candidates:
        raise ParameterError(f"variator: no ratio range for R_min = {v.R_min:g}, R_max = "
                             f"{v.R_max:g}, L_belt = {v.L_belt:g}, a = {v.a:g} m")
    r_max = min(candidates)
    return 1.0 / r_max, r_max


def check_ratio(r_g: ArrayLike, variator: VariatorParams, name: str = "r_g") -> NDArray[np.float64]:
    """Return `r_g` as an array, or raise `ParameterError` if any value is outside the range.

    Parameters
    ----------
    r_g : array_like
        Geometric ratio(s) ``R_p / R_s`` [-], any shape.
    variator : VariatorParams
        The variator whose `ratio_range` bounds the ratio.
    name : str
        The name the error message gives the value.

    Returns
    -------
    ndarray
        `r_g` as a float array, its shape.

    Raises
    ------
    ParameterError
        When a value is not finite or outside the variator's ratio range.
    """
    r = np.asarray(r_g, float)
    lo, hi = ratio_range(variator)
    bad = ~np.isfinite(r) | (r < lo * (1 - 1e-12)) | (r > hi * (1 + 1e-12))
    if np.any(bad):
        value = r[bad].flat[0] if r.ndim else float(r)
        raise ParameterError(f"{name} = {value:g}: outside the geometric ratio range "
                             f"[{lo:.4g}, {hi:.4g}] of the variator")
    return r


def primary_radius_per_ratio(r_g: ArrayLike, variator: VariatorParams) -> NDArray[np.float64]:
    """``dR_p / dr_g`` [m] along a shift at constant belt length: eq. 6 gives ``dR_s =
    -kappa_geo dR_p`` with ``kappa_geo = (pi + 2 phi) / (pi - 2 phi)``, so ``dr_g = dR_p (1 +
    r_g kappa_geo) / R_s``.

    Parameters
    ----------
    r_g : array_like
        Geometric ratio(s) ``R_p / R_s`` [-] (checked against the ratio range), any shape.
    variator : VariatorParams
        Centre distance, belt length and radius range (``params.variator``).

    Returns
    -------
    ndarray
        ``dR_p / dr_g`` [m] (per unit ratio), the shape of `r_g`.
    """
    v = variator
    r = check_ratio(r_g, v)
    R_p, R_s = radii(r, v.L_belt, v.a)
    phi = wrap_angle(R_p, R_s, v.a)
    return R_s / (1 + r * _laws.kappa_geo(phi))


@dataclass(frozen=True)
class VariatorState(Result):
    """Geometry of the variator at one or more ratios (arrays broadcast like `r_g`).

    Attributes
    ----------
    r_g : geometric ratio [-]
    R_p, R_s : running radii [m]
    phi : wrapped-angle term [rad] (eq. 4)
    x_p, x_s : sheave translations ``(R - R0) tan(beta)`` [m]
    delta_x : ``x_p - x_s = a sin(phi) tan(beta)`` [m] (eq. 5)
    L : belt length [m] (eq. 6), equal to ``L_belt`` to solver precision
    dL_dRp, dL_dRs : ``pi + 2 phi`` and ``pi - 2 phi`` [-]
    """

    r_g: NDArray[np.float64]
    R_p: NDArray[np.float64]
    R_s: NDArray[np.float64]
    phi: NDArray[np.float64]
    x_p: NDArray[np.float64]
    x_s: NDArray[np.float64]
    delta_x: NDArray[np.float64]
    L: NDArray[np.float64]
    dL_dRp: NDArray[np.float64]
    dL_dRs: NDArray[np.float64]


def variator_state(r_g: ArrayLike, variator: VariatorParams) -> VariatorState:
    """Geometry at ratio(s) `r_g` (checked against the geometric range).

    Parameters
    ----------
    r_g : array_like
        Geometric ratio(s) ``R_p / R_s`` [-], shape (n,) or scalar.
    variator : VariatorParams
        Centre distance, wedge angle, belt length, radius range (``params.variator``).

    Returns
    -------
    VariatorState
        Radii ``R_p, R_s`` [m], wrap angle term ``phi`` [rad], sheave translations ``x_p, x_s``
        and ``delta_x`` [m], belt length ``L`` [m] and ``dL_dRp, dL_dRs`` [-], each the shape
        of `r_g`.
    """
    v = variator
    r = check_ratio(r_g, v)
    R_p, R_s = radii(r, v.L_belt, v.a)
    phi = wrap_angle(R_p, R_s, v.a)
    tb = np.tan(v.beta)
    return VariatorState(r_g=r, R_p=R_p, R_s=R_s, phi=phi, x_p=(R_p - v.R_min) * tb,
                         x_s=(R_s - v.R_min) * tb, delta_x=v.a * np.sin(phi) * tb,
                         L=belt_length(R_p, R_s, v.a), dL_dRp=np.pi + 2 * phi,
                         dL_dRs=np.pi - 2 * phi)
