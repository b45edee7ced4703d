"""The nonlinear model's options (`ModelOptions`): the drive and load motors, the belt, the
damping level, the sheave kinematics, the shift law, the controllers a run closes, and the
tabulated laws a user measured (thrust ratio, shift speed, traction, losses); all validated on
construction.  `empact.nonlinear.model` builds the model from them and re-exports them.
"""
from __future__ import annotations

import os
from dataclasses import InitVar, dataclass, fields
from typing import Literal

from .._deprecate import warn_renamed
from .._validate import check_bool, check_choice, check_number
from ..errors import ParameterError
from ..params import DAMPING_LEVELS
from ..variator.losses import LossMap, load_loss_map
from ..variator.shift_law import SHIFT_LAWS, CreepMap, load_creep_map
from ..variator.thrust_ratio import TabulatedThrustRatio, load_thrust_ratio
from ..variator.traction import (
    DEFAULT_TRACTION_LAW,
    TRACTION_LAWS,
    TabulatedTraction,
    load_traction,
)

__all__ = ["KINEMATICS", "DRIVELINES", "ModelOptions", "VEHICLE_OPTIONS"]

#: sheave kinematics: the machine, and the paper's Sec. 2.1 rows as published
KINEMATICS = ("equal-translation", "paper-sec2.1")
#: the machine's surroundings: the test bench or the car (`ModelOptions.driveline`)
DRIVELINES = ("bench", "vehicle")


@dataclass(frozen=True)
class ModelOptions:
    """Choices of the nonlinear model (all validated on construction).

    Parameters
    ----------
    damping : {"none", "moderate", "large"}
        Damping level of the actuation (``params.damping``).
    belt : {"traction", "locked"}
        Traction with slip (eqs. 1-2), or the belt as the elastic chain element of the
        driveline model (no slip; the linear model's limit).
    driveline : {"bench", "vehicle"}
        The machine's surroundings: the paper's test bench (``"bench"``: a drive motor and a
        load motor, ``[driveline]``), or the car (``"vehicle"``: the engine's inertia
        ``[engine] J_e`` as the drive, torque-controlled (input ``T_d``, the engine's brake
        torque); the vehicle reflected to the secondary's speed as the load: inertia ``m (1 +
        e_rot) r_w^2 / i_fd^2``, the driveline's stiffness ``[vehicle] k_driveline / i_fd^2``,
        the road load and the final drive's loss as a load torque that depends on the state
        (`empact.nonlinear._kernel._vehicle_load`), and the input ``T_l`` the load torque
        beyond them (the friction brakes); needs ``drive = load = "torque"``).  The locked
        torque converter and the pulleys are the bench's (``[driveline] J_p, J_s, k_tc``).
    drive, load : {"torque", "speed"}
        Drive / load motor torque-controlled (input ``T_d`` / ``T_l``) or speed-controlled by a
        PI loop (input ``omega_d_ref`` / ``omega_l_ref`` [rad/s]).
    ratio_control : bool
        Replace the input ``T_mp`` by ``r_g_ref`` and a ratio controller (see module notes).
    coulomb_sp, coulomb_ss : float
        Coulomb friction torque of the primary (q3) and secondary (q4 - q3) spindle [N m], >= 0.
    coulomb_omega : float
        Velocity scale of the smooth Coulomb friction ``tanh(omega / coulomb_omega)`` [rad/s].
    drive_bandwidth_hz, load_bandwidth_hz : float
        Speed-loop bandwidths [Hz]: ``K_p = 2 pi f J``, ``K_i = K_p 2 pi f / 4``.
        (``drive_bandwidth``, ``load_bandwidth``: deprecated names.)
    ratio_bandwidth_hz : float
        Ratio-loop crossover [Hz] (see the module notes; integral at a quarter of it).
        (``ratio_bandwidth``: deprecated name.)
    kinematics : {"equal-translation", "paper-sec2.1"}
        Sheave kinematics.  ``"equal-translation"`` (default, the Empact as built, Secs. 1 and
        2.3): ``R_s = R_min + q6 / tan(beta)``; with the secondary servo held a primary-servo
        rotation translates both sheaves equally (the primary servo shifts, the secondary
        clamps); stiffnesses from ``[actuation]``.  ``"paper-sec2.1"``: the paper's Sec. 2.1
        rows as published, ``R_s = R_max - q6 / tan(beta)``, with the stiffness overlay
        ``[paper_sec21]`` calibrated to Table 1 for them (a named variant, for reproducing the
        paper, not the machine).
    shift_law : {"carbone", "ide", "shafai"}
        The sheaves' axial resistance to a ratio change (`empact.shift_law`): creep-mode
        shifting after Carbone et al. 2007 (default) or Ide et al., with the equilibrium
        thrust ratio of `empact.thrust_ratio`; or Shafai's ``c / |omega|`` on each sheave at
        the damping level's ``c_shafai`` with the geometric thrust ratio (no path from the
        load to the ratio: the first model's choice).  The creep law replaces Shafai's term:
        both are a sheave resistance that falls with speed, and keeping both would count the
        belt's resistance twice.
    thrust_ratio : TabulatedThrustRatio, optional
        A measured map ``kappa*(tau, r_g)`` (`empact.variator.thrust_ratio.load_thrust_ratio`);
        default the analytic one of ``[thrust_ratio]``.
    creep_map : CreepMap, optional
        A measured shift-speed map ``K_c(r_g, F_s)``
        (`empact.variator.shift_law.load_creep_map`); default the analytic creep coefficient
        of ``[shift]``.
    traction : TabulatedTraction, optional
        Measured traction curves ``mu(nu, r_g)`` (`empact.variator.traction.load_traction`;
        a path is loaded): the kernel evaluates their interpolant (PCHIP in slip, linear in
        ``r_g``) and ``mu_max(r_g)`` is its peak (`TabulatedTraction.mu_max`); default the
        analytic law of ``[traction]`` (`traction_law`).
    loss_map : LossMap, optional
        A measured torque-loss map ``T_loss(r_g, omega_in, T_in, F_s)``
        (`empact.variator.losses.load_loss_map`; a path is loaded): the kernel applies its
        torque loss on the primary in place of the clamping, load and drag losses of
        ``[losses]`` (the slip stays the traction law's); default those analytic losses.
    traction_law : str
        The analytic traction law the kernel evaluates without measured curves, one of the
        registered laws (`empact.variator.traction.TRACTION_LAWS`: ``"magic-formula"``,
        the default, ...), its coefficients from ``[traction]``.
    reference_ratio : float, optional
        Ratio of the output ``nu_r = 1 - omega_s / (r_ref omega_p)`` (the slip of eq. 3 and
        Fig. 12, at a fixed operating ratio); default ``params.operating.r_g``.  The
        linearisation (`empact.nonlinear.linearization.linearize`) always refers ``nu_r`` to
        the trimmed ratio.
    """

    damping: Literal["none", "moderate", "large"] = "moderate"
    belt: Literal["traction", "locked"] = "traction"
    driveline: Literal["bench", "vehicle"] = "bench"
    drive: Literal["torque", "speed"] = "torque"
    load: Literal["torque", "speed"] = "torque"
    ratio_control: bool = False
    coulomb_sp: float = 0.0
    coulomb_ss: float = 0.0
    coulomb_omega: float = 0.5
    drive_bandwidth_hz: float = 5.0
    load_bandwidth_hz: float = 5.0
    ratio_bandwidth_hz: float = 2.0
    kinematics: Literal["equal-translation", "paper-sec2.1"] = "equal-translation"
    shift_law: Literal["carbone", "ide", "shafai"] = "carbone"
    thrust_ratio: TabulatedThrustRatio | None = None
    reference_ratio: float | None = None
    creep_map: CreepMap | None = None
    traction: TabulatedTraction | None = None
    traction_law: str = DEFAULT_TRACTION_LAW
    loss_map: LossMap | None = None
    drive_bandwidth: InitVar[float | None] = None
    load_bandwidth: InitVar[float | None] = None
    ratio_bandwidth: InitVar[float | None] = None

    def __post_init__(self, drive_bandwidth: float | None = None,
                      load_bandwidth: float | None = None,
                      ratio_bandwidth: float | None = None) -> None:
        for old, value in (("drive_bandwidth", drive_bandwidth),
                           ("load_bandwidth", load_bandwidth),
                           ("ratio_bandwidth", ratio_bandwidth)):
            if value is not None:
                warn_renamed(f"ModelOptions.{old}", f"{old}_hz [Hz]", stacklevel=3)
                object.__setattr__(self, f"{old}_hz", value)
        check_choice("damping", self.damping, DAMPING_LEVELS)
        check_choice("kinematics", self.kinematics, KINEMATICS)
        check_choice("shift_law", self.shift_law, SHIFT_LAWS)
        check_choice("traction_law", self.traction_law, TRACTION_LAWS)
        if self.thrust_ratio is not None and not isinstance(self.thrust_ratio,
                                                            TabulatedThrustRatio):
            raise ParameterError(f"thrust_ratio = {self.thrust_ratio!r}: must be a "
                                 "TabulatedThrustRatio (empact.variator.thrust_ratio."
                                 "load_thrust_ratio)")
        if self.creep_map is not None and not isinstance(self.creep_map, CreepMap):
            raise ParameterError(f"creep_map = {self.creep_map!r}: must be a CreepMap "
                                 "(empact.variator.shift_law.load_creep_map)")
        if self.traction is not None and not isinstance(self.traction, TabulatedTraction):
            raise ParameterError(f"traction = {self.traction!r}: must be a TabulatedTraction "
                                 "(empact.variator.traction.load_traction)")
        if self.loss_map is not None and not isinstance(self.loss_map, LossMap):
            raise ParameterError(f"loss_map = {self.loss_map!r}: must be a LossMap "
                                 "(empact.variator.losses.load_loss_map)")
        if self.reference_ratio is not None:
            object.__setattr__(self, "reference_ratio", check_number(
                "reference_ratio", self.reference_ratio, 0.0, lo_open=True))
        check_choice("belt", self.belt, ("traction", "locked"))
        check_choice("drive", self.drive, ("torque", "speed"))
        check_choice("load", self.load, ("torque", "speed"))
        check_choice("driveline", self.driveline, DRIVELINES)
        if self.driveline == "vehicle" and (self.drive, self.load) != ("torque", "torque"):
            raise ParameterError(f"driveline = 'vehicle' with drive = {self.drive!r}, load = "
                                 f"{self.load!r}: the car's engine and road are torques "
                                 "(drive = 'torque', load = 'torque')")
        check_bool("ratio_control", self.ratio_control)
        for name, unit in (("coulomb_sp", "N m"), ("coulomb_ss", "N m")):
            object.__setattr__(self, name, check_number(name, getattr(self, name), 0.0,
                                                        unit=unit))
        for name, unit in (("coulomb_omega", "rad/s"), ("drive_bandwidth_hz", "Hz"),
                           ("load_bandwidth_hz", "Hz"), ("ratio_bandwidth_hz", "Hz")):
            object.__setattr__(self, name, check_number(name, getattr(self, name), 0.0,
                                                        lo_open=True, unit=unit))

    @classmethod
    def from_mapping(cls, values: dict) -> "ModelOptions":
        """Options from keyword values; an unknown key is an error naming the allowed ones.

        Parameters
        ----------
        values : dict
            Option names (the fields of `ModelOptions`, or a deprecated name) to values;
            ``thrust_ratio``, ``creep_map``, ``traction`` and ``loss_map`` may be file paths
            (read here).
        """
        allowed = [f.name for f in fields(cls)] + list(_DEPRECATED_OPTIONS)
        for key in values:
            if key not in allowed:
                raise ParameterError(f"unknown model option {key!r} (allowed: "
                                     f"{', '.join(allowed)})")
        values = dict(values)
        if isinstance(values.get("thrust_ratio"), (str, os.PathLike)):
            values["thrust_ratio"] = load_thrust_ratio(values["thrust_ratio"])
        if isinstance(values.get("creep_map"), (str, os.PathLike)):
            values["creep_map"] = load_creep_map(values["creep_map"])
        if isinstance(values.get("traction"), (str, os.PathLike)):
            values["traction"] = load_traction(values["traction"])
        if isinstance(values.get("loss_map"), (str, os.PathLike)):
            values["loss_map"] = load_loss_map(values["loss_map"])
        return cls(**values)


#: the options of the car (`ModelOptions.driveline`): the engine and the road as torques
VEHICLE_OPTIONS = {"driveline": "vehicle", "drive": "torque", "load": "torque"}

#: option names kept for one release (a DeprecationWarning names the new one)
_DEPRECATED_OPTIONS = ("drive_bandwidth", "load_bandwidth", "ratio_bandwidth")
