"""Equilibrium thrust ratio of the pushbelt variator, ``kappa*(tau, r_g) = F_p* / F_s``.

The thrust ratio at which the ratio holds still: the primary clamping force per unit secondary
clamping force.  It depends on the ratio ``r_g`` and on the torque ratio

    ``tau = T_b cos(beta) / (2 mu_max F_s R_s)``  (1 at the traction limit),

and it is the path by which the transmitted torque pushes the ratio: with the clamping forces
held, a load change moves ``r_g`` until ``kappa*`` matches them again.

Without torque an elastic belt holds the ratio at the geometric thrust ratio of virtual work,
``kappa_geo = (pi + 2 phi) / (pi - 2 phi)`` (the wrap angles' ratio; Carbone et al.'s
frictionless limit): the nonlinear model's belt element gives exactly that.  Two maps are
provided:

`AnalyticThrustRatio` (parameter section ``[thrust_ratio]``)
    ``ln kappa* = p0 ln kappa_geo + (b0 - b1 ln r_g) tau``: rising with torque, faster at
    LOW than at OD, as published pushbelt curves are; with ``p0 = 1`` it equals kappa_geo at
    zero torque.  Values are estimates (no measured map could be read).
`TabulatedThrustRatio`
    A measured map, one curve ``kappa(tau)`` per ratio, from CSV (columns ``r_g, tau, kappa``)
    or TOML (``[[curve]]`` tables with ``r_g``, ``tau = [...]``, ``kappa = [...]``): linear in
    ``tau`` along each curve and in ``ln r_g`` between curves, held constant outside (the
    interpolation the compiled model uses, so that both agree to rounding).

`zero_torque_difference` states how a map differs from kappa_geo at zero torque.
Compute only.
"""
from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._results import Result
from .._section import Section, param
from ..errors import ParameterError
from . import _laws
from ._tables import check_curve, encode_curves, interpolate_curves, read_curves
from .geometry import VariatorParams, radii, wrap_angle

__all__ = ["ThrustRatioParams", "ratio_stability", "ratio_stability_map", "RatioStabilityMap",
           "kappa_geo", "AnalyticThrustRatio", "TabulatedThrustRatio", "load_thrust_ratio",
           "thrust_ratio_from_params", "zero_torque_difference", "TAU_RANGE"]

#: Torque ratios a tabulated map may cover (|tau| > 1 is beyond the traction limit).
TAU_RANGE = (-1.0, 1.0)


@dataclass(frozen=True)
class ThrustRatioParams(Section):
    """Torque-dependent equilibrium thrust ratio ``kappa* = F_p* / F_s`` (analytic default).

    ``ln kappa*(tau, r_g) = p0 ln kappa_geo(r_g) + (b0 - b1 ln r_g) tau`` with the torque ratio
    ``tau = T_b cos(beta) / (2 mu_max F_s R_s)`` (1 at the traction limit) and the geometric
    thrust ratio of the elastic belt ``kappa_geo = (pi + 2 phi) / (pi - 2 phi)`` (virtual
    work; Carbone's frictionless limit): with ``p0 = 1`` it agrees exactly at zero torque.
    Shaped like published pushbelt curves (rising with torque, faster at LOW, flat or falling
    at OD); the values are estimates, no measured map could be read: a tabulated map (CSV or
    TOML, `empact.thrust_ratio.load_thrust_ratio`) replaces it.

    Attributes
    ----------
    p0 : float
        Steepness of the zero-torque curve relative to ``kappa_geo`` [-] (1: equal to it).
    b0 : float
        ``d ln kappa* / d tau`` at ``r_g = 1`` [-].
    b1 : float
        How much faster ``ln kappa*`` rises with the torque ratio ``tau`` at LOW than at OD
        [-] (the slope is ``b0 - b1 ln r_g``).
    """

    _name = "thrust_ratio"
    p0: float = param("-", "steepness of the zero-torque curve relative to kappa_geo", 0.5, 2.0,
                   lo_open=False)
    b0: float = param("-", "d ln kappa* / d tau at r_g = 1", 0.0, 1.5, lo_open=False)
    b1: float = param("-", "how much faster ln kappa* rises with tau at LOW than at OD", -1.0, 2.0)


class _HasThrustRatio(Protocol):
    """A parameter set (`empact.params.Params`): what the analytic map reads of it."""

    @property
    def variator(self) -> VariatorParams: ...
    @property
    def thrust_ratio(self) -> ThrustRatioParams: ...


def kappa_geo(r_g: ArrayLike, variator: VariatorParams) -> NDArray[np.float64]:
    """Geometric thrust ratio ``(pi + 2 phi) / (pi - 2 phi)`` of the unstretched belt [-].

    Parameters
    ----------
    r_g : array_like
        Geometric ratio(s) [-].
    variator : VariatorParams

    Returns
    -------
    ndarray
        The geometric thrust ratio [-], the shape of `r_g`.
    """
    R_p, R_s = radii(np.asarray(r_g, float), variator.L_belt, variator.a)
    return _laws.kappa_geo(wrap_angle(R_p, R_s, variator.a))


@dataclass(frozen=True)
class AnalyticThrustRatio:
    """``ln kappa* = p0 ln kappa_geo(r_g) + (b0 - b1 ln r_g) tau`` (see the module notes).

    Parameters
    ----------
    p0, b0, b1 : float
        As `empact.params.ThrustRatioParams`.
    variator : VariatorParams
        Geometry for kappa_geo.
    """

    p0: float
    b0: float
    b1: float
    variator: VariatorParams
    source: str = "[thrust_ratio] (analytic)"

    @classmethod
    def from_params(cls, params: _HasThrustRatio) -> "AnalyticThrustRatio":
        """The analytic thrust ratio of a parameter set's ``[thrust_ratio]`` section on its
        variator geometry.

        Parameters
        ----------
        params : Params or section
            A parameter set, or a block, with the thrust-ratio parameters.
        """
        t: ThrustRatioParams = params.thrust_ratio
        return cls(t.p0, t.b0, t.b1, params.variator)

    def kappa(self, tau: ArrayLike, r_g: ArrayLike) -> NDArray[np.float64]:
        """``kappa*`` [-] at torque ratios `tau` and ratios `r_g` (broadcast).

        Parameters
        ----------
        tau : array_like
            Torque ratios ``mu / mu_max`` [-].
        r_g : array_like
            Geometric ratios [-] (broadcast against `tau`).
        """
        tau, r = np.broadcast_arrays(np.asarray(tau, float), np.asarray(r_g, float))
        return np.exp(_laws.log_kappa_eq(tau, np.log(r), kappa_geo(r, self.variator), self.p0,
                                         self.b0, self.b1))


@dataclass(frozen=True)
class TabulatedThrustRatio:
    """A measured thrust-ratio map: one curve ``kappa(tau)`` per ratio.

    Parameters
    ----------
    ratios : tuple of float, shape (k,)
        Ratios [-], strictly increasing.
    tau_data, kappa_data : tuple of arrays
        Per curve: torque ratios [-] strictly increasing in [-1, 1] (at least 2) and thrust
        ratios [-] > 0.
    source : str
        Where the table came from (used in messages).
    """

    ratios: tuple[float, ...]
    tau_data: tuple[NDArray[np.float64], ...]
    kappa_data: tuple[NDArray[np.float64], ...]
    source: str = "thrust-ratio table"

    def __post_init__(self) -> None:
        ratios = tuple(float(r) for r in self.ratios)
        if not ratios or len(ratios) != len(self.tau_data) or len(ratios) != len(self.kappa_data):
            raise ParameterError(f"{self.source}: need one (tau, kappa) curve per ratio, got "
                                 f"{len(ratios)} ratios")
        for r in ratios:
            if not (math.isfinite(r) and r > 0):
                raise ParameterError(f"{self.source}: r_g = {r!r}: must be a positive finite "
                                     "ratio")
        if any(b <= a for a, b in zip(ratios, ratios[1:])):
            raise ParameterError(f"{self.source}: ratios {ratios!r} must be distinct and "
                                 "increasing")
        taus, kaps = [], []
        for r, tau, kap in zip(ratios, self.tau_data, self.kappa_data):
            t, k = _validate_curve(r, tau, kap, self.source)
            taus.append(t)
            kaps.append(k)
        object.__setattr__(self, "ratios", ratios)
        object.__setattr__(self, "tau_data", tuple(taus))
        object.__setattr__(self, "kappa_data", tuple(kaps))

    def __hash__(self) -> int:  # arrays are not hashable: hash the contents
        return hash((self.ratios, tuple(t.tobytes() for t in self.tau_data),
                     tuple(k.tobytes() for k in self.kappa_data)))

    def __eq__(self, other: object) -> bool:
        return isinstance(other, TabulatedThrustRatio) and hash(self) == hash(other)

    def kappa(self, tau: ArrayLike, r_g: ArrayLike) -> NDArray[np.float64]:
        """``kappa`` [-] at torque ratios `tau` and ratios `r_g` (broadcast).

        Parameters
        ----------
        tau : array_like
            Torque ratios ``mu / mu_max`` [-] (held at the table's ends outside it).
        r_g : array_like
            Geometric ratios [-], broadcast with `tau` (interpolated in ``ln r_g``).
        """
        return np.exp(interpolate_curves(self.ratios, self.tau_data,
                                         [np.log(k) for k in self.kappa_data], tau, r_g))

    def encode(self) -> NDArray[np.float64]:
        """Flat encoding for the compiled model (`empact.variator._tables.encode_curves` of
        the curves ``ln kappa(tau)``)."""
        return encode_curves(self.ratios, self.tau_data, [np.log(k) for k in self.kappa_data])


def _validate_curve(r: float, tau: ArrayLike, kap: ArrayLike, source: str):
    where = f"{source}, curve r_g = {r:g}"
    t, k = check_curve(where, tau, kap, ("tau", "kappa"), 2)
    out = np.flatnonzero((t < TAU_RANGE[0]) | (t > TAU_RANGE[1]))
    if out.size:
        i = int(out[0])
        raise ParameterError(f"{where}: tau[{i}] = {t[i]:g}: allowed range is [-1, 1] (the "
                             "torque ratio; 1 is the traction limit)")
    bad = np.flatnonzero((k <= 0) | (k > 10))
    if bad.size:
        i = int(bad[0])
        raise ParameterError(f"{where}: kappa[{i}] = {k[i]:g}: allowed range is (0, 10] "
                             "(thrust ratio F_p / F_s)")
    return t, k


def load_thrust_ratio(path: str | os.PathLike[str]) -> TabulatedThrustRatio:
    """Read a thrust-ratio map from ``.csv`` (header ``r_g,tau,kappa``, rows with the same
    ``r_g`` form one curve) or ``.toml`` (``[[curve]]`` tables with ``r_g``, ``tau``,
    ``kappa``).  Raises `ParameterError` naming the file, row and value.

    Parameters
    ----------
    path : str or path-like
        The ``.csv`` or ``.toml`` map.

    Returns
    -------
    TabulatedThrustRatio
        ``kappa*(tau, r_g)`` [-] interpolated between the tabulated curves.
    """
    curves = read_curves(path, "thrust-ratio table", "tau", "kappa")
    items = sorted(curves.items())
    return TabulatedThrustRatio(ratios=tuple(r for r, _ in items),
                                tau_data=tuple(np.asarray(c[0], float) for _, c in items),
                                kappa_data=tuple(np.asarray(c[1], float) for _, c in items),
                                source=str(Path(path)))


def thrust_ratio_from_params(params: _HasThrustRatio) -> AnalyticThrustRatio:
    """The analytic map of a parameter set (its ``[thrust_ratio]`` section).

    Parameters
    ----------
    params : Params
        Its ``[variator]`` and ``[thrust_ratio]`` blocks are read.

    Returns
    -------
    AnalyticThrustRatio
        ``kappa*(tau, r_g)`` [-] of the analytic estimate (``p0, b0, b1``).
    """
    return AnalyticThrustRatio.from_params(params)


def zero_torque_difference(kmap: AnalyticThrustRatio | TabulatedThrustRatio,
                           variator: VariatorParams, r_g: ArrayLike) -> NDArray[np.float64]:
    """``kappa*(0, r_g) / kappa_geo(r_g) - 1`` [-]: how far the map's zero-torque thrust ratio
    lies from the elastic belt's geometric one (0 for the analytic map with ``p0 = 1``).  A
    non-zero value is a static shift force at zero load: ``F_s (kappa* - kappa_geo)``.

    Parameters
    ----------
    kmap : AnalyticThrustRatio or TabulatedThrustRatio
        The equilibrium thrust-ratio map.
    variator : VariatorParams
        The geometry of ``kappa_geo``.
    r_g : array_like
        Geometric ratio(s) [-], any shape.

    Returns
    -------
    ndarray
        The relative difference [-], the shape of `r_g`.
    """
    r = np.asarray(r_g, float)
    return kmap.kappa(np.zeros_like(r), r) / kappa_geo(r, variator) - 1


def ratio_stability(kmap: AnalyticThrustRatio | TabulatedThrustRatio, variator: VariatorParams,
                    mu_max: Callable[[NDArray], NDArray], r_g: ArrayLike, tau: ArrayLike,
                    dr: float = 1e-5) -> NDArray[np.float64]:
    """``d ln kappa* / d r_g`` at a fixed load torque and clamping force [-] (arrays
    broadcast): the static stability of the ratio with the servo torques held.

    With the servo torques held the actual thrust ratio stays put, and a ratio disturbance
    obeys ``d(delta r)/dt = -omega_p K_c (d ln kappa*/d r_g) delta r`` (model notes Sec. 9):
    the ratio is statically unstable where this derivative is negative.  Along the
    derivative the load torque and the clamping force are fixed, so the torque ratio
    ``tau = T_l cos(beta) / (2 mu_max F_s R_s)`` moves with the ratio as ``tau(r) = tau0
    mu_max(r0) R_s(r0) / (mu_max(r) R_s(r))`` (the unstretched belt's radii); central
    difference of relative step `dr`.

    Parameters
    ----------
    kmap : AnalyticThrustRatio or TabulatedThrustRatio
        The equilibrium thrust-ratio map.
    variator : VariatorParams
        The geometry.
    mu_max : callable
        The traction curve's peak value [-] over the ratio, vectorised (e.g.
        ``traction_from_params(params).mu_max``).
    r_g, tau : array_like
        Ratios [-] and torque ratios [-] of the operating points, broadcast together.
    dr : float
        Relative ratio step of the central difference [-].

    Returns
    -------
    ndarray
        ``d ln kappa* / d r_g`` [-] (per unit ratio), the broadcast shape of `r_g` and
        `tau`; negative where the ratio is statically unstable.
    """
    r, t = np.broadcast_arrays(np.asarray(r_g, float), np.asarray(tau, float))

    def capacity(rr):
        return np.asarray(mu_max(rr), float) * radii(rr, variator.L_belt, variator.a)[1]

    c0 = capacity(r)
    out = []
    for s in (1 + dr, 1 - dr):
        rr = r * s
        out.append(np.log(kmap.kappa(t * c0 / capacity(rr), rr)))
    return (out[0] - out[1]) / (2 * dr * r)


@dataclass(frozen=True)
class RatioStabilityMap(Result):
    """`ratio_stability` over a grid of torque ratios and ratios.

    Attributes
    ----------
    tau : torque ratios [-], shape (n_tau,)
    r_g : ratios [-], shape (n_r,)
    S : ``d ln kappa* / d r_g`` at fixed load torque [-], shape (n_r, n_tau); the ratio is
        statically unstable with the servo torques held where it is negative
    points : optional marked operating points ``(tau, r_g)`` (e.g. shipped set-points)
    """

    tau: NDArray[np.float64]
    r_g: NDArray[np.float64]
    S: NDArray[np.float64]
    points: tuple[tuple[float, float], ...] = ()

    @property
    def unstable_fraction(self) -> float:
        """Share of the grid where the ratio is statically unstable [-]."""
        return float(np.mean(self.S < 0))


def ratio_stability_map(kmap: AnalyticThrustRatio | TabulatedThrustRatio,
                        variator: VariatorParams, mu_max: Callable[[NDArray], NDArray],
                        tau: ArrayLike, r_g: ArrayLike,
                        points: tuple[tuple[float, float], ...] = ()) -> RatioStabilityMap:
    """`ratio_stability` on the grid ``r_g x tau`` (1-D arrays), with optional marked
    ``(tau, r_g)`` points.

    Parameters
    ----------
    kmap, variator, mu_max
        As `ratio_stability`: the equilibrium thrust-ratio map (analytic or tabulated), the
        geometry (`VariatorParams`) and the traction curve's peak value [-] over the ratio
        (a vectorised callable).
    tau : array_like, shape (n_tau,)
        Torque ratios [-].
    r_g : array_like, shape (n_r,)
        Geometric ratios [-].
    points : tuple of (tau, r_g) pairs
        Operating points to mark on the map (e.g. shipped set-points).

    Returns
    -------
    RatioStabilityMap
        ``S`` of shape (n_r, n_tau) [-] with the grid axes and the points.
    """
    t = np.atleast_1d(np.asarray(tau, float))
    r = np.atleast_1d(np.asarray(r_g, float))
    S = ratio_stability(kmap, variator, mu_max, r[:, None], t[None, :])
    return RatioStabilityMap(t, r, S, tuple((float(a), float(b)) for a, b in points))
