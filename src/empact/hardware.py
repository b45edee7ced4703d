"""The machine's servo drives and sensors as a controller sees them: torque and speed limits of
the two servos, their electrical and transmission losses, and the instruments the loop
measures with; and the hydraulic actuation the machine is compared with.

Three parameter sections (``[servo]``, ``[sensors]`` of a parameter file; a closed-loop
scenario's ``[limits]`` and ``[sensors]`` tables override them key by key; ``[hydraulic]``,
`HydraulicParams`, billed by `empact.actuation_energy`):

``[servo]``
    ``T_mp_max``, ``T_ms_max`` [N m]: the largest torque each servo drive delivers (its
    current limit); ``omega_mp_max``, ``omega_ms_max`` [rad/s]: the largest speed (above
    ``1 - SPEED_BAND`` of it the torque that would drive the servo faster falls linearly to
    zero, a drive's speed limiter).  The same section gives the servos' losses
    (`empact.actuation_energy` bills them): ``k_m_mp``, ``k_m_ms`` [N m/sqrt(W)] motor
    constants (copper loss ``(T / k_m)^2``), ``eta_drive`` [-] the drives' (inverters')
    efficiency, ``overload`` [-] peak over continuous torque (the continuous torque is
    ``T_*_max / overload``: one source of the torque ratings), ``omega_hold`` [rad/s] the
    speed below which a servo counts as holding, and the transmissions: the worm's lead
    angle ``worm_lead`` [rad] and friction coefficient ``worm_mu`` [-], the chain's and the
    epicyclic sets' efficiencies ``eta_chain``, ``eta_epicyclic`` [-], the screws' mean
    diameter ``screw_d`` [m] and friction coefficient ``screw_mu`` [-].
``[sensors]``
    ``delay`` [samples]: every measurement reaches the controller this many samples late;
    ``speed_counts`` [counts/rev] and ``speed_window`` [s]: the primary and secondary shaft
    speeds come from counting encoders, i.e. the mean speed over the window, quantised to
    ``2 pi / (speed_counts * speed_window)``; ``speed_noise`` [rad/s]: added white noise;
    ``ratio_quantum`` [-]: resolution of the ratio (sheave-position sensor);
    ``torque_noise`` [N m]: white noise of the driveshaft torque sensor.  The slip the
    controller uses is computed from these (``1 - omega_s / (r_g omega_p)``).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from ._section import Section, param
from .errors import ParameterError

__all__ = ["ServoLimits", "SensorParams", "HydraulicParams", "SPEED_BAND"]

#: the share of the speed range over which a drive's speed limiter takes the torque to zero
SPEED_BAND = 0.05


@dataclass(frozen=True)
class ServoLimits(Section):
    """Torque and speed limits of the primary (shift) and secondary (clamping) servo drives.

    Attributes
    ----------
    T_mp_max : float
        Largest primary servo torque [N m], in (0, 1000] (default 3).
    T_ms_max : float
        Largest secondary servo torque [N m], in (0, 1000] (default 15).
    omega_mp_max : float
        Largest primary servo speed [rad/s], in (0, 1e5] (default 630); above
        ``1 - SPEED_BAND`` of it the torque that would drive the servo faster falls linearly
        to zero.
    omega_ms_max : float
        Largest secondary servo speed [rad/s], in (0, 1e5] (default 630), limited the same
        way.
    k_m_mp, k_m_ms : float
        Motor constants of the primary and secondary servo [N m/sqrt(W)], in (0, 100]
        (defaults 0.2 and 0.6): ``k_t / sqrt(R)`` of a datasheet's torque constant and
        winding resistance (the same convention for both); the copper loss at torque ``T``
        is ``(T / k_m)^2`` [W].
    eta_drive : float
        Efficiency of each servo drive (inverter) [-], in (0, 1] (default 0.95).
    overload : float
        Peak over continuous (standstill) torque of each servo [-], in [1, 20] (default 3):
        the continuous torques are ``T_mp_max / overload`` and ``T_ms_max / overload``.
    omega_hold : float
        Servo speed below which a servo counts as holding [rad/s], in [0, 1e3] (default 0:
        only a servo at rest, as in a trim).
    worm_lead : float
        Lead angle of the worm [rad], in (0, pi/2) (default atan(3/10), 16.7 deg).
    worm_mu : float
        Friction coefficient of the worm mesh [-], in [0, 1) (default 0.05).
    eta_chain, eta_epicyclic : float
        Efficiency of the chain and of each epicyclic set [-], forward and backward, in
        (0, 1] (defaults 0.98, 0.98).
    screw_d : float
        Mean diameter of the screws [m], in (0, 1] (default 0.06); with the pitch ``s`` it
        gives the screws' lead angle ``atan(2 s / screw_d)``.
    screw_mu : float
        Friction coefficient of the screws [-], in [0, 1) (default 0.005, a ball screw's).
    """

    _name = "servo"

    T_mp_max: float = param("N m", "largest primary servo torque", 0.0, 1e3, default=3.0)
    T_ms_max: float = param("N m", "largest secondary servo torque", 0.0, 1e3, default=15.0)
    omega_mp_max: float = param("rad/s", "largest primary servo speed", 0.0, 1e5,
                                default=630.0)
    omega_ms_max: float = param("rad/s", "largest secondary servo speed", 0.0, 1e5,
                                default=630.0)
    k_m_mp: float = param("N m/sqrt(W)", "motor constant of the primary servo (copper loss "
                          "(T / k_m)^2)", 0.0, 100.0, default=0.2)
    k_m_ms: float = param("N m/sqrt(W)", "motor constant of the secondary servo (copper loss "
                          "(T / k_m)^2)", 0.0, 100.0, default=0.6)
    eta_drive: float = param("-", "efficiency of each servo drive (inverter)", 0.0, 1.0,
                             default=0.95)
    overload: float = param("-", "peak over continuous torque of each servo (continuous "
                            "torque T_max / overload)", 1.0, 20.0, lo_open=False, default=3.0)
    omega_hold: float = param("rad/s", "servo speed below which a servo counts as holding",
                              0.0, 1e3, lo_open=False, default=0.0)
    worm_lead: float = param("rad", "lead angle of the worm", 0.0, math.pi / 2, hi_open=True,
                             default=math.atan(0.3))
    worm_mu: float = param("-", "friction coefficient of the worm mesh", 0.0, 1.0,
                           lo_open=False, hi_open=True, default=0.05)
    eta_chain: float = param("-", "efficiency of the chain (forward and backward)", 0.0, 1.0,
                             default=0.98)
    eta_epicyclic: float = param("-", "efficiency of each epicyclic set (forward and "
                                 "backward)", 0.0, 1.0, default=0.98)
    screw_d: float = param("m", "mean diameter of the screws (lead angle atan(2 s / "
                           "screw_d))", 0.0, 1.0, default=0.06)
    screw_mu: float = param("-", "friction coefficient of the screws", 0.0, 1.0,
                            lo_open=False, hi_open=True, default=0.005)


@dataclass(frozen=True)
class SensorParams(Section):
    """The loop's instruments: delay, encoder quantisation and noise.

    Attributes
    ----------
    delay : float
        Measurement delay [samples], a whole number in [0, 100] (default 1): every
        measurement reaches the controller this many samples late.
    speed_counts : float
        Shaft encoder counts per revolution [counts/rev], in (0, 1e9] (default 8192).
    speed_window : float
        Counting window of the shaft speeds [s], in (0, 1] (default 0.01): a measured speed
        is the mean over the window, quantised to ``2 pi / (speed_counts * speed_window)``.
    speed_noise : float
        White noise on each shaft speed (standard deviation) [rad/s], in [0, 1000]
        (default 0).
    ratio_quantum : float
        Resolution of the measured ratio [-], in [0, 0.1] (default 2e-4).
    torque_noise : float
        White noise on the driveshaft torque (standard deviation) [N m], in [0, 1000]
        (default 0.25).
    engine_torque_delay : float
        Delay of the engine-torque estimate [s], in [0, 0.5] (default 0.02): what an engine
        controller's torque signal lags the engine by (the clamping feedforward on
        ``feedforward_signal = "T_e_est"``), rounded to whole samples.
    engine_torque_error : float
        Relative error of the engine-torque estimate [-], in [-0.5, 0.5] (default 0): the
        estimate is ``(1 + engine_torque_error)`` times the engine's torque.
    """

    _name = "sensors"

    delay: float = param("samples", "measurement delay (whole samples)", 0.0, 100.0,
                         lo_open=False, default=1.0, note="a whole number of samples")
    speed_counts: float = param("counts/rev", "shaft encoder counts per revolution", 0.0,
                                1e9, default=8192.0)
    speed_window: float = param("s", "counting window of the shaft speeds", 0.0, 1.0,
                                default=0.01)
    speed_noise: float = param("rad/s", "white noise on each shaft speed (standard "
                               "deviation)", 0.0, 1e3, lo_open=False, default=0.0)
    ratio_quantum: float = param("-", "resolution of the measured ratio", 0.0, 0.1,
                                 lo_open=False, default=2e-4)
    torque_noise: float = param("N m", "white noise on the driveshaft torque (standard "
                                "deviation)", 0.0, 1e3, lo_open=False, default=0.25)
    engine_torque_delay: float = param("s", "delay of the engine-torque estimate", 0.0, 0.5,
                                       lo_open=False, default=0.02)
    engine_torque_error: float = param("-", "relative error of the engine-torque estimate",
                                       -0.5, 0.5, lo_open=False, default=0.0)

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.delay != int(self.delay):
            raise ParameterError(f"sensors.delay = {self.delay!r}: must be a whole number of "
                                 "samples (0-100)")


@dataclass(frozen=True)
class HydraulicParams(Section):
    """A hydraulic actuation of the same variator (the reference a conventional pushbelt CVT
    gives), ``[hydraulic]`` of a parameter file.

    Attributes
    ----------
    displacement : float
        Pump displacement [m^3/rad], in (0, 1e-3] (default 19 cc/rev, SAE 04CVT-49).
    pump_ratio : float
        Pump speed over primary (engine) speed [-], in (0, 10] (default 1).
    eta_vol : float
        Volumetric efficiency of the pump [-], in (0, 1] (default 0.9).
    eta_hm : float
        Hydromechanical efficiency of the pump [-], in (0, 1] (default 0.85).
    c_leak : float
        Leakage of the valves and rotating seals per line pressure [m^3/(s Pa)], in [0,
        1e-8] (default 1.7e-11: 2 l/min at 20 bar).
    A_p, A_s : float
        Piston areas of the primary and secondary cylinders [m^2], in (0, 0.1] (default
        6.2e-3: 31 kN at 50 bar).
    p_margin : float
        Line pressure above the larger cylinder's need [Pa], in [0, 1e7] (default 2 bar).
    """

    _name = "hydraulic"

    displacement: float = param("m^3/rad", "pump displacement", 0.0, 1e-3,
                                default=19e-6 / (2 * math.pi))
    pump_ratio: float = param("-", "pump speed over primary (engine) speed", 0.0, 10.0,
                              default=1.0)
    eta_vol: float = param("-", "volumetric efficiency of the pump", 0.0, 1.0, default=0.9)
    eta_hm: float = param("-", "hydromechanical efficiency of the pump", 0.0, 1.0,
                          default=0.85)
    c_leak: float = param("m^3/(s Pa)", "leakage of the valves and seals per line pressure",
                          0.0, 1e-8, lo_open=False, default=1.7e-11)
    A_p: float = param("m^2", "piston area of the primary cylinder", 0.0, 0.1, default=6.2e-3)
    A_s: float = param("m^2", "piston area of the secondary cylinder", 0.0, 0.1,
                       default=6.2e-3)
    p_margin: float = param("Pa", "line pressure above the larger cylinder's need", 0.0, 1e7,
                            lo_open=False, default=2e5)
