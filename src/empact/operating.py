"""The operating point of the variator: the one type every analysis is taken at (the slip
model's point, a trim request, a scenario's ``[initial]`` table, the ``[operating]`` section of
a parameter file), its resolved form with every slip-model variable a float, and the rules on
its variables (one slip spelling, a positive clamping force), each checked in one place.

Split out of `empact.params` (which re-exports every name here); a parameter set reaches it
only through the attributes `resolve` and `from_params` read (`variator`, `traction`,
`operating`).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any, Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ._deprecate import warn_renamed
from ._lazy import lazy_module
from ._section import Section, param
from ._validate import check_values
from .errors import ParameterError
from .variator.geometry import VariatorParams, variator_state
from .variator.traction import TractionParams, traction_from_params

__all__ = ["OPERATING_VARIABLES", "OperatingPoint", "ResolvedPoint", "CruisePoint",
           "check_clamping",
           "check_one_slip", "curve_peak"]

optimize = lazy_module("scipy.optimize")


class _Machine(Protocol):
    """What an operating point reads of a parameter set (`empact.params.Params`)."""

    @property
    def variator(self) -> VariatorParams: ...

    @property
    def traction(self) -> TractionParams: ...

    @property
    def operating(self) -> "OperatingPoint": ...


#: Operating-point variables: unit and description (names as in the paper).  An operating
#: point gives the ratio, the primary speed and exactly two of: the slip (as ``nu`` or as the
#: torque ratio ``tau``), the clamping force ``F_s`` and the load torque ``T_l``.
OPERATING_VARIABLES = {"r_g": ("-", "geometric ratio R_p / R_s"),
                       "nu": ("-", "slip (fraction, 0.01 is 1 %)"),
                       "F_s": ("N", "secondary clamping force"),
                       "omega_p": ("rad/s", "primary pulley speed"),
                       "T_l": ("N m", "load torque (the belt torque on the secondary at steady "
                                      "state)"),
                       "tau": ("-", "torque ratio mu(nu) / mu_max: the share of the traction "
                                    "capacity in use (the torque reserve is 1 - tau)")}

#: the variables that fix a point besides r_g and omega_p (two of them; nu or tau, not both)
_SLIP = ("nu", "tau")


@dataclass(frozen=True)
class OperatingPoint(Section):
    """An operating point of the variator (names as in the paper), validated on construction.

    The one operating-point type of empact: the ``[operating]`` table of a parameter file, the
    point of the slip model, a scenario's ``[initial]`` table and the trim request of the
    nonlinear model.  It gives the ratio ``r_g``, the primary speed ``omega_p`` and exactly
    two of: the slip (``nu``, or the torque ratio ``tau``, which is how a clamping strategy
    states it), the clamping force ``F_s`` and the load torque ``T_l``; the trim
    (`empact.nonlinear.equilibrium.trim`) solves the third.  `resolve` completes a point on the
    variator's unstretched geometry (what the linear slip model uses).

    Attributes
    ----------
    r_g : geometric ratio ``R_p / R_s`` [-], > 0 (checked against the variator where used)
    nu : slip [-] (a fraction: 0.01 is 1 %), in (-1, 1), or None
    F_s : secondary clamping force [N], >= 0, or None
    omega_p : primary pulley speed [rad/s], > 0 (eq. 2 is undefined at standstill)
    T_l : load torque [N m], or None
    tau : torque ratio ``mu(nu) / mu_max`` [-] in [-1, 1] (1: the traction limit), or None

    Examples
    --------
    >>> OperatingPoint(r_g=1.0, nu=0.01, F_s=10e3, omega_p=300.0).given
    ('nu', 'F_s')
    >>> OperatingPoint(r_g=1.0, omega_p=300.0, tau=0.9, T_l=80.0).given
    ('T_l', 'tau')
    """

    _name = "operating"
    r_g: float = param("-", OPERATING_VARIABLES["r_g"][1])
    nu: float | None = param("-", OPERATING_VARIABLES["nu"][1], -1.0, 1.0, hi_open=True,
                             default=None)
    F_s: float | None = param("N", OPERATING_VARIABLES["F_s"][1], lo_open=False, default=None)
    omega_p: float = param("rad/s", OPERATING_VARIABLES["omega_p"][1],
                           note="the slip nu = 1 - omega_s / (r_g omega_p) of eq. 2 is "
                                "undefined at standstill", default=None)
    T_l: float | None = param("N m", OPERATING_VARIABLES["T_l"][1], -math.inf,
                              default=None)
    tau: float | None = param("-", OPERATING_VARIABLES["tau"][1], -1.0, 1.0, lo_open=False,
                              default=None)

    def __post_init__(self) -> None:
        if self.omega_p is None:
            raise ParameterError("operating point: omega_p (primary speed [rad/s]) is missing")
        super().__post_init__()
        check_one_slip(self.nu is not None, self.tau is not None, where="operating point: ")
        given = self.given
        if len(given) != 2:
            shown = ", ".join(f"{k} = {getattr(self, k):g}" for k in given) or "none"
            raise ParameterError(f"operating point: give exactly two of nu (or tau), F_s, T_l "
                                 f"besides r_g and omega_p; given: {shown}")

    @property
    def given(self) -> tuple[str, ...]:
        """The two variables that fix the point besides r_g and omega_p, in the order
        ``nu, F_s, T_l, tau``."""
        return tuple(k for k in ("nu", "F_s", "T_l", "tau") if getattr(self, k) is not None)

    @property
    def omega_s(self) -> float:
        """Secondary speed ``r_g (1 - nu) omega_p`` [rad/s] (eq. 2 solved for omega_s)."""
        if self.nu is None:
            raise ParameterError("operating point: omega_s needs the slip nu (resolve the "
                                 "point first)")
        return self.r_g * (1 - self.nu) * self.omega_p

    @classmethod
    def from_params(cls, params: _Machine, **changes: float | None) -> "OperatingPoint":
        """The ``[operating]`` point of a parameter set, with keyword `changes`.

        Parameters
        ----------
        params : Params
            The parameter set.
        **changes : float or None
            Variables to change, as `replace` takes them.
        """
        return params.operating.replace(**changes)

    def replace(self, **changes: float | None) -> "OperatingPoint":
        """A copy with some variables changed (validated).  Setting the slip as ``nu`` drops
        a ``tau`` and the other way round; a value of None drops a variable.

        Parameters
        ----------
        **changes : float or None
            Operating variables (``r_g``, ``nu``, ``tau``, ``F_s``, ``T_l``, ``omega_p``) to set,
            in SI units; None drops one.
        """
        unknown = set(changes) - set(OPERATING_VARIABLES)
        if unknown:
            raise ParameterError(f"unknown operating-point variable {sorted(unknown)[0]!r}: "
                                 f"choose from {', '.join(OPERATING_VARIABLES)}")
        for a, b in (("nu", "tau"), ("tau", "nu")):
            if changes.get(a) is not None and b not in changes:
                changes[b] = None
        return replace(self, **changes)  # type: ignore[arg-type]  # checked on construction

    def to_dict(self) -> dict[str, float]:
        """The given variables by name (SI): ``r_g``, two of ``nu, F_s, T_l, tau``, then
        ``omega_p``."""
        out = {"r_g": self.r_g}
        for k in ("nu", "F_s", "T_l", "tau"):
            if getattr(self, k) is not None:
                out[k] = getattr(self, k)
        out["omega_p"] = self.omega_p
        return out

    def label(self, ratio: bool = False) -> str:
        """The given variables as text with units (``"tau = 0.9, F_s = 10000 N, omega_p = 300
        rad/s"``; the ratio first with `ratio`).

        Parameters
        ----------
        ratio : bool, optional
            Start with the ratio ``r_g`` (default False).
        """
        names = (("r_g",) if ratio else ()) + tuple(k for k in ("nu", "tau", "F_s", "T_l")
                                                     if getattr(self, k) is not None)
        parts = [f"{k} = {getattr(self, k):g}" + (f" {OPERATING_VARIABLES[k][0]}"
                                                  if OPERATING_VARIABLES[k][0] != "-" else "")
                 for k in names + ("omega_p",)]
        return ", ".join(parts)

    def as_dict(self) -> dict[str, float]:
        """Deprecated: `to_dict`."""
        warn_renamed("OperatingPoint.as_dict", "to_dict")
        return self.to_dict()

    def resolve_given(self) -> "OperatingPoint":
        """The point as a `ResolvedPoint` when it is given by ``nu`` and ``F_s`` (no model
        needed), else itself."""
        if self.nu is None or self.F_s is None or isinstance(self, ResolvedPoint):
            return self
        return ResolvedPoint(r_g=self.r_g, nu=self.nu, F_s=self.F_s, omega_p=self.omega_p)

    def resolve(self, params: _Machine, traction: Any = None) -> "ResolvedPoint":
        """The point with ``nu`` and ``F_s`` given (the slip model's variables, every one a
        float: a `ResolvedPoint`), solved on the variator's unstretched radii with the
        traction curve of `params` (or `traction`): ``T_l = 2 mu(nu) F_s R_s / cos(beta)``
        (eq. 1), the slip on the rising branch of the curve where a torque ratio or a load
        fixes it.  A point given by ``nu`` and ``F_s`` keeps its values.

        Parameters
        ----------
        params : Params
            The parameter set (variator geometry and ``[traction]``).
        traction : TractionModel, optional
            The traction curve to solve on (default `traction_from_params(params)`).
        """
        r_g, omega_p = self.r_g, self.omega_p
        if self.nu is not None and self.F_s is not None:
            return self if isinstance(self, ResolvedPoint) else \
                ResolvedPoint(r_g=r_g, nu=self.nu, F_s=self.F_s, omega_p=omega_p)
        tr = traction_from_params(params) if traction is None else traction
        R_s = float(variator_state(r_g, params.variator).R_s)
        cosb = math.cos(params.variator.beta)
        nu = self.nu
        if nu is None and self.tau is not None:
            nu = _slip_at(tr, r_g, self.tau * _mu_max(tr, r_g), "tau", self.tau)
        if nu is not None:
            mu = float(tr.mu(nu, r_g))
            if self.F_s is not None:
                return ResolvedPoint(r_g=r_g, nu=nu, F_s=self.F_s, omega_p=omega_p)
            T_l = _given(self.T_l)
            if mu * T_l <= 0:
                raise ParameterError(f"operating point: mu(nu) = {mu:.4g} cannot carry T_l = "
                                     f"{T_l:g} N m with a positive clamping force")
            return ResolvedPoint(r_g=r_g, nu=nu, F_s=T_l * cosb / (2 * mu * R_s),
                                 omega_p=omega_p)
        T_l, F_s = _given(self.T_l), _given(self.F_s)
        need = T_l * cosb / (2 * F_s * R_s) if F_s > 0 else math.inf
        return ResolvedPoint(r_g=r_g, nu=_slip_at(tr, r_g, need, "T_l", T_l), F_s=F_s,
                             omega_p=omega_p)


@dataclass(frozen=True)
class ResolvedPoint(OperatingPoint):
    """An operating point given by its slip and clamping force, both known (what
    `OperatingPoint.resolve` returns, and what the models use inward).

    The same point as an `OperatingPoint` given by ``nu`` and ``F_s`` (it is one, validated
    alike), typed so that its ``r_g``, ``nu``, ``F_s`` and ``omega_p`` are floats: code that
    runs after `resolve` needs no None checks.  ``T_l`` and ``tau`` are not stored (None):
    the unstretched-geometry load follows from eq. 1, the stretched one from the trim
    (`empact.nonlinear.equilibrium.trim`).

    Attributes
    ----------
    r_g : geometric ratio ``R_p / R_s`` [-]
    nu : slip [-] (a fraction), in (-1, 1)
    F_s : secondary clamping force [N], >= 0
    omega_p : primary pulley speed [rad/s], > 0
    """

    nu: float = param("-", OPERATING_VARIABLES["nu"][1], -1.0, 1.0, hi_open=True)
    F_s: float = param("N", OPERATING_VARIABLES["F_s"][1], lo_open=False)

    @property
    def request(self) -> OperatingPoint:
        """The point as a plain `OperatingPoint` (given by ``nu`` and ``F_s``)."""
        return OperatingPoint(r_g=self.r_g, nu=self.nu, F_s=self.F_s, omega_p=self.omega_p)

    def replace(self, **changes: float | None) -> OperatingPoint:
        """A copy with some variables changed (validated): a `ResolvedPoint` while it is
        given by ``nu`` and ``F_s``, else the `OperatingPoint` request (resolve it).

        Parameters
        ----------
        **changes : float or None
            Operating variables by name (``r_g``, ``nu``, ``tau``, ``F_s``, ``T_l``,
            ``omega_p``) and their new values (SI; None removes one).

        Returns
        -------
        OperatingPoint
            A `ResolvedPoint` when the copy is given by ``nu`` and ``F_s``.
        """
        out = self.request.replace(**changes)
        return out.resolve_given()


@dataclass(frozen=True)
class CruisePoint(OperatingPoint):
    """A car's steady cruise (the vehicle driveline, `empact.nonlinear.model.ModelOptions`
    ``driveline = "vehicle"``): the ratio ``r_g``, the primary (engine) speed ``omega_p``
    and exactly one of the slip (``nu`` or ``tau``) and the clamping force ``F_s``; the road
    load at the speed the point drives sets the load torque ``T_l`` (the trim solves it,
    `empact.nonlinear.equilibrium.trim`), so no ``T_l`` is given.

    Attributes
    ----------
    r_g : geometric ratio ``R_p / R_s`` [-]
    omega_p : primary (engine) speed [rad/s], > 0
    nu, tau : slip [-] or torque ratio [-] (one of them, or neither with `F_s`)
    F_s : secondary clamping force [N] (or None with a slip)
    T_l : None (the road load's)

    Examples
    --------
    >>> CruisePoint(r_g=2.0, omega_p=200.0, tau=0.5).given
    ('tau',)
    """

    def __post_init__(self) -> None:
        if self.omega_p is None:
            raise ParameterError("cruise point: omega_p (primary speed [rad/s]) is missing")
        Section.__post_init__(self)
        check_one_slip(self.nu is not None, self.tau is not None, where="cruise point: ")
        if self.T_l is not None:
            raise ParameterError(f"cruise point: T_l = {self.T_l:g} N m given: the road load "
                                 "sets it (give one of nu, tau, F_s besides r_g and omega_p)")
        if len(self.given) != 1:
            shown = ", ".join(f"{k} = {getattr(self, k):g}" for k in self.given) or "none"
            raise ParameterError(f"cruise point: give exactly one of nu (or tau), F_s besides "
                                 f"r_g and omega_p; given: {shown}")


def check_one_slip(nu: bool, tau: bool, *, names: tuple[str, str] = ("nu", "tau"),
                   where: str = "", error: type[ParameterError] = ParameterError) -> None:
    """The one rule on the slip's two spellings: a point gives its slip as ``nu`` or as the
    torque ratio ``tau``, not both (`OperatingPoint`, `empact.nonlinear.equilibrium.trim_grid`,
    `empact.control.family.plant_family` and the command line's ``--slip`` / ``--tau``).

    Parameters
    ----------
    nu, tau : bool
        Whether each is given.
    names : (str, str)
        How the user spells them (``("--slip", "--tau")`` at the command line).
    where : str
        A prefix for the message (``"operating point: "``).
    error : type
        The `ParameterError` subclass to raise (`~empact.errors.TrimError` for the trim).

    Raises
    ------
    ParameterError
        One line, when both are given.
    """
    if nu and tau:
        raise error(f"{where}give the slip as {names[0]} or as {names[1]}, not both")


def check_clamping(name: str, value: ArrayLike, *, where: str = "") -> NDArray[np.float64]:
    """The one rule on the clamping force of a point the nonlinear model is trimmed at or
    driven to: > 0 [N] (a belt without clamping carries no torque).  The slip model's
    `OperatingPoint` allows ``F_s = 0`` (no clamping, no belt damping); the trim, a
    scenario's ``F_s_ref`` and a parameter file's ``[operating]`` point need it positive.

    Parameters
    ----------
    name : the field or option as the user knows it (``"--clamp"``, ``"inputs.F_s_ref"``)
    value : the clamping force(s) [N], any shape
    where : the file or table it came from (prefixed to the message)

    Returns
    -------
    ndarray
        `value` as floats, its shape.
    """
    return check_values(name, value, 0.0, lo_open=True, unit="N", where=where,
                        note="a belt without clamping carries no torque")


def _given(value: float | None) -> float:
    """A variable that `OperatingPoint` guarantees here (two of nu, F_s, T_l are given)."""
    assert value is not None
    return value


def _mu_max(traction: Any, r_g: float) -> float:
    """Peak traction coefficient of a curve at `r_g` (its ``mu_max`` where it has one)."""
    if hasattr(traction, "mu_max"):
        return float(traction.mu_max(r_g))
    return curve_peak(traction, r_g)[1]


def curve_peak(traction: Any, r_g: float, refine: bool = False) -> tuple[float, float]:
    """The peak of a traction curve at one ratio: the best of 4001 slips evenly spaced over
    its non-negative valid range, refined on request by a bounded scalar search between that
    slip's neighbours (to 1e-12 in slip; the curve is unimodal in slip).

    Parameters
    ----------
    traction : TractionModel
        The curve (``mu(nu, r_g)`` and ``nu_range``), analytic or tabulated.
    r_g : float
        Geometric ratio [-].
    refine : bool, optional
        Refine the grid's best slip (default False: the grid point).

    Returns
    -------
    nu_peak, mu_peak : float
        Slip [-] at the peak and the traction coefficient [-] there.
    """
    lo, hi = max(traction.nu_range[0], 0.0), traction.nu_range[1]
    nu = np.linspace(lo, hi, 4001)
    mu = traction.mu(nu, r_g)
    k = int(np.argmax(mu))
    a, b = nu[max(k - 1, 0)], nu[min(k + 1, nu.size - 1)]
    if not refine or a == b:
        return float(nu[k]), float(mu[k])
    best = optimize.minimize_scalar(lambda x: -float(traction.mu(x, r_g)), bounds=(a, b),
                                    method="bounded", options={"xatol": 1e-12})
    return float(best.x), -float(best.fun)


def _slip_at(traction: Any, r_g: float, mu: float, name: str, value: float) -> float:
    """The slip on the rising branch of the traction curve where it reaches `mu` (bisection
    to 1e-15), or a one-line error naming the variable that asked for it."""
    nu_pk, mu_pk = curve_peak(traction, r_g)
    if abs(mu) > mu_pk:
        raise ParameterError(f"operating point: {name} = {value:g} needs mu = {abs(mu):.4g}, "
                             f"above the traction peak {mu_pk:.4g} at r_g = {r_g:g}")
    a, b = 0.0, nu_pk
    for _ in range(80):
        mid = 0.5 * (a + b)
        if float(traction.mu(mid, r_g)) < abs(mu):
            a = mid
        else:
            b = mid
    return math.copysign(0.5 * (a + b), mu) if mu else 0.0
