"""The car around the CVT: mass, wheels, final drive and road load (``[vehicle]``).

The road load at speed ``v`` [m/s] is ``f0 + f1 v + f2 v^2`` [N] (the coast-down form of UN
GTR 15 and the EPA test-car list) plus ``m g sin(grade)``; the wheel force adds the inertia
``m (1 + e_rot) a`` (``e_rot`` the rotating parts' mass factor).  The shipped car is the JRC
``wltp`` package's example vehicle (0.1.2a0, ``wltp.model.validate_model``'s docstring:
``test_mass = 1300`` kg, ``resistance_coeffs = [100, 0.5, 0.04]`` in N, N/(km/h),
N/(km/h)^2), a compact car.

The final drive ratio ``i_fd`` (secondary speed over wheel speed) is chosen so that the
variator's ratio range (``r_g = omega_s / omega_p`` in 0.43-2.25) covers the car: in OD
(2.25) 120 km/h is 2450 rpm of engine speed (``omega_e = v i_fd / (r_w r_g)``), 131.3 km/h
2680 rpm; in LOW (0.43) the engine's minimum driving speed of 1200 rpm is reached at
11.2 km/h (below it the launch clutch slips).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ._section import Section, param

__all__ = ["G", "VehicleParams", "road_load", "wheel_force"]

#: standard gravity [m/s^2]
G = 9.80665


@dataclass(frozen=True)
class VehicleParams(Section):
    """The car, ``[vehicle]`` of a parameter file (every key has a default; module notes).

    Attributes
    ----------
    mass : float
        Test mass [kg].
    e_rot : float
        Rotating parts' equivalent mass over the mass [-] (wheels, driveshafts, final drive).
    r_wheel : float
        Dynamic rolling radius [m].
    i_fd : float
        Final drive ratio (secondary speed over wheel speed) [-].
    eta_fd : float
        Final drive efficiency [-] (constant).
    f0, f1, f2 : float
        Road load coefficients [N], [N s/m], [N s^2/m^2].
    grade : float
        Road grade angle [rad].
    k_driveline : float
        Torsional stiffness of the driveline between the final drive and the road, at the
        wheels [N m/rad]: both half-shafts in parallel with the tyres' compliance in series
        (the nonlinear vehicle driveline reflects it to the secondary as ``k_driveline /
        i_fd^2``; the quasi-static cycle does not use it).
    """

    _name = "vehicle"

    mass: float = param("kg", "test mass", 100.0, 1e5, default=1300.0)
    e_rot: float = param("-", "rotating parts' mass factor", 0.0, 1.0, lo_open=False,
                         default=0.03)
    r_wheel: float = param("m", "dynamic rolling radius", 0.1, 1.0, default=0.30)
    i_fd: float = param("-", "final drive ratio (secondary over wheel speed)", 0.5, 20.0,
                        default=5.2)
    eta_fd: float = param("-", "final drive efficiency", 0.5, 1.0, default=0.97)
    f0: float = param("N", "road load, constant term", 0.0, 1e4, lo_open=False,
                      default=100.0)
    f1: float = param("N s/m", "road load, linear term", 0.0, 1e3, lo_open=False,
                      default=0.5 * 3.6)
    f2: float = param("N s^2/m^2", "road load, quadratic term", 0.0, 100.0, lo_open=False,
                      default=0.04 * 3.6 ** 2)
    grade: float = param("rad", "road grade angle", -0.5, 0.5, lo_open=False, default=0.0)
    k_driveline: float = param("N m/rad", "driveline torsional stiffness at the wheels "
                               "(half-shafts and tyres; the nonlinear vehicle driveline's)",
                               100.0, 1e6, default=8000.0)


def road_load(vehicle: VehicleParams, v: ArrayLike) -> NDArray[np.float64]:
    """The road load at speed `v`: ``f0 + f1 v + f2 v^2 + m g sin(grade)`` while moving,
    ``m g sin(grade)`` at rest (no rolling resistance without motion) [N].

    Parameters
    ----------
    vehicle : VehicleParams
    v : array_like
        Speeds [m/s], >= 0.

    Returns
    -------
    array
        Forces [N], the shape of `v`.
    """
    v = np.asarray(v, float)
    slope = vehicle.mass * G * math.sin(vehicle.grade)
    return np.where(v > 0, vehicle.f0 + vehicle.f1 * v + vehicle.f2 * v ** 2, 0.0) + slope


def wheel_force(vehicle: VehicleParams, v: ArrayLike, a: ArrayLike) -> NDArray[np.float64]:
    """The tractive force at the wheels for speed `v` and acceleration `a`: road load plus
    ``m (1 + e_rot) a`` [N].

    Parameters
    ----------
    vehicle : VehicleParams
    v, a : array_like
        Speeds [m/s] and accelerations [m/s^2] (broadcast).

    Returns
    -------
    array
        Forces [N] (negative: braking).
    """
    a = np.asarray(a, float)
    return road_load(vehicle, v) + vehicle.mass * (1 + vehicle.e_rot) * a
