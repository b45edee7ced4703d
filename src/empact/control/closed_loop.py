"""A controller in closed loop with the nonlinear machine: the loop law, the run and its
metrics.

A closed-loop scenario is an ordinary scenario (`empact.nonlinear.scenario`) with a
``[controller]`` table and ``[references]``.  `run_closed_loop` builds the loop law
(`LoopLaw`) from the controller (`empact.control.controller.Controller`, discretised by Tustin
at the table's ``rate``) and hands it to the one simulator (`empact.nonlinear.simulation.
simulate`), which samples the measured signals, calls the law and holds the servo torques
over each period (zero-order hold).

The law: the servo torques are the trimmed holding torques plus the controller's output from
the errors ``reference - measured`` of its signals (``r_g`` and a slip, or its logarithm
``ln_nu``).  Optionally a static feedforward of the measured load to the clamping
(``feedforward = true``: from the driveshaft torque ``T_ds`` a test bench measures, the
secondary servo torque that holds the slip set-point at that torque, ``T_ms = i_e s F_s /
i_c`` with ``F_s = T_ds cos(beta) / (2 mu(nu*) R_s)``).  Measured on the shipped load steps it
keeps the slip excursions 3-10 times smaller than a feedforward of the load motor's torque
itself (lagged 0-0.2 s), which clamps before the torque reaches the variator; it also closes a
second loop through the slip (the shaft torque follows the belt torque).

``clamping = "safety-factor"`` replaces the slip loop by the open-loop clamping strategy of a
production CVT without slip control: ``F_s = SF T_l cos(beta) / (2 mu_design R_s)`` with the
safety factor SF (1.3) and the design traction coefficient ``mu_design``, the smallest traction
peak over the ratio range (the strategy cannot know the curve at each ratio); the ratio loop
stays.
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass, field, replace
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..errors import ParameterError
from ..nonlinear.equilibrium import TrimResult
from ..nonlinear.model import EmpactModel
from ..nonlinear.scenario import Scenario, example_path, list_examples, load_scenario
from ..nonlinear.simulation import SimulationResult, run_scenario, scenario_model
from ..params import Params
from ..variator.geometry import radii
from .controller import Controller, load_controller

__all__ = ["LoopLaw", "ClosedLoopResult", "run_closed_loop", "metrics", "resolve_controller",
           "control_examples", "control_example_path", "load_control_scenario",
           "ControlScenario"]

#: Deprecated name of the closed-loop scenario (one `Scenario` type now).
ControlScenario = Scenario


def control_examples() -> dict[str, str]:
    """The shipped closed-loop scenarios: name -> description."""
    return list_examples(closed_loop=True)


def control_example_path(name: str) -> Path:
    """Path of a shipped closed-loop scenario."""
    if name not in control_examples():
        raise ParameterError(f"unknown control example {name!r} (choose from "
                             f"{', '.join(control_examples())})")
    return example_path(name)


def load_control_scenario(path) -> Scenario:
    """Deprecated: `empact.nonlinear.scenario.load_scenario` reads every scenario; this
    checks that the file has a ``[controller]`` table."""
    warnings.warn("load_control_scenario is deprecated; use load_scenario (one scenario "
                  "format)", DeprecationWarning, stacklevel=2)
    sc = load_scenario(path)
    if not sc.closed_loop:
        raise ParameterError(f"{path}: no [controller] table (not a closed-loop scenario)")
    return sc


def resolve_controller(ref: str) -> Controller:
    """A controller file, or a shipped one (``shipped:NAME``)."""
    if ref.startswith("shipped:"):
        name = ref.split(":", 1)[1]
        p = Path(str(resources.files("empact.data").joinpath("control", f"{name}.json")))
        if not p.is_file():
            raise ParameterError(f"controller {ref!r}: no shipped controller {name!r}")
        return load_controller(p)
    return load_controller(ref)


def _pl(arr: NDArray, t: NDArray) -> NDArray:
    """A piecewise-linear signal ``[[t, v], ...]`` at times `t` (vectorised): right-continuous
    (a repeated time is a step), held before its first and after its last point."""
    ts, vs = arr[:, 0], arr[:, 1]
    n = len(ts)
    tt = np.asarray(t, float)
    i = np.clip(np.searchsorted(ts, tt, side="right") - 1, 0, max(n - 2, 0))
    j = np.minimum(i + 1, n - 1)
    span = ts[j] - ts[i]
    frac = np.divide(tt - ts[i], span, out=np.ones_like(tt), where=span > 0)
    return np.where(tt < ts[0], vs[0], np.where(tt >= ts[-1], vs[-1],
                                                 vs[i] + (vs[j] - vs[i]) * frac))


class LoopLaw:
    """The closed-loop law of a scenario, with the step interface of
    `empact.nonlinear.simulation.SampledController`: at each sample the discrete controller
    acts on the tracking errors, the servo torques are the trimmed holding torques plus its
    output, with the clamping feedforward or the safety-factor strategy (module notes).

    Parameters
    ----------
    controller : Controller
        Continuous (discretised here by Tustin at ``scenario.controller.rate``) or discrete at
        that rate.
    scenario : Scenario
        With a ``[controller]`` table.
    model : EmpactModel
    op : TrimResult
        The trimmed initial point (the holding torques, the default references).
    """

    commands = ("T_mp", "T_ms")

    def __init__(self, controller: Controller, scenario: Scenario, model: EmpactModel,
                 op: TrimResult) -> None:
        spec = scenario.controller
        if spec is None:
            raise ParameterError(f"scenario {scenario.name!r} has no [controller] table")
        if controller.outputs != ("T_mp", "T_ms"):
            raise ParameterError(f"controller outputs {controller.outputs}: must drive T_mp, "
                                 "T_ms")
        self.dt = 1.0 / spec.rate
        cd = controller.discretize(self.dt) if not controller.dt else controller
        if abs(cd.dt - self.dt) > 1e-12:
            raise ParameterError(f"controller sample time {cd.dt:g} s differs from the "
                                 f"scenario's controller rate {spec.rate:g} Hz")
        self.controller = cd
        self.spec = spec
        base = [m[3:] if m.startswith("ln_") else m for m in cd.measured]
        for m in base:
            if m not in ("r_g", "nu", "nu_r"):
                raise ParameterError(f"the controller measures {m!r}: the loop tracks r_g, "
                                     "nu or nu_r")
        self.logs = np.array([m.startswith("ln_") for m in cd.measured])
        default = {"r_g": op.r_g, "nu": op.nu, "nu_r": op.nu}
        self.references = {m: scenario.references.get(m, np.array([[0.0, default[m]]]))
                           for m in base}
        n_k = int(round(scenario.duration / self.dt))
        t_k = np.minimum(np.arange(n_k + 1) * self.dt, scenario.duration)
        self._refs = np.column_stack([_pl(self.references[m], t_k) for m in base])
        self._n_e = len(base)
        extra = ["T_ds", "R_s"]
        if "T_l" in model.inputs:
            extra.append("T_l")
        self.measured = tuple(base) + tuple(extra)
        a, v = model.params.actuation, model.params.variator
        self._tpf = a.i_e * a.s * model.constants.sheave_sense / a.i_c  # T_ms per F_s
        self._cosb = float(np.cos(v.beta))
        self._L, self._a = v.L_belt, v.a
        slip_ref = next((self.references[m][0, 1] for m in self.references
                         if m.startswith("nu")), op.nu)
        self._mu_ref = float(model.traction(slip_ref, op.r_g))
        t = model.params.traction
        self._mu_design = min(t.D_low, t.D_med, t.D_od)
        self._u0 = op.u[:2].copy()
        self._T_l0 = op.T_l
        self._has_load = "T_l" in model.inputs
        self._safety = spec.clamping == "safety-factor"
        self.reset()

    def reset(self) -> None:
        """Back to the first sample (controller state zero)."""
        self._xc = np.zeros(self.controller.n)
        self._k = 0

    def step(self, t: float, measured: NDArray[np.float64]) -> NDArray[np.float64]:
        """Servo torques ``[T_mp, T_ms]`` [N m] over ``[t, t + dt)``."""
        c = self.controller
        ne = self._n_e
        ym = measured[:ne]
        rv = self._refs[min(self._k, len(self._refs) - 1)]
        self._k += 1
        e = np.where(self.logs, np.log(np.maximum(rv, 1e-6)) - np.log(np.maximum(ym, 1e-6)),
                     rv - ym)
        if self._safety:
            e[1:] = 0.0  # the slip loop is replaced by the open-loop clamping strategy
        du = c.C @ self._xc + c.D @ e
        self._xc = c.A @ self._xc + c.B @ e
        T_mp = self._u0[0] + du[0]
        T_ds, R_s = measured[ne], measured[ne + 1]
        T_l = measured[ne + 2] if self._has_load else self._T_l0
        if self._safety:
            R_s0 = float(radii(max(ym[0], 1e-3), self._L, self._a)[1])
            F_set = self.spec.safety_factor * abs(T_l) * self._cosb / (2 * self._mu_design
                                                                         * R_s0)
            T_ms = self._tpf * F_set
        else:
            T_ms = self._u0[1] + du[1]
            if self.spec.feedforward:  # from the measured driveshaft torque
                T_ms += self._tpf * (T_ds - self._T_l0) * self._cosb / (2 * self._mu_ref
                                                                          * R_s)
        return np.array([T_mp, T_ms])


@dataclass(frozen=True, eq=False)
class ClosedLoopResult:
    """A closed-loop run: the simulation (`result`), references at its sample times, the
    trimmed start and the metrics (`metrics`)."""

    result: SimulationResult
    references: dict[str, NDArray[np.float64]]
    op: TrimResult
    scenario: Scenario
    controller: Controller
    metrics: dict[str, Any] = field(default_factory=dict)


def run_closed_loop(scenario: Scenario, params: Params, controller: Controller | None = None,
                    *, progress: bool = False) -> ClosedLoopResult:
    """Trim the scenario's start and simulate the machine with its controller in the loop.

    Parameters
    ----------
    scenario : Scenario
        A scenario with a ``[controller]`` table.
    params : Params
    controller : Controller, optional
        Replaces the scenario's controller file.
    progress : bool
        A progress bar on stderr.

    Returns
    -------
    ClosedLoopResult
    """
    if scenario.controller is None:
        raise ParameterError(f"scenario {scenario.name!r} has no [controller] table: run it "
                             "with empact.run_scenario")
    ctrl = resolve_controller(scenario.controller.file) if controller is None else controller
    model, op = scenario_model(scenario, params)
    law = LoopLaw(ctrl, scenario, model, op)
    res = run_scenario(scenario, params, controller=law, progress=progress)
    ref_t = {m: _pl(law.references[m], res.t) for m in law.references}
    out = ClosedLoopResult(res, ref_t, op, scenario, ctrl)
    return replace(out, metrics=metrics(out))


def metrics(run: ClosedLoopResult) -> dict[str, Any]:
    """The scenario's figures of merit (SI; slips in percentage points where named ``_pp``).

    * ``slip_error_pp``: largest ``|nu - nu*|`` from 0.3 s after the load step to the end (or
      over the shift window, or over the whole run);
    * ``peak_slip_pp``, ``slip_setpoint_pp``; ``ratio_error``: largest relative ratio error
      ``|r_g - r_ref| / r_ref`` over the same window;
    * ``ratio_rate``: the mean |d r_g / dt| over the shift window [1/s] (NaN when the run
      stopped before it);
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
        if np.count_nonzero(w) >= 2:
            out["ratio_rate"] = float(np.mean(np.abs(np.gradient(r, t))[w]))
            out["ratio_span"] = [float(r[w][0]), float(r[w][-1])]
        else:  # the run stopped before the shift window
            out["ratio_rate"] = float("nan")
            out["ratio_span"] = [float("nan"), float("nan")]
    T_b, w_p, w_s = res.output("T_b"), res.output("omega_p"), res.output("omega_s")
    p_slip = T_b * (r * w_p - w_s)
    p_act = np.abs(res.output("T_mp") * res.output("omega_mp")) \
        + np.abs(res.output("T_ms") * res.output("omega_ms"))
    out["mean_clamping_force"] = float(np.mean(res.output("F_s")))
    out["mean_slip_power"] = float(np.mean(p_slip))
    out["mean_actuation_power"] = float(np.mean(p_act))
    out["mean_losses"] = float(np.mean(p_slip + p_act))
    return out

