"""A controller in closed loop with the nonlinear machine: the run and its metrics.

A closed-loop scenario is an ordinary scenario (`empact.nonlinear.scenario`) with a
``[controller]`` table and ``[references]``.  `run_closed_loop` builds the loop law
(`empact.control.law.LoopLaw`: sensors, references, the controller, the clamping
feedforward, servo limits and anti-windup) and hands it to the one simulator
(`empact.nonlinear.simulation.simulate`), which samples the measured signals, calls the law
and holds the servo torques over each period (zero-order hold).  `empact.control.loop`
builds the linear model of the same law around the linearised machine.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Mapping

import numpy as np
from numpy.typing import NDArray

from .._deprecate import warn_renamed
from .._results import Result
from ..errors import ParameterError
from ..nonlinear.equilibrium import TrimResult, smallest_slip_reserve
from ..nonlinear.model import EmpactModel, nonlinear_model
from ..nonlinear.scenario import Scenario, example_path, list_examples, load_scenario
from ..nonlinear.simulation import (
    SimulationResult,
    run_scenario,
    scenario_model,
    scenario_options,
    scenario_signals,
)
from ..params import OperatingPoint, Params
from .controller import Controller, load_controller
from .law import LoopConfig, LoopLaw

__all__ = ["LoopLaw", "ClosedLoopResult", "run_closed_loop", "build_law", "metrics",
           "resolve_controller", "control_examples", "control_example_path",
           "safety_factor_twin", "check_targets", "SLIP_METRICS", "shown_metric",
           "torque_request_metrics", "protection_metrics"]


def __getattr__(name: str) -> Any:
    """``ControlScenario``: deprecated name of the closed-loop scenario (one `Scenario` type
    now; removed in empact 0.3.0)."""
    if name == "ControlScenario":
        warn_renamed("empact.control.closed_loop.ControlScenario",
                     "empact.nonlinear.scenario.Scenario")
        return Scenario
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def control_examples() -> dict[str, str]:
    """The shipped closed-loop scenarios: name -> description.

    Returns
    -------
    dict str -> str
        Each shipped scenario with a ``[controller]`` table, by name (for
        `control_example_path`), with its ``[scenario] description``.
    """
    return list_examples(closed_loop=True)


def control_example_path(name: str) -> Path:
    """Path of a shipped closed-loop scenario.

    Parameters
    ----------
    name : str
        One of `control_examples` (e.g. ``"slip-load-step-r1"``).

    Returns
    -------
    Path
        The scenario file (TOML), for `empact.nonlinear.scenario.load_scenario`.

    Raises
    ------
    ParameterError
        For a name that is not a shipped closed-loop scenario (one line listing them).
    """
    if name not in control_examples():
        raise ParameterError(f"unknown control example {name!r} (choose from "
                             f"{', '.join(control_examples())})")
    return example_path(name)


def load_control_scenario(path) -> Scenario:
    """Deprecated: `empact.nonlinear.scenario.load_scenario` reads every scenario; this
    checks that the file has a ``[controller]`` table.

    Parameters
    ----------
    path : str or path-like
        A closed-loop scenario (TOML).

    Returns
    -------
    Scenario
    """
    warn_renamed("load_control_scenario", "load_scenario (one scenario format)")
    sc = load_scenario(path)
    if not sc.closed_loop:
        raise ParameterError(f"{path}: no [controller] table (not a closed-loop scenario)")
    return sc


def resolve_controller(ref: str) -> Controller:
    """A controller file, or a shipped one (``shipped:NAME``).

    Parameters
    ----------
    ref : str
        A controller JSON file (`Controller.save`), or ``"shipped:NAME"`` for the one
        shipped as ``empact/data/control/NAME.json`` (``"shipped:pi"``, ``"shipped:hinf"``).

    Returns
    -------
    Controller
        The controller read (`empact.control.controller.load_controller`).

    Raises
    ------
    ParameterError
        For a missing or bad file, or an unknown shipped name.
    """
    return load_controller(ref)  # (which reads ``shipped:NAME`` too)


@dataclass(frozen=True, eq=False)
class ClosedLoopResult(Result):
    """A closed-loop run: the simulation (`result`), references at its sample times
    (``r_g`` and the slip set-point under the controller's slip signal), the trimmed start,
    the law that ran (`law`: its configuration, limits and sensors) and the metrics.

    Attributes
    ----------
    result : SimulationResult
        The simulation of the machine with the law in the loop.
    references : dict str -> ndarray
        ``"r_g"`` [-] and the slip set-point under the controller's slip signal (``"nu"``
        or ``"nu_r"``) [-] at the sample times ``result.t``, each shape (n_t,).
    op : TrimResult
        The trimmed start.
    scenario : Scenario
        The scenario that ran.
    controller : Controller
        The controller that ran.
    metrics : dict str -> object
        The run's numbers (`metrics`: slips and slip errors [-], forces [N], powers [W],
        torques [N m]).
    law : LoopLaw or None
        The law that ran: its configuration, limits and sensors.
    """

    result: SimulationResult
    references: dict[str, NDArray[np.float64]]
    op: TrimResult
    scenario: Scenario
    controller: Controller
    metrics: dict[str, Any] = field(default_factory=dict)
    law: LoopLaw | None = None

    def _data(self) -> dict[str, Any]:
        """`to_dict`: the simulation, references, trimmed start, the scenario's name, the
        controller and the metrics (the law and the scenario are inputs, not data)."""
        return {"scenario": self.scenario.name, "result": self.result,
                "references": self.references, "op": self.op, "controller": self.controller,
                "metrics": self.metrics}


def build_law(scenario: Scenario, params: Params, controller: Controller | None = None,
              model: EmpactModel | None = None, op: TrimResult | None = None,
              ideal: bool = False, nominal: Params | None = None) -> LoopLaw:
    """The loop law of a closed-loop scenario on a parameter set (its trimmed start and
    model unless given); `ideal`: without servo limits, quantisation and noise
    (`LoopConfig.ideal`: what the linear loop model linearises); `nominal`: the parameter
    set the controller knows (its traction curve for the set-points and the feedforward,
    its geometry, holding torques and creep law), when the machine's differ (a Monte Carlo
    run); default: the machine's own.

    Parameters
    ----------
    scenario : Scenario
        A scenario with a ``[controller]`` table.
    params : Params
        The machine's parameter set.
    controller : Controller, optional
        Replaces the scenario's controller file (`resolve_controller`).
    model : EmpactModel, optional
        The machine's model (with `op`; default: `scenario_model` of the scenario).
    op : TrimResult, optional
        The trimmed start (with `model`; both are recomputed when either is missing).
    ideal : bool
        Without servo limits, quantisation and noise.
    nominal : Params, optional
        The parameter set the controller knows (default: `params`).

    Returns
    -------
    LoopLaw
        The sampled law, ready for `empact.nonlinear.simulation.simulate`: measured
        signals in, servo torques ``(T_mp, T_ms)`` [N m] out.

    Raises
    ------
    ParameterError
        When the scenario has no ``[controller]`` table.
    """
    if scenario.controller is None:
        raise ParameterError(f"scenario {scenario.name!r} has no [controller] table: run it "
                             "with empact.run_scenario")
    ctrl = resolve_controller(scenario.controller.file) if controller is None else controller
    if model is None or op is None:
        model, op = scenario_model(scenario, params)
    point = {"r_g": op.r_g, "nu": op.nu, "omega_p": op.omega_p, "T_l": op.T_l, "F_s": op.F_s,
             "T_d": op.T_d}
    # the model the controller knows (its trim is the machine's: `op`)
    knows = model if nominal is None else nonlinear_model(nominal, scenario_options(scenario))
    cfg = LoopConfig.for_scenario(scenario, params if nominal is None else nominal)
    load = None
    if scenario.controller.torque_request == "honoured":
        if "T_l" not in model.inputs:
            raise ParameterError(f"scenario {scenario.name!r}: controller.torque_request = "
                                 "'honoured' needs a torque-controlled load (model.load = "
                                 "'torque')")
        load = scenario_signals(scenario, model, op).get("T_l", np.array([[0.0, op.T_l]]))
    return LoopLaw(ctrl, knows, point, op.u[:2], cfg.ideal() if ideal else cfg,
                   scenario.references, scenario.duration, load)


def run_closed_loop(scenario: Scenario, params: Params, controller: Controller | None = None,
                    *, progress: bool = False, ideal: bool = False,
                    nominal: Params | None = None) -> ClosedLoopResult:
    """Trim the scenario's start and simulate the machine with its loop law in the loop.

    Parameters
    ----------
    scenario : Scenario
        A scenario with a ``[controller]`` table.
    params : Params
    controller : Controller, optional
        Replaces the scenario's controller file.
    progress : bool
        A progress bar on stderr.
    ideal : bool
        Run the law without servo limits, quantisation and noise (the loop the linear model
        `empact.control.loop` describes).
    nominal : Params, optional
        What the controller knows, when the machine (`params`) differs from it (`build_law`).

    Returns
    -------
    ClosedLoopResult
        The simulation (``result``), the references at its sample times, the trimmed start,
        the law that ran and the ``metrics`` (`metrics`: slips and slip errors as fractions
        [-], forces [N], powers [W]).

    Examples
    --------
    The shipped load step at r_g = 1 (50 % of the torque capacity at 0.5 s) with the
    shipped PI:

    >>> import empact
    >>> from empact.control.closed_loop import control_example_path
    >>> from empact.nonlinear.scenario import load_scenario
    >>> run = empact.run_closed_loop(load_scenario(control_example_path("slip-load-step-r1")),
    ...                              empact.load_params())
    >>> run.metrics["macro_slip"], bool(run.metrics["peak_slip_error"] < 0.006)
    (False, True)
    """
    model, op = scenario_model(scenario, params)
    law = build_law(scenario, params, controller, model, op, ideal, nominal)
    res = run_scenario(scenario, params, controller=law, progress=progress, start=(model, op))
    slip = law.refs.slip
    if law.config.spec.reserve_ahead:  # the set-point the law ran (the reserve ahead's)
        ran = law.setpoint_trace[:, 0]
        slip = np.where(np.isfinite(ran), ran, slip)
    refs = {"r_g": np.interp(res.t, law.t_k, law.refs.r_g),
            law.slip_signal: np.interp(res.t, law.t_k, slip)}
    out = ClosedLoopResult(res, refs, op, scenario, law.controller, law=law)
    return replace(out, metrics=metrics(out))


def metrics(run: ClosedLoopResult) -> dict[str, Any]:
    """The numbers a closed-loop run is judged by (true signals of the machine, not the
    sensors'):

    * ``slip_error``: largest ``|nu - nu*|`` [-] from 0.3 s after the load step to the end
      (or over the shift window, or the whole run); ``peak_slip_error`` [-]: the largest
      from the load step (or the shift window's start, or 0) to the end;
    * ``peak_slip``, ``slip_setpoint`` [-]; ``macro_slip``: the slip reached the traction
      peak's slip at the current ratio somewhere (``slip_reserve`` [-]: the smallest
      distance to it);
    * ``ratio_error``: largest relative ratio error ``|r_g - r*| / r*`` over the window;
      ``ratio_rate``: the mean ``|dr_g/dt|`` over the shift window [1/s] (NaN when the run
      stopped before it), ``ratio_span`` its first and last ratio;
    * ``mean_clamping_force``, ``min_clamping_force``, ``max_clamping_force`` [N];
      ``mean_slip_power``, ``mean_actuation_power``, ``mean_losses`` [W] (slip power
      ``T_b (r_g omega_p - omega_s)`` plus the servos' mechanical power
      ``|T_mp omega_mp| + |T_ms omega_ms|``);
    * ``peak_T_mp``, ``peak_T_ms`` [N m] against ``T_mp_max``, ``T_ms_max`` (NaN without
      limits), ``saturated``: the share of samples with a servo at its torque limit;
    * with a torque request (``controller.torque_request``; `torque_request_metrics`):
      what the law did when its secondary servo could not hold the clamping.

    Parameters
    ----------
    run : ClosedLoopResult
        A run (its ``metrics`` are not read).

    Returns
    -------
    dict str -> object
        The numbers above (floats, ``ratio_span`` a list of two ratios [-], ``macro_slip`` a
        bool), with ``complete`` (bool) and ``message`` (str) of the simulation.  Every slip
        is a fraction (0.01 is 1 %); `shown_metric` writes them in % and percentage points
        for people.
    """
    res, sc = run.result, run.scenario
    t = res.t
    slip_name = next((m for m in run.references if m.startswith("nu")), "nu")
    nu = res.output(slip_name)
    nu_ref = run.references.get(slip_name, np.full_like(t, run.op.nu))
    r, r_ref = res.output("r_g"), run.references.get("r_g", np.full_like(t, run.op.r_g))
    start = 0.0
    if sc.load_step_time is not None:
        window = t >= sc.load_step_time + 0.3
        start = sc.load_step_time
    elif sc.shift_window is not None:
        window = (t >= sc.shift_window[0]) & (t <= sc.shift_window[1])
        start = sc.shift_window[0]
    else:
        window = np.ones_like(t, dtype=bool)
    out: dict[str, Any] = {"complete": bool(res.complete), "message": res.message}
    if not np.any(window):
        window = np.ones_like(t, dtype=bool)
    after = t >= start
    if not np.any(after):
        after = np.ones_like(t, dtype=bool)
    err = np.abs(nu - nu_ref)
    out["slip_error"] = float(np.max(err[window]))
    out["peak_slip_error"] = float(np.max(err[after]))
    out["peak_slip"] = float(np.max(nu))
    out["slip_setpoint"] = float(np.max(nu_ref))
    model = run.op.model  # the machine's own traction curve (not the controller's knowledge)
    if model is not None:
        reserve = smallest_slip_reserve(model, np.clip(r, 0.3, 3.0), res.output("nu"))[0]
        out["slip_reserve"] = reserve
        out["macro_slip"] = bool(reserve <= 0.0 or not res.complete)
    out["ratio_error"] = float(np.max(np.abs(r - r_ref)[window] / r_ref[window]))
    if sc.shift_window is not None:
        w = (t >= sc.shift_window[0]) & (t <= sc.shift_window[1])
        if np.count_nonzero(w) >= 2:
            out["ratio_rate"] = float(np.mean(np.abs(np.gradient(r, t))[w]))
            out["ratio_span"] = [float(r[w][0]), float(r[w][-1])]
        else:  # the run stopped before the shift window
            out["ratio_rate"] = float("nan")
            out["ratio_span"] = [float("nan"), float("nan")]
    T_b, w_p, w_s = res.output("T_b"), res.output("omega_p"), res.output("omega_s")
    p_slip = T_b * (r * w_p - w_s)
    T_mp, T_ms = res.output("T_mp_act"), res.output("T_ms_act")
    p_act = np.abs(T_mp * res.output("omega_mp")) + np.abs(T_ms * res.output("omega_ms"))
    F_s = res.output("F_s")
    out["mean_clamping_force"] = float(np.mean(F_s))
    out["min_clamping_force"] = float(np.min(F_s))
    out["max_clamping_force"] = float(np.max(F_s))
    out["mean_slip_power"] = float(np.mean(p_slip))
    out["mean_actuation_power"] = float(np.mean(p_act))
    out["mean_losses"] = float(np.mean(p_slip + p_act))
    out["peak_T_mp"] = float(np.max(np.abs(T_mp)))
    out["peak_T_ms"] = float(np.max(np.abs(T_ms)))
    lim = run.law.config.limits if run.law is not None else None
    out["T_mp_max"] = float(lim.T_mp_max) if lim is not None else float("nan")
    out["T_ms_max"] = float(lim.T_ms_max) if lim is not None else float("nan")
    if lim is not None:
        sat = (np.abs(T_mp) >= lim.T_mp_max * (1 - 1e-9)) | \
            (np.abs(T_ms) >= lim.T_ms_max * (1 - 1e-9))
        out["saturated"] = float(np.mean(sat))
    else:
        out["saturated"] = 0.0
    if run.law is not None and run.law.config.spec.torque_request != "off":
        out.update(torque_request_metrics(run))
    if run.law is not None and (run.law.config.spec.reserve_ahead
                                or run.law.config.spec.slip_guard):
        out.update(protection_metrics(run))
    return out


def protection_metrics(run: ClosedLoopResult) -> dict[str, Any]:
    """What the reserve ahead and the slip-runaway guard (``controller.reserve_ahead``,
    ``slip_guard``) did over a run, from the law's trace (`LoopLaw.setpoint_trace`):

    * ``slip_setpoint_lowest`` [-]: the lowest slip set-point the law ran (the reference's
      where the reserve ahead did not move it), ``reserve_ahead_time`` [s]: the time the
      set-point was below the reference's;
    * ``guard_peak`` [-]: the guard's largest clamping share (of the clamping that holds the
      set-point), ``guard_time`` [s]: the time it added more than 1 % of it.

    Parameters
    ----------
    run : ClosedLoopResult
        A run whose law had the reserve ahead or the guard.

    Returns
    -------
    dict str -> float
        The numbers above (NaN for the one that did not run).
    """
    law = run.law
    assert law is not None
    tr = law.setpoint_trace
    n = tr.shape[0]
    sp, g = tr[:, 0], tr[:, 1]
    ran = np.isfinite(sp)
    nan = float("nan")
    below = ran & (sp < law.refs.slip[:n] * (1 - 1e-12))
    ran_g = np.isfinite(g)
    return {"slip_setpoint_lowest": float(np.min(sp[ran])) if ran.any() else nan,
            "reserve_ahead_time": float(np.count_nonzero(below) * law.dt) if ran.any() else nan,
            "guard_peak": float(np.max(g[ran_g])) if ran_g.any() else nan,
            "guard_time": float(np.count_nonzero(ran_g & (g > 0.01)) * law.dt)
            if ran_g.any() else nan}


def torque_request_metrics(run: ClosedLoopResult) -> dict[str, Any]:
    """What a law with a torque request (``controller.torque_request``) did over a run,
    from its trace (`LoopLaw.request_trace`) and the machine's driveshaft torque:

    * ``servo_capacity_force`` [N]: the clamping the request is computed for (the secondary
      servo's torque limit less ``torque_request_margin``);
    * ``torque_request_min`` [N m]: the smallest request (secondary-shaft torque);
    * ``torque_request_exceeded`` [-]: the share of samples whose driveshaft torque
      ``T_ds`` was above the request (the belt asked for more clamping than the servo
      holds within its margin);
    * ``torque_request_honoured`` (bool); where honoured, ``torque_limited`` [-]: the share
      of samples whose load torque the request limited, ``torque_reduction`` [N m]: the
      largest cut of the load-torque demand, ``torque_limited_time`` [s]: the time under
      the limit.

    Parameters
    ----------
    run : ClosedLoopResult
        A run whose law had a torque request.

    Returns
    -------
    dict str -> object
        The numbers above (floats [N], [N m], [-], [s]; ``torque_request_honoured`` a bool).
    """
    law = run.law
    assert law is not None
    tr = law.request_trace
    ran = np.isfinite(tr[:, 0])
    req = tr[ran, 0]
    t_k = law.t_k[:tr.shape[0]][ran]
    T_ds = np.interp(t_k, run.result.t, run.result.output("T_ds"))
    out: dict[str, Any] = {
        "servo_capacity_force": float(law.servo_capacity),
        "torque_request_min": float(np.min(req)) if req.size else float("nan"),
        "torque_request_exceeded": float(np.mean(np.abs(T_ds) > req)) if req.size else 0.0,
        "torque_request_honoured": law.config.spec.torque_request == "honoured"}
    if out["torque_request_honoured"]:
        demand = np.abs(law._load[:tr.shape[0]][ran])
        cut = demand - np.abs(tr[ran, 1])
        limited = cut > 1e-9 * np.maximum(demand, 1.0)
        out["torque_limited"] = float(np.mean(limited)) if req.size else 0.0
        out["torque_reduction"] = float(np.max(cut)) if req.size else 0.0
        out["torque_limited_time"] = float(np.count_nonzero(limited) * law.dt)
    return out


def safety_factor_twin(scenario: Scenario, params: Params, mu_design: str = "ratio-blind",
                       safety_factor: float = 1.3) -> Scenario:
    """The same run under a production CVT's open-loop clamping (``clamping =
    "safety-factor"``, `empact.control.law`): the same load torque history (a ``load_step``
    becomes the same absolute step of ``T_l``), the same ratio reference, started at the
    strategy's own steady clamping ``SF |T_l| cos(beta) / (2 mu_design R_s)``.

    Parameters
    ----------
    scenario : Scenario
        A scenario with a ``[controller]`` table.
    params : Params
        The parameter set its start is trimmed on.
    mu_design : {"ratio-blind", "ratio-aware"}
        The strategy's traction coefficient: the smallest traction peak over the ratio
        range, or the peak at the measured ratio.
    safety_factor : float
        The clamping safety factor ``SF`` [-] on the load torque.

    Returns
    -------
    Scenario
        A copy named ``<name>-sf<SF>-<mu_design>``: the safety-factor clamping, started at
        its steady clamping force ``F_s`` [N] and the same load torque ``T_l`` [N m], the
        ratio reference kept, no ``load_step`` and no ``[targets]``.

    Raises
    ------
    ParameterError
        When the scenario has no ``[controller]`` table.
    """
    if scenario.controller is None:
        raise ParameterError(f"scenario {scenario.name!r} has no [controller] table")
    model, op = scenario_model(scenario, params)
    signals = scenario_signals(scenario, model, op)
    spec = replace(scenario.controller, clamping="safety-factor", mu_design=mu_design,
                   safety_factor=safety_factor)
    law = LoopLaw(Controller(np.zeros((0, 0)), np.zeros((0, 2)), np.zeros((2, 0)),
                             np.zeros((2, 2)), ("r_g", "nu"), ("T_mp", "T_ms")), model,
                  {"r_g": op.r_g, "nu": op.nu, "omega_p": op.omega_p, "T_l": op.T_l,
                   "F_s": op.F_s}, op.u[:2], LoopConfig(spec), {}, 0.0)
    F_sf = law._T_ms_start / law._tpf
    initial = OperatingPoint(r_g=op.r_g, omega_p=op.omega_p, F_s=float(F_sf),
                             T_l=float(op.T_l))
    inputs = dict(scenario.inputs)
    if "T_l" in signals:
        inputs["T_l"] = signals["T_l"]
    refs = {k: v for k, v in scenario.references.items() if k == "r_g"}
    refs["nu"] = np.array([[0.0, op.nu]])  # unused: the slip loop is off
    return replace(scenario, name=f"{scenario.name}-sf{safety_factor:g}-{mu_design}",
                   controller=spec, initial=initial, inputs=inputs, load_step=None,
                   references=refs, targets={})


#: The slip metrics (fractions [-] in `metrics`) and how people read them: ``"pp"``
#: (percentage points, a difference of slips) or ``"%"`` (a slip).
SLIP_METRICS = {"slip_error": "pp", "peak_slip_error": "pp", "peak_slip": "%",
                "slip_setpoint": "%", "slip_reserve": "pp"}


def shown_metric(name: str, value: Any) -> tuple[Any, str]:
    """A metric as people read it: a slip metric (`SLIP_METRICS`) times 100 with its unit
    (``"pp"`` or ``"%"``), any other value as it is with the unit ``""``.

    Parameters
    ----------
    name : str
        The metric's name (a key of `metrics`).
    value : object
        Its value (a fraction [-] for a slip metric).

    Returns
    -------
    value : object
        ``100 * value`` for a slip metric, else `value`.
    unit : str
        ``"pp"``, ``"%"`` or ``""``.
    """
    unit = SLIP_METRICS.get(name, "")
    if unit and isinstance(value, (int, float)) and not isinstance(value, bool):
        return 100 * value, unit
    return value, unit


@dataclass(frozen=True)
class TargetCheck(Result):
    """One target of a run: the metric, its value, the target and whether it is met."""

    name: str
    value: Any
    target: Any
    met: bool

    def describe(self) -> str:
        """``name = value (target ...): met|MISSED``, for people: a slip metric and its
        target in percentage points or % (`shown_metric`)."""
        unit = SLIP_METRICS.get(self.name, "")
        scale, sfx = (100.0, f" {unit}") if unit else (1.0, "")
        if isinstance(self.target, bool):
            want = f"must be {str(self.target).lower()}"
        else:
            lo, hi = (scale * x for x in self.target)
            want = (f"<= {hi:g}{sfx}" if lo == -np.inf else f">= {lo:g}{sfx}" if hi == np.inf
                    else f"in [{lo:g}, {hi:g}]{sfx}")
        v = self.value
        shown = str(v).lower() if isinstance(v, bool) else f"{scale * v:.4g}{sfx}"
        return f"{self.name} = {shown} ({want}): {'met' if self.met else 'MISSED'}"


def check_targets(metrics: Mapping[str, Any], targets: Mapping[str, Any]) -> list[TargetCheck]:
    """Each of a scenario's ``[targets]`` against a run's metrics (`metrics`); a run that
    did not complete misses every target.

    Parameters
    ----------
    metrics : dict str -> object
        A run's metrics (`metrics`, or ``ClosedLoopResult.metrics``).
    targets : dict str -> (lo, hi) or bool
        A scenario's ``[targets]``: a band ``(lo, hi)`` in the metric's units (an upper
        bound is ``(-inf, hi)``), or the bool a flag must have.

    Returns
    -------
    list of TargetCheck
        One per target, in the order of `targets`: the metric's value, the target and
        whether it is met.

    Raises
    ------
    ParameterError
        A target naming no metric (one line listing the metrics).
    """
    out = []
    for name, target in targets.items():
        if name not in metrics:
            raise ParameterError(f"targets.{name}: no such metric (choose from "
                                 f"{', '.join(k for k in metrics if k != 'message')})")
        v = metrics[name]
        if isinstance(target, bool):
            met = bool(v) == target
        else:
            lo, hi = target
            met = bool(np.isfinite(v) and lo <= v <= hi)
        out.append(TargetCheck(name, v, target, bool(met and metrics.get("complete", True))))
    return out
