"""The drive cycle, quasi-static (backward): from the speed trace to the variator's operating
point, its losses and actuation, the engine and its fuel, by clamping strategy.

At every sample of the trace (speed ``v``, acceleration ``a`` by central differences):

1. The wheel force ``F`` (`empact.vehicle.wheel_force`) and power ``P_w = F v``; the
   positive part summed is the traction energy at the wheels.
2. Traction (``F > 0``, ``v > 0``): the final drive asks of the secondary the load torque
   ``T_l = F r_w / (i_fd eta_fd)`` at ``omega_s = v i_fd / r_w``.  The operating line
   (`empact.engine.operating_speed`) gives the engine speed for the power ``T_l omega_s``
   (the variator's output: its losses, a few %, do not move the reference, which the
   drivability reserve covers); the ratio ``r_g = omega_s / omega_e`` is clipped to the
   design range `RATIO_LIMITS`.  Below the speed at which LOW reaches ``omega_drive`` the
   launch clutch (the torque converter's lock-up, slipping) keeps the engine at
   ``omega_drive``: its loss is ``T_p (omega_e - omega_p)``.
3. The variator is trimmed there (`empact.nonlinear.equilibrium.trim_grid`, vectorised over
   the samples, no interpolation): at the strategy's clamping (`empact.efficiency`), never
   below `MIN_CLAMPING`; the primary speed is iterated so that the slipping belt gives the
   wheels' ``omega_s`` (to 1e-12).
4. Coasting and braking (``F <= 0`` while moving): no regeneration; the friction brakes take
   the whole negative demand, the variator runs unloaded (``T_l = 0``) at ``MIN_CLAMPING``
   at the operating line's ratio for zero power, and the engine, fuelled (no fuel cut),
   supplies its losses and the actuation.  At rest the drive clutch is open (idle
   neutral): the variator stands still (no losses), its actuation holds ``MIN_CLAMPING``,
   and the engine idles.
5. The actuation: the servos' electrical power (`empact.actuation_energy.servo_power`,
   holding torques at steady state) from the alternator (``eta_alternator``), or the
   hydraulic reference's pump on the engine (`empact.actuation_energy.hydraulic_power`, at
   the engine's speed).  The engine's brake power ``P_e`` closes the balance ``P_e = P_w+
   + final drive + launch + variator losses + actuation + alternator``; its fuel is the
   Willans line's (`empact.engine.fuel_rate`).

Energies are the trapezoid rule over the samples (weights ``w_k``); a phase's energy is the
sum over its samples, so that the phases add up to the cycle.  The engine's and the
variator's own inertia are neglected (steady-state trims); the dynamic cycle is issue 34's
stage 3.
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ._results import Result, plain
from ._validate import check_choice
from .actuation_energy import hydraulic_power, servo_power
from .cycles import Cycle
from .efficiency import strategy_clamping
from .engine import fuel_rate, full_load_torque, operating_speed
from .errors import ParameterError
from .nonlinear import VARIATOR_LOSSES
from .nonlinear.equilibrium import trim_grid
from .nonlinear.model import EmpactModel, nonlinear_model
from .params import Params
from .vehicle import wheel_force

__all__ = ["STRATEGIES", "DEFAULT_STRATEGIES", "REFERENCE", "RATIO_LIMITS", "MIN_CLAMPING",
           "top_speed", "check_trace",
           "TERMS", "CycleResult",
           "quasi_static_cycle"]

#: the strategies of the cycle -> their clamping in `empact.efficiency` (a ``hydraulic-``
#: strategy is actuated by the hydraulic reference, the others by the servos)
STRATEGIES = {"hydraulic-sf1.3": "hydraulic", "sf1.3": "sf1.3", "sf1.3-aware": "sf1.3-aware",
              "slip": "slip", "hydraulic-slip": "slip"}
#: the strategies `quasi_static_cycle` and ``empact cycle`` run by default
DEFAULT_STRATEGIES = ("hydraulic-sf1.3", "sf1.3", "sf1.3-aware", "slip")
#: the strategy the savings are against
REFERENCE = "hydraulic-sf1.3"
#: the operating ratio range: the shipped loop's design range
#: (`empact.control.family.DESIGN_GRID`'s ratios 0.43-2.25)
RATIO_LIMITS = (0.43, 2.25)
#: the lowest clamping force [N]: the design grid's lowest clamping (3 kN)
MIN_CLAMPING = 3000.0
_LOSS = {k: k.removeprefix("P_loss_") for k in VARIATOR_LOSSES}
#: the energy terms [J] besides the wheels': the variator's losses by their kernel names
#: without ``P_loss_`` (``map``: a measured loss map's, which replaces ``clamp``, ``load`` and
#: ``drag``), the final drive, the launch clutch, the actuation (the servos' electrical
#: energy or the pump's shaft energy: the other is zero) and the alternator
TERMS = (*_LOSS.values(), "final_drive", "launch", "servo_electrical", "pump", "alternator")


@dataclass(frozen=True, eq=False)
class CycleResult(Result):
    """A quasi-static cycle (`quasi_static_cycle`).

    Attributes
    ----------
    cycle : Cycle
    strategies : tuple of str
    t, v, a, P_wheel : arrays, shape (N,)
        Time [s], speed [m/s], acceleration [m/s^2], wheel power [W].
    r_g, omega_e : dict str -> array, shape (N,)
        By strategy: ratio [-] and engine speed [rad/s].
    F_s : dict str -> array, shape (N,)
        By strategy: clamping force [N].
    power : dict str -> dict str -> array, shape (N,)
        By strategy, by term (`TERMS`, and ``engine``, ``variator_in``, ``variator_out``,
        ``actuation``: servo electrical plus pump) [W].
    fuel_rate : dict str -> array, shape (N,)
        By strategy [kg/s].
    weights : array, shape (N,)
        The trapezoid rule's weights [s].
    engine_short : dict str -> int
        Samples whose engine torque exceeds full load or whose engine speed exceeds
        ``omega_max`` (the car cannot follow the trace there; computed as asked).
    rho_fuel : float
        The fuel's density [kg/m^3] (for l/100 km).
    """

    cycle: Cycle
    strategies: tuple[str, ...]
    t: NDArray[np.float64]
    v: NDArray[np.float64]
    a: NDArray[np.float64]
    P_wheel: NDArray[np.float64]
    r_g: dict[str, NDArray[np.float64]]
    omega_e: dict[str, NDArray[np.float64]]
    F_s: dict[str, NDArray[np.float64]]
    power: dict[str, dict[str, NDArray[np.float64]]]
    fuel_rate: dict[str, NDArray[np.float64]]
    weights: NDArray[np.float64]
    engine_short: dict[str, int]
    rho_fuel: float

    def _sum(self, p: NDArray, mask: NDArray | None = None) -> float:
        w = self.weights if mask is None else np.where(mask, self.weights, 0.0)
        return float(np.sum(w * p))

    def summary(self, strategy: str, phase: str | None = None) -> dict[str, Any]:
        """One strategy's energies over the cycle or one phase.

        Parameters
        ----------
        strategy : str
        phase : str, optional
            One of the cycle's phases (default the whole cycle).

        Returns
        -------
        dict
            ``energy_J`` by term (`TERMS`), ``engine_J``, ``wheel_energy_J``, ``fuel_g``,
            ``fuel_l_per_100km``, ``variator_efficiency`` and ``transmission_efficiency``
            [-] (wheels' traction over engine output), ``distance_m``.
        """
        check_choice("strategy", strategy, self.strategies)
        mask = None
        dist_w = self.weights
        if phase is not None:
            check_choice("phase", phase, self.cycle.phases)
            mask = np.asarray([p == phase for p in self.cycle.phase])
            dist_w = np.where(mask, self.weights, 0.0)
        P = self.power[strategy]
        energy = {k: self._sum(P[k], mask) for k in TERMS}
        wheel = self._sum(np.maximum(self.P_wheel, 0.0), mask)
        fuel = self._sum(self.fuel_rate[strategy], mask)
        dist = float(np.sum(dist_w * self.v))
        var_in, var_out = self._sum(P["variator_in"], mask), self._sum(P["variator_out"], mask)
        engine = self._sum(P["engine"], mask)
        out = {"energy_J": energy, "engine_J": engine, "wheel_energy_J": wheel,
               "fuel_g": 1e3 * fuel, "distance_m": dist,
               "variator_efficiency": var_out / var_in if var_in > 0 else float("nan"),
               "transmission_efficiency": wheel / engine if engine > 0 else float("nan")}
        return out

    def to_dict(self) -> dict[str, Any]:
        """``cycle``, ``distance_m``, ``duration_s``, ``wheel_energy_J``, ``phases`` and
        ``strategies`` (by name: `summary`, its ``phases`` by name, ``saving`` against
        `REFERENCE` when it ran, ``engine_short``).

        Returns
        -------
        dict
        """
        ref = self.summary(REFERENCE)["fuel_g"] if REFERENCE in self.strategies else None
        strategies: dict[str, Any] = {}
        for s in self.strategies:
            d = self.summary(s)
            d["fuel_l_per_100km"] = self._l_100km(d)
            d["saving"] = (1 - d["fuel_g"] / ref) if ref else None
            d["engine_short"] = self.engine_short[s]
            d["phases"] = {p: self.summary(s, p) for p in self.cycle.phases}
            for p in d["phases"].values():
                p["fuel_l_per_100km"] = self._l_100km(p)
            strategies[s] = d
        return plain({"cycle": self.cycle.name, "distance_m": self.cycle.distance,
                      "duration_s": self.cycle.duration,
                      "wheel_energy_J": self._sum(np.maximum(self.P_wheel, 0.0)),
                      "phases": list(self.cycle.phases), "strategies": strategies})

    def _l_100km(self, d: dict[str, Any]) -> float:
        """Fuel [l/100 km] of a summary."""
        if d["distance_m"] <= 0:
            return float("nan")
        return d["fuel_g"] / 1e3 / self.rho_fuel * 1e3 / (d["distance_m"] / 1e5)


def _weights(t: NDArray) -> NDArray:
    """The trapezoid rule's weights on the samples `t` [s]."""
    dt = np.diff(t)
    w = np.zeros_like(t)
    w[:-1] += dt / 2
    w[1:] += dt / 2
    return w


def _trim(model: EmpactModel, strategy: str, r: NDArray, w_s: NDArray, T_l: NDArray,
          tau: float) -> tuple[dict[str, NDArray], NDArray]:
    """The variator at ratio `r`, load `T_l` and secondary speed `w_s` (module notes, 3):
    the outputs by name and the primary speeds."""
    eff = STRATEGIES[strategy]
    w_p = w_s / r
    y: dict[str, NDArray] = {}
    for _ in range(30):
        if eff == "slip":
            g = trim_grid(model, r, w_p, tau=np.full(r.size, tau), T_l=T_l)
            F = np.asarray(g.F_s, float)
            low = ~(F >= MIN_CLAMPING) | ~g.ok
            if np.any(low):
                g2 = trim_grid(model, r[low], w_p[low], F_s=np.full(int(low.sum()),
                                                                     MIN_CLAMPING),
                               T_l=T_l[low])
                assert g.y is not None and g2.y is not None
                Y = g.y.copy()
                Y[low] = g2.y
                ok = g.ok.copy()
                ok[low] = g2.ok
                reason = list(g.reason)
                for k, i in enumerate(np.flatnonzero(low)):
                    reason[i] = g2.reason[k]
            else:
                assert g.y is not None
                Y, ok, reason = g.y, g.ok, list(g.reason)
        else:
            F = np.maximum(strategy_clamping(model, eff, T_l, r), MIN_CLAMPING)
            g = trim_grid(model, r, w_p, F_s=F, T_l=T_l)
            assert g.y is not None
            Y, ok, reason = g.y, g.ok, list(g.reason)
        if not np.all(ok):
            k = int(np.flatnonzero(~ok)[0])
            raise ParameterError(
                f"strategy {strategy}: the variator cannot be trimmed at r_g = {r[k]:.4g}, "
                f"omega_p = {w_p[k]:.4g} rad/s, T_l = {T_l[k]:.4g} N m ({reason[k]})")
        y = {n: Y[:, j] for j, n in enumerate(model.outputs)}
        miss = w_s / y["omega_s"]
        if np.all(np.abs(miss - 1) <= 1e-12):
            break
        w_p = w_p * miss
    return y, w_p


def top_speed(params: Params) -> float:
    """The car's top speed by its gearing: the engine at ``omega_max`` through the highest
    ratio of `RATIO_LIMITS` and the final drive [m/s].

    Parameters
    ----------
    params : Params
        Reads ``[engine] omega_max`` and ``[vehicle] i_fd, r_wheel``.

    Returns
    -------
    float
        ``omega_max r_max r_wheel / i_fd`` [m/s].
    """
    veh = params.vehicle
    return float(params.engine.omega_max * RATIO_LIMITS[1] * veh.r_wheel / veh.i_fd)


def check_trace(params: Params, cycle: Cycle) -> Cycle:
    """Refuse, before any work, a trace the car cannot drive at any ratio: a speed above its
    `top_speed` (the engine would exceed ``omega_max`` at every ratio; the variator's trim
    fails far above it).

    Parameters
    ----------
    params : Params
        The parameter set.
    cycle : Cycle
        The speed trace.

    Returns
    -------
    Cycle
        `cycle` itself.

    Raises
    ------
    ParameterError
        One line naming the trace, the first sample above the top speed and the top speed.
    """
    v_top = top_speed(params)
    over = np.flatnonzero(cycle.v > v_top * (1 + 1e-9))
    if over.size:
        k = int(over[0])
        raise ParameterError(
            f"{cycle.name}: speed {3.6 * cycle.v[k]:.4g} km/h at t = {cycle.t[k]:g} s "
            f"({over.size} sample{'s' * (over.size > 1)} above): the car's top speed by its "
            f"gearing is {3.6 * v_top:.4g} km/h (engine.omega_max "
            f"{params.engine.omega_max:g} rad/s through the highest ratio "
            f"{RATIO_LIMITS[1]:g}, vehicle.i_fd {params.vehicle.i_fd:g}, vehicle.r_wheel "
            f"{params.vehicle.r_wheel:g} m)")
    return cycle


def quasi_static_cycle(params: Params, cycle: Cycle, *,
                       strategies: Sequence[str] = DEFAULT_STRATEGIES,
                       tau: float | None = None,
                       model: EmpactModel | None = None) -> CycleResult:
    """The quasi-static (backward) drive cycle by strategy (module notes).

    Parameters
    ----------
    params : Params
        The parameter set (``[vehicle]``, ``[engine]``, ``[servo]``, ``[hydraulic]``).
    cycle : Cycle
        The speed trace (`empact.cycles.load_cycle`, `empact.cycles.read_trace`).
    strategies : sequence of str, optional
        Any of `STRATEGIES` (default `DEFAULT_STRATEGIES`; ``hydraulic-slip``: slip control
        on the hydraulic reference, SAE 04CVT-39's case).
    tau : float, optional
        The slip strategy's torque ratio set-point [-] (default the parameter set's
        ``[operating] tau``, else 0.9).
    model : EmpactModel, optional
        The nonlinear model to trim (default ``nonlinear_model(params)``).

    Returns
    -------
    CycleResult

    Raises
    ------
    ParameterError
        For an unknown strategy or a trace faster than the car's top speed (`check_trace`;
        both before any work), or a sample the variator cannot be trimmed at (naming it).
    """
    strategies = tuple(dict.fromkeys(check_choice("strategy", s, tuple(STRATEGIES))
                                     for s in strategies))
    if not strategies:
        raise ParameterError("strategies: give at least one of " + ", ".join(STRATEGIES))
    check_trace(params, cycle)
    if tau is None:
        tau = params.operating.tau if params.operating.tau is not None else 0.9
    model = nonlinear_model(params) if model is None else model
    veh, eng = params.vehicle, params.engine
    t, v = cycle.t, cycle.v
    a = cycle.acceleration()
    F = wheel_force(veh, v, a)
    P_w = F * v
    moving = v > 0
    traction = moving & (F > 0)
    w_s = v * veh.i_fd / veh.r_wheel
    T_l = np.where(traction, F * veh.r_wheel / (veh.i_fd * veh.eta_fd), 0.0)
    w_line = operating_speed(eng, T_l * w_s)
    r_lo, r_hi = RATIO_LIMITS
    r = np.clip(np.where(moving, w_s / np.where(moving, w_line, 1.0), r_lo), r_lo, r_hi)
    out: dict[str, Any] = {"r_g": {}, "omega_e": {}, "F_s": {}, "power": {}, "fuel_rate": {},
                           "engine_short": {}}
    n = t.size
    idx = np.flatnonzero(moving)
    for s in strategies:
        terms = {k: np.zeros(n) for k in TERMS}
        var_in, var_out = np.zeros(n), np.zeros(n)
        w_e = np.full(n, eng.omega_idle)
        F_s = np.zeros(n)
        F_p, T_mp, T_ms = np.zeros(n), np.zeros(n), np.zeros(n)
        if idx.size:
            y, w_p = _trim(model, s, r[idx], w_s[idx], T_l[idx], tau)
            for kname, term in _LOSS.items():
                terms[term][idx] = y[kname]
            var_in[idx], var_out[idx] = y["P_var_in"], y["P_var_out"]
            terms["final_drive"][idx] = np.where(traction[idx], y["P_var_out"] - P_w[idx],
                                                 0.0)
            we = np.maximum(w_p, eng.omega_drive)
            w_e[idx] = we
            T_p = y["P_var_in"] / w_p
            terms["launch"][idx] = T_p * (we - w_p)
            F_s[idx], F_p[idx] = y["F_s"], y["F_p"]
            T_mp[idx], T_ms[idx] = y["T_mp_act"], y["T_ms_act"]
        rest = np.flatnonzero(~moving)
        if rest.size:  # idle neutral: the variator stands still, its actuation holds
            y0, _ = _trim(model, s, np.full(1, r_lo), np.full(1, eng.omega_idle * r_lo),
                          np.zeros(1), tau)
            F_s[rest], F_p[rest] = y0["F_s"][0], y0["F_p"][0]
            T_mp[rest], T_ms[rest] = y0["T_mp_act"][0], y0["T_ms_act"][0]
        if s.startswith("hydraulic"):
            act = hydraulic_power(params.hydraulic, F_p, F_s, w_e)
            terms["pump"] = np.asarray(sum(act.values()), float)
        else:
            zero = np.zeros(n)
            act = servo_power(params, T_mp, T_ms, zero, zero)
            terms["servo_electrical"] = np.asarray(sum(act.values()), float)
            terms["alternator"] = np.maximum(terms["servo_electrical"], 0.0) * (
                1 / eng.eta_alternator - 1)
        P_e = np.maximum(P_w, 0.0) * traction + sum(terms.values())
        T_e = P_e / w_e
        out["r_g"][s], out["omega_e"][s], out["F_s"][s] = np.where(moving, r, np.nan), w_e, F_s
        out["power"][s] = {**terms, "engine": P_e, "variator_in": var_in,
                           "actuation": terms["servo_electrical"] + terms["pump"],
                           "variator_out": var_out}
        out["fuel_rate"][s] = fuel_rate(eng, T_e, w_e)
        out["engine_short"][s] = int(np.sum((T_e > full_load_torque(eng, w_e))
                                            | (w_e > eng.omega_max)))
    res = CycleResult(cycle=cycle, strategies=strategies, t=t, v=v, a=a, P_wheel=P_w,
                      weights=_weights(t), rho_fuel=eng.rho_fuel, **out)
    return res
