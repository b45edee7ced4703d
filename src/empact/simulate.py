"""Time simulation of the nonlinear model: scenarios, the runner, CSV output.

A scenario (TOML) names the model options, the trimmed initial point and piecewise-linear
input signals::

    [scenario]
    name = "shift-and-load-step"
    description = "LOW -> OD shift, then a load step"
    duration = 2.0            # [s]
    sample_rate = 1000.0      # output samples per second [Hz]

    [model]                   # empact.nonlinear.ModelOptions
    drive = "speed"
    ratio_control = true

    [initial]                 # empact.trim.trim: r_g, omega_p and two of nu, F_s, T_l
    r_g = 0.43
    omega_p = 300.0
    F_s = 15000.0
    T_l = 30.0

    [inputs]                  # [[t, value], ...] in SI; a repeated time is a step
    r_g_ref = [[0.2, 0.43], [1.2, 2.25]]
    T_l = [[1.5, 30.0], [1.5, 60.0]]

    [solver]                  # optional
    rtol = 1e-4
    max_step = 0.01           # [s]
    omega_min = 1.0           # stop when omega_p falls to this [rad/s]

Input names are the model's (``T_mp`` or ``r_g_ref``, ``T_ms``, ``T_d`` or ``omega_d_ref``,
``T_l`` or ``omega_l_ref``); ``F_s_ref`` [N] may replace ``T_ms`` and is mapped to the static
servo torque ``T_ms = i_e s F_s_ref / i_c``.  A signal holds its first value before its first
point and its last value after its last point; inputs not given hold their trimmed values.

The integrator is a compiled, L-stable Rosenbrock method with an exact Jacobian
(`empact._rosenbrock`).  It stops - keeping everything computed so far, marked incomplete -
when omega_p reaches ``omega_min`` (the slip of eq. 2 is undefined at a standing primary), the
belt goes slack, a radius leaves the variator's range, or the solver fails.
"""
from __future__ import annotations

import csv
import io
import os
import sys
import time
import tomllib
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any, Mapping

import numpy as np
from numpy.typing import NDArray

from . import _nonlinear_kernel as K
from .nonlinear import INPUT_UNITS, OUTPUT_UNITS, STATE_UNITS, EmpactModel, ModelOptions, \
    nonlinear_model
from .params import ParameterError, Params, read_toml
from .trim import TrimResult, trim

__all__ = ["Scenario", "SimulationResult", "load_scenario", "list_examples", "example_path",
           "simulate", "run_scenario", "write_csv", "state_tolerances"]

_SCENARIO_KEYS = {"scenario": {"name", "description", "duration", "sample_rate"},
                  "model": None, "initial": {"r_g", "omega_p", "nu", "F_s", "T_l"},
                  "inputs": None, "solver": {"rtol", "max_step", "omega_min", "max_steps"}}


@dataclass(frozen=True)
class Scenario:
    """A validated simulation scenario (see the module docstring for the file format).

    Attributes
    ----------
    name, description : str
    duration : float
        End time [s].
    sample_rate : float
        Output samples per second [Hz].
    options : ModelOptions
    initial : dict
        The trim request (keys r_g, omega_p and two of nu, F_s, T_l; SI).
    inputs : dict name -> array, shape (k, 2)
        Piecewise-linear signals ``[[t, value], ...]``.
    rtol : float
        Relative tolerance of the integrator.
    max_step : float
        Largest step [s].
    omega_min : float
        Stop when omega_p falls to this [rad/s].
    max_steps : int
        Give up (incomplete result) after this many integration steps.
    """

    name: str
    description: str
    duration: float
    sample_rate: float
    options: ModelOptions
    initial: Mapping[str, float]
    inputs: Mapping[str, NDArray[np.float64]]
    rtol: float = 1e-4
    max_step: float = 0.01
    omega_min: float = 1.0
    max_steps: int = 2_000_000

    def with_duration(self, duration: float) -> "Scenario":
        """A copy with another end time [s]."""
        from dataclasses import replace
        _number("--duration", duration, 0.0)
        return replace(self, duration=float(duration))


def _number(where: str, value: Any, lo: float, hi: float = np.inf) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not np.isfinite(value) \
            or not lo < value <= hi:
        raise ParameterError(f"{where} = {value!r}: allowed range is ({lo:g}, {hi:g}]")
    return float(value)


def load_scenario(path: str | os.PathLike[str]) -> Scenario:
    """Read and validate a scenario file.

    Raises
    ------
    ParameterError
        One line naming the file, the key, the bad value and what is allowed.
    """
    src = str(path)
    data = read_toml(path, "scenario")
    return scenario_from_dict(data, src)


def scenario_from_dict(data: Mapping[str, Any], src: str = "scenario") -> Scenario:
    """Validate a scenario given as a nested mapping (the parsed TOML)."""
    for key, value in data.items():
        if key not in _SCENARIO_KEYS:
            raise ParameterError(f"{src}: unknown table [{key}] (allowed: "
                                 f"{', '.join(_SCENARIO_KEYS)})")
        if not isinstance(value, Mapping):
            raise ParameterError(f"{src}: {key!r} must be a table")
        allowed = _SCENARIO_KEYS[key]
        for sub in value:
            if allowed is not None and sub not in allowed:
                raise ParameterError(f"{src}: unknown key {key}.{sub} (allowed: "
                                     f"{', '.join(sorted(allowed))})")
    head = data.get("scenario", {})
    if "duration" not in head:
        raise ParameterError(f"{src}: missing scenario.duration [s]")
    duration = _number(f"{src}: scenario.duration", head["duration"], 0.0, 3600.0)
    rate = _number(f"{src}: scenario.sample_rate", head.get("sample_rate", 1000.0), 0.0, 1e6)
    try:
        options = ModelOptions.from_mapping(dict(data.get("model", {})))
    except ParameterError as exc:
        raise ParameterError(f"{src}: [model] {exc}") from None
    initial = dict(data.get("initial", {}))
    for key in ("r_g", "omega_p"):
        if key not in initial:
            raise ParameterError(f"{src}: missing initial.{key}")
    for key, value in initial.items():
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ParameterError(f"{src}: initial.{key} = {value!r}: must be a number")
    model_inputs = _input_names(options)
    inputs: dict[str, NDArray[np.float64]] = {}
    for name, pts in data.get("inputs", {}).items():
        allowed = model_inputs + ("F_s_ref",)
        if name not in allowed:
            raise ParameterError(f"{src}: unknown input {name!r} for this model (allowed: "
                                 f"{', '.join(allowed)})")
        arr = _signal(f"{src}: inputs.{name}", pts, duration)
        inputs[name] = arr
    if "F_s_ref" in inputs and "T_ms" in inputs:
        raise ParameterError(f"{src}: give inputs.T_ms or inputs.F_s_ref, not both")
    solver = data.get("solver", {})
    rtol = _number(f"{src}: solver.rtol", solver.get("rtol", 1e-4), 1e-12, 0.1)
    max_step = _number(f"{src}: solver.max_step", solver.get("max_step", 0.01), 0.0, 1.0)
    omega_min = _number(f"{src}: solver.omega_min", solver.get("omega_min", 1.0), 0.0, 1e4)
    max_steps = int(_number(f"{src}: solver.max_steps", solver.get("max_steps", 2_000_000),
                            0.0, 1e9))
    return Scenario(name=str(head.get("name", Path(src).stem)),
                    description=str(head.get("description", "")), duration=duration,
                    sample_rate=rate, options=options, initial=initial, inputs=inputs,
                    rtol=rtol, max_step=max_step, omega_min=omega_min, max_steps=max_steps)


def _input_names(options: ModelOptions) -> tuple[str, ...]:
    return ("r_g_ref" if options.ratio_control else "T_mp", "T_ms",
            "omega_d_ref" if options.drive == "speed" else "T_d",
            "omega_l_ref" if options.load == "speed" else "T_l")


def _signal(where: str, pts: Any, duration: float) -> NDArray[np.float64]:
    try:
        arr = np.array(pts, dtype=float)
    except (TypeError, ValueError):
        raise ParameterError(f"{where} = {pts!r}: must be a list of [t, value] pairs") from None
    if arr.ndim != 2 or arr.shape[1] != 2 or len(arr) < 1:
        raise ParameterError(f"{where}: must be a non-empty list of [t, value] pairs, got shape "
                             f"{arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ParameterError(f"{where}: every time and value must be finite")
    t = arr[:, 0]
    if t[0] < 0 or np.any(np.diff(t) < 0):
        raise ParameterError(f"{where}: times {t.tolist()} must be >= 0 and non-decreasing [s]")
    if len(t) > 2 and np.any((np.diff(t)[1:] == 0) & (np.diff(t)[:-1] == 0)):
        raise ParameterError(f"{where}: a time may repeat at most once (one step)")
    return arr


@dataclass(frozen=True, eq=False)
class SimulationResult:
    """Sampled time history of a simulation.

    Attributes
    ----------
    t : array, shape (n_t,)
        Sample times [s].
    x : array, shape (n_t, n)
        States (``states``; units in `empact.nonlinear.STATE_UNITS`).
    y : array, shape (n_t, n_y)
        Outputs (``outputs``; units in `empact.nonlinear.OUTPUT_UNITS`).
    u : array, shape (n_t, 4)
        External inputs (``inputs``).
    states, outputs, inputs : tuple of str
    complete : bool
        False when the run stopped early; `message` says why, when, and in which state.
    message : str
    scenario : str
    stats : dict
        ``n_steps``, ``n_rejected``, ``wall_time`` [s], ``t_end`` [s].
    """

    t: NDArray[np.float64]
    x: NDArray[np.float64]
    y: NDArray[np.float64]
    u: NDArray[np.float64]
    states: tuple[str, ...]
    outputs: tuple[str, ...]
    inputs: tuple[str, ...]
    complete: bool
    message: str
    scenario: str = ""
    stats: Mapping[str, float] = field(default_factory=dict)

    def output(self, name: str) -> NDArray[np.float64]:
        """One output (or state, or input) over time, shape (n_t,)."""
        for names, data in ((self.outputs, self.y), (self.states, self.x),
                            (self.inputs, self.u)):
            if name in names:
                return data[:, names.index(name)]
        raise ValueError(f"unknown signal {name!r}: choose from "
                         f"{', '.join(self.outputs + self.states + self.inputs)}")


def state_tolerances(model: EmpactModel, rtol: float) -> tuple[NDArray, NDArray]:
    """Per-state ``(rtol, atol)`` vectors of the integrator.

    Positions are absolute (their offsets are arbitrary), so they get no relative tolerance;
    the absolute tolerances are ``rtol`` times a characteristic size of each state, chosen so
    that the belt stretch (~0.3 mm) and the bearing deflections are resolved.
    """
    scale = {"theta_mp": 0.1, "theta_ms": 0.1, "theta_sp": 0.01, "theta_ss": 0.01,
             "x_p": 1e-6, "x_s": 1e-6, "omega_mp": 1.0, "omega_ms": 1.0, "omega_sp": 0.1,
             "omega_ss": 0.1, "v_p": 1e-4, "v_s": 1e-4, "twist_tc": 1e-3, "twist_ds": 1e-3,
             "omega_d": 1.0, "omega_p": 1.0, "omega_s": 1.0, "omega_l": 1.0, "s_b": 1e-6,
             "z_d": 0.1, "z_l": 0.1, "z_r": 0.01}
    atol = rtol * np.array([scale[s] for s in model.states])
    rel = np.array([0.0 if s in ("theta_mp", "theta_ms", "theta_sp", "theta_ss", "x_p", "x_s")
                    else rtol for s in model.states])
    return rel, atol


def simulate(model: EmpactModel, x0: NDArray, signals: Mapping[str, NDArray],
             duration: float, *, u0: NDArray | None = None, sample_rate: float = 1000.0,
             rtol: float = 1e-4, max_step: float = 0.01, omega_min: float = 1.0,
             max_steps: int = 2_000_000, progress: bool = False,
             name: str = "") -> SimulationResult:
    """Integrate `model` from `x0` over ``[0, duration]``.

    Parameters
    ----------
    model : EmpactModel
    x0 : array, shape (n,)
        Initial state (e.g. ``trim(...).x``).
    signals : dict name -> array, shape (k, 2)
        Piecewise-linear input signals ``[[t, value], ...]`` by model input name.
    duration : float
        End time [s].
    u0 : array, shape (4,), optional
        Values of the inputs without a signal (default zero).
    sample_rate : float
        Output samples per second [Hz].
    rtol : float
        Relative tolerance (see `state_tolerances`).
    max_step : float
        Largest step [s].
    omega_min : float
        Stop when omega_p falls to this [rad/s].
    max_steps : int
        Give up (incomplete result) after this many integration steps.
    progress : bool
        A tqdm progress bar on stderr.

    Returns
    -------
    SimulationResult
    """
    from tqdm import tqdm

    from ._rosenbrock import STATUS, integrate

    x = np.array(x0, dtype=float)
    if x.shape != (model.n,):
        raise ValueError(f"x0 has shape {x.shape}: expected ({model.n},)")
    u0 = np.zeros(4) if u0 is None else np.asarray(u0, float)
    for k in signals:
        if k not in model.inputs:
            raise ValueError(f"unknown input {k!r}: choose from {', '.join(model.inputs)}")
    kmax = max([2] + [len(v) for v in signals.values()])
    sig_t = np.zeros((4, kmax))
    sig_v = np.zeros((4, kmax))
    sig_n = np.ones(4, dtype=np.int64)
    brk = [float(duration)]
    for j, name_j in enumerate(model.inputs):
        if name_j in signals:
            arr = np.asarray(signals[name_j], float)
            sig_n[j] = len(arr)
            sig_t[j, :len(arr)] = arr[:, 0]
            sig_v[j, :len(arr)] = arr[:, 1]
            brk.extend(arr[:, 0].tolist())
        else:
            sig_v[j, 0] = u0[j]
    brk_arr = np.unique(np.array([b for b in brk if 0 < b <= duration]))
    n_t = int(np.floor(duration * sample_rate + 1e-9)) + 1
    samples = np.arange(n_t) / sample_rate
    X = np.full((n_t, model.n), np.nan)
    Y = np.full((n_t, K.NY), np.nan)
    X[0] = x
    y0 = np.empty(K.NY)
    dx = np.empty(model.n)
    u_first = _inputs_at(0.0, sig_t, sig_v, sig_n)
    K._eval(x, u_first, model.p, model.ix, dx, y0)
    Y[0] = y0
    rel, atol = state_tolerances(model, rtol)
    t, h = 0.0, min(1e-5, max_step)
    chunks = np.linspace(0.0, duration, 101)[1:]
    status, n_steps, n_rej, filled = 0, 0, 0, 1
    wall = time.perf_counter()
    with tqdm(total=len(chunks), desc=f"simulate {name}".strip(), unit="%", disable=not progress,
              file=sys.stderr, leave=False) as bar:
        for t_chunk in chunks:
            status, t, h, filled, ns, nr = integrate(
                x, t, float(t_chunk), h, samples, model.p, model.ix, sig_t, sig_v, sig_n,
                brk_arr, rel, atol, 1e-14, max_step, omega_min, max_steps - n_steps, X, Y)
            n_steps += ns
            n_rej += nr
            bar.update(1)
            if status != 0:
                break
    wall = time.perf_counter() - wall
    complete = status == 0
    if complete:
        message = f"completed: {n_steps} steps ({n_rej} rejected), {wall:.2f} s wall time"
    else:
        state = ", ".join(f"{s} = {v:.6g}" for s, v in zip(model.states, x))
        message = (f"stopped at t = {t:.6g} s: {STATUS[status]}; state: {state}")
    keep = slice(0, max(filled, 1))
    tt = samples[keep]
    U = _inputs_at(tt, sig_t, sig_v, sig_n)
    return SimulationResult(t=tt, x=X[keep], y=Y[keep], u=U, states=model.states,
                            outputs=model.outputs, inputs=model.inputs, complete=complete,
                            message=message, scenario=name,
                            stats={"n_steps": n_steps, "n_rejected": n_rej, "wall_time": wall,
                                   "t_end": t})


def _inputs_at(t, sig_t, sig_v, sig_n) -> NDArray[np.float64]:
    """Right-continuous value of every input signal at time(s) `t`.

    A scalar `t` gives shape (n_inputs,); an array of shape (n_t,) gives (n_t, n_inputs).
    """
    tt = np.atleast_1d(np.asarray(t, float))
    u = np.empty((tt.size, len(sig_n)))
    for k, n in enumerate(sig_n):
        ts, vs = sig_t[k, :n], sig_v[k, :n]
        i = np.clip(np.searchsorted(ts, tt, side="right") - 1, 0, max(n - 2, 0))
        j = np.minimum(i + 1, n - 1)
        dt = ts[j] - ts[i]
        frac = np.divide(tt - ts[i], dt, out=np.ones_like(tt), where=dt > 0)
        u[:, k] = np.where(tt < ts[0], vs[0], np.where(
            tt >= ts[-1], vs[-1], vs[i] + (vs[j] - vs[i]) * frac))
    return u[0] if np.ndim(t) == 0 else u


def scenario_model(scenario: Scenario, params: Params) -> tuple[EmpactModel, TrimResult]:
    """The model and the trimmed initial point of a scenario."""
    model = nonlinear_model(params, scenario.options)
    req = dict(scenario.initial)
    r_g, omega_p = req.pop("r_g"), req.pop("omega_p")
    return model, trim(model, r_g, omega_p, **req)


def run_scenario(scenario: Scenario, params: Params, *, progress: bool = False) -> SimulationResult:
    """Trim the scenario's initial point and simulate it (see `simulate`)."""
    model, op = scenario_model(scenario, params)
    signals = dict(scenario.inputs)
    if "F_s_ref" in signals:
        a = params.actuation
        sig = model.p[K.P_SIG]
        arr = np.array(signals.pop("F_s_ref"), float)
        arr[:, 1] = a.i_e * a.s * sig * arr[:, 1] / a.i_c
        signals["T_ms"] = arr
    return simulate(model, op.x, signals, scenario.duration, u0=op.u,
                    sample_rate=scenario.sample_rate, rtol=scenario.rtol,
                    max_step=scenario.max_step, omega_min=scenario.omega_min,
                    max_steps=scenario.max_steps, progress=progress, name=scenario.name)


# -- shipped examples ----------------------------------------------------------------------
def list_examples() -> dict[str, str]:
    """Shipped example scenarios: name -> description."""
    out = {}
    for res in sorted(resources.files("empact.data").joinpath("scenarios").iterdir(),
                      key=lambda r: r.name):
        if res.name.endswith(".toml"):
            data = tomllib.loads(res.read_text())
            out[res.name[:-5]] = data.get("scenario", {}).get("description", "")
    return out


def example_path(name: str) -> Path:
    """Path of a shipped example scenario (`list_examples` names)."""
    names = list_examples()
    if name not in names:
        raise ParameterError(f"example {name!r}: choose from {', '.join(names)}")
    return Path(str(resources.files("empact.data").joinpath("scenarios", f"{name}.toml")))


# -- output ---------------------------------------------------------------------------------
def csv_text(result: SimulationResult, states: bool = False) -> str:
    """CSV of a result: time, outputs, inputs (and states); units in the header."""
    buf = io.StringIO()
    status = "complete" if result.complete else "INCOMPLETE"
    buf.write(f"# empact simulation {result.scenario!r}: {status}: {result.message}\n")
    w = csv.writer(buf, lineterminator="\n")
    cols = ["t [s]"] + [f"{o} [{OUTPUT_UNITS[o]}]" for o in result.outputs] \
        + [f"{i} [{INPUT_UNITS[i]}] (input)" for i in result.inputs]
    data = [result.t[:, None], result.y, result.u]
    if states:
        cols += [f"{s} [{STATE_UNITS[s]}] (state)" for s in result.states]
        data.append(result.x)
    w.writerow(cols)
    for row in np.hstack(data):
        w.writerow([f"{v:.10g}" for v in row])
    return buf.getvalue()


def write_csv(result: SimulationResult, path: str | os.PathLike[str], states: bool = False) -> Path:
    """Write `csv_text` to `path` atomically (temporary file, then rename)."""
    from .params import atomic_write_text

    atomic_write_text(path, csv_text(result, states))
    return Path(path)
