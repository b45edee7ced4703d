"""A controller in closed loop with the nonlinear machine: scenarios, simulation and metrics.

The controller (`empact.control.controller.Controller`, discretised by Tustin at the
scenario's ``controller_rate``) samples the measured ratio and slip, and holds the servo
torques over each sample period (zero-order hold) while the compiled integrator of
`empact.nonlinear.simulation` advances the machine.  The servo torques are the trimmed holding
torques plus the controller's output; optionally a static feedforward of the measured load to
the clamping (``feedforward = true``: from the driveshaft torque ``T_ds = k_ds twist_ds`` a
test bench measures, the secondary servo torque that holds the slip set-point at that torque,
``T_ms = i_e s F_s / i_c`` with ``F_s = T_ds cos(beta) / (2 mu(nu*) R_s)``).  Measured on the
shipped load steps it keeps the slip excursions 3-10 times smaller than a feedforward of the
load motor's torque itself (lagged 0-0.2 s), which clamps before the torque reaches the
variator; it also closes a second loop through the slip (the shaft torque follows the belt
torque), part of the limit cycle the report shows.

``clamping = "safety-factor"`` replaces the slip loop by the open-loop clamping strategy of a
production CVT without slip control: ``F_s = SF T_l cos(beta) / (2 mu_design R_s)`` with the
safety factor SF (1.3) and the design traction coefficient ``mu_design``, the smallest traction
peak over the ratio range (the strategy cannot know the curve at each ratio); the ratio loop
stays.

Scenario file (TOML)::

    [scenario]
    name = "slip-load-step-r1"
    duration = 2.0
    sample_rate = 1000.0          # output samples [Hz]
    controller = "pi.json"        # relative to this file; or "shipped:pi"
    controller_rate = 1000.0      # [Hz]
    feedforward = true
    clamping = "feedback"         # or "safety-factor"
    safety_factor = 1.3
    load_step_time = 0.5          # [s] for the metrics (optional)

    [model]                       # ModelOptions (default: test bench, drive speed-controlled;
                                  # a thrust_ratio file is relative to this file)
    [initial]                     # trim: r_g, omega_p and two of nu, F_s, T_l
    [references]                  # [[t, value], ...]; default: the trimmed values held
    r_g = [[0.0, 1.0]]
    nu = [[0.0, 0.01]]
    [inputs]                      # the machine's other inputs (T_l, omega_d_ref)
    T_l = [[0.5, 50.0], [0.5, 80.0]]
"""
from __future__ import annotations

import os
import time
from dataclasses import dataclass, field, replace
from importlib import resources
from pathlib import Path
from typing import Any, Mapping

import numpy as np
from numpy.typing import NDArray

from .._validate import check_choice, check_number
from ..errors import ParameterError
from ..geometry import radii
from ..nonlinear import _kernel as K
from ..nonlinear._rosenbrock import STATUS, integrate
from ..nonlinear.equilibrium import TrimResult, trim
from ..nonlinear.model import ModelOptions, nonlinear_model
from ..nonlinear.scenario import _signal, check_tables, model_options
from ..nonlinear.simulation import SimulationResult, state_tolerances
from ..params import Params, read_toml
from .controller import Controller, load_controller

__all__ = ["ControlScenario", "ClosedLoopResult", "load_control_scenario",
           "run_closed_loop", "control_examples", "control_example_path", "metrics"]

_KEYS = {"scenario": {"name", "description", "duration", "sample_rate", "controller",
                      "controller_rate", "feedforward", "clamping", "safety_factor",
                      "load_step_time", "shift_window", "rtol", "max_step"},
         "model": None, "initial": {"r_g", "omega_p", "nu", "F_s", "T_l"},
         "references": {"r_g", "nu", "nu_r"}, "inputs": None}


@dataclass(frozen=True)
class ControlScenario:
    """A validated closed-loop scenario (see the module notes)."""

    name: str
    description: str
    duration: float
    sample_rate: float
    controller: str
    controller_rate: float
    options: ModelOptions
    initial: Mapping[str, float]
    references: Mapping[str, NDArray[np.float64]]
    inputs: Mapping[str, NDArray[np.float64]]
    feedforward: bool = False
    clamping: str = "feedback"
    safety_factor: float = 1.3
    load_step_time: float | None = None
    shift_window: tuple[float, float] | None = None
    rtol: float = 1e-4
    max_step: float = 0.01
    source: str = ""


def control_examples() -> dict[str, str]:
    """The shipped closed-loop scenarios: name -> description."""
    out = {}
    for f in sorted(resources.files("empact.data").joinpath("control").iterdir()):
        if f.name.endswith(".toml"):
            out[f.name[:-5]] = load_control_scenario(Path(str(f))).description
    return out


def control_example_path(name: str) -> Path:
    """Path of a shipped closed-loop scenario."""
    p = Path(str(resources.files("empact.data").joinpath("control", f"{name}.toml")))
    if not p.is_file():
        raise ParameterError(f"unknown control example {name!r} (choose from "
                             f"{', '.join(control_examples())})")
    return p


def load_control_scenario(path: str | os.PathLike[str]) -> ControlScenario:
    """Read and validate a closed-loop scenario; one-line errors naming file and key."""
    src = str(path)
    data = read_toml(path, "control scenario")
    check_tables(data, _KEYS, src)
    head = data.get("scenario", {})
    for key in ("duration", "controller"):
        if key not in head:
            raise ParameterError(f"{src}: missing scenario.{key}")
    duration = check_number("scenario.duration", head["duration"], 0.0, 600.0, lo_open=True,
                            unit="s", where=src)
    rate = check_number("scenario.sample_rate", head.get("sample_rate", 1000.0), 0.0, 1e5,
                        lo_open=True, unit="Hz", where=src)
    c_rate = check_number("scenario.controller_rate", head.get("controller_rate", 1000.0), 1.0,
                          1e5, unit="Hz", where=src)
    clamping = check_choice("scenario.clamping", head.get("clamping", "feedback"),
                            ("feedback", "safety-factor"))
    sf = check_number("scenario.safety_factor", head.get("safety_factor", 1.3), 1.0, 3.0,
                      where=src)
    options = model_options(data.get("model", {}), src, {"drive": "speed", "load": "torque"})
    if options.ratio_control:
        raise ParameterError(f"{src}: [model] ratio_control must be false: the controller "
                             "drives the servo torques")
    initial = dict(data.get("initial", {}))
    for key in ("r_g", "omega_p"):
        if key not in initial:
            raise ParameterError(f"{src}: missing initial.{key}")
    for key, value in initial.items():
        check_number(f"initial.{key}", value, where=src)
    refs = {k: _signal(f"{src}: references.{k}", v, duration)
            for k, v in data.get("references", {}).items()}
    allowed = ("omega_d_ref" if options.drive == "speed" else "T_d",
               "omega_l_ref" if options.load == "speed" else "T_l")
    inputs = {}
    for k, v in data.get("inputs", {}).items():
        if k not in allowed:
            raise ParameterError(f"{src}: unknown input {k!r} (the controller drives the "
                                 f"servos; allowed: {', '.join(allowed)})")
        inputs[k] = _signal(f"{src}: inputs.{k}", v, duration)
    controller = str(head["controller"])
    if not controller.startswith("shipped:") and not Path(controller).is_absolute():
        controller = str(Path(src).parent / controller)
    t_step = head.get("load_step_time")
    window = head.get("shift_window")
    return ControlScenario(
        name=str(head.get("name", Path(src).stem)), description=str(head.get("description", "")),
        duration=duration, sample_rate=rate, controller=controller, controller_rate=c_rate,
        options=options, initial=initial, references=refs, inputs=inputs,
        feedforward=bool(head.get("feedforward", False)), clamping=clamping, safety_factor=sf,
        load_step_time=None if t_step is None else check_number(
            "scenario.load_step_time", t_step, 0.0, duration, unit="s", where=src),
        shift_window=None if window is None else tuple(float(w) for w in window),
        rtol=check_number("scenario.rtol", head.get("rtol", 1e-4), 1e-10, 0.1, lo_open=True,
                          where=src),
        max_step=check_number("scenario.max_step", head.get("max_step", 0.01), 0.0, 1.0,
                              lo_open=True, unit="s", where=src), source=src)


def resolve_controller(ref: str) -> Controller:
    """A controller file, or a shipped one (``shipped:NAME``)."""
    if ref.startswith("shipped:"):
        name = ref.split(":", 1)[1]
        p = Path(str(resources.files("empact.data").joinpath("control", f"{name}.json")))
        if not p.is_file():
            raise ParameterError(f"controller {ref!r}: no shipped controller {name!r}")
        return load_controller(p)
    return load_controller(ref)


@dataclass(frozen=True, eq=False)
class ClosedLoopResult:
    """A closed-loop run: the simulation (`result`), references, the trimmed start and the
    metrics (`metrics`)."""

    result: SimulationResult
    references: dict[str, NDArray[np.float64]]
    op: TrimResult
    scenario: ControlScenario
    controller: Controller
    metrics: dict[str, Any] = field(default_factory=dict)


def _pl(arr: NDArray, t: NDArray | float) -> NDArray:
    """A piecewise-linear signal ``[[t, v], ...]`` at times `t`: right-continuous (a repeated
    time is a step), held before its first and after its last point."""
    ts, vs = arr[:, 0], arr[:, 1]
    n = len(ts)
    tt = np.atleast_1d(np.asarray(t, float))
    i = np.clip(np.searchsorted(ts, tt, side="right") - 1, 0, max(n - 2, 0))
    j = np.minimum(i + 1, n - 1)
    span = ts[j] - ts[i]
    frac = np.divide(tt - ts[i], span, out=np.ones_like(tt), where=span > 0)
    out = np.where(tt < ts[0], vs[0], np.where(tt >= ts[-1], vs[-1],
                                                vs[i] + (vs[j] - vs[i]) * frac))
    return out if np.ndim(t) else float(out[0])


def run_closed_loop(scenario: ControlScenario, params: Params,
                    controller: Controller | None = None) -> ClosedLoopResult:
    """Trim the scenario's start and simulate the machine with the controller in the loop."""
    ctrl = resolve_controller(scenario.controller) if controller is None else controller
    if ctrl.outputs != ("T_mp", "T_ms"):
        raise ParameterError(f"controller outputs {ctrl.outputs}: must drive T_mp, T_ms")
    model = nonlinear_model(params, replace(scenario.options, reference_ratio=float(
        scenario.initial["r_g"])))
    req = dict(scenario.initial)
    r0, w0 = req.pop("r_g"), req.pop("omega_p")
    op = trim(model, r0, w0, **req)
    dt = 1.0 / scenario.controller_rate
    cd = ctrl.discretize(dt) if not ctrl.dt else ctrl
    if abs(cd.dt - dt) > 1e-12:
        raise ParameterError(f"controller sample time {cd.dt:g} s differs from the scenario's "
                             f"controller_rate {scenario.controller_rate:g} Hz")
    measured_idx = [model.outputs.index(m[3:] if m.startswith("ln_") else m)
                    for m in cd.measured]
    logs = np.array([m.startswith("ln_") for m in cd.measured])
    ref_default = {"r_g": op.r_g, "nu": op.nu, "nu_r": op.nu}
    refs = {m: scenario.references.get(m, np.array([[0.0, ref_default[m]]]))
            for m in (n[3:] if n.startswith("ln_") else n for n in cd.measured)}
    n_steps = int(round(scenario.duration / dt))
    n_t = int(np.floor(scenario.duration * scenario.sample_rate + 1e-9)) + 1
    samples = np.arange(n_t) / scenario.sample_rate
    X = np.full((n_t, model.n), np.nan)
    Y = np.full((n_t, K.NY), np.nan)
    U = np.full((n_t, 4), np.nan)
    x = op.x.copy()
    X[0] = x
    y = np.empty(K.NY)
    dxb = np.empty(model.n)
    K._eval(x, op.u, model.p, model.ix, dxb, y)
    Y[0] = y
    rel, atol = state_tolerances(model, scenario.rtol)
    cols = K.varying_columns(model.ix)
    # the other inputs: piecewise-linear signals, as `simulate` passes them
    kmax = max([2] + [len(v) for v in scenario.inputs.values()])
    sig_t, sig_v = np.zeros((4, kmax)), np.zeros((4, kmax))
    sig_n = np.ones(4, dtype=np.int64)
    brk = [scenario.duration]
    for j, name in enumerate(model.inputs):
        if name in scenario.inputs:
            arr = scenario.inputs[name]
            sig_n[j] = len(arr)
            sig_t[j, :len(arr)], sig_v[j, :len(arr)] = arr[:, 0], arr[:, 1]
            brk.extend(arr[:, 0].tolist())
        else:
            sig_v[j, 0] = op.u[j]
    brk_arr = np.unique(np.array([b for b in brk if 0 < b <= scenario.duration]))

    def other(j: int, tq):
        """Input j (not a servo) at times tq, as the integrator sees it."""
        return _pl(np.column_stack([sig_t[j, :sig_n[j]], sig_v[j, :sig_n[j]]]), tq)

    a, v = params.actuation, params.variator
    sig_q6 = model.p[K.P_SIG]
    torque_per_force = a.i_e * a.s * sig_q6 / a.i_c  # T_ms per unit secondary force
    cosb = np.cos(v.beta)
    slip_ref = next((refs[m][0, 1] for m in refs if m.startswith("nu")), op.nu)
    mu_ref = float(model.traction(slip_ref, op.r_g))
    mu_design = min(params.traction.D_low, params.traction.D_med, params.traction.D_od)
    j_load = model.inputs.index("T_l") if "T_l" in model.inputs else None
    xc = np.zeros(cd.n)
    t, h = 0.0, 1e-5
    status, steps, filled = 0, 0, 1
    wall = time.perf_counter()
    for k in range(n_steps):
        t_k = k * dt
        ym = y[measured_idx]
        rv = np.array([_pl(refs[m], t_k) for m in refs])
        e = np.where(logs, np.log(np.maximum(rv, 1e-6)) - np.log(np.maximum(ym, 1e-6)),
                     rv - ym)
        if scenario.clamping == "safety-factor":
            e[1:] = 0.0  # the slip loop is replaced by the open-loop clamping strategy
        du = cd.C @ xc + cd.D @ e
        xc = cd.A @ xc + cd.B @ e
        T_mp = op.u[0] + du[0]
        T_l = other(j_load, t_k) if j_load is not None else op.T_l
        if scenario.clamping == "safety-factor":
            R_s = float(radii(max(y[K.Y_RG], 1e-3), v.L_belt, v.a)[1])
            F_set = scenario.safety_factor * abs(T_l) * cosb / (2 * mu_design * R_s)
            T_ms = torque_per_force * F_set
        else:
            T_ms = op.u[1] + du[1]
            if scenario.feedforward:  # from the measured driveshaft torque
                T_ds = model.params.driveline.k_ds * x[13]
                T_ms += torque_per_force * (T_ds - op.T_l) * cosb / (2 * mu_ref * y[K.Y_RS])
        sig_v[0, 0], sig_v[1, 0] = T_mp, T_ms
        sig_n[0] = sig_n[1] = 1
        t_end = min((k + 1) * dt, scenario.duration)
        status, t, h, filled_new, ns, _ = integrate(
            x, t, t_end, h, samples, model.p, model.ix, sig_t, sig_v, sig_n, brk_arr, rel,
            atol, 1e-14, scenario.max_step, 1.0, 10_000_000, X, Y, cols)
        U[filled:filled_new, :2] = T_mp, T_ms
        for j in (2, 3):
            U[filled:filled_new, j] = other(j, samples[filled:filled_new])
        filled = filled_new
        steps += ns
        if status != 0:
            break
        K._eval(x, np.array([T_mp, T_ms, other(2, t), other(3, t)]), model.p, model.ix, dxb,
                y)
    wall = time.perf_counter() - wall
    U[0] = op.u
    complete = status == 0
    msg = (f"completed: {steps} steps, {wall:.2f} s wall time" if complete else
           f"stopped at t = {t:.6g} s: {STATUS[status]}")
    keep = slice(0, max(filled, 1))
    res = SimulationResult(t=samples[keep], x=X[keep], y=Y[keep], u=U[keep],
                           states=model.states, outputs=model.outputs, inputs=model.inputs,
                           complete=complete, message=msg, scenario=scenario.name,
                           stats={"n_steps": steps, "wall_time": wall, "t_end": t})
    ref_t = {m: _pl(refs[m], res.t) for m in refs}
    out = ClosedLoopResult(res, ref_t, op, scenario, ctrl)
    return replace(out, metrics=metrics(out))


def metrics(run: ClosedLoopResult) -> dict[str, Any]:
    """The scenario's figures of merit (SI; slips in percentage points where named ``_pp``).

    * ``slip_error_pp``: largest ``|nu - nu*|`` from 0.3 s after the load step to the end (or
      over the shift window, or over the whole run);
    * ``peak_slip_pp``, ``slip_setpoint_pp``; ``ratio_error``: largest relative ratio error
      ``|r_g - r_ref| / r_ref`` over the same window;
    * ``ratio_rate``: the mean |d r_g / dt| over the shift window [1/s];
    * ``mean_clamping_force`` [N], ``mean_slip_power``, ``mean_actuation_power``,
      ``mean_losses`` [W] (slip power ``T_b (r_g omega_p - omega_s)`` plus the servos'
      mechanical power ``|T_mp omega_mp| + |T_ms omega_ms|``).
    """
    res, sc = run.result, run.scenario
    t = res.t
    slip_name = next((m for m in run.references if m.startswith("nu")), "nu")
    nu = res.output(slip_name)
    nu_ref = run.references.get(slip_name, np.full_like(t, run.op.nu))
    r, r_ref = res.output("r_g"), run.references.get("r_g", np.full_like(t, run.op.r_g))
    if sc.load_step_time is not None:
        window = t >= sc.load_step_time + 0.3
    elif sc.shift_window is not None:
        window = (t >= sc.shift_window[0]) & (t <= sc.shift_window[1])
    else:
        window = np.ones_like(t, dtype=bool)
    out: dict[str, Any] = {"complete": bool(res.complete), "message": res.message}
    if not np.any(window):
        window = np.ones_like(t, dtype=bool)
    out["slip_error_pp"] = float(100 * np.max(np.abs(nu - nu_ref)[window]))
    out["peak_slip_pp"] = float(100 * np.max(nu))
    out["slip_setpoint_pp"] = float(100 * np.max(nu_ref))
    out["ratio_error"] = float(np.max(np.abs(r - r_ref)[window] / r_ref[window]))
    if sc.shift_window is not None:
        w = (t >= sc.shift_window[0]) & (t <= sc.shift_window[1])
        out["ratio_rate"] = float(np.mean(np.abs(np.gradient(r, t))[w]))
        out["ratio_span"] = [float(r[w][0]), float(r[w][-1])]
    T_b, w_p, w_s = res.output("T_b"), res.output("omega_p"), res.output("omega_s")
    p_slip = T_b * (r * w_p - w_s)
    p_act = np.abs(res.output("T_mp") * res.output("omega_mp")) \
        + np.abs(res.output("T_ms") * res.output("omega_ms"))
    out["mean_clamping_force"] = float(np.mean(res.output("F_s")))
    out["mean_slip_power"] = float(np.mean(p_slip))
    out["mean_actuation_power"] = float(np.mean(p_act))
    out["mean_losses"] = float(np.mean(p_slip + p_act))
    return out
