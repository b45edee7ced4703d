"""The engine that drives the CVT (``[engine]``): full-load torque, a Willans-line fuel
model and the minimum-fuel operating line.

Full load
    ``T_full(omega) = T_peak (1 - c_full (omega / omega_T - 1)^2)`` [N m], a representative
    shape of a 1.6 l naturally aspirated spark-ignition engine (150 N m at 4000 rpm, 125 N m
    at 1000 rpm, 139 N m and 87 kW at 6000 rpm): a stated shape, not a measured curve.
Fuel (Willans line)
    The brake mean effective pressure is ``p_me = e p_mf - p_me0`` (Guzzella and Sciarretta,
    *Vehicle Propulsion Systems*, Springer, 3rd ed. 2013, Sec. 4.2: for SI engines ``e``
    about 0.4 and ``p_me0`` about 1-2 bar), so that the fuel power at brake torque ``T`` and
    speed ``omega`` is ``(T + T_0) omega / e`` with the friction torque ``T_0 = p_me0 V_d /
    (4 pi)``; the mass rate divides it by the lower heating value.  The coefficients are the
    book's typical values (the basis), not a fit to one engine: at idle (800 rpm, no load)
    the line gives 0.33 kg/h (0.45 l/h).
Operating line
    For a Willans line with constant ``e`` and ``p_me0`` the fuel at a given power grows with
    the speed, so the minimum-fuel speed for a power is the lowest that delivers it.  The
    drivability rule keeps a torque reserve: the engine runs at most at ``load_max`` (0.85)
    of its full-load torque, and never below ``omega_drive`` (1200 rpm) while driving.  A
    power beyond the reserve line is met at the speed of the line's largest power.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ._section import Section, param

__all__ = ["EngineParams", "full_load_torque", "friction_torque", "fuel_rate",
           "operating_speed", "max_line_power"]

_RPM = math.pi / 30


@dataclass(frozen=True)
class EngineParams(Section):
    """The engine, ``[engine]`` of a parameter file (every key has a default; module notes).

    Attributes
    ----------
    J_e : float
        Engine inertia with the torque converter's [kg m^2] (the nonlinear vehicle driveline's;
        the quasi-static cycle neglects it).
    omega_idle, omega_drive, omega_max : float
        Idle speed, lowest speed while driving, highest speed [rad/s].
    T_peak, omega_T, c_full : float
        Full-load curve: peak torque [N m], its speed [rad/s], curvature [-].
    V_d : float
        Displacement [m^3].
    e_willans : float
        Willans line's efficiency [-].
    p_me0 : float
        Willans line's friction mean effective pressure [Pa].
    load_max : float
        Drivability rule: the operating line's largest share of the full-load torque [-].
    rho_fuel : float
        Fuel density [kg/m^3].
    lhv : float
        Fuel's lower heating value [J/kg].
    eta_alternator : float
        Alternator efficiency [-]: the servos' electrical energy from the engine.
    """

    _name = "engine"

    J_e: float = param("kg m^2", "engine inertia with the torque converter's", 0.0, 10.0,
                       default=0.2)
    omega_idle: float = param("rad/s", "idle speed", 0.0, 500.0, default=800 * _RPM)
    omega_drive: float = param("rad/s", "lowest engine speed while driving", 0.0, 1000.0,
                               default=1200 * _RPM)
    omega_max: float = param("rad/s", "highest engine speed", 0.0, 2000.0,
                             default=6000 * _RPM)
    T_peak: float = param("N m", "full-load peak torque", 0.0, 2000.0, default=150.0)
    omega_T: float = param("rad/s", "speed of the peak torque", 0.0, 2000.0,
                           default=4000 * _RPM)
    c_full: float = param("-", "full-load curvature", 0.0, 0.9, lo_open=False, default=0.3)
    V_d: float = param("m^3", "displacement", 0.0, 0.01, default=1.6e-3)
    e_willans: float = param("-", "Willans line efficiency", 0.0, 0.6, default=0.4)
    p_me0: float = param("Pa", "Willans friction mean effective pressure", 0.0, 1e6,
                         lo_open=False, default=1.5e5)
    load_max: float = param("-", "operating line's largest share of full load", 0.0, 1.0,
                            default=0.85)
    rho_fuel: float = param("kg/m^3", "fuel density", 500.0, 1000.0, default=745.0)
    lhv: float = param("J/kg", "fuel lower heating value", 1e7, 1e8, default=43.0e6)
    eta_alternator: float = param("-", "alternator efficiency", 0.0, 1.0, default=0.6)


def full_load_torque(engine: EngineParams, omega: ArrayLike) -> NDArray[np.float64]:
    """The full-load torque at `omega` (module notes) [N m].

    Parameters
    ----------
    engine : EngineParams
    omega : array_like
        Engine speeds [rad/s].

    Returns
    -------
    array
        Torques [N m], the shape of `omega`.
    """
    x = np.asarray(omega, float) / engine.omega_T - 1
    return engine.T_peak * (1 - engine.c_full * x ** 2)


def friction_torque(engine: EngineParams) -> float:
    """The Willans line's friction torque ``p_me0 V_d / (4 pi)`` [N m] (four-stroke).

    Parameters
    ----------
    engine : EngineParams

    Returns
    -------
    float
    """
    return engine.p_me0 * engine.V_d / (4 * math.pi)


def fuel_rate(engine: EngineParams, T: ArrayLike, omega: ArrayLike) -> NDArray[np.float64]:
    """The fuel mass rate at brake torque `T` and speed `omega` [kg/s]: ``(T + T_0) omega /
    (e LHV)``, not below zero (no fuel while the engine is dragged beyond its friction).

    Parameters
    ----------
    engine : EngineParams
    T, omega : array_like
        Brake torques [N m] and speeds [rad/s] (broadcast).

    Returns
    -------
    array
        Fuel rates [kg/s].
    """
    T, w = np.asarray(T, float), np.asarray(omega, float)
    P = (T + friction_torque(engine)) * w / engine.e_willans
    return np.maximum(P, 0.0) / engine.lhv


def _line_power(engine: EngineParams, omega: NDArray) -> NDArray:
    """The operating line's largest power at `omega`: ``load_max T_full omega`` [W]."""
    return engine.load_max * full_load_torque(engine, omega) * omega


def max_line_power(engine: EngineParams) -> tuple[float, float]:
    """The operating line's largest power [W] and its speed [rad/s] (up to ``omega_max``).

    Parameters
    ----------
    engine : EngineParams

    Returns
    -------
    (float, float)
    """
    w = np.linspace(engine.omega_drive, engine.omega_max, 4001)
    P = _line_power(engine, w)
    k = int(np.argmax(P))
    return float(P[k]), float(w[k])


def operating_speed(engine: EngineParams, P: ArrayLike) -> NDArray[np.float64]:
    """The minimum-fuel engine speed for the power `P` under the drivability rule (module
    notes): the lowest speed in ``[omega_drive, omega(P_max)]`` whose reserve line delivers
    `P` (bisection to 1e-9 rad/s); ``omega_drive`` for ``P <= 0``.

    Parameters
    ----------
    engine : EngineParams
    P : array_like
        Powers [W].

    Returns
    -------
    array
        Engine speeds [rad/s], the shape of `P`.
    """
    P = np.asarray(P, float)
    P_max, w_max = max_line_power(engine)
    lo = np.full(P.shape, engine.omega_drive)
    hi = np.full(P.shape, w_max)
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        short = _line_power(engine, mid) < P
        lo = np.where(short, mid, lo)
        hi = np.where(short, hi, mid)
        if np.all(hi - lo <= 1e-9):
            break
    w = np.where(_line_power(engine, lo) >= P, lo, hi)
    return np.where(P >= P_max, w_max, w)
