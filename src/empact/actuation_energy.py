"""Where the actuation's energy goes: the servos' electrical power with their transmissions'
friction, and a hydraulic reference actuation of the same variator.

Servos (``[servo]``, `empact.hardware.ServoLimits`)
    Each servo's electrical (DC-bus) power is the sum of four terms [W]:

    * ``mechanical``: the motor shaft's power ``T_m omega``;
    * ``gear``: the transmission's friction, ``T_m omega - T omega`` (>= 0), with ``T`` the
      torque the model's lossless transmission asks of the servo (the simulation's
      ``T_mp_act``, ``T_ms_act``) and ``T_m`` the motor torque that carries it through the
      real one: ``T / eta_f`` when the servo drives (``T omega > 0``), ``eta_b T`` when the
      mechanism drives the servo back (``eta_b <= 0``: a self-locking path, which the servo
      must drive even to let it go back);
    * ``copper``: ``(T_m / k_m)^2``, the winding loss, which a servo pays at standstill too
      (holding 8 N m costs ``(8 / k_m)^2`` W);
    * ``drive``: the inverter's loss, ``(1 / eta_drive - 1)`` of the motor's electrical power
      ``mechanical + copper`` when it draws, ``(1 - eta_drive)`` of it when it regenerates
      (the regenerated power goes back to a DC bus that takes it, e.g. the other servo's).

    A servo slower than ``omega_hold`` holds: its transmission passes no power and the motor
    holds ``T`` (a back-drivable path; its static friction would allow anything between
    ``eta_b T`` and ``T / eta_f``: the frictionless ``T`` is billed) or nothing (a
    self-locking path, ``eta_b <= 0``: friction holds the load with the motor off).

    The transmissions: primary servo -> worm -> epicyclic set -> screw; secondary servo ->
    chain -> epicyclic set -> screw.  The worm and the screws have the closed-form
    efficiencies of a thread of lead angle ``gamma`` and friction coefficient ``mu`` at
    normal pressure angle ``phi_n`` (Shigley's *Mechanical Engineering Design*, worm gearing;
    ``phi_n = 0`` for a screw): forward ``(cos phi_n - mu tan gamma) / (cos phi_n + mu cot
    gamma)``, backward ``(cos phi_n - mu cot gamma) / (cos phi_n + mu tan gamma)``; the
    thread is self-locking when the backward efficiency is not positive, i.e. when ``tan
    gamma <= mu / cos phi_n`` (the lead angle at most the friction angle).  A path's
    efficiency is the product of its stages' (exact while only the stage next to the servo,
    the worm, can lock).  With a self-locking worm holding the ratio costs the primary servo
    nothing; with a back-drivable one it holds the primary thrust difference with current.

    **Limitation.** The losses are billed quasi-statically to the servos' electrical power
    from the model's servo torques and speeds: the kernel's dynamics keeps its lossless
    transmission (no friction torque acts on its shafts, no stick-slip), so a run's motion is
    that of the lossless machine and only its energy bill includes the friction.

Hydraulic reference (``[hydraulic]``, `empact.hardware.HydraulicParams`)
    The same variator clamped and shifted by oil pressure, as production pushbelt CVTs are
    (Veenhuizen, Bonsen, Klaassen et al., SAE 04CVT-49, 2004): an engine-driven fixed
    displacement pump at ``pump_ratio`` times the primary speed, the line pressure the larger
    of the two pulley forces over their piston areas plus ``p_margin``, all the pump's flow
    at line pressure.  The pump's shaft power ``V omega p / eta_hm`` splits into the terms
    ``pump_friction`` (hydromechanical), ``pump_leakage`` (volumetric), ``leakage`` (the
    valves' and seals' ``c_leak p`` at line pressure), ``shift`` (the flow that fills a
    moving sheave's cylinder) and ``relief`` (the rest, spilled over the pressure valve;
    negative: the pump cannot supply the demand).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ._results import Result
from .hardware import HydraulicParams
from .nonlinear.model import sheave_sense
from .nonlinear.simulation import SimulationResult
from .params import Params

__all__ = ["PRESSURE_ANGLE", "SERVO_TERMS", "PUMP_TERMS", "thread_efficiency",
           "Transmissions", "transmissions", "motor_power", "servo_power", "line_pressure",
           "hydraulic_power", "ActuationEnergy", "actuation_energy"]

#: normal pressure angle of the worm's thread [rad] (20 deg, the standard pressure angle of
#: ISO 54 / DIN 3975 worm gearing)
PRESSURE_ANGLE = math.radians(20.0)
#: a servo's power terms [W] (their sum is its electrical power)
SERVO_TERMS = ("mechanical", "gear", "copper", "drive")
#: the hydraulic reference's power terms [W] (their sum is the pump's shaft power)
PUMP_TERMS = ("pump_friction", "pump_leakage", "leakage", "shift", "relief")


def thread_efficiency(lead: ArrayLike, mu: ArrayLike,
                      pressure_angle: float = 0.0) -> tuple[Any, Any]:
    """Forward and backward efficiency of a thread (a worm or a screw).

    Parameters
    ----------
    lead : array_like
        Lead angle ``gamma`` [rad], in (0, pi/2).
    mu : array_like
        Friction coefficient [-], >= 0.
    pressure_angle : float, optional
        Normal pressure angle ``phi_n`` [rad] (0: a screw; `PRESSURE_ANGLE` for a worm).

    Returns
    -------
    forward : float or array
        ``(cos phi_n - mu tan gamma) / (cos phi_n + mu cot gamma)`` [-]: output power over
        input power when the thread's driving member drives.
    backward : float or array
        ``(cos phi_n - mu cot gamma) / (cos phi_n + mu tan gamma)`` [-] when the load drives
        it back; ``<= 0``: self-locking (``tan gamma <= mu / cos phi_n``), the driving member
        must drive the load back.
    """
    g, m = np.asarray(lead, float), np.asarray(mu, float)
    c, t = math.cos(pressure_angle), np.tan(g)
    forward = (c - m * t) / (c + m / t)
    backward = (c - m / t) / (c + m * t)
    return forward[()], backward[()]


@dataclass(frozen=True)
class Transmissions(Result):
    """The servos' transmissions: each stage's and each path's efficiency.

    Attributes
    ----------
    worm, screw : tuple of float
        ``(forward, backward)`` efficiency of the worm and of each screw [-].
    screw_lead : float
        Lead angle of the screws [rad] (``atan(2 s / screw_d)``).
    primary, secondary : tuple of float
        ``(forward, backward)`` efficiency of the primary path (worm, epicyclic set, screw)
        and of the secondary path (chain, epicyclic set, screw) [-].
    worm_self_locking : bool
        The worm's lead angle is at most its friction angle (``tan(worm_lead) <= worm_mu /
        cos(PRESSURE_ANGLE)``): holding the ratio costs the primary servo nothing.
    worm_friction_angle : float
        ``atan(worm_mu / cos(PRESSURE_ANGLE))`` [rad].
    """

    worm: tuple[float, float]
    screw: tuple[float, float]
    screw_lead: float
    primary: tuple[float, float]
    secondary: tuple[float, float]
    worm_self_locking: bool
    worm_friction_angle: float


def transmissions(params: Params) -> Transmissions:
    """The servos' transmissions of a parameter set (``[servo]`` and the screw pitch ``s``).

    Parameters
    ----------
    params : Params
        The parameter set.

    Returns
    -------
    Transmissions
        Each stage's and each path's forward and backward efficiency, and whether the worm
        self-locks.
    """
    sv, s = params.servo, params.actuation.s
    worm = tuple(float(v) for v in thread_efficiency(sv.worm_lead, sv.worm_mu,
                                                        PRESSURE_ANGLE))
    lead = math.atan(2 * s / sv.screw_d)
    screw = tuple(float(v) for v in thread_efficiency(lead, sv.screw_mu))
    e = sv.eta_epicyclic
    primary = (worm[0] * e * screw[0], worm[1] * e * screw[1])
    secondary = (sv.eta_chain * e * screw[0], sv.eta_chain * e * screw[1])
    phi = math.atan(sv.worm_mu / math.cos(PRESSURE_ANGLE))
    return Transmissions(worm=(worm[0], worm[1]), screw=(screw[0], screw[1]), screw_lead=lead,
                         primary=primary, secondary=secondary,
                         worm_self_locking=bool(worm[1] <= 0.0), worm_friction_angle=phi)


def motor_power(T: ArrayLike, omega: ArrayLike, k_m: float, efficiency: tuple[float, float],
                eta_drive: float, omega_hold: float = 0.0) -> dict[str, NDArray[np.float64]]:
    """One servo's power terms (module notes) over arrays of its torque and speed.

    Parameters
    ----------
    T : array_like
        The torque the model's lossless transmission asks of the servo [N m].
    omega : array_like
        The servo's speed [rad/s] (broadcast against `T`).
    k_m : float
        Motor constant [N m/sqrt(W)].
    efficiency : tuple of float
        ``(forward, backward)`` efficiency of the servo's transmission [-] (backward ``<=
        0``: self-locking).
    eta_drive : float
        Drive (inverter) efficiency [-].
    omega_hold : float, optional
        Speed below which the servo holds [rad/s] (default 0: only at rest).

    Returns
    -------
    dict str -> array
        `SERVO_TERMS` [W] (``mechanical`` signed, the others >= 0), each of the broadcast
        shape; their sum is the servo's electrical power.
    """
    T, w = np.broadcast_arrays(np.asarray(T, float), np.asarray(omega, float))
    eta_f, eta_b = efficiency
    holding = np.abs(w) <= omega_hold
    P = T * w
    T_m = np.where(P > 0, T / eta_f, eta_b * T)
    T_m = np.where(holding, T if eta_b > 0 else 0.0 * T, T_m)
    mech = np.where(holding, 0.0, T_m * w)
    gear = np.where(holding, 0.0, mech - P)
    copper = (T_m / k_m) ** 2
    motor = mech + copper
    drive = np.where(motor >= 0, (1 / eta_drive - 1) * motor, -(1 - eta_drive) * motor)
    return {"mechanical": mech, "gear": gear, "copper": copper, "drive": drive}


def servo_power(params: Params, T_mp: ArrayLike, T_ms: ArrayLike, omega_mp: ArrayLike,
                omega_ms: ArrayLike) -> dict[str, NDArray[np.float64]]:
    """Both servos' power terms (module notes) over arrays of their torques and speeds.

    Parameters
    ----------
    params : Params
        The parameter set (``[servo]``, the screw pitch).
    T_mp, T_ms : array_like
        Primary and secondary servo torques [N m] (a simulation's ``T_mp_act``,
        ``T_ms_act``; a trim's holding torques).
    omega_mp, omega_ms : array_like
        Primary and secondary servo speeds [rad/s] (``omega_mp``, ``omega_ms``).

    Returns
    -------
    dict str -> array
        ``<term>_mp`` and ``<term>_ms`` for each of `SERVO_TERMS` [W]; their sum is the
        servos' electrical power.
    """
    sv, tr = params.servo, transmissions(params)
    out = {}
    for side, T, w, k_m, eff in (("mp", T_mp, omega_mp, sv.k_m_mp, tr.primary),
                                 ("ms", T_ms, omega_ms, sv.k_m_ms, tr.secondary)):
        terms = motor_power(T, w, k_m, eff, sv.eta_drive, sv.omega_hold)
        out.update({f"{k}_{side}": v for k, v in terms.items()})
    return out


def line_pressure(hydraulic: HydraulicParams, F_p: ArrayLike,
                  F_s: ArrayLike) -> NDArray[np.float64]:
    """Line pressure of the hydraulic reference [Pa]: the larger of ``F_p / A_p`` and ``F_s /
    A_s`` plus ``p_margin``.

    Parameters
    ----------
    hydraulic : HydraulicParams
        The ``[hydraulic]`` section (`empact.hardware.HydraulicParams`).
    F_p, F_s : array_like
        Primary and secondary pulley (clamping) forces [N] (negative taken as 0).

    Returns
    -------
    array
        Line pressure [Pa], the broadcast shape.
    """
    h = hydraulic
    need = np.maximum(np.maximum(np.asarray(F_p, float), 0.0) / h.A_p,
                      np.maximum(np.asarray(F_s, float), 0.0) / h.A_s)
    return np.asarray(need + h.p_margin)


def hydraulic_power(hydraulic: HydraulicParams, F_p: ArrayLike, F_s: ArrayLike,
                    omega_p: ArrayLike, fill_p: ArrayLike = 0.0,
                    fill_s: ArrayLike = 0.0) -> dict[str, NDArray[np.float64]]:
    """The hydraulic reference's power terms (module notes) over arrays of the pulley forces
    and the primary speed.

    Parameters
    ----------
    hydraulic : HydraulicParams
        The ``[hydraulic]`` section (`empact.hardware.HydraulicParams`).
    F_p, F_s : array_like
        Primary and secondary pulley forces [N].
    omega_p : array_like
        Primary (engine) speed [rad/s]; the pump turns at ``pump_ratio`` times it.
    fill_p, fill_s : array_like, optional
        Axial speeds of the moving sheaves [m/s], positive where the cylinder fills (the
        running radius grows); emptying needs no flow (default 0: steady state).

    Returns
    -------
    dict str -> array
        `PUMP_TERMS` [W]; their sum is the pump's shaft power ``V omega p / eta_hm``.
    """
    h = hydraulic
    p = line_pressure(h, F_p, F_s)
    q = h.displacement * h.pump_ratio * np.asarray(omega_p, float)
    hyd = q * p
    friction = hyd * (1 / h.eta_hm - 1)
    volumetric = hyd * (1 - h.eta_vol)
    leakage = h.c_leak * p * p
    shift = (h.A_p * np.maximum(np.asarray(fill_p, float), 0.0)
             + h.A_s * np.maximum(np.asarray(fill_s, float), 0.0)) * p
    relief = h.eta_vol * hyd - leakage - shift
    terms = {"pump_friction": friction, "pump_leakage": volumetric, "leakage": leakage,
             "shift": shift, "relief": relief}
    shape = np.broadcast_shapes(*(np.shape(v) for v in terms.values()))
    return {k: np.broadcast_to(v, shape).astype(float) for k, v in terms.items()}


@dataclass(frozen=True)
class ActuationEnergy(Result):
    """A simulation's actuation energy: the servos' (with their transmissions) and the
    hydraulic reference's on the same motion (`actuation_energy`).

    Attributes
    ----------
    duration : float
        The run's length [s].
    energy : dict str -> float
        The servos' energy by term [J] (``<term>_mp``, ``<term>_ms`` of `SERVO_TERMS`) and
        their sum ``servo_electrical``.
    hydraulic : dict str -> float
        The hydraulic reference's energy by term [J] (`PUMP_TERMS`) and their sum ``pump``.
    mean_power : dict str -> float
        ``servo_electrical`` and ``pump`` over the run's length [W].
    rms_torque : dict str -> float
        RMS torque of each servo over the run [N m] (``mp``, ``ms``).
    continuous_torque : dict str -> float
        Each servo's continuous torque ``T_max / overload`` [N m].
    worm_self_locking : bool
        Whether the worm self-locks (`Transmissions`).
    """

    duration: float
    energy: dict[str, float]
    hydraulic: dict[str, float]
    mean_power: dict[str, float]
    rms_torque: dict[str, float]
    continuous_torque: dict[str, float]
    worm_self_locking: bool


def _integral(t: NDArray, v: NDArray) -> float:
    """Trapezoidal integral of `v` over `t`."""
    return float(np.trapezoid(v, t)) if t.size > 1 else 0.0


def actuation_energy(result: SimulationResult, params: Params,
                     kinematics: str = "equal-translation") -> ActuationEnergy:
    """The servos' electrical energy of a simulation by term, and the hydraulic reference's
    pump energy on the same motion (quasi-static billing: module notes).

    Parameters
    ----------
    result : SimulationResult
        A run of the nonlinear model (`empact.nonlinear.simulation.simulate`; outputs
        ``T_mp_act``, ``T_ms_act``, ``omega_mp``, ``omega_ms``, ``F_p``, ``F_s``,
        ``omega_p``, states ``v_p``, ``v_s``).
    params : Params
        The parameter set whose ``[servo]`` and ``[hydraulic]`` bill the run.
    kinematics : str, optional
        The run's model option ``kinematics`` (the sense of the secondary sheave's
        coordinate, `empact.nonlinear.model.sheave_sense`; default the model's default).

    Returns
    -------
    ActuationEnergy
        Energies by term [J], mean powers [W], the servos' RMS and continuous torques [N m].
    """
    t = np.asarray(result.t, float)
    T_mp, T_ms = result.output("T_mp_act"), result.output("T_ms_act")
    servo = servo_power(params, T_mp, T_ms, result.output("omega_mp"),
                        result.output("omega_ms"))
    energy = {k: _integral(t, v) for k, v in servo.items()}
    energy["servo_electrical"] = sum(energy.values())
    sig = sheave_sense(kinematics)
    pump = hydraulic_power(params.hydraulic, result.output("F_p"), result.output("F_s"),
                           result.output("omega_p"), result.output("v_p"),
                           -sig * result.output("v_s"))
    hyd = {k: _integral(t, v) for k, v in pump.items()}
    hyd["pump"] = sum(hyd.values())
    duration = float(t[-1] - t[0]) if t.size else 0.0
    mean = {k: (e / duration if duration > 0 else float("nan"))
            for k, e in (("servo_electrical", energy["servo_electrical"]),
                         ("pump", hyd["pump"]))}
    rms = {k: (float(np.sqrt(_integral(t, T * T) / duration)) if duration > 0
               else float(np.abs(T).max(initial=0.0)))
           for k, T in (("mp", T_mp), ("ms", T_ms))}
    sv = params.servo
    cont = {"mp": sv.T_mp_max / sv.overload, "ms": sv.T_ms_max / sv.overload}
    return ActuationEnergy(duration=duration, energy=energy, hydraulic=hyd, mean_power=mean,
                           rms_torque=rms, continuous_torque=cont,
                           worm_self_locking=transmissions(params).worm_self_locking)
