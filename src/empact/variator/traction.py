"""Traction curves ``mu(nu, r_g)`` of the pushbelt variator (paper Fig. 10).

The belt torque (paper eq. 1) is ``T_b = 2 mu(nu, r_g) F_s R_s / cos(beta)``; its linearisation
(eq. 3) needs the slope ``mu' = d mu / d nu``.  A traction model is any object with

``mu(nu, r_g)``
    traction coefficient [-], vectorised: `nu` (slip [-], a fraction: 0.01 is 1 %) and `r_g`
    (geometric ratio [-]) broadcast against each other;
``dmu(nu, r_g)``
    its exact slope ``d mu / d nu`` [-] (the derivative of the model as implemented, not a
    finite difference);
``nu_range``
    ``(nu_min, nu_max)``, the slips where the model is valid; both methods raise
    `~empact.params.ParameterError` naming the value and the range for a slip outside it.

The models provided:

`AnalyticTraction`
    Any analytic law of the registry (`empact.variator._laws.TRACTION_LAWS`; the law's own
    plain-Python functions evaluated on arrays), its coefficients given at the LOW, MED and
    OD ratios of ``[traction]`` and interpolated linearly in ``log(r_g)`` between them.
    `traction_from_params` builds it for a law by name (default ``"magic-formula"``).

`MagicFormulaTraction`
    The registry's ``"magic-formula"``, by its four coefficients: a Pacejka-type "magic
    formula", smooth and odd in ``nu``::

        phi(nu) = B nu - E (B nu - arctan(B nu))
        mu(nu)  = D sin(C arctan(phi))
        mu'(nu) = D C cos(C arctan(phi)) / (1 + phi^2) * B (1 - E + E / (1 + (B nu)^2))

    ``D`` is the peak traction coefficient, ``B D C`` the slope at ``nu = 0``, ``C`` sets how far
    ``mu`` falls beyond the peak (``C = 1``: no fall) and ``E`` shapes the knee (``E = 0``, the
    shipped curve: a micro-slip slope up to the peak; ``E`` close to 1: a steep rise and a flat
    top).  The four coefficients are
    given at three ratios (LOW, MED, OD) and interpolated *linearly in log(r_g)* between them,
    held constant outside (``numpy.interp`` on ``log(r_g)``); `MagicFormulaTraction.coefficients`
    returns them, for re-implementation elsewhere (e.g. a compiled simulation kernel).

`TabulatedTraction`
    A user's measured curves, one per ratio, from CSV (columns ``r_g,nu,mu``) or TOML
    (``[[curve]]`` tables with ``r_g = ...``, ``nu = [...]``, ``mu = [...]``).  Shape-preserving
    PCHIP interpolation in ``nu`` (no overshoot between samples, monotone where the data are),
    the slope is the derivative of that interpolant; linear in ``r_g`` between the tabulated
    ratios, held constant outside.  A curve that starts at ``nu = 0`` with ``mu = 0`` is
    extended oddly to negative slip (``mu(-nu) = -mu(nu)``).  ``mu_max(r_g)`` is the true
    peak of the interpolated curve at that ratio (the torque ratio is ``tau = mu / mu_max``).
    The nonlinear model evaluates the same law compiled (`TabulatedTraction.encode`, the
    option ``traction`` of `empact.nonlinear.nonlinear_model`).

`traction_from_params` builds the analytic model of a parameter set (section ``[traction]``).
Compute only: plots are in `empact.plotting.slip`.
"""
from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping, Protocol, Sequence, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._lazy import lazy_module
from .._section import Section, param
from ..errors import ParameterError
from . import _laws
from ._tables import check_curve, interp_knots, knot_segments, read_curves

interpolate = lazy_module("scipy.interpolate")
#: the compiled law (numba: loaded when a peak is first asked for)
_compiled = lazy_module("empact.variator._traction_table")

__all__ = ["TractionParams", "TractionModel", "AnalyticTraction", "MagicFormulaTraction",
           "TabulatedTraction", "TractionCurves", "traction_from_params", "traction_parameters",
           "load_traction", "traction_curves", "TRACTION_LAWS", "DEFAULT_TRACTION_LAW",
           "MAGIC_NU_MAX"]

#: the analytic traction laws by name (the registry, `empact.variator._laws.TRACTION_LAWS`),
#: the first the default: the choices of ``ModelOptions(traction_law=...)`` and
#: ``--traction-law``
TRACTION_LAWS = _laws.TRACTION_LAWS
#: the default analytic traction law (the first registered)
DEFAULT_TRACTION_LAW = "magic-formula"


@dataclass(frozen=True)
class TractionParams(Section):
    """Analytic traction curve mu(nu, r_g) (Fig. 10), a Pacejka-type magic formula.

    ``mu = D sin(C arctan(B nu - E (B nu - arctan(B nu))))``; B, C, D, E are given at the
    LOW, MED and OD ratios and interpolated linearly in log(r_g) in between (held
    constant outside).

    Attributes
    ----------
    r_low, r_med, r_od : float
        The LOW, MED and OD geometric ratios [-] where the ``*_low``, ``*_med`` and ``*_od``
        coefficients hold, strictly increasing.
    B_low, B_med, B_od : float
        Stiffness factor ``B`` [-] at LOW, MED and OD.
    C_low, C_med, C_od : float
        Shape factor ``C`` [-] at LOW, MED and OD, in [1, 2] (1: no fall beyond the peak).
    D_low, D_med, D_od : float
        Peak traction coefficient ``D`` [-] at LOW, MED and OD.
    E_low, E_med, E_od : float
        Curvature factor ``E`` [-] at LOW, MED and OD, in [-10, 1] (the knee's shape).
    """

    _name = "traction"
    r_low: float = param("-", "LOW ratio where the *_low coefficients hold", 0.05, 20.0)
    r_med: float = param("-", "MED ratio where the *_med coefficients hold", 0.05, 20.0)
    r_od: float = param("-", "OD ratio where the *_od coefficients hold", 0.05, 20.0)
    B_low: float = param("-", "stiffness factor at LOW", 1.0, 1e6)
    B_med: float = param("-", "stiffness factor at MED", 1.0, 1e6)
    B_od: float = param("-", "stiffness factor at OD", 1.0, 1e6)
    C_low: float = param("-", "shape factor at LOW", 1.0, 2.0, lo_open=False)
    C_med: float = param("-", "shape factor at MED", 1.0, 2.0, lo_open=False)
    C_od: float = param("-", "shape factor at OD", 1.0, 2.0, lo_open=False)
    D_low: float = param("-", "peak traction coefficient at LOW", 0.0, 1.0)
    D_med: float = param("-", "peak traction coefficient at MED", 0.0, 1.0)
    D_od: float = param("-", "peak traction coefficient at OD", 0.0, 1.0)
    E_low: float = param("-", "curvature factor at LOW", -10.0, 1.0, lo_open=False)
    E_med: float = param("-", "curvature factor at MED", -10.0, 1.0, lo_open=False)
    E_od: float = param("-", "curvature factor at OD", -10.0, 1.0, lo_open=False)

    def __post_init__(self) -> None:
        super().__post_init__()
        if not self.r_low < self.r_med < self.r_od:
            raise ParameterError(
                f"traction.r_med = {self.r_med!r}: must lie strictly between r_low = "
                f"{self.r_low!r} and r_od = {self.r_od!r}")


class _HasTraction(Protocol):
    @property
    def traction(self) -> TractionParams: ...

#: Slip range [-] in which the magic formula is used: beyond 20 % slip a pushbelt is destroyed
#: (gross slip); the formula would be pure extrapolation there.
MAGIC_NU_MAX = 0.2

#: Fewest samples per tabulated curve.
MIN_POINTS = 3


@runtime_checkable
class TractionModel(Protocol):
    """What the slip model needs of a traction curve (see the module docstring).

    Attributes
    ----------
    nu_range : (nu_min, nu_max)
        The slips [-] where the model is valid; ``mu`` and ``dmu`` raise `ParameterError`
        for a slip outside it.
    """

    @property
    def nu_range(self) -> tuple[float, float]: ...

    def mu(self, nu: ArrayLike, r_g: ArrayLike) -> NDArray[np.float64]:
        """Traction coefficient [-].

        Parameters
        ----------
        nu : array_like
            Slip [-] (a fraction), in `nu_range`.
        r_g : array_like
            Geometric ratio ``R_p / R_s`` [-], broadcast with `nu`.
        """

    def dmu(self, nu: ArrayLike, r_g: ArrayLike) -> NDArray[np.float64]:
        """Slope ``d mu / d nu`` [-].

        Parameters
        ----------
        nu, r_g : array_like
            Slip [-] in `nu_range` and geometric ratio [-], broadcast together.
        """


def _fmt_range(lo: float, hi: float) -> str:
    return f"[{lo:g}, {hi:g}]"


def _check_inputs(nu: ArrayLike, r_g: ArrayLike, nu_range: tuple[float, float],
                  what: str) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Broadcast `nu`, `r_g`; `ParameterError` for a slip outside `nu_range` or a bad ratio."""
    nu_a, r_a = np.broadcast_arrays(np.asarray(nu, float), np.asarray(r_g, float))
    lo, hi = nu_range
    bad = ~np.isfinite(nu_a) | (nu_a < lo) | (nu_a > hi)
    if np.any(bad):
        value = float(nu_a[bad].flat[0])
        raise ParameterError(f"nu = {value:g}: outside the valid slip range {_fmt_range(lo, hi)} "
                             f"of {what}")
    bad = ~np.isfinite(r_a) | (r_a <= 0)
    if np.any(bad):
        raise ParameterError(f"r_g = {float(r_a[bad].flat[0]):g}: must be a positive finite ratio")
    return nu_a, r_a


# --------------------------------------------------------------------------------------------
# Analytic model
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class AnalyticTraction:
    """A registered analytic traction law with coefficients interpolated over the ratio.

    Parameters
    ----------
    law : str
        The law's name, one of `TRACTION_LAWS` (`empact.variator._laws.TRACTION_LAWS`).
    ratios : tuple of float, length 3
        LOW, MED, OD ratios [-] where the coefficients hold (strictly increasing).
    knots : tuple of tuples of float, shape (m, 3)
        Each of the law's coefficients (its order) at those ratios.
    nu_max : float
        Valid slip range is ``[-nu_max, nu_max]`` [-].

    Examples
    --------
    >>> from empact.params import default_params
    >>> tr = traction_from_params(default_params(), "magic-formula")
    >>> float(tr.mu(0.0, 1.0))
    0.0
    """

    law: str
    ratios: tuple[float, float, float]
    knots: tuple[tuple[float, float, float], ...]
    nu_max: float = MAGIC_NU_MAX

    def __post_init__(self) -> None:
        spec = _laws.TRACTION_LAWS.get(self.law)
        if spec is None:
            raise ParameterError(f"traction law {self.law!r}: choose from "
                                 f"{', '.join(_laws.TRACTION_LAWS)}")
        if len(self.knots) != len(spec.coefficients):
            raise ParameterError(f"traction law {self.law!r}: need {len(spec.coefficients)} "
                                 f"coefficients ({', '.join(spec.coefficients)}), got "
                                 f"{len(self.knots)}")
        for name, values in zip(("ratios",) + spec.coefficients, (self.ratios,) + self.knots):
            value = tuple(float(x) for x in values)
            if len(value) != 3 or not all(math.isfinite(x) for x in value):
                raise ParameterError(f"{type(self).__name__}.{name} = {value!r}: need three "
                                     "finite values (LOW, MED, OD)")
        object.__setattr__(self, "ratios", tuple(float(x) for x in self.ratios))
        object.__setattr__(self, "knots", tuple(tuple(float(x) for x in k) for k in self.knots))
        if not 0 < self.ratios[0] < self.ratios[1] < self.ratios[2]:
            raise ParameterError(f"{type(self).__name__}.ratios = {self.ratios!r}: must be "
                                 "positive and strictly increasing")
        if not (math.isfinite(self.nu_max) and 0 < self.nu_max < 1):
            raise ParameterError(f"{type(self).__name__}.nu_max = {self.nu_max!r}: allowed "
                                 "range is (0, 1)")

    @property
    def nu_range(self) -> tuple[float, float]:
        """Valid slip range ``(-nu_max, nu_max)`` [-]."""
        return (-self.nu_max, self.nu_max)

    def coefficients(self, r_g: ArrayLike) -> tuple[NDArray[np.float64], ...]:
        """The law's coefficients at ratio(s) `r_g`, each shaped like `r_g` (its order: for
        the magic formula ``(B, C, D, E)``).

        Linear interpolation in ``log(r_g)`` between the LOW, MED and OD values, constant
        outside (`empact.variator._tables.interp_knots`: the compiled kernel's numbers).

        Parameters
        ----------
        r_g : array_like
            Geometric ratio(s) [-].
        """
        r = np.asarray(r_g, float)
        if np.any(~np.isfinite(r) | (r <= 0)):
            bad = r[~np.isfinite(r) | (r <= 0)] if r.ndim else r
            raise ParameterError(f"r_g = {float(np.ravel(bad)[0]):g}: must be a positive finite "
                                 "ratio")
        x, xp = np.log(r), np.log(self.ratios)
        seg = knot_segments(x, xp)
        return tuple(interp_knots(x, xp, k, seg) for k in self.knots)

    def mu_max(self, r_g: ArrayLike) -> NDArray[np.float64]:
        """The curve's peak value [-] (the law's ``peak_d``; the magic formula's ``D(r_g)``):
        the torque ratio is ``tau = mu / mu_max``, as the compiled model computes it.

        Parameters
        ----------
        r_g : array_like
            Geometric ratio(s) [-].
        """
        c = self.coefficients(r_g)
        return np.asarray(self._spec.peak_d(*c, *(0.0 * x for x in c))[0], float)

    def mu(self, nu: ArrayLike, r_g: ArrayLike) -> NDArray[np.float64]:
        """Traction coefficient [-] (the law's ``mu``), shape of ``broadcast(nu, r_g)``.

        Parameters
        ----------
        nu : array_like
            Slip [-], within `nu_range`.
        r_g : array_like
            Geometric ratio [-] (broadcast against `nu`).
        """
        nu_a, c = self._at(nu, r_g)
        return self._spec.mu(nu_a, *c)

    def dmu(self, nu: ArrayLike, r_g: ArrayLike) -> NDArray[np.float64]:
        """Slope ``d mu / d nu`` [-] (analytic: the law's ``mu_d``), shape of
        ``broadcast(nu, r_g)``.

        Parameters
        ----------
        nu, r_g : array_like
            Slip [-] within `nu_range` and geometric ratio [-], broadcast together.
        """
        nu_a, c = self._at(nu, r_g)
        return self._spec.mu_d(nu_a, *c, *(0.0 for _ in c))[1]

    @property
    def _spec(self) -> _laws.TractionLaw:
        return _laws.TRACTION_LAWS[self.law]

    def _at(self, nu: ArrayLike, r_g: ArrayLike) \
            -> tuple[NDArray[np.float64], tuple[NDArray[np.float64], ...]]:
        """``(nu, coefficients)`` at the checked, broadcast slips and ratios."""
        nu_a, r_a = _check_inputs(nu, r_g, self.nu_range, f"the {self.law} traction curve")
        return nu_a, self.coefficients(r_a)


class MagicFormulaTraction(AnalyticTraction):
    """The magic-formula traction curve (the registry's ``"magic-formula"``) by its
    coefficients, interpolated over the ratio.

    Parameters
    ----------
    ratios : tuple of float, length 3
        LOW, MED, OD ratios [-] where the coefficients hold (strictly increasing).
    B, C, D, E : tuple of float, length 3
        Stiffness, shape, peak and curvature factors [-] at those ratios.
    nu_max : float
        Valid slip range is ``[-nu_max, nu_max]`` [-].

    Examples
    --------
    >>> from empact.params import default_params
    >>> tr = MagicFormulaTraction.from_params(default_params().traction)
    >>> float(tr.mu(0.0, 1.0))
    0.0
    """

    def __init__(self, ratios: Sequence[float], B: Sequence[float], C: Sequence[float],
                 D: Sequence[float], E: Sequence[float], nu_max: float = MAGIC_NU_MAX) -> None:
        for name, value in (("ratios", ratios), ("B", B), ("C", C), ("D", D), ("E", E)):
            if len(tuple(value)) != 3:
                raise ParameterError(f"MagicFormulaTraction.{name} = {tuple(value)!r}: need "
                                     "three finite values (LOW, MED, OD)")
        super().__init__("magic-formula", tuple(ratios),  # type: ignore[arg-type]
                         (tuple(B), tuple(C), tuple(D), tuple(E)),  # type: ignore[arg-type]
                         nu_max)

    @property
    def B(self) -> tuple[float, float, float]:
        """Stiffness factor [-] at LOW, MED, OD."""
        return self.knots[0]

    @property
    def C(self) -> tuple[float, float, float]:
        """Shape factor [-] at LOW, MED, OD."""
        return self.knots[1]

    @property
    def D(self) -> tuple[float, float, float]:
        """Peak traction coefficient [-] at LOW, MED, OD."""
        return self.knots[2]

    @property
    def E(self) -> tuple[float, float, float]:
        """Curvature factor [-] at LOW, MED, OD."""
        return self.knots[3]

    @classmethod
    def from_params(cls, traction: TractionParams, nu_max: float = MAGIC_NU_MAX) \
            -> "MagicFormulaTraction":
        """The model of a ``[traction]`` parameter section.

        Parameters
        ----------
        traction : TractionParams
            The ``[traction]`` section.
        nu_max : float, optional
            The valid slip range is ``[-nu_max, nu_max]`` [-] (default 0.2).

        Returns
        -------
        MagicFormulaTraction
            The magic formula at the section's three ratios.
        """
        t = traction
        return cls(ratios=(t.r_low, t.r_med, t.r_od), B=(t.B_low, t.B_med, t.B_od),
                   C=(t.C_low, t.C_med, t.C_od), D=(t.D_low, t.D_med, t.D_od),
                   E=(t.E_low, t.E_med, t.E_od), nu_max=nu_max)


def traction_parameters(traction: TractionParams, law: str) -> dict[str, float]:
    """The traction laws' part of the nonlinear kernel's parameter vector, by name
    (`empact.variator._laws.traction_parameter_names`): the law's index, the knots'
    log-ratios and every registered law's coefficients from the section's fields.

    Parameters
    ----------
    traction : TractionParams
        The ``[traction]`` section.
    law : str
        The analytic law the kernel evaluates, one of `TRACTION_LAWS`.

    Returns
    -------
    dict of str to float
        ``traction_law`` (the law's index), ``ln_r_low`` ... and ``<c>_low`` ... [SI].
    """
    if law not in _laws.TRACTION_LAWS:
        raise ParameterError(f"traction_law = {law!r}: choose from "
                             f"{', '.join(_laws.TRACTION_LAWS)}")
    values = {"traction_law": float(list(_laws.TRACTION_LAWS).index(law))}
    for knot in _laws.TRACTION_KNOTS:
        values[f"ln_r_{knot}"] = float(np.log(getattr(traction, f"r_{knot}")))
    for name in _laws.traction_parameter_names()[1 + len(_laws.TRACTION_KNOTS):]:
        values[name] = float(getattr(traction, name))
    return values


# --------------------------------------------------------------------------------------------
# Tabulated model
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class TabulatedTraction:
    """Measured traction curves, one per ratio, interpolated shape-preservingly.

    Parameters
    ----------
    ratios : tuple of float, shape (k,)
        Tabulated ratios [-], strictly increasing.
    nu_data : tuple of arrays
        Slip samples [-] of each curve, strictly increasing, at least 3.
    mu_data : tuple of arrays
        Traction coefficients [-] of each curve, in [0, 1] (in [-1, 0] where ``nu < 0``).
        After construction both hold the samples actually interpolated (with the odd
        extension).
    source : str
        Where the table came from (used in messages).

    Notes
    -----
    In ``nu``: `scipy.interpolate.PchipInterpolator` per curve (after the odd extension when a
    curve starts at ``(0, 0)``); ``dmu`` evaluates ``PchipInterpolator.derivative()``, so it is
    the exact slope of the interpolant.  In ``r_g``: linear between neighbouring tabulated
    ratios, constant outside.  ``nu_range`` is the intersection of the curves' slip ranges.
    Use `from_curves` or `load_traction` rather than the constructor.
    """

    ratios: tuple[float, ...]
    nu_data: tuple[NDArray[np.float64], ...]
    mu_data: tuple[NDArray[np.float64], ...]
    source: str = "traction table"
    # scipy.interpolate.PchipInterpolator per curve (scipy is untyped here)
    _interp: tuple[Any, ...] = field(init=False, repr=False, compare=False)
    _slope: tuple[Any, ...] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        ratios = tuple(float(r) for r in self.ratios)
        if len(ratios) == 0 or len(ratios) != len(self.nu_data) \
                or len(ratios) != len(self.mu_data):
            raise ParameterError(f"{self.source}: need one (nu, mu) curve per ratio, got "
                                 f"{len(ratios)} ratios")
        for r in ratios:
            if not (math.isfinite(r) and r > 0):
                raise ParameterError(f"{self.source}: r_g = {r!r}: must be a positive finite ratio")
        if any(b <= a for a, b in zip(ratios, ratios[1:])):
            raise ParameterError(f"{self.source}: ratios {ratios!r} must be distinct and "
                                 "increasing")
        nus, mus, interp, slope = [], [], [], []
        for r, nu, mu in zip(ratios, self.nu_data, self.mu_data):
            nu, mu = _validate_curve(r, nu, mu, self.source)
            if nu[0] == 0.0 and mu[0] == 0.0:  # odd extension to negative slip
                nu = np.concatenate([-nu[:0:-1], nu])
                mu = np.concatenate([-mu[:0:-1], mu])
            p = interpolate.PchipInterpolator(nu, mu, extrapolate=False)
            nus.append(nu)
            mus.append(mu)
            interp.append(p)
            slope.append(p.derivative())
        object.__setattr__(self, "ratios", ratios)
        object.__setattr__(self, "nu_data", tuple(nus))
        object.__setattr__(self, "mu_data", tuple(mus))
        object.__setattr__(self, "_interp", tuple(interp))
        object.__setattr__(self, "_slope", tuple(slope))

    # -- construction ---------------------------------------------------------------------
    @classmethod
    def from_curves(cls, curves: Mapping[float, tuple[ArrayLike, ArrayLike]],
                    source: str = "traction table") -> "TabulatedTraction":
        """From ``{r_g: (nu, mu)}`` (curves in any order of ratio).

        Parameters
        ----------
        curves : mapping of float to (array_like, array_like)
            Ratio ``r_g`` [-] to the curve's slips ``nu`` [-] and traction coefficients ``mu``
            [-].
        source : str, optional
            What the messages call the table (default ``"traction table"``).
        """
        items = sorted(((float(r), c) for r, c in curves.items()), key=lambda t: t[0])
        return cls(ratios=tuple(r for r, _ in items),
                   nu_data=tuple(np.asarray(c[0], float) for _, c in items),
                   mu_data=tuple(np.asarray(c[1], float) for _, c in items), source=source)

    # -- evaluation -----------------------------------------------------------------------
    @property
    def nu_range(self) -> tuple[float, float]:
        """Slip range [-] covered by every curve."""
        return (max(float(n[0]) for n in self.nu_data), min(float(n[-1]) for n in self.nu_data))

    def _weights(self, r: NDArray[np.float64]) -> NDArray[np.float64]:
        """Interpolation weights over the curves, shape ``r.shape + (k,)`` (linear in r_g)."""
        k = len(self.ratios)
        w = np.zeros(r.shape + (k,))
        if k == 1:
            w[..., 0] = 1.0
            return w
        rp = np.asarray(self.ratios)
        rc = np.clip(r, rp[0], rp[-1])
        j = np.clip(np.searchsorted(rp, rc, side="right") - 1, 0, k - 2)
        t = (rc - rp[j]) / (rp[j + 1] - rp[j])
        np.put_along_axis(w, j[..., None], (1 - t)[..., None], axis=-1)
        np.put_along_axis(w, (j + 1)[..., None], t[..., None], axis=-1)
        return w

    def _evaluate(self, nu: ArrayLike, r_g: ArrayLike,
                  funcs: Sequence[Any]) -> NDArray[np.float64]:
        nu_a, r_a = _check_inputs(nu, r_g, self.nu_range, self.source)
        w = self._weights(r_a)
        out = np.zeros(nu_a.shape)
        for i, f in enumerate(funcs):
            wi = w[..., i]
            used = wi != 0
            if np.any(used):
                out[used] += wi[used] * f(nu_a[used])
        return out

    def mu(self, nu: ArrayLike, r_g: ArrayLike) -> NDArray[np.float64]:
        """Traction coefficient [-], shape of ``broadcast(nu, r_g)``.

        Parameters
        ----------
        nu : array_like
            Slip [-], within `nu_range` (the slips every curve covers).
        r_g : array_like
            Geometric ratio [-] (broadcast against `nu`; held at the end curves outside).
        """
        return self._evaluate(nu, r_g, self._interp)

    def dmu(self, nu: ArrayLike, r_g: ArrayLike) -> NDArray[np.float64]:
        """Slope ``d mu / d nu`` of the interpolant [-], shape of ``broadcast(nu, r_g)``.

        Parameters
        ----------
        nu, r_g : array_like
            As `mu`'s.
        """
        return self._evaluate(nu, r_g, self._slope)

    def encode(self) -> NDArray[np.float64]:
        """Flat encoding for the compiled model (layout in `empact.variator._traction_table`):
        the ratios, and per curve the knots, values and the knot slopes of its
        `~scipy.interpolate.PchipInterpolator`, and its segments by their larger knot value,
        largest first."""
        head = [float(len(self.ratios)), *self.ratios]
        starts: list[float] = []
        body: list[float] = []
        for nu, mu, slope in zip(self.nu_data, self.mu_data, self._slope):
            starts.append(float(3 + 2 * len(self.ratios) + len(body)))
            order = np.argsort(-np.maximum(mu[:-1], mu[1:]), kind="stable")
            body += [float(len(nu)), *nu, *mu, *np.asarray(slope(nu), float),
                     *order.astype(float)]
        return np.array(head + starts + list(self.nu_range) + body, dtype=float)

    def peak(self, r_g: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Slip [-] and value [-] of the interpolated curve's peak at ratio(s) `r_g`, each
        shaped like `r_g`.

        The true largest value of ``mu(., r_g)`` over `nu_range` (the slips every curve
        covers), found exactly on the piecewise-cubic interpolant by the compiled law the
        nonlinear model uses (`empact.variator._traction_table.table_peak`).

        Parameters
        ----------
        r_g : array_like
            Geometric ratio(s) [-], > 0.

        Returns
        -------
        nu_peak, mu_peak : ndarray
            Slip [-] and traction coefficient [-] at the peak, each shaped like `r_g`.
        """
        r = np.asarray(r_g, float)
        if np.any(~np.isfinite(r) | (r <= 0)):
            bad = r[~np.isfinite(r) | (r <= 0)] if r.ndim else r
            raise ParameterError(f"r_g = {float(np.ravel(bad)[0]):g}: must be a positive finite "
                                 "ratio")
        flat = np.ascontiguousarray(r.ravel())
        n = flat.size
        mu, dmu, nu_pk, mu_pk = (np.empty(n) for _ in range(4))
        _compiled.table_many(np.full(n, float(self.nu_data[0][0])), flat, self.encode(), 0, mu,
                             dmu, nu_pk, mu_pk)
        return nu_pk.reshape(r.shape), mu_pk.reshape(r.shape)

    def mu_max(self, r_g: ArrayLike) -> NDArray[np.float64]:
        """Peak traction coefficient ``mu_max(r_g)`` [-] of the interpolated curve at each
        ratio (`peak`), shaped like `r_g`: the torque ratio is ``tau = mu / mu_max``, as the
        compiled model computes it.

        Parameters
        ----------
        r_g : array_like
            Geometric ratio(s) [-], > 0.
        """
        return self.peak(r_g)[1]


def _validate_curve(r: float, nu: ArrayLike, mu: ArrayLike, source: str) \
        -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Check one tabulated curve; raise `ParameterError` with a one-line reason."""
    where = f"{source}, curve r_g = {r:g}"
    nu_a, mu_a = check_curve(where, nu, mu, ("nu", "mu"), MIN_POINTS)
    if np.any(np.abs(nu_a) >= 1):
        i = int(np.flatnonzero(np.abs(nu_a) >= 1)[0])
        raise ParameterError(f"{where}: nu[{i}] = {nu_a[i]:g}: allowed range is (-1, 1)")
    lo = np.where(nu_a < 0, -1.0, 0.0)
    hi = np.where(nu_a < 0, 0.0, 1.0)
    bad = np.flatnonzero((mu_a < lo) | (mu_a > hi))
    if bad.size:
        i = int(bad[0])
        allowed = "[-1, 0] where nu < 0" if nu_a[i] < 0 else "[0, 1]"
        raise ParameterError(f"{where}: mu[{i}] = {mu_a[i]:g} (at nu = {nu_a[i]:g}): allowed "
                             f"range is {allowed}")
    return nu_a, mu_a


def load_traction(path: str | os.PathLike[str]) -> TabulatedTraction:
    """Read tabulated traction curves from a ``.csv`` or ``.toml`` file.

    CSV: a header with the columns ``r_g``, ``nu``, ``mu`` (any order, further columns are an
    error), one sample per row; rows with the same ``r_g`` form one curve, in file order.
    TOML: ``[[curve]]`` tables, each with ``r_g = <float>``, ``nu = [...]``, ``mu = [...]``.
    Slip ``nu`` is a fraction (0.01 is 1 %).

    Parameters
    ----------
    path : str or path-like
        The ``.csv`` or ``.toml`` file.

    Returns
    -------
    TabulatedTraction
        ``mu(nu, r_g)`` [-], the curves interpolated shape-preservingly (one per ratio).

    Raises
    ------
    ParameterError
        For a missing file, a bad format, or a curve that `TabulatedTraction` refuses.
    """
    curves = read_curves(path, "traction table", "nu", "mu")
    return TabulatedTraction.from_curves(curves, source=str(Path(path)))


def traction_from_params(params: _HasTraction | TractionParams,
                         law: str = DEFAULT_TRACTION_LAW) -> AnalyticTraction:
    """The analytic traction model of a parameter set (its ``[traction]`` section), or of the
    section itself.

    Parameters
    ----------
    params : Params or TractionParams
        A parameter set (its ``[traction]`` block is read) or the block itself.
    law : str, optional
        The registered law (`TRACTION_LAWS`; default ``"magic-formula"``).

    Returns
    -------
    AnalyticTraction
        ``mu(nu, r_g)`` [-] and its slope, by the law at the block's three ratios.
    """
    section = params if isinstance(params, TractionParams) else params.traction
    if law not in _laws.TRACTION_LAWS:
        raise ParameterError(f"traction_law = {law!r}: choose from "
                             f"{', '.join(_laws.TRACTION_LAWS)}")
    ratios = tuple(getattr(section, f"r_{k}") for k in _laws.TRACTION_KNOTS)
    knots = tuple(tuple(getattr(section, f"{c}_{k}") for k in _laws.TRACTION_KNOTS)
                  for c in _laws.TRACTION_LAWS[law].coefficients)
    return AnalyticTraction(law, ratios, knots)


# --------------------------------------------------------------------------------------------
# Result object for Fig. 10
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class TractionCurves:
    """Traction curves sampled for display (Fig. 10).

    Attributes
    ----------
    nu : slip [-], shape (n_nu,)
    r_g : ratios [-], shape (n_r,)
    mu : traction coefficient [-], shape (n_r, n_nu)
    dmu : slope ``d mu / d nu`` [-], shape (n_r, n_nu)
    label : name of the model
    """

    nu: NDArray[np.float64]
    r_g: NDArray[np.float64]
    mu: NDArray[np.float64]
    dmu: NDArray[np.float64]
    label: str = ""

    def peak(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Slip [-] and value [-] of the largest ``mu`` of each curve, shapes (n_r,)."""
        j = np.argmax(self.mu, axis=1)
        return self.nu[j], self.mu[np.arange(len(self.r_g)), j]


def traction_curves(traction: TractionModel, r_g: ArrayLike, nu: ArrayLike,
                    label: str = "") -> TractionCurves:
    """Sample `traction` at ratios `r_g` (shape (n_r,)) and slips `nu` (shape (n_nu,)).

    Parameters
    ----------
    traction : TractionModel
        Analytic (`traction_from_params`) or tabulated (`load_traction`).
    r_g : array_like
        Ratios [-], shape (n_r,).
    nu : array_like
        Slips [-] (0.01 is 1 %), shape (n_nu,).
    label : str
        Free text for plots.

    Returns
    -------
    TractionCurves
        ``mu`` and ``dmu`` (d mu / d nu), shape (n_r, n_nu) [-].
    """
    r = np.atleast_1d(np.asarray(r_g, float))
    n = np.atleast_1d(np.asarray(nu, float))
    return TractionCurves(nu=n, r_g=r, mu=traction.mu(n[None, :], r[:, None]),
                          dmu=traction.dmu(n[None, :], r[:, None]), label=label)
