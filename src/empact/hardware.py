"""The machine's servo drives and sensors as a controller sees them: torque and speed limits of
the two servos, and the instruments the loop measures with.

Two parameter sections (``[servo]``, ``[sensors]`` of a parameter file; a closed-loop
scenario's ``[limits]`` and ``[sensors]`` tables override them key by key):

``[servo]``
    ``T_mp_max``, ``T_ms_max`` [N m]: the largest torque each servo drive delivers (its
    current limit); ``omega_mp_max``, ``omega_ms_max`` [rad/s]: the largest speed (above
    ``1 - SPEED_BAND`` of it the torque that would drive the servo faster falls linearly to
    zero, a drive's speed limiter).
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

from dataclasses import dataclass

from ._section import Section, param
from .errors import ParameterError

__all__ = ["ServoLimits", "SensorParams", "SPEED_BAND"]

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
    """

    _name = "servo"

    T_mp_max: float = param("N m", "largest primary servo torque", 0.0, 1e3, default=3.0)
    T_ms_max: float = param("N m", "largest secondary servo torque", 0.0, 1e3, default=15.0)
    omega_mp_max: float = param("rad/s", "largest primary servo speed", 0.0, 1e5,
                                default=630.0)
    omega_ms_max: float = param("rad/s", "largest secondary servo speed", 0.0, 1e5,
                                default=630.0)


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
