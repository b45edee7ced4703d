"""The drive cycle, dynamic (forward): the whole cycle on the nonlinear vehicle driveline
with the transmission's loop law at 1 kHz and a driver (issue 34, items 4 and 6).

For each clamping strategy (`empact.drive_cycle.STRATEGIES`) the car (`ModelOptions`
``driveline = "vehicle"``) runs forward: the driver (`empact.control.driver.Driver`: a PI on
the car's speed with the feedforward of the trace's acceleration and road load) asks the
engine for torque (at most its full-load curve) or the brakes; the loop law (the shipped PI,
`empact.control.driver.DrivenLaw`) holds the ratio on the operating line and the clamping by
the strategy; both compiled into one sample loop with the integrator (no Python per sample).

References, prepared from the trace in advance (at its 1 Hz samples, linear between): the
ratio of the quasi-static cycle's operating line (`empact.drive_cycle.quasi_static_cycle`:
the engine's minimum-fuel speed for the wheels' power, clipped to the ratio range), and the
slip strategy's torque ratio ``tau``.  The loops by strategy (`LOOPS`): the slip loop at
``tau`` with the clamping feedforward of the engine's torque as its controller reports it
(`empact.control.law.CAR_SOURCE`: the driveshaft torque's would feed the car's shuffle back,
`docs/drive_cycle.rst`); the safety-factor clamping (1.3, ratio-blind or ratio-aware) of the
engine's torque; every one at least `MIN_CLAMPING` (the quasi-static cycle's floor).

Launch and standstill (`LAUNCH_MODEL`): the variator's slip is undefined at a standing
primary, so the dynamic run covers each stretch of the trace at or above the launch speed
(LOW at the engine's lowest driving speed, ``omega_drive r_lo r_w / i_fd``, 11.2 km/h), each
from a steady cruise trimmed at its first sample (the trace's speed, the quasi-static ratio,
the strategy's clamping at that sample, at least the floor; the driver's integral zero);
below it (the slipping launch clutch, braking to a stop) and at rest (idle neutral) the
quasi-static cycle's samples count, interval by interval.

Energies: the kernel's loss powers (`empact.nonlinear.VARIATOR_LOSSES`, the final drive's),
the servos' electrical power (`empact.actuation_energy.servo_power`, of the run's servo
torques and speeds) and the alternator, or the hydraulic reference's pump (of the run's
pulley forces and engine speed), the brakes, integrated by the trapezoid rule on the output
samples (`output_rate`); the engine's fuel (`empact.engine.fuel_rate`) at its torque plus
the accessories' (actuation and alternator, or pump) at its speed.  The quasi-static
cycle's energies over the same stretches are beside them (`DynamicRun.quasi_static_J`).
"""
from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ._results import Result, plain
from ._validate import check_choice, check_number
from .actuation_energy import hydraulic_power, servo_power
from .control.closed_loop import resolve_controller
from .control.driver import DrivenLaw, Driver
from .control.law import LoopConfig
from .cycles import Cycle
from .drive_cycle import (
    DEFAULT_STRATEGIES,
    MIN_CLAMPING,
    RATIO_LIMITS,
    REFERENCE,
    STRATEGIES,
    TERMS,
    CycleResult,
    quasi_static_cycle,
)
from .efficiency import strategy_clamping
from .engine import fuel_rate
from .errors import ParameterError
from .lti import oscillatory
from .nonlinear import VARIATOR_LOSSES
from .nonlinear.equilibrium import traction_peak, trim
from .nonlinear.linearization import linearized_plant
from .nonlinear.model import EmpactModel, nonlinear_model
from .nonlinear.simulation import METHODS, simulate
from .operating import CruisePoint
from .params import Params

__all__ = ["LAUNCH_MODEL", "LOOPS", "DynamicRun", "DynamicCycleResult", "dynamic_cycle",
           "launch_speed", "driving_stretches", "clamping_release"]

#: how the dynamic cycle treats the launch and standstill (module notes; in the JSON)
LAUNCH_MODEL = ("dynamic at and above the launch speed (LOW at the engine's lowest driving "
                "speed: omega_drive r_lo r_w / i_fd), each stretch from a steady cruise "
                "trimmed at its first sample; below it (the slipping launch clutch) and at "
                "rest (idle neutral) the quasi-static cycle's samples, interval by interval")

#: the loop law's ``[controller]`` keys by strategy (besides ``file`` and ``rate``): the
#: slip loop with the engine torque's clamping feedforward, or the safety-factor clamping of
#: the engine's torque (its release `clamping_release`); every one at least `MIN_CLAMPING`
LOOPS: dict[str, dict[str, Any]] = {
    "feedback": dict(clamping="feedback", feedforward=True, feedforward_signal="T_e_est",
                     feedforward_gain=0.9, feedforward_filter_hz=100.0, decoupling=True,
                     decoupling_filter_hz=5.0, min_clamping=MIN_CLAMPING),
    "sf1.3": dict(clamping="safety-factor", safety_factor=1.3, mu_design="ratio-blind",
                  decoupling=True, decoupling_filter_hz=5.0, min_clamping=MIN_CLAMPING),
    "sf1.3-aware": dict(clamping="safety-factor", safety_factor=1.3, mu_design="ratio-aware",
                        decoupling=True, decoupling_filter_hz=5.0, min_clamping=MIN_CLAMPING),
}
_LOOP_OF = {"hydraulic-sf1.3": "sf1.3", "sf1.3": "sf1.3", "sf1.3-aware": "sf1.3-aware",
            "slip": "feedback", "hydraulic-slip": "feedback"}
#: the outputs a run keeps (model outputs, SI)
_KEEP = ("v", "r_g", "nu", "F_s", "F_p", "omega_d", "T_d_act", "T_l_act", "omega_l",
         "T_mp_act", "T_ms_act", "omega_mp", "omega_ms", "P_loss_fd", "P_road", "E",
         "P_diss", "tau") + VARIATOR_LOSSES
_LOSS = {k: k.removeprefix("P_loss_") for k in VARIATOR_LOSSES}


def launch_speed(params: Params) -> float:
    """The launch speed [m/s]: LOW (`RATIO_LIMITS`) at the engine's lowest driving speed,
    ``omega_drive r_lo r_w / i_fd`` (11.2 km/h for the shipped car).

    Parameters
    ----------
    params : Params

    Returns
    -------
    float
    """
    veh = params.vehicle
    return float(params.engine.omega_drive * RATIO_LIMITS[0] * veh.r_wheel / veh.i_fd)


def clamping_release(model: EmpactModel) -> float:
    """The safety-factor clamping's release time constant in the car [s]: one period of the
    car's slowest torsional mode (the shuffle: engine, variator and vehicle against the
    driveshaft's twist), at LOW and the engine's lowest driving speed with `MIN_CLAMPING`
    (2.7 Hz, 0.37 s for the shipped car; 4-5 Hz at r_g = 1, 6-9 Hz in overdrive).

    At a tip-out the engine's torque falls at once, while the driveline's twist and the
    engine's inertia keep pushing the old torque through the belt for about half that
    period; a clamping that follows the engine's torque down at once lets the belt slip
    (the dynamic WLTC 3b run macro-slipped so, at 540 s).  Released with this time constant
    the clamping still holds 61 % of the drop half a period later.

    Parameters
    ----------
    model : EmpactModel
        The car (``driveline = "vehicle"``).

    Returns
    -------
    float
        ``1 / f_1`` [s], ``f_1`` the lowest natural frequency of the linearised car [Hz].
    """
    op = trim(model, CruisePoint(r_g=RATIO_LIMITS[0], omega_p=model.params.engine.omega_drive,
                                 F_s=MIN_CLAMPING))
    f_n, _ = oscillatory(np.linalg.eigvals(linearized_plant(op).A))
    return float(1.0 / f_n[0])


def driving_stretches(cycle: Cycle, v_launch: float) -> list[tuple[int, int]]:
    """The trace's stretches at or above `v_launch`: index pairs ``(i0, i1)`` of their first
    and last samples (at least two samples each).

    Parameters
    ----------
    cycle : Cycle
    v_launch : float
        The launch speed [m/s].

    Returns
    -------
    list of (int, int)
    """
    above = cycle.v >= v_launch
    out = []
    i = 0
    n = above.size
    while i < n:
        if above[i]:
            j = i
            while j + 1 < n and above[j + 1]:
                j += 1
            if j > i:
                out.append((i, j))
            i = j + 1
        else:
            i += 1
    return out


@dataclass(frozen=True, eq=False)
class DynamicRun(Result):
    """One strategy's dynamic cycle (`dynamic_cycle`): its dynamic stretches' outputs and the
    energies of the whole cycle (dynamic stretches and the quasi-static rest).

    Attributes
    ----------
    strategy : str
    t : array, shape (n,)
        Output times over the dynamic stretches [s] (cycle time; stretches concatenated).
    signals : dict str -> array, shape (n,)
        The kept outputs (SI: ``v``, ``r_g``, ``nu``, ``F_s``, ``omega_d``, ``T_d_act``,
        the loss powers, ...), ``v_ref`` and ``r_ref`` (the references), ``P_actuation``
        and ``P_accessory`` [W], ``fuel_rate`` [kg/s].
    energy_J : dict str -> float
        The cycle's energies by term [J] (`empact.drive_cycle.TERMS`) and ``brakes``,
        ``engine`` (the engine's brake work with its accessories), ``road``.
    phases : dict str -> dict str -> float
        The same by cycle phase.
    fuel_g : float
    dynamic_J : dict str -> float
        The dynamic stretches' energies by term [J] (`TERMS` and ``brakes``).
    quasi_static_J : dict str -> float
        The quasi-static cycle's energies by term over the same stretches [J].
    speed_error_max_kmh : float
        Largest ``|v - v*|`` over the dynamic stretches [km/h].
    macro_slip : bool
        The slip reached the traction peak's slip at its ratio somewhere.
    slip_reserve : float
        The smallest distance of ``|nu|`` to the peak's slip [-].
    belt_slack : bool
        The clamping force fell to zero somewhere (the run stops there).
    min_clamping_force : float
        [N].
    complete : bool
        Every stretch ran to its end.
    messages : tuple of str
        The simulator's message per stretch.
    wall_time_s : float
        The stretches' runs (the simulator's own time) [s].
    n_steps : int
        The integrator's steps.
    """

    strategy: str
    t: NDArray[np.float64]
    signals: dict[str, NDArray[np.float64]]
    energy_J: dict[str, float]
    phases: dict[str, dict[str, float]]
    fuel_g: float
    dynamic_J: dict[str, float]
    quasi_static_J: dict[str, float]
    speed_error_max_kmh: float
    macro_slip: bool
    slip_reserve: float
    belt_slack: bool
    min_clamping_force: float
    complete: bool
    messages: tuple[str, ...]
    wall_time_s: float
    n_steps: int

    @property
    def variator_loss_J(self) -> tuple[float, float]:
        """The variator's losses over the dynamic stretches [J]: ``(dynamic,
        quasi-static)`` (the sum of `VARIATOR_LOSSES`' terms)."""
        keys = list(_LOSS.values())
        return (sum(self.dynamic_J[k] for k in keys),
                sum(self.quasi_static_J[k] for k in keys))


@dataclass(frozen=True, eq=False)
class DynamicCycleResult(Result):
    """A dynamic cycle (`dynamic_cycle`).

    Attributes
    ----------
    cycle : Cycle
    strategies : tuple of str
    quasi_static : CycleResult
        The quasi-static cycle it takes its references and its rest from.
    stretches : tuple of (float, float)
        The dynamic stretches' start and end [s].
    v_launch : float
        The launch speed [m/s] (`launch_speed`).
    runs : dict str -> DynamicRun
        By strategy.
    rate_hz : float
        The loop law's and the driver's rate [Hz].
    """

    _not_data = ("quasi_static",)

    cycle: Cycle
    strategies: tuple[str, ...]
    quasi_static: CycleResult
    stretches: tuple[tuple[float, float], ...]
    v_launch: float
    runs: dict[str, DynamicRun] = field(default_factory=dict)
    rate_hz: float = 1000.0

    def to_dict(self) -> dict[str, Any]:
        """``cycle``, ``distance_m``, ``duration_s``, ``wheel_energy_J``, ``launch_model``,
        ``v_launch_m_s``, ``dynamic_duration_s``, ``stretches`` ([start, end] [s]),
        ``rate_hz``, ``phases`` and ``strategies``
        by name: ``energy_J`` (by term), ``fuel_g``, ``fuel_l_per_100km``, ``saving``
        (against `REFERENCE` when it ran), ``speed_error_max_kmh``, ``macro_slip``,
        ``belt_slack``, ``slip_reserve``, ``min_clamping_force``, ``complete``,
        ``variator_loss_J`` and ``quasi_static_variator_loss_J`` (the dynamic stretches),
        ``dynamic_J``, ``quasi_static_J``, ``phases``, ``wall_time_s``.

        Returns
        -------
        dict
        """
        qs = self.quasi_static
        dist = self.cycle.distance
        ref = self.runs[REFERENCE].fuel_g if REFERENCE in self.runs else None
        rho = self.quasi_static.rho_fuel
        strategies = {}
        for s, run in self.runs.items():
            dyn, stat = run.variator_loss_J
            strategies[s] = {
                "energy_J": run.energy_J, "fuel_g": run.fuel_g,
                "fuel_l_per_100km": run.fuel_g / 1e3 / rho * 1e3 / (dist / 1e5),
                "saving": (1 - run.fuel_g / ref) if ref else None,
                "speed_error_max_kmh": run.speed_error_max_kmh, "macro_slip": run.macro_slip,
                "belt_slack": run.belt_slack, "slip_reserve": run.slip_reserve,
                "min_clamping_force": run.min_clamping_force, "complete": run.complete,
                "variator_loss_J": dyn, "quasi_static_variator_loss_J": stat,
                "dynamic_J": run.dynamic_J, "quasi_static_J": run.quasi_static_J,
                "phases": run.phases, "wall_time_s": run.wall_time_s,
                "n_steps": run.n_steps, "messages": list(run.messages)}
        return plain({"cycle": self.cycle.name, "distance_m": dist,
                      "duration_s": self.cycle.duration,
                      "wheel_energy_J": qs._sum(np.maximum(qs.P_wheel, 0.0)),
                      "launch_model": LAUNCH_MODEL, "v_launch_m_s": self.v_launch,
                      "dynamic_duration_s": float(sum(b - a for a, b in self.stretches)),
                      "stretches": [list(x) for x in self.stretches],
                      "rate_hz": self.rate_hz, "phases": list(self.cycle.phases),
                      "strategies": strategies})


def _weights(t: NDArray) -> NDArray:
    """The trapezoid rule's weights on the samples `t` [s]."""
    dt = np.diff(t)
    w = np.zeros_like(t)
    w[:-1] += dt / 2
    w[1:] += dt / 2
    return w


def dynamic_cycle(params: Params, cycle: Cycle, *,
                  strategies: Sequence[str] = DEFAULT_STRATEGIES,
                  tau: float | None = None, driver: Driver | None = None,
                  output_rate: float = 100.0, rate: float = 1000.0,
                  quasi_static: CycleResult | None = None,
                  model: EmpactModel | None = None,
                  method: str = "rodas4") -> DynamicCycleResult:
    """The dynamic (forward) drive cycle by strategy (module notes).

    Parameters
    ----------
    params : Params
        The parameter set (``[vehicle]``, ``[engine]``, ``[servo]``, ``[sensors]``,
        ``[hydraulic]``).
    cycle : Cycle
        The speed trace.
    strategies : sequence of str, optional
        Any of `empact.drive_cycle.STRATEGIES` (default its `DEFAULT_STRATEGIES`).
    tau : float, optional
        The slip strategy's torque ratio set-point [-] (default ``[operating] tau``, else
        0.9).
    driver : Driver, optional
        The driver model (default `Driver()`).
    output_rate : float, optional
        Output samples per second of the dynamic runs [Hz] (the energies' quadrature;
        default 100).
    rate : float, optional
        The loop law's and the driver's rate [Hz] (default 1000).
    quasi_static : CycleResult, optional
        The quasi-static cycle of the same strategies (computed when not given).
    model : EmpactModel, optional
        The car's model (default ``nonlinear_model(params, driveline="vehicle")``).
    method : str, optional
        The integrator (`empact.nonlinear.simulation.METHODS`; default ``"rodas4"``).

    Returns
    -------
    DynamicCycleResult

    Raises
    ------
    ParameterError
        For an unknown strategy or bad rates (before any work).
    """
    strategies = tuple(dict.fromkeys(check_choice("strategy", s, tuple(STRATEGIES))
                                     for s in strategies))
    if not strategies:
        raise ParameterError("strategies: give at least one of " + ", ".join(STRATEGIES))
    output_rate = check_number("output_rate", output_rate, 1.0, 1e4, unit="Hz")
    rate = check_number("rate", rate, 10.0, 1e5, unit="Hz")
    check_choice("method", method, METHODS)
    if tau is None:
        tau = params.operating.tau if params.operating.tau is not None else 0.9
    driver = Driver() if driver is None else driver
    model = nonlinear_model(params, driveline="vehicle") if model is None else model
    if not model.vehicle:
        raise ParameterError("dynamic_cycle: the model needs driveline = 'vehicle'")
    qs = quasi_static_cycle(params, cycle, strategies=strategies, tau=tau) \
        if quasi_static is None else quasi_static
    v_launch = launch_speed(params)
    stretches = driving_stretches(cycle, v_launch)
    # the safety-factor strategies' release (a trim and a linearisation: once, not a strategy)
    release = clamping_release(model) if any(
        LOOPS[_LOOP_OF[s]]["clamping"] == "safety-factor" for s in strategies) else 0.0
    runs = {s: _run_strategy(params, cycle, qs, model, s, stretches, float(tau), driver,
                             output_rate, rate, method, release) for s in strategies}
    return DynamicCycleResult(cycle=cycle, strategies=strategies, quasi_static=qs,
                              stretches=tuple((float(cycle.t[a]), float(cycle.t[b]))
                                              for a, b in stretches),
                              v_launch=v_launch, runs=runs, rate_hz=rate)


def _covered(cycle: Cycle, stretches: list[tuple[int, int]]) -> NDArray[np.bool_]:
    """Which intervals ``[t_k, t_k+1]`` of the trace the dynamic stretches cover."""
    cov = np.zeros(cycle.t.size - 1, dtype=bool)
    for a, b in stretches:
        cov[a:b] = True
    return cov


def _interval_weights(t: NDArray, use: NDArray[np.bool_]) -> NDArray:
    """Trapezoid weights of the samples `t` over the intervals where `use` is True."""
    dt = np.where(use, np.diff(t), 0.0)
    w = np.zeros_like(t)
    w[:-1] += dt / 2
    w[1:] += dt / 2
    return w


def _run_strategy(params: Params, cycle: Cycle, qs: CycleResult, model: EmpactModel,
                  strategy: str, stretches: list[tuple[int, int]], tau: float,
                  driver: Driver, output_rate: float, rate: float,
                  method: str, release: float) -> DynamicRun:
    """One strategy over every dynamic stretch, then the cycle's energies (`release`: the
    safety-factor clamping's, `clamping_release` [s])."""
    veh, eng = params.vehicle, params.engine
    gear = veh.r_wheel / veh.i_fd
    keys = LOOPS[_LOOP_OF[strategy]]
    if keys["clamping"] == "safety-factor":
        keys = {**keys, "clamping_release": release}
    loop = LoopConfig.of(params, rate=rate, **keys)
    ctrl = resolve_controller("shipped:pi")
    hydraulic = strategy.startswith("hydraulic")
    parts: list[dict[str, NDArray]] = []
    ts: list[NDArray] = []
    messages = []
    wall = 0.0
    n_steps = 0
    complete = True
    for a, b in stretches:
        t_k = cycle.t[a:b + 1] - cycle.t[a]
        v_k = cycle.v[a:b + 1]
        r_k = qs.r_g[strategy][a:b + 1]
        op = _start(model, strategy, float(r_k[0]), float(v_k[0] / (gear * r_k[0])), tau)
        point = {"r_g": op.r_g, "nu": op.nu, "omega_p": op.omega_p, "T_l": op.T_l,
                 "F_s": op.F_s, "T_d": op.T_d}
        refs = {"r_g": np.column_stack([t_k, r_k]),
                "tau": np.column_stack([t_k, np.full(t_k.size, tau)])}
        duration = float(t_k[-1])
        law: Any = DrivenLaw(ctrl, model, point, op.u[:2], loop, refs, duration, driver,
                             np.column_stack([t_k, v_k]))
        t0 = time.perf_counter()
        res = simulate(model, op.x, {}, duration, u0=op.u, controller=law,
                       sample_rate=output_rate, method=method,
                       name=f"{cycle.name} {strategy} {cycle.t[a]:g}-{cycle.t[b]:g} s")
        wall += time.perf_counter() - t0
        n_steps += int(res.stats["n_steps"])
        complete &= res.complete
        messages.append(res.message)
        part = {k: res.output(k) for k in _KEEP}
        part["T_l_brake"] = res.output("T_l")
        part["v_ref"] = np.interp(res.t, t_k, v_k)
        part["r_ref"] = np.interp(res.t, t_k, r_k)
        parts.append(part)
        ts.append(res.t + cycle.t[a])
    sig = {k: np.concatenate([p[k] for p in parts]) if parts else np.zeros(0)
           for k in (parts[0] if parts else _KEEP)}
    t = np.concatenate(ts) if ts else np.zeros(0)
    # the actuation and the accessories the engine drives
    w_e = sig.get("omega_d", np.zeros(0))
    terms_dyn = {k: np.zeros(t.size) for k in TERMS}
    for kname, term in _LOSS.items():
        terms_dyn[term] = sig[kname] if t.size else np.zeros(0)
    if t.size:
        terms_dyn["final_drive"] = sig["P_loss_fd"]
        if hydraulic:
            terms_dyn["pump"] = np.asarray(sum(hydraulic_power(
                params.hydraulic, sig["F_p"], sig["F_s"], w_e).values()), float)
        else:
            el = np.asarray(sum(servo_power(params, sig["T_mp_act"], sig["T_ms_act"],
                                            sig["omega_mp"], sig["omega_ms"]).values()),
                            float)
            terms_dyn["servo_electrical"] = el
            terms_dyn["alternator"] = np.maximum(el, 0.0) * (1 / eng.eta_alternator - 1)
    accessory = terms_dyn["servo_electrical"] + terms_dyn["alternator"] + terms_dyn["pump"]
    P_engine = sig["T_d_act"] * w_e + accessory if t.size else np.zeros(0)
    fuel = fuel_rate(eng, P_engine / w_e, w_e) if t.size else np.zeros(0)
    brakes = sig["T_l_brake"] * sig["omega_l"] if t.size else np.zeros(0)
    sig.update(P_actuation=terms_dyn["servo_electrical"] + terms_dyn["pump"],
               P_accessory=accessory, fuel_rate=fuel)
    # the dynamic stretches' energies (per stretch: the trapezoid within each)
    w_dyn = np.concatenate([_weights(tt) for tt in ts]) if ts else np.zeros(0)
    phase_of = _phase_at(cycle, t)
    extra = {"brakes": brakes, "engine": P_engine, "road": sig.get("P_road", np.zeros(0))}
    dynamic_J = {k: float(np.sum(w_dyn * p)) for k, p in {**terms_dyn, **extra}.items()}
    # the quasi-static rest, interval by interval, and the quasi-static stretches
    cov = _covered(cycle, stretches)
    w_rest = _interval_weights(cycle.t, ~cov)
    w_cov = _interval_weights(cycle.t, cov)
    P = qs.power[strategy]
    qs_rest = {k: float(np.sum(w_rest * P[k])) for k in TERMS}
    qs_rest.update(brakes=0.0, engine=float(np.sum(w_rest * P["engine"])), road=0.0)
    quasi_static_J = {k: float(np.sum(w_cov * P[k])) for k in TERMS}
    quasi_static_J["engine"] = float(np.sum(w_cov * P["engine"]))
    energy = {k: dynamic_J[k] + qs_rest[k] for k in dynamic_J}
    fuel_g = 1e3 * (float(np.sum(w_dyn * fuel)) + float(np.sum(w_rest * qs.fuel_rate[strategy])))
    phases = {}
    for ph in cycle.phases:
        md = phase_of == ph
        ms = np.asarray([p == ph for p in cycle.phase])
        d = {k: float(np.sum(np.where(md, w_dyn, 0.0) * p))
             for k, p in {**terms_dyn, **extra}.items()}
        for k in TERMS:
            d[k] += float(np.sum(np.where(ms, w_rest, 0.0) * P[k]))
        d["engine"] += float(np.sum(np.where(ms, w_rest, 0.0) * P["engine"]))
        d["fuel_g"] = 1e3 * (float(np.sum(np.where(md, w_dyn, 0.0) * fuel))
                             + float(np.sum(np.where(ms, w_rest, 0.0)
                                            * qs.fuel_rate[strategy])))
        phases[ph] = d
    # the checks: speed error, macro slip, belt slack
    if t.size:
        err = float(np.max(np.abs(sig["v"] - sig["v_ref"]))) * 3.6
        nu_pk = traction_peak(model, np.clip(sig["r_g"], *RATIO_LIMITS))[0]
        reserve = float(np.min(np.asarray(nu_pk) - np.abs(sig["nu"])))
        F_min = float(np.min(sig["F_s"]))
    else:
        err, reserve, F_min = 0.0, float("nan"), float("nan")
    slack = (F_min <= 0.0) or any("slack" in m for m in messages)
    return DynamicRun(strategy=strategy, t=t, signals=sig, energy_J=energy, phases=phases,
                      fuel_g=fuel_g, dynamic_J=dynamic_J, quasi_static_J=quasi_static_J,
                      speed_error_max_kmh=err, macro_slip=bool(reserve < 0.0),
                      slip_reserve=reserve, belt_slack=bool(slack),
                      min_clamping_force=F_min, complete=bool(complete),
                      messages=tuple(messages), wall_time_s=wall, n_steps=n_steps)


def _start(model: EmpactModel, strategy: str, r_g: float, omega_p: float,
           tau: float) -> Any:
    """A stretch's start: the steady cruise at `r_g`, `omega_p` with the clamping the
    strategy's loop holds there (so that the law starts at rest): the slip loop's at `tau`,
    or the safety factor's of the engine's torque at the secondary; at least
    `MIN_CLAMPING`."""
    op = trim(model, CruisePoint(r_g=r_g, omega_p=omega_p, F_s=MIN_CLAMPING))
    loop = LOOPS[_LOOP_OF[strategy]]
    if loop["clamping"] == "feedback":
        F = trim(model, CruisePoint(r_g=r_g, omega_p=omega_p, tau=tau)).F_s
    else:
        T_src = op.T_d * op.omega_p / op.omega_s  # the engine's torque at the secondary
        eff = "sf1.3-aware" if loop["mu_design"] == "ratio-aware" else "sf1.3"
        F = float(strategy_clamping(model, eff, T_src, r_g,
                                    safety_factor=loop["safety_factor"]))
    return op if F <= MIN_CLAMPING else trim(model, CruisePoint(r_g=r_g, omega_p=omega_p,
                                                                 F_s=F))


def _phase_at(cycle: Cycle, t: NDArray) -> NDArray:
    """The trace's phase at times `t` (the phase of the sample at or before each)."""
    k = np.clip(np.searchsorted(cycle.t, t, side="right") - 1, 0, cycle.t.size - 1)
    return np.asarray(cycle.phase, dtype=object)[k]
