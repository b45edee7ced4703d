"""Frozen, validated model parameters, loaded from and saved to TOML.

A parameter set has one section per concept::

    [variator]          belt and pulley geometry (eqs. 4-6 of the paper)
    [actuation]         inertias, ratios and stiffnesses of the actuation (Fig. 3)
    [damping.none]      damping levels of the actuation model (Fig. 6)
    [damping.moderate]
    [damping.large]
    [driveline]         inertias and stiffnesses of the test-bench driveline (Fig. 7)
    [traction]          traction curve mu(nu, r_g) (Fig. 10)
    [shift]             creep-mode shifting of the belt (Carbone et al. 2007; Ide et al.)
    [thrust_ratio]      torque-dependent equilibrium thrust ratio kappa(tau, r_g)
    [paper_sec21]       stiffnesses of the paper's Sec. 2.1 kinematics (the published variant)
    [servo]             torque and speed limits of the servo drives (`empact.hardware`)
    [sensors]           the closed loop's instruments: delay, encoders, noise
    [operating]         the default operating point (r_g, nu, F_s, omega_p), used by every
                        analysis that is not given one (slip model, trim, plants, NMP, Fig. 2)

All values are SI (radians, metres, kilograms, seconds).  The shipped set
(`default_params`) is the result of ``empact calibrate`` on the paper's
eigenfrequencies; a user file may give any subset of keys, the rest are taken
from the shipped set.  Every value is checked on construction: a bad value
raises `ParameterError` whose message names the field, the value and the
allowed range.
"""
from __future__ import annotations

import math
import os
import tomllib
from dataclasses import asdict, dataclass, fields, replace
from importlib import resources
from typing import Any, Literal, Mapping, overload

import numpy as np
import tomli_w
from numpy.typing import ArrayLike, NDArray

from ._deprecate import warn_renamed
from ._io import atomic_write_text
from ._section import Section, param
from ._validate import check_choice, check_number, check_values
from .errors import ParameterError
from .hardware import SensorParams, ServoLimits
from .variator.geometry import VariatorParams, ratio_range, variator_state
from .variator.shift_law import ShiftParams
from .variator.thrust_ratio import ThrustRatioParams
from .variator.traction import TractionParams, traction_from_params

__all__ = [
    "ParameterError", "VariatorParams", "ActuationParams", "DampingLevel", "DampingParams",
    "DrivelineParams", "TractionParams", "ShiftParams", "ThrustRatioParams", "Sec21Stiffness",
    "OperatingPoint", "ResolvedPoint", "Params", "default_params",
    "load_params", "save_params", "dumps_params", "read_toml", "DAMPING_LEVELS",
    "OPERATING_VARIABLES", "ParameterInfo", "describe_parameters", "parameter_sources",
    "check_clamping", "check_one_slip",
]

DAMPING_LEVELS = ("none", "moderate", "large")

@dataclass(frozen=True)
class ActuationParams(Section):
    """Linear actuation model (paper Sec. 2.1, Fig. 3).

    Attributes
    ----------
    J_mp : float
        Primary servo inertia (rotor and worm), coordinate q1 [kg m^2].
    J_ms : float
        Secondary servo inertia (rotor and chain sprocket), coordinate q2 [kg m^2].
    J_sp : float
        Primary sun gear with screw (ring, carrier and planets lumped), q3 [kg m^2].
    J_ss : float
        Secondary sun gear with screw input, q4 [kg m^2].
    m_p, m_s : float
        Primary and secondary moving sheaves with screw output, q5 and q6 [kg].
    i_w : float
        Worm ratio (servo turns per ring turn) [-].
    i_c : float
        Chain ratio (servo turns per ring turn) [-].
    i_e : float
        Ring to sun ratio of the epicyclic sets (the paper: 2) [-].
    s : float
        Screw pitch (translation per radian) [m/rad].
    k_w, k_c : float
        Worm stiffness (spring 1) and chain stiffness (spring 2) [N m/rad].
    k_belt : float
        Longitudinal pushbelt stiffness (spring 3) [N/m].
    k_tp, k_ts : float
        Primary and secondary thrust bearing stiffnesses (springs 4 and 5) [N/m].
    """

    _name = "actuation"
    J_mp: float = param("kg m^2", "primary servo inertia (rotor and worm), coordinate q1",
                        1e-8, 1.0)
    J_ms: float = param("kg m^2", "secondary servo inertia (rotor and chain sprocket), "
                     "coordinate q2", 1e-8, 1.0)
    J_sp: float = param("kg m^2", "primary sun gear with screw, ring/carrier/planets lumped, q3",
                     1e-7, 10.0)
    J_ss: float = param("kg m^2", "secondary sun gear with screw input, q4", 1e-7, 10.0)
    m_p: float = param("kg", "primary moving sheave with screw output, q5", 0.01, 100.0)
    m_s: float = param("kg", "secondary moving sheave with screw output, q6", 0.01, 100.0)
    i_w: float = param("-", "worm ratio (servo turns per ring turn)", 0.1, 1000.0)
    i_c: float = param("-", "chain ratio (servo turns per ring turn)", 0.01, 100.0)
    i_e: float = param("-", "ring to sun ratio of the epicyclic sets (the paper: 2)", 1.0, 10.0)
    s: float = param("m/rad", "screw pitch (translation per radian)", 1e-7, 1e-2)
    k_w: float = param("N m/rad", "worm stiffness (spring 1)", 1e-3, 1e8)
    k_c: float = param("N m/rad", "chain stiffness (spring 2)", 1e-3, 1e8)
    k_belt: float = param("N/m", "longitudinal pushbelt stiffness (spring 3)", 1e2, 1e11)
    k_tp: float = param("N/m", "primary thrust bearing stiffness (spring 4)", 1e4, 1e12)
    k_ts: float = param("N/m", "secondary thrust bearing stiffness (spring 5)", 1e4, 1e12)


@dataclass(frozen=True)
class DampingLevel(Section):
    """One damping level of the actuation model (Fig. 6).

    Attributes
    ----------
    alpha : float
        Proportional spring damping, ``C_spring = alpha K`` [s].
    c_mp, c_ms : float
        Viscous friction of the primary and secondary servos [N m s/rad].
    c_sp, c_ss : float
        Viscous friction of the primary and secondary screws [N m s/rad].
    c_shafai : float
        Shafai pulley damping coefficient [N/m]: the pulley damping is ``c_pulley =
        c_shafai / |omega|`` [N s/m] at pulley speed ``omega``.
    """

    _name = "damping"
    alpha: float = param("s", "proportional spring damping, C_spring = alpha K", 0.0, 0.1,
                      lo_open=False)
    c_mp: float = param("N m s/rad", "viscous friction of the primary servo", 0.0, 100.0,
                     lo_open=False)
    c_ms: float = param("N m s/rad", "viscous friction of the secondary servo", 0.0, 100.0,
                     lo_open=False)
    c_sp: float = param("N m s/rad", "viscous friction of the primary screw", 0.0, 1e4,
                     lo_open=False)
    c_ss: float = param("N m s/rad", "viscous friction of the secondary screw", 0.0, 1e4,
                     lo_open=False)
    c_shafai: float = param("N/m", "Shafai pulley damping: c_pulley = c_shafai / |omega| [N s/m]",
                         0.0, 1e10, lo_open=False)


@dataclass(frozen=True)
class DampingParams:
    """The three damping levels of Fig. 6 and the pulley speed for Shafai's model.

    Attributes
    ----------
    none, moderate, large : DampingLevel
        The damping levels ``[damping.none]``, ``[damping.moderate]`` and
        ``[damping.large]`` (`DAMPING_LEVELS`).
    omega_pulley : float
        Pulley speed of Shafai's damping model in the linear actuation model [rad/s], in
        (0, 2000].
    """

    none: DampingLevel
    moderate: DampingLevel
    large: DampingLevel
    omega_pulley: float = 300.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "omega_pulley",
                           check_number("damping.omega_pulley", self.omega_pulley, 0.0, 2000.0,
                                        lo_open=True, unit="rad/s"))

    def level(self, name: str) -> DampingLevel:
        """The damping level called `name` (one of ``DAMPING_LEVELS``).

        Parameters
        ----------
        name : str
            One of ``DAMPING_LEVELS``.
        """
        return getattr(self, check_choice("damping", name, DAMPING_LEVELS))


@dataclass(frozen=True)
class DrivelineParams(Section):
    """Test-bench driveline (paper Sec. 2.2, Fig. 7).

    Attributes
    ----------
    J_d : float
        Drive motor inertia, q1 [kg m^2].
    J_p : float
        Primary pulley with torque converter, q2 [kg m^2].
    J_s : float
        Secondary pulley, q3 [kg m^2].
    J_l : float
        Load motor inertia, q4 [kg m^2].
    k_tc : float
        Torque converter lock-up clutch stiffness [N m/rad].
    k_belt : float
        Pushbelt stiffness as a chain element, on the elongation ``R_p q2 - R_s q3`` [N/m].
    k_ds : float
        Driveshaft stiffness [N m/rad].
    """

    _name = "driveline"
    J_d: float = param("kg m^2", "drive motor inertia, q1", 1e-6, 1e3)
    J_p: float = param("kg m^2", "primary pulley with torque converter, q2", 1e-6, 1e2)
    J_s: float = param("kg m^2", "secondary pulley, q3", 1e-6, 1e2)
    J_l: float = param("kg m^2", "load motor inertia, q4", 1e-6, 1e3)
    k_tc: float = param("N m/rad", "torque converter lock-up clutch stiffness", 1e-2, 1e8)
    k_belt: float = param("N/m", "pushbelt stiffness as a chain element (elongation R_p q2 - R_s "
                              "q3)", 1e2, 1e11)
    k_ds: float = param("N m/rad", "driveshaft stiffness", 1e-2, 1e8)


@dataclass(frozen=True)
class Sec21Stiffness(Section):
    """Stiffnesses of the actuation model with the paper's Sec. 2.1 kinematics as published
    (kinematics ``"paper-sec2.1"``), calibrated to Table 1 on its own: the overlay that
    `empact.linear.actuation.actuation_model` and the nonlinear model use for that variant.

    Attributes
    ----------
    k_w, k_c : float
        Worm stiffness (spring 1) and chain stiffness (spring 2) [N m/rad].
    k_belt : float
        Longitudinal pushbelt stiffness (spring 3) [N/m].
    k_tp, k_ts : float
        Primary and secondary thrust bearing stiffnesses (springs 4 and 5) [N/m].
    """

    _name = "paper_sec21"
    k_w: float = param("N m/rad", "worm stiffness (spring 1)", 1e-3, 1e8)
    k_c: float = param("N m/rad", "chain stiffness (spring 2)", 1e-3, 1e8)
    k_belt: float = param("N/m", "longitudinal pushbelt stiffness (spring 3)", 1e2, 1e11)
    k_tp: float = param("N/m", "primary thrust bearing stiffness (spring 4)", 1e4, 1e12)
    k_ts: float = param("N/m", "secondary thrust bearing stiffness (spring 5)", 1e4, 1e12)


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
    def from_params(cls, params: "Params", **changes: float | None) -> "OperatingPoint":
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

    def resolve(self, params: "Params", traction: Any = None) -> "ResolvedPoint":
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
    return _peak(traction, r_g)[1]


def _peak(traction: Any, r_g: float) -> tuple[float, float]:
    lo, hi = max(traction.nu_range[0], 0.0), traction.nu_range[1]
    nu = np.linspace(lo, hi, 4001)
    mu = traction.mu(nu, r_g)
    k = int(np.argmax(mu))
    return float(nu[k]), float(mu[k])


def _slip_at(traction: Any, r_g: float, mu: float, name: str, value: float) -> float:
    """The slip on the rising branch of the traction curve where it reaches `mu` (bisection
    to 1e-15), or a one-line error naming the variable that asked for it."""
    nu_pk, mu_pk = _peak(traction, r_g)
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


_SECTIONS = {
    "variator": VariatorParams, "actuation": ActuationParams, "driveline": DrivelineParams,
    "traction": TractionParams, "shift": ShiftParams, "thrust_ratio": ThrustRatioParams,
    "paper_sec21": Sec21Stiffness, "servo": ServoLimits, "sensors": SensorParams,
    "operating": OperatingPoint,
}
#: sections whose every key has a default (a file may leave them out)
_OPTIONAL_SECTIONS = ("servo", "sensors")


@dataclass(frozen=True)
class Params:
    """A complete, validated parameter set.  Immutable: `from_dotted` returns a changed copy.

    Attributes
    ----------
    variator, actuation, damping, driveline, traction, shift : Section
        The frozen, validated blocks of the parameter file's tables (``[variator]``, ...;
        SI units, each field's unit and range in ``empact params show --describe``).
    thrust_ratio, paper_sec21, servo, sensors : Section
        The same, for the ``[thrust_ratio]``, ``[paper_sec21]``, ``[servo]`` and
        ``[sensors]`` tables.
    operating : OperatingPoint
        The default operating point (``[operating]``).
    """

    variator: VariatorParams
    actuation: ActuationParams
    damping: DampingParams
    driveline: DrivelineParams
    traction: TractionParams
    shift: ShiftParams
    thrust_ratio: ThrustRatioParams
    paper_sec21: Sec21Stiffness
    servo: ServoLimits
    sensors: SensorParams
    operating: OperatingPoint

    def __post_init__(self) -> None:
        if self.shift.k_D * self.shift.F_ref >= 0.9:
            raise ParameterError(
                f"shift.k_D = {self.shift.k_D:g}: with F_ref = {self.shift.F_ref:g} N the "
                f"deformation D would vanish at low clamping force; need k_D F_ref < 0.9")
        lo, hi = ratio_range(self.variator)
        if not lo <= self.operating.r_g <= hi:
            raise ParameterError(
                f"operating.r_g = {self.operating.r_g!r}: outside the geometric ratio range "
                f"[{lo:.4g}, {hi:.4g}] of this variator")

    # -- conversion -----------------------------------------------------------------
    def to_dict(self) -> dict[str, Any]:
        """Nested plain dictionary, as written to TOML (variables of the operating point that
        are not given are left out)."""
        d = asdict(self)
        d["operating"] = self.operating.to_dict()
        return d

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], base: "Params | None" = None,
                  source: str = "parameters") -> "Params":
        """Build from a nested mapping; keys not given are taken from `base`.

        Parameters
        ----------
        data : mapping
            Sections (``"actuation"``, ...) to mappings of keys to values (SI units).
        base : Params, optional
            The set that gives the keys `data` leaves out (default none: `data` gives every
            section and key without a default).
        source : str, optional
            What the messages call `data` (e.g. the file's name; default ``"parameters"``).

        Raises
        ------
        ParameterError
            For an unknown section or key, a wrong type or a value out of range.
        """
        merged = base.to_dict() if base is not None else {}
        op_base = dict(merged.get("operating", {}))
        _merge(merged, data, source, _schema())
        _merge_operating(merged, op_base, data.get("operating", {}))
        try:
            damping = merged["damping"]
            levels = {name: DampingLevel(**damping[name]) for name in DAMPING_LEVELS}
            for name in _OPTIONAL_SECTIONS:  # every key has a default
                merged.setdefault(name, {})
            sections = {name: kind(**merged[name]) for name, kind in _SECTIONS.items()}
            return cls(damping=DampingParams(**levels, omega_pulley=damping["omega_pulley"]),
                       **sections)
        except KeyError as exc:
            raise ParameterError(f"{source}: missing section or key {exc.args[0]!r}") from None
        except TypeError as exc:  # missing fields of a section
            raise ParameterError(f"{source}: {exc}") from None
        except ParameterError as exc:  # name the file in every message
            raise ParameterError(f"{source}: {exc}") from None

    def from_dotted(self, values: Mapping[str, float]) -> "Params":
        """A copy with values changed by dotted name, e.g. ``{"damping.large.alpha": 1e-3}``.

        Parameters
        ----------
        values : mapping of str to float
            Dotted names (``"section.key"`` or ``"damping.level.key"``) to new values (SI).
        """
        nested: dict[str, Any] = {}
        for name, value in values.items():
            node = nested
            *path, last = name.split(".")
            for part in path:
                node = node.setdefault(part, {})
            node[last] = value
        return Params.from_dict(nested, base=self)

    @overload
    def get(self, dotted: str, *, unset_ok: Literal[False] = False) -> float: ...

    @overload
    def get(self, dotted: str, *, unset_ok: bool) -> float | None: ...

    def get(self, dotted: str, *, unset_ok: bool = False) -> float | None:
        """The value of a dotted name such as ``"actuation.k_w"`` (with `unset_ok`, None for
        an operating-point variable the set does not give, e.g. ``operating.nu`` of a point
        given by its torque ratio).

        Parameters
        ----------
        dotted : str
            A dotted parameter name.
        unset_ok : bool, optional
            Return None for an operating-point variable the set does not give, instead of
            raising (default False).
        """
        node: Any = self
        for part in dotted.split("."):
            if not hasattr(node, part) or part.startswith("_"):
                raise ParameterError(f"unknown parameter {dotted!r}")
            node = getattr(node, part)
        if node is None:
            if unset_ok:
                return None
            raise ParameterError(f"parameter {dotted!r} is not set in this parameter set")
        if not isinstance(node, float):
            raise ParameterError(f"parameter {dotted!r} is a section, not a value")
        return node

    def unit(self, dotted: str) -> str:
        """The unit of a dotted parameter name, e.g. ``"N m/rad"`` for ``"actuation.k_w"``.

        Parameters
        ----------
        dotted : str
            A dotted parameter name.
        """
        self.get(dotted, unset_ok=True)
        *path, last = dotted.split(".")
        node: Any = self
        for part in path:
            node = getattr(node, part)
        meta = {f.name: f.metadata for f in fields(node)}[last]
        return str(meta.get("unit", ""))


def _merge_operating(merged: dict[str, Any], base: Mapping[str, Any],
                     given: Mapping[str, Any]) -> None:
    """The ``[operating]`` table of a file over the base set's: a file that names two of the
    variables ``nu`` (or ``tau``), ``F_s``, ``T_l`` states its own point; one that names one
    of them changes that one (``nu`` and ``tau`` replace each other), as
    `OperatingPoint.replace` does."""
    if not isinstance(given, Mapping):
        return
    pair = [k for k in ("nu", "F_s", "T_l", "tau") if k in given]
    if not pair:
        return
    table = {k: v for k, v in merged["operating"].items()
             if k not in ("nu", "F_s", "T_l", "tau")}
    if len(pair) == 1:
        table.update({k: v for k, v in base.items() if k in ("nu", "F_s", "T_l", "tau")})
        if pair[0] in ("nu", "tau"):
            table.pop("tau" if pair[0] == "nu" else "nu", None)
    table.update({k: given[k] for k in pair})
    merged["operating"] = table


def _schema() -> dict[str, Any]:
    """Nested dict of the allowed keys (values None) of a parameter file."""
    names = lambda kind: {f.name: None for f in fields(kind)}  # noqa: E731
    schema: dict[str, Any] = {name: names(kind) for name, kind in _SECTIONS.items()}
    schema["damping"] = {"omega_pulley": None,
                         **{lvl: names(DampingLevel) for lvl in DAMPING_LEVELS}}
    return schema


def _merge(into: dict[str, Any], data: Mapping[str, Any], where: str,
           schema: Mapping[str, Any], path: str = "") -> None:
    """Recursively merge `data` into `into`, refusing keys and tables not in `schema`."""
    for key, value in data.items():
        name = f"{path}.{key}" if path else key
        if key not in schema:
            raise ParameterError(f"{where}: unknown key {name!r} (allowed here: "
                                 f"{', '.join(schema)})")
        if isinstance(schema[key], Mapping):
            if not isinstance(value, Mapping):
                raise ParameterError(f"{where}: {name!r} must be a table, not {value!r}")
            _merge(into.setdefault(key, {}), value, where, schema[key], name)
        elif isinstance(value, Mapping):
            raise ParameterError(f"{where}: {name!r} must be a value, not a table")
        else:
            into[key] = value


def read_toml(path: str | os.PathLike[str], what: str = "parameter") -> dict[str, Any]:
    """Parse a TOML file; a missing file or bad syntax is a one-line `ParameterError`.

    Parameters
    ----------
    path : str or path-like
        The TOML file to read.
    what : str
        What the file is, for the error messages (``"no such parameter file"``).

    Returns
    -------
    dict
        The parsed tables and values (nested dicts, as `tomllib.load` returns them).

    Raises
    ------
    ParameterError
        When the file is missing, a folder, not UTF-8, not valid TOML or unreadable.
    """
    try:
        with open(path, "rb") as fh:
            return tomllib.load(fh)
    except FileNotFoundError:
        raise ParameterError(f"{path}: no such {what} file") from None
    except IsADirectoryError:
        raise ParameterError(f"{path}: is a folder, not a {what} file") from None
    except UnicodeDecodeError:
        raise ParameterError(f"{path}: not a text file (TOML must be UTF-8)") from None
    except tomllib.TOMLDecodeError as exc:
        raise ParameterError(f"{path}: not valid TOML ({exc})") from None
    except OSError as exc:
        raise ParameterError(f"{path}: cannot be read ({exc.strerror})") from None


_DEFAULT: Params | None = None


def default_params() -> Params:
    """The shipped parameter set (``empact/data/default.toml``), calibrated to the paper.

    Returns
    -------
    Params
        The shipped set (cached: every call returns the same frozen object).
    """
    global _DEFAULT
    if _DEFAULT is None:
        text = resources.files("empact.data").joinpath("default.toml").read_text()
        _DEFAULT = Params.from_dict(tomllib.loads(text), source="default.toml")
    return _DEFAULT


@dataclass(frozen=True)
class ParameterInfo:
    """What `describe_parameters` says of one parameter.

    Attributes
    ----------
    name : dotted name (``"traction.B_med"``)
    unit : SI unit
    allowed : the interval a value must lie in (validation)
    doc : what it is
    value : the shipped value
    band : ``(lo, hi)``, the plausible band of the shipped value (a value outside it is
        allowed but not physically credible for a pushbelt CVT and its test bench)
    source : where the shipped value comes from, or the stated rationale for it
    """

    name: str
    unit: str
    allowed: str
    doc: str
    value: float | None
    band: tuple[float, float]
    source: str


def parameter_sources() -> dict[str, dict[str, Any]]:
    """Source and plausible band of every shipped parameter (``data/parameter_sources.toml``):
    dotted name -> ``{"source": str, "band": [lo, hi]}``.

    Returns
    -------
    dict
        Dotted parameter name (``"traction.B_med"``) -> ``{"source": str, "band": [lo,
        hi]}``, the band in the parameter's SI unit.
    """
    text = resources.files("empact.data").joinpath("parameter_sources.toml").read_text()
    return dict(tomllib.loads(text))


def describe_parameters(params: Params | None = None) -> list[ParameterInfo]:
    """Every parameter of a set (default: the shipped one) with its unit, allowed interval,
    meaning, value, plausible band and source, in file order.

    Parameters
    ----------
    params : Params, optional
        The parameter set whose values are shown (default: `default_params`).

    Returns
    -------
    list of ParameterInfo
        One entry per parameter, in the order of the parameter file's tables; the band is
        ``(nan, nan)`` and the source empty for a parameter without an entry in
        `parameter_sources`.
    """
    params = default_params() if params is None else params
    sources = parameter_sources()
    out = []
    blocks: list[tuple[str, Any]] = []
    for name in ("variator", "actuation", "damping", "driveline", "traction", "shift",
                 "thrust_ratio", "paper_sec21", "servo", "sensors", "operating"):
        block = getattr(params, name)
        if name == "damping":
            blocks += [(f"damping.{lvl}", getattr(block, lvl)) for lvl in DAMPING_LEVELS]
            blocks.append(("damping", block))
        else:
            blocks.append((name, block))
    for prefix, block in blocks:
        if isinstance(block, DampingParams):
            rows = [("omega_pulley", "rad/s", "(0, 2000]", "pulley speed of Shafai's model "
                     "in the linear actuation model (Fig. 6)")]
        else:
            rows = type(block).describe()
        for key, unit, allowed, doc in rows:
            dotted = f"{prefix}.{key}"
            info = sources.get(dotted, {})
            lo, hi = (float(v) for v in info.get("band", (float("nan"), float("nan"))))
            band = (lo, hi)
            out.append(ParameterInfo(dotted, unit, allowed, doc, getattr(block, key),
                                     band, str(info.get("source", ""))))
    return out


def load_params(path: str | os.PathLike[str] | None = None) -> Params:
    """Load a TOML parameter file over the shipped defaults.

    Parameters
    ----------
    path : str or path-like, optional
        A TOML parameter file with any subset of the shipped keys (``[section] key = value``,
        SI units); the other keys keep their shipped values. `None`: the shipped set.

    Returns
    -------
    Params
        The frozen, validated parameter set.

    Raises
    ------
    ParameterError
        One line naming the file, the bad field, its value and the allowed range.

    Examples
    --------
    >>> import empact
    >>> params = empact.load_params()
    >>> params.operating.r_g, params.operating.F_s, params.operating.tau   # [-], [N], [-]
    (1.0, 10000.0, 0.9)
    """
    if path is None:
        return default_params()
    return Params.from_dict(read_toml(path), base=default_params(), source=str(path))


def dumps_params(params: Params, header: str = "") -> str:
    """TOML text of a parameter set, with an optional comment header.

    Parameters
    ----------
    params : Params
        The parameter set (every key, SI units; only the given operating-point variables).
    header : str
        Comment lines put at the top of the text (each prefixed with ``#``).

    Returns
    -------
    str
        The TOML text, as `save_params` writes it and `load_params` reads it back.
    """
    lines = "".join(f"# {line}\n" for line in header.splitlines())
    return lines + tomli_w.dumps(params.to_dict())


def save_params(params: Params, path: str | os.PathLike[str], header: str = "") -> None:
    """Write a parameter set to TOML atomically (temporary file, then rename).

    Parameters
    ----------
    params : Params
        The parameter set to write (every key, SI units).
    path : str or path-like
        The TOML file written.
    header : str
        Comment lines written at the top of the file (without ``#``).
    """
    atomic_write_text(path, dumps_params(params, header))
