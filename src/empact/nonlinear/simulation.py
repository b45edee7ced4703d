"""Time simulation of the nonlinear model: the runner, its result, CSV output.

`simulate` integrates an `~empact.nonlinear.model.EmpactModel` from a state under
piecewise-linear input signals; `run_scenario` trims a scenario's initial point
(`empact.nonlinear.scenario`) and simulates it.

The integrator is a compiled, L-stable Rosenbrock method with an exact Jacobian: by
default the order-4 Rodas4 of `empact.nonlinear._rodas` (``method="rodas4"``), or the
order-5 Rodas5P (``"rodas5p"``) or the order-2 ode23s tableau of the same driver
(``"ros2"``, the default up to 0.1); see `METHODS`.  It stops - keeping everything computed
so far, marked incomplete - when omega_p reaches ``omega_min`` (the slip of eq. 2 is undefined
at a standing primary), the belt goes slack, a radius leaves the variator's range, or the solver
fails.
"""
from __future__ import annotations

import csv
import io
import os
import time
from dataclasses import dataclass, field, fields, replace
from pathlib import Path
from typing import Any, Mapping, NamedTuple, Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray

from .._io import atomic_write_text
from .._lazy import lazy_module
from .._progress import progress as progress_bar
from .._results import frame, plain
from .._validate import check_choice, check_number
from ..errors import ParameterError
from ..params import Params
from . import _kernel as K
from . import _rodas
from ._rodas import integrate_ros2 as integrate
from ._rosenbrock import STATUS
from .equilibrium import TrimResult, trim
from .model import INPUT_UNITS, OUTPUT_UNITS, STATE_UNITS, EmpactModel, nonlinear_model
from .options import ModelOptions
from .scenario import DEFAULT_METHOD, METHODS, Scenario

__all__ = ["SimulationResult", "SampledController", "CompiledSampledController", "SampledLoop",
           "Stepper", "simulate", "run_scenario", "energy_balance",
           "scenario_model", "scenario_options", "scenario_signals", "csv_text", "write_csv",
           "state_tolerances", "STATUS", "METHODS", "DEFAULT_METHOD"]


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
    energy_integrals : dict
        The integrals over the run, ``[0, stats["t_end"]]``, of the energy rates
        `empact.nonlinear._kernel.ENERGY_RATES` by name [J], taken by the integrator on its
        own steps, and the stored energy at the start and at ``t_end``, ``E_start`` and
        ``E_end`` [J] (`energy_balance`); empty for a result that no integrator made.
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
    energy_integrals: Mapping[str, float] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        """The run as plain JSON types (SI; the result contract of `empact._results`):
        ``t``, ``x``, ``y``, ``u`` as nested lists (shapes as the fields), the names,
        ``complete``, ``message``, ``scenario`` and ``stats``; NaN as None.

        Returns
        -------
        dict
            Field name -> value, ready for ``json.dumps(..., allow_nan=False)``.
        """
        return plain({f.name: getattr(self, f.name) for f in fields(self)})

    def to_pandas(self) -> Any:
        """The run as a table: a pandas.DataFrame with ``t`` [s], then every output and
        every input (SI, the model's names; pandas is optional).

        Returns
        -------
        pandas.DataFrame
            One row per sample time, one column per signal.

        Raises
        ------
        ImportError
            Where pandas is not installed.
        """
        columns = {"t": self.t, **{n: self.y[:, k] for k, n in enumerate(self.outputs)},
                   **{n: self.u[:, k] for k, n in enumerate(self.inputs)
                      if n not in self.outputs}}
        return frame(columns, "SimulationResult")

    def output(self, name: str) -> NDArray[np.float64]:
        """One output (or state, or input) over time, shape (n_t,).

        Parameters
        ----------
        name : str
            An output, state or input name of the run.
        """
        for names, data in ((self.outputs, self.y), (self.states, self.x),
                            (self.inputs, self.u)):
            if name in names:
                return data[:, names.index(name)]
        raise ValueError(f"unknown signal {name!r}: choose from "
                         f"{', '.join(self.outputs + self.states + self.inputs)}")

    def energy_balance(self) -> dict[str, Any]:
        """Where the run's energy went (`energy_balance`).

        Returns
        -------
        dict
            ``energy`` (energies by term [J]) and ``energy_balance_residual`` [-].
        """
        return energy_balance(self)


#: scipy.integrate, imported on first use (`energy_balance`)
_integrate = lazy_module("scipy.integrate")

#: the power outputs [W] whose integrals `energy_balance` reports, by energy name
_POWERS = {"drive": ("T_d_act", "omega_d"), "load": ("T_l_act", "omega_l"),
           "servo_mechanical_primary": ("T_mp_act", "omega_mp"),
           "servo_mechanical_secondary": ("T_ms_act", "omega_ms")}


def _integral(t: NDArray[np.float64], f: NDArray[np.float64]) -> float:
    """``int f dt`` over the samples `t` (uniform): composite Simpson on the even part, the
    last interval (an odd count) by the cubic through the last four samples."""
    return float(_integrate.simpson(f, x=t)) if len(t) > 2 else float(np.trapezoid(f, t))


def energy_balance(result: SimulationResult) -> dict[str, Any]:
    """The energy balance of a run: input = output + losses + change of stored energy.

    The powers are the integrator's integrals over its own steps
    (`SimulationResult.energy_integrals`: Simpson's rule on each step, its midpoint from the
    dense output, no step across an input breakpoint or a held command's change), and the
    stored energy ``E`` (kinetic and elastic) is read at the start and at the end of the
    integration.
    ``P_in - P_diss = dE/dt`` holds at every instant (the kernel's outputs), so the residual
    is the integration's error along the computed trajectory: it falls with the
    integrator's tolerance (about 10x ``rtol`` or below on the shipped scenarios; the
    output grid no longer limits it: Simpson's rule on the 1 kHz samples integrated a step
    between samples at first order, a floor of 1e-5-5e-5).  A result without those
    integrals (made by hand) is integrated on its output samples by the composite Simpson
    rule (`scipy.integrate.simpson`), and ``quadrature`` says which.

    Parameters
    ----------
    result : SimulationResult
        A run (complete or not: the balance of what was computed).

    Returns
    -------
    dict
        ``energy``: energies [J] by term: ``input`` (drive and both servos' mechanical
        energy), ``drive``, ``servo_mechanical_primary``, ``servo_mechanical_secondary``,
        ``output`` (what the load motor absorbs), each of `DISSIPATION_TERMS` (the
        variator's losses, ``P_creep``, the actuation's damping), ``losses`` (their sum),
        ``stored_change``; ``energy_balance_residual`` [-]: ``(input - output - losses -
        stored_change) / input``; ``quadrature``: ``"integrator steps"`` or ``"output
        samples"``.  (The servos' electrical energy is not part of this mechanical balance:
        `empact.efficiency.energy_summary` adds it as ``servo_electrical``.)
    """
    q = result.energy_integrals
    energy: dict[str, float] = {}
    if q:
        energy.update({name: float(q[name]) for name in _POWERS})
        energy.update({name: float(q[name]) for name in K.DISSIPATION_TERMS})
        stored = float(q["E_end"] - q["E_start"])
    else:
        t = result.t
        for name, (torque, speed) in _POWERS.items():
            energy[name] = _integral(t, result.output(torque) * result.output(speed))
        for name in K.DISSIPATION_TERMS:
            energy[name] = _integral(t, result.output(name))
        E = result.output("E")
        stored = float(E[-1] - E[0])
    energy["input"] = (energy["drive"] + energy["servo_mechanical_primary"]
                       + energy["servo_mechanical_secondary"])
    energy["output"] = energy.pop("load")
    energy["losses"] = sum(energy[name] for name in K.DISSIPATION_TERMS)
    energy["stored_change"] = stored
    balance = energy["input"] - energy["output"] - energy["losses"] - energy["stored_change"]
    scale = abs(energy["input"]) if energy["input"] != 0.0 else 1.0
    return {"energy": energy, "energy_balance_residual": balance / scale,
            "quadrature": "integrator steps" if q else "output samples"}


def state_tolerances(model: EmpactModel, rtol: float) -> tuple[NDArray, NDArray]:
    """Per-state ``(rtol, atol)`` vectors of the integrator.

    Positions are absolute (their offsets are arbitrary), so they get no relative tolerance;
    the absolute tolerances are ``rtol`` times a characteristic size of each state, chosen so
    that the belt stretch (~0.3 mm) and the bearing deflections are resolved.

    Parameters
    ----------
    model : EmpactModel
        The model whose states (``model.states``) the tolerances are for.
    rtol : float
        The integrator's relative tolerance [-].

    Returns
    -------
    rtol, atol : ndarray, shape (n,)
        Relative tolerances [-] (0 for the angles and sheave positions) and absolute
        tolerances, in each state's unit (`empact.nonlinear.STATE_UNITS`), ordered as
        ``model.states``.
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


@runtime_checkable
class SampledController(Protocol):
    """What `simulate` needs of a controller in the loop (the step interface).

    Attributes
    ----------
    dt : float
        Sample period [s]; the commands are held over each period (zero-order hold).
    measured : tuple of str
        The signals it reads at each sample, by name: the model's outputs, states or inputs
        (an input's value at the sample time).
    commands : tuple of str
        The model inputs it drives, by name (the others follow their signals).

    Methods
    -------
    step(t, measured) -> commands
        At sample time `t` [s] with the measured values (array in the order of `measured`),
        the command values (array in the order of `commands`) held over ``[t, t + dt)``.
    """

    dt: float
    measured: tuple[str, ...]
    commands: tuple[str, ...]

    def step(self, t: float, measured: NDArray[np.float64]) -> NDArray[np.float64]:
        """Commands over ``[t, t + dt)`` from the measurements at `t`.

        Parameters
        ----------
        t : float
            The sample time [s].
        measured : ndarray, shape (len(measured),)
            The measured values at `t`, in the order of `measured` (SI).
        """


class SampledLoop(NamedTuple):
    """What a compiled sampled loop (`CompiledSampledController.run_compiled`) needs of the
    simulator: its arrays (written in place) and the integrator's arguments.

    Attributes
    ----------
    x, u : ndarray, shape (n,), (4,)
        The state and the inputs (both updated in place).
    U_free : ndarray, shape (n_k + 1, n_free)
        The inputs the controller does not drive, on the sample grid.
    t_grid : ndarray, shape (n_k + 1,)
        The sample times [s].
    out_idx, cmd_idx, free_idx : ndarray of int
        The outputs the controller measures, the inputs it drives, the others.
    commands : ndarray, shape (n_k, n_cmd)
        The commands of each sample (written).
    dx, y, meas : ndarray
        Work arrays: the derivatives, the outputs, the measurements.
    tableau : tuple
        The Rosenbrock method's tableau as `empact.nonlinear._rodas._run` takes it
        (`_rodas.TABLEAUX`).
    samples : ndarray
        The output sample times [s].
    p, ix : ndarray
        The model's parameter vector and state layout (`EmpactModel.p`, ``ix``).
    sig_t, sig_v, sig_n, brk : ndarray
        The input signals (`_signal_table`) and their breakpoints.
    rtol, atol : ndarray, shape (n,)
        Per-state tolerances (`state_tolerances`).
    hmax, omega_min : float
        Largest step [s]; the primary speed that stops the run [rad/s].
    max_steps : int
        The integrator's step budget.
    X, Y, cols, J : ndarray
        The output states and outputs (written), the Jacobian's varying columns and its
        work array.
    Q : ndarray, shape (len(ENERGY_RATES),)
        The energy rates' integrals, accumulated by the integrator (`simulate`).
    """

    x: NDArray[np.float64]
    u: NDArray[np.float64]
    U_free: NDArray[np.float64]
    t_grid: NDArray[np.float64]
    out_idx: NDArray[np.intp]
    cmd_idx: NDArray[np.intp]
    free_idx: NDArray[np.intp]
    commands: NDArray[np.float64]
    dx: NDArray[np.float64]
    y: NDArray[np.float64]
    meas: NDArray[np.float64]
    tableau: tuple[Any, ...]
    samples: NDArray[np.float64]
    p: NDArray[np.float64]
    ix: NDArray[np.int64]
    sig_t: NDArray[np.float64]
    sig_v: NDArray[np.float64]
    sig_n: NDArray[np.int64]
    brk: NDArray[np.float64]
    rtol: NDArray[np.float64]
    atol: NDArray[np.float64]
    hmax: float
    omega_min: float
    max_steps: int
    X: NDArray[np.float64]
    Y: NDArray[np.float64]
    cols: NDArray[Any]
    J: NDArray[np.float64]
    Q: NDArray[np.float64]


@runtime_checkable
class CompiledSampledController(SampledController, Protocol):
    """A `SampledController` that can also run a stretch of samples with the integrator in
    one compiled loop (bitwise what its `step` between the integrator's calls gives);
    `simulate` uses it when `compiled` and the method is a Rodas method
    (`empact.control.law.LoopLaw`).

    Attributes
    ----------
    compiled : bool
        Whether `run_compiled` may be called.

    Methods
    -------
    run_compiled(k0, k1, loop, t, h, filled, n_steps, n_rej) -> tuple
        Samples `k0` to ``k1 - 1`` (`SampledLoop` `loop`; from time `t` [s], step `h` [s],
        `filled` output samples, `n_steps` and `n_rej` steps taken and rejected): the
        tuple ``(status, t, h, filled, n_steps, n_rej, k)``: the integrator's status after
        sample `k`, the last one run.
    """

    compiled: bool

    def run_compiled(self, k0: int, k1: int, loop: SampledLoop, t: float, h: float,
                     filled: int, n_steps: int, n_rej: int) -> tuple[int, float, float, int,
                                                                     int, int, int]:
        """Samples `k0` to ``k1 - 1`` with the integrator in one compiled loop.

        Parameters
        ----------
        k0, k1 : int
            Sample range ``[k0, k1)`` to run.
        loop : SampledLoop
            What `simulate` hands over (signals, outputs, the integrator's settings).
        t, h : float
            Where the integration stands: time [s] and next step size [s].
        filled, n_steps, n_rej : int
            Counters carried across calls (rows written, steps accepted, steps rejected).

        Returns
        -------
        tuple
            The counters and the time after the range, with the integrator's status and
            the last sample run: ``(status, t, h, filled, n_steps, n_rej, k)``.
        """


class Stepper:
    """The simulator stepped from one communication point to the next with the inputs held
    over each step (zero-order hold): what a co-simulation unit's step does
    (`empact.fmu`).

    The integrator continues across the points as in the sampled loop of `simulate`: the
    state, the proposed step size and the Jacobian carry over, only the varying columns of
    the Jacobian are re-evaluated after the first call, and every call ends on its point.
    So a run of steps ``t_0 < t_1 < ...`` is bitwise `simulate` with a sampled controller
    of that period (the inputs it does not drive with their breakpoints on the points).

    Parameters
    ----------
    model : EmpactModel
        The model stepped.
    x0 : ndarray, shape (n,)
        The initial state (e.g. ``trim(...).x``).
    u0 : ndarray, shape (4,)
        The initial inputs (``model.inputs``; SI); `u` holds them, the caller changes it
        between steps.
    t0 : float
        The initial time [s].
    rtol, max_step, omega_min, max_steps, method
        As `simulate`'s.

    Attributes
    ----------
    x : ndarray, shape (n,)
        The state at `t` (updated in place).
    u : ndarray, shape (4,)
        The inputs held over the next step (set them before `advance`).
    t : float
        The time [s] the integration stands at.
    message : str
        Why the last `advance` stopped (empty while the run goes on).
    """

    def __init__(self, model: EmpactModel, x0: NDArray, u0: NDArray, *, t0: float = 0.0,
                 rtol: float = 1e-4, max_step: float = 0.01, omega_min: float = 1.0,
                 max_steps: int = 2_000_000, method: str = DEFAULT_METHOD) -> None:
        self.model = model
        self._step = _integrator(method)
        self.x = np.array(x0, dtype=float)
        if self.x.shape != (model.n,):
            raise ValueError(f"x0 has shape {self.x.shape}: expected ({model.n},)")
        self.u = np.array(u0, dtype=float)
        if self.u.shape != (4,):
            raise ValueError(f"u0 has shape {self.u.shape}: expected (4,)")
        self.t = float(t0)
        self.max_step = float(max_step)
        self.h = min(1e-5, self.max_step)
        self.omega_min = float(omega_min)
        self.max_steps = int(max_steps)
        self.n_steps = 0
        self.n_rejected = 0
        self.message = ""
        self._rel, self._atol = state_tolerances(model, rtol)
        self._cols = K.varying_columns(model.ix, model.p)
        self.J = np.zeros((model.n, model.n))
        self._full = True
        self._sig_t = np.zeros((4, 2))
        self._sig_v = np.zeros((4, 2))
        self._sig_n = np.ones(4, dtype=np.int64)
        self._none = np.empty(0)
        self._X = np.empty((0, model.n))
        self._Y = np.empty((0, len(model.outputs)))
        self._dx = np.empty(model.n)

    def outputs(self) -> NDArray[np.float64]:
        """The model's outputs at `x` under the inputs `u`.

        Returns
        -------
        ndarray, shape (len(model.outputs),)
            The outputs (`empact.nonlinear.OUTPUT_UNITS`).
        """
        y = np.empty(len(self.model.outputs))
        K._eval(self.x, self.u, self.model.p, self.model.ix, self._dx, y)
        return y

    def advance(self, t_end: float) -> int:
        """Integrate to `t_end` with the inputs `u` held.

        Parameters
        ----------
        t_end : float
            The next communication point [s] (at or after `t`).

        Returns
        -------
        int
            The integrator's status (`STATUS`: 0 reached `t_end`; otherwise the run stopped
            at `t`, `message` says why).
        """
        if t_end < self.t:
            raise ValueError(f"t_end = {t_end:g} s: before the current time {self.t:g} s")
        self._sig_v[:, 0] = self.u
        status, t, h, _, ns, nr = self._step(
            self.x, self.t, float(t_end), self.h, self._none, self.model.p, self.model.ix,
            self._sig_t, self._sig_v, self._sig_n, self._none, self._rel, self._atol, 1e-14,
            self.max_step, self.omega_min, self.max_steps - self.n_steps, self._X, self._Y,
            self._cols, self.J, self._full, self._none)
        self._full = False
        self.t, self.h = float(t), float(h)
        self.n_steps += ns
        self.n_rejected += nr
        if status != 0:
            state = ", ".join(f"{s} = {v:.6g}" for s, v in zip(self.model.states, self.x))
            self.message = f"stopped at t = {self.t:.6g} s: {STATUS[status]}; state: {state}"
        return int(status)

    def snapshot(self) -> dict[str, Any]:
        """Everything `advance` continues from, as plain JSON types (floats round-trip
        exactly through JSON).

        Returns
        -------
        dict
            ``x``, ``u``, ``J`` (lists), ``t``, ``h`` [s], the step counters and whether the
            next call evaluates the whole Jacobian.
        """
        return {"x": self.x.tolist(), "u": self.u.tolist(), "J": self.J.tolist(),
                "t": self.t, "h": self.h, "n_steps": self.n_steps,
                "n_rejected": self.n_rejected, "full": self._full, "message": self.message}

    def restore(self, snap: Mapping[str, Any]) -> None:
        """Back to a `snapshot`.

        Parameters
        ----------
        snap : mapping
            What `snapshot` returned (of a stepper of the same model).
        """
        self.x[:] = snap["x"]
        self.u[:] = snap["u"]
        self.J[:] = np.asarray(snap["J"], float)
        self.t, self.h = float(snap["t"]), float(snap["h"])
        self.n_steps, self.n_rejected = int(snap["n_steps"]), int(snap["n_rejected"])
        self._full, self.message = bool(snap["full"]), str(snap["message"])


def _signal_table(model: EmpactModel, signals: Mapping[str, NDArray], u0: NDArray,
                  duration: float):
    """The piecewise-linear inputs as the compiled integrator takes them: per input the times,
    the values and the number of points (``sig_t``, ``sig_v``, ``sig_n``), and the sorted
    breakpoints in (0, duration]."""
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
    return sig_t, sig_v, sig_n, brk_arr


def simulate(model: EmpactModel, x0: NDArray, signals: Mapping[str, NDArray],
             duration: float, *, u0: NDArray | None = None,
             controller: SampledController | None = None, sample_rate: float = 1000.0,
             rtol: float = 1e-4, max_step: float = 0.01, omega_min: float = 1.0,
             max_steps: int = 2_000_000, method: str = DEFAULT_METHOD,
             progress: bool = False,
             name: str = "") -> SimulationResult:
    """Integrate `model` from `x0` over ``[0, duration]``, open loop or with a sampled
    controller in the loop.

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
        Values of the inputs without a signal (default zero); the controller's commands
        start from them.
    controller : SampledController, optional
        Runs at its own sample period inside the integration: at each sample time it reads
        its measured signals and sets its commanded inputs, held until the next sample.
    sample_rate : float
        Output samples per second [Hz].
    rtol : float
        Relative tolerance (see `state_tolerances`).
    max_step : float
        Largest integration step [s].
    omega_min : float
        The run stops when omega_p falls to this [rad/s] (slip undefined).
    max_steps : int
        Give up (incomplete result) after this many integration steps.
    method : {"rodas4", "rodas5p", "ros2"}
        The integrator (`METHODS`): Rodas4 (order 4, the default), Rodas5P (order 5, dense
        output of order 4) or the order-2 Rosenbrock method (ode23s); the same tolerances,
        stops and outputs (``bench/RESULTS.md``: which is faster where, at equal accuracy).
    progress : bool
        A progress bar on stderr (`empact._progress`).

    Returns
    -------
    SimulationResult
        ``u`` holds the inputs as applied (commands with their hold).

    Examples
    --------
    A step of 0.5 N m on the secondary servo torque at 0.1 s, from a trimmed point:

    >>> import numpy as np
    >>> import empact
    >>> params = empact.load_params()
    >>> m = empact.nonlinear_model(params)
    >>> op = empact.trim(m, empact.OperatingPoint(r_g=1.0, tau=0.9, F_s=10e3, omega_p=300.0))
    >>> T = op.u[1]
    >>> steps = {"T_ms": np.array([[0, T], [0.1, T], [0.1001, T + 0.5], [0.5, T + 0.5]])}
    >>> res = empact.simulate(m, op.x, steps, 0.5, u0=op.u)
    >>> res.complete, res.t.shape                      # 1 kHz samples
    (True, (501,))
    >>> res.output("nu")[[0, -1]].round(4)             # the slip [-] before and after
    array([0.0144, 0.0244])
    """
    step = _integrator(method)
    x = np.array(x0, dtype=float)
    if x.shape != (model.n,):
        raise ValueError(f"x0 has shape {x.shape}: expected ({model.n},)")
    u0 = np.zeros(4) if u0 is None else np.asarray(u0, float)
    sig_t, sig_v, sig_n, brk_arr = _signal_table(model, signals, u0, duration)
    n_t = int(np.floor(duration * sample_rate + 1e-9)) + 1
    samples = np.arange(n_t) / sample_rate
    # rows past the last filled one are never returned: not written before the run (a NaN
    # fill of 2400 s at 2000 Hz, 4.8 million rows, took 6 s before the first step)
    X = np.empty((n_t, model.n))
    Y = np.empty((n_t, len(model.outputs)))
    X[0] = x
    y = np.empty(len(model.outputs))
    dx = np.empty(model.n)
    rel, atol = state_tolerances(model, rtol)
    cols = K.varying_columns(model.ix, model.p)
    J = np.empty((model.n, model.n))
    Q = np.zeros(len(K.ENERGY_RATES))  # the energy rates' integrals (`energy_balance`)
    t, h = 0.0, min(1e-5, max_step)
    status, n_steps, n_rej, filled = 0, 0, 0, 1
    wall = time.perf_counter()
    if controller is None:
        K._eval(x, _inputs_at(0.0, sig_t, sig_v, sig_n), model.p, model.ix, dx, y)
        Y[0] = y
        # calls of the integrator (progress-bar ticks): every call ends on a step, so no
        # shorter than 20 largest steps, at most 100; the same with and without a bar
        n_chunks = int(min(100, max(1, np.ceil(duration / (20.0 * max_step) - 1e-9))))
        chunks = np.linspace(0.0, duration, n_chunks + 1)[1:]
        with progress_bar(total=100, desc=f"simulate {name}".strip(), unit="%",
                          enabled=progress) as bar:
            for k, t_chunk in enumerate(chunks):
                status, t, h, filled, ns, nr = step(
                    x, t, float(t_chunk), h, samples, model.p, model.ix, sig_t, sig_v, sig_n,
                    brk_arr, rel, atol, 1e-14, max_step, omega_min, max_steps - n_steps, X, Y,
                    cols, J, k == 0, Q)
                n_steps += ns
                n_rej += nr
                bar.update(100 * (k + 1) // n_chunks - 100 * k // n_chunks)
                if status != 0:
                    break
        U = _inputs_at(samples[:max(filled, 1)], sig_t, sig_v, sig_n)
    else:
        status, t, filled, n_steps, n_rej, U = _run_sampled(
            model, controller, x, u0, duration, samples, sig_t, sig_v, sig_n, brk_arr, rel,
            atol, max_step, omega_min, max_steps, X, Y, cols, J, progress, name, step, Q)
    wall = time.perf_counter() - wall
    complete = status == 0
    if complete:
        message = f"completed: {n_steps} steps ({n_rej} rejected)"  # wall time: stats
    else:
        state = ", ".join(f"{s} = {v:.6g}" for s, v in zip(model.states, x))
        message = (f"stopped at t = {t:.6g} s: {STATUS[status]}; state: {state}")
    keep = slice(0, max(filled, 1))
    E_start = float(Y[0, K.Y_EN])
    K._eval(x, U[0], model.p, model.ix, dx, y)  # the stored energy where the run ended
    integrals = {**dict(zip(K.ENERGY_RATES, Q.tolist())), "E_start": E_start,
                 "E_end": float(y[K.Y_EN])}
    return SimulationResult(t=samples[keep], x=X[keep], y=Y[keep], u=U[keep],
                            states=model.states, outputs=model.outputs, inputs=model.inputs,
                            complete=complete, message=message, scenario=name,
                            energy_integrals=integrals,
                            stats={"n_steps": n_steps, "n_rejected": n_rej, "wall_time": wall,
                                   "t_end": t, "method": method})


def _integrator(method: str):
    """The compiled integrator of `method` (`METHODS`); a one-line error for another name."""
    check_choice("method", method, METHODS)
    if method == "ros2":
        return integrate  # looked up here, so that a benchmark may swap the module's
    return _rodas.METHODS[method]


def _measurement(model: EmpactModel, names: tuple[str, ...]):
    """Where each measured signal lives: (0, output index), (1, state index) or (2, input
    index)."""
    where = []
    for m in names:
        if m in model.outputs:
            where.append((0, model.outputs.index(m)))
        elif m in model.states:
            where.append((1, model.states.index(m)))
        elif m in model.inputs:
            where.append((2, model.inputs.index(m)))
        else:
            raise ParameterError(f"the controller measures {m!r}: not an output, state or "
                                 f"input of the model (outputs: {', '.join(model.outputs)})")
    return where


def _run_sampled(model, controller, x, u0, duration, samples, sig_t, sig_v, sig_n, brk_arr,
                 rel, atol, max_step, omega_min, max_steps, X, Y, cols, J, progress, name,
                 step=None, Q=None):
    """The loop of `simulate` with a sampled controller: at every sample ``t_k = k dt`` the
    controller reads its signals (outputs and states at ``x(t_k)``, inputs at ``t_k``) and
    sets its commands, held by giving the integrator a constant signal for each commanded
    input up to ``t_(k+1)``.  The inputs the controller does not drive are evaluated on the
    sample grid once, before the loop."""
    step = integrate if step is None else step
    Q = np.empty(0) if Q is None else Q
    dt = float(check_number("controller dt", controller.dt, 0.0, duration, lo_open=True,
                            unit="s"))
    cmd_list = [model.input_index(c) for c in controller.commands]
    free_list = [j for j in range(4) if j not in cmd_list]
    cmd = _as_index(cmd_list)  # a slice where the indices run on (indexing with a list costs
    free = _as_index(free_list)  # ~1-2 us a sample)
    where = _measurement(model, tuple(controller.measured))
    n_k = int(round(duration / dt))
    t_grid = np.minimum(np.arange(n_k + 1) * dt, duration)
    U_free = _inputs_at(t_grid, sig_t, sig_v, sig_n)[:, free]  # right-continuous
    t_list = t_grid.tolist()
    commands = np.empty((n_k, len(cmd_list)))
    u = np.array(u0, float)
    y = np.empty(len(model.outputs))
    dx = np.empty(model.n)
    meas = np.empty(len(where))
    # all of them outputs (the loop law's): one indexing per sample
    out_idx = np.array([j for _, j in where]) if all(kind == 0 for kind, _ in where) else None
    for j in cmd_list:
        sig_n[j] = 1
    t, h = 0.0, min(1e-5, max_step)
    status, n_steps, n_rej, filled, k = 0, 0, 0, 1, 0
    every = max(1, n_k // 100)
    # a controller whose sample is compiled runs with the integrator in one compiled loop
    # (`CompiledSampledController.run_compiled`), `every` samples a call (the progress bar
    # and Ctrl-C between calls): bitwise this loop's result, without its Python per sample
    tableau = _rodas.TABLEAUX.get(step)
    fast = (isinstance(controller, CompiledSampledController) and controller.compiled
            and tableau is not None and out_idx is not None)
    with progress_bar(total=n_k, desc=f"simulate {name}".strip(), unit="samples",
                      enabled=progress) as bar:
        if fast:
            loop = SampledLoop(
                x=x, u=u, U_free=np.ascontiguousarray(U_free), t_grid=t_grid, out_idx=out_idx,
                cmd_idx=np.array(cmd_list, dtype=np.intp),
                free_idx=np.array(free_list, dtype=np.intp), commands=commands, dx=dx, y=y,
                meas=np.empty(out_idx.size), tableau=tableau, samples=samples, p=model.p,
                ix=model.ix, sig_t=sig_t, sig_v=sig_v, sig_n=sig_n, brk=brk_arr, rtol=rel,
                atol=atol, hmax=float(max_step), omega_min=float(omega_min),
                max_steps=int(max_steps), X=X, Y=Y, cols=cols, J=J, Q=Q)
            for k0 in range(0, n_k, every):
                k1 = min(k0 + every, n_k)
                status, t, h, filled, n_steps, n_rej, k = controller.run_compiled(
                    k0, k1, loop, t, h, filled, n_steps, n_rej)
                bar.update(k1 - k0)
                if status != 0:
                    break
        else:
            for k in range(n_k):
                u[free] = U_free[k]
                K._eval(x, u, model.p, model.ix, dx, y)
                if k == 0:
                    Y[0] = y
                if out_idx is not None:
                    meas = y[out_idx]
                else:
                    for i, (kind, j) in enumerate(where):
                        meas[i] = y[j] if kind == 0 else (x[j] if kind == 1 else u[j])
                c = np.asarray(controller.step(t_list[k], meas), float)
                commands[k] = c
                u[cmd] = c
                sig_v[cmd, 0] = c
                status, t, h, filled, ns, nr = step(
                    x, t, t_list[k + 1], h, samples, model.p, model.ix, sig_t, sig_v,
                    sig_n, brk_arr, rel, atol, 1e-14, max_step, omega_min, max_steps - n_steps,
                    X, Y, cols, J, k == 0, Q)
                n_steps += ns
                n_rej += nr
                if (k + 1) % every == 0:
                    bar.update(every)
                if status != 0:
                    break
    # the applied inputs at the output samples: the free ones from their signals, the
    # commands of the period (t_k, t_(k+1)] that ends at or after each sample (u0 at t = 0)
    n_out = max(filled, 1)
    U = _inputs_at(samples[:n_out], sig_t, sig_v, sig_n)
    idx = np.clip(np.ceil(samples[:n_out] / dt - 1e-9).astype(int) - 1, 0, max(k, 0))
    U[:, cmd] = commands[idx]
    U[0, cmd] = u0[cmd]
    return status, t, filled, n_steps, n_rej, U


def _as_index(idx: list[int]) -> slice | NDArray[np.intp]:
    """`idx` as a slice when it is a run of consecutive indices, else as an index array."""
    if idx and idx == list(range(idx[0], idx[-1] + 1)):
        return slice(idx[0], idx[-1] + 1)
    return np.array(idx, dtype=np.intp)


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
    """The model and the trimmed initial point of a scenario (``nu_r`` refers to the initial
    point's ratio).

    Parameters
    ----------
    scenario : Scenario
        The scenario (its model options and initial point).
    params : Params
        The parameter set of the model.

    Returns
    -------
    model : EmpactModel
        The nonlinear model under the scenario's options (``reference_ratio`` the initial
        ratio unless the options set one).
    op : TrimResult
        The trimmed initial point.

    Raises
    ------
    TrimError
        When the initial point cannot be trimmed.
    """
    model = nonlinear_model(params, scenario_options(scenario))
    return model, trim(model, scenario.initial)


def scenario_options(scenario: Scenario) -> ModelOptions:
    """The model options of a scenario (`scenario_model`'s): its own, with
    ``reference_ratio`` the initial ratio unless they set one.

    Parameters
    ----------
    scenario : Scenario
        The scenario.

    Returns
    -------
    ModelOptions
    """
    return replace(scenario.options, reference_ratio=scenario.options.reference_ratio
                   if scenario.options.reference_ratio is not None
                   else scenario.initial.r_g)


def scenario_signals(scenario: Scenario, model: EmpactModel,
                     op: TrimResult) -> dict[str, NDArray[np.float64]]:
    """The scenario's input signals for `simulate`: ``F_s_ref`` mapped to the static servo
    torque ``T_ms = i_e s F_s_ref / i_c`` (with the sense of q6), offsets added to the
    trimmed inputs, and a ``load_step`` (a fraction of the torque capacity ``T_l / tau`` at
    the trimmed start) as a step of ``T_l`` at ``load_step_time``.

    Parameters
    ----------
    scenario : Scenario
        The scenario (its inputs, offsets and load step).
    model : EmpactModel
        The model it runs on (`scenario_model`).
    op : TrimResult
        The trimmed initial point (its inputs ``u``, load torque and torque ratio).

    Returns
    -------
    dict of str to ndarray
        Model input name -> piecewise-linear signal ``[[t, value], ...]``, shape (k, 2),
        times [s] and values in SI.

    Raises
    ------
    ParameterError
        When a ``load_step`` is asked for from an unloaded start.
    """
    signals = dict(scenario.inputs)
    if scenario.load_step is not None:
        T_l0, t0 = op.T_l, scenario.load_step_time
        capacity = T_l0 / op.tau if op.tau else 0.0
        if not capacity:
            raise ParameterError(f"scenario {scenario.name!r}: load_step needs a loaded start "
                                 f"(T_l = {T_l0:g} N m: no torque capacity in use)")
        signals["T_l"] = np.array([[t0, T_l0], [t0, T_l0 + scenario.load_step * capacity]])
    if "F_s_ref" in signals:
        a = model.params.actuation
        arr = np.array(signals.pop("F_s_ref"), float)
        arr[:, 1] = a.i_e * a.s * model.constants.sheave_sense * arr[:, 1] / a.i_c
        signals["T_ms"] = arr
    for name, arr in scenario.offsets.items():
        arr = np.array(arr, float)
        arr[:, 1] += op.u[model.input_index(name)]
        signals[name] = arr
    return signals


def run_scenario(scenario: Scenario, params: Params, *,
                 controller: SampledController | None = None,
                 progress: bool = False,
                 start: tuple[EmpactModel, TrimResult] | None = None) -> SimulationResult:
    """Trim the scenario's initial point and simulate it (see `simulate`).

    A closed-loop scenario (one with a ``[controller]`` table) needs its `controller` built
    (`empact.control.closed_loop.run_closed_loop` does that).

    Parameters
    ----------
    scenario : Scenario
        An open-loop scenario (`load_scenario`).
    params : Params
    controller : SampledController, optional
        The sampled law of a closed-loop scenario.
    progress : bool
        A progress bar on stderr.
    start : (EmpactModel, TrimResult), optional
        The scenario's model and trimmed start (`scenario_model` of `scenario` and
        `params`) when the caller has them (not trimmed again).

    Returns
    -------
    SimulationResult
        ``t`` [s], shape (n_t,), states ``x`` (n_t, n), outputs ``y`` and inputs ``u`` by name
        (``output(name)``), ``complete`` and ``message``.
    """
    if scenario.closed_loop and controller is None:
        raise ParameterError(f"scenario {scenario.name!r} has a [controller] table: run it "
                             "with empact.run_closed_loop (or 'empact control simulate')")
    model, op = scenario_model(scenario, params) if start is None else start
    return simulate(model, op.x, scenario_signals(scenario, model, op), scenario.duration,
                    u0=op.u, controller=controller, sample_rate=scenario.sample_rate,
                    rtol=scenario.rtol, max_step=scenario.max_step,
                    omega_min=scenario.omega_min, max_steps=scenario.max_steps,
                    method=scenario.method, progress=progress, name=scenario.name)


def csv_text(result: SimulationResult, states: bool = False) -> str:
    """CSV of a result: a ``#`` comment line with the status, then a header of names with
    units (``time [s]``, the outputs, the inputs, and with `states` the states as
    ``x_<state>``) and one row per sample; `empact.identification.load_records` reads it.

    Parameters
    ----------
    result : SimulationResult
        The simulation.
    states : bool
        Also write the states.

    Returns
    -------
    str
        The CSV text (values with 10 significant digits, SI units as in the header).
    """
    buf = io.StringIO()
    status = "complete" if result.complete else "INCOMPLETE"
    detail = result.message.removeprefix("completed: ")  # (not "complete: completed: ...")
    buf.write(f"# empact simulation {result.scenario!r}: {status}: {detail}\n")
    w = csv.writer(buf, lineterminator="\n")
    cols = ["time [s]"] + [f"{o} [{OUTPUT_UNITS[o]}]" for o in result.outputs] \
        + [f"{i} [{INPUT_UNITS[i]}]" for i in result.inputs]
    data = [result.t[:, None], result.y, result.u]
    if states:
        cols += [f"x_{s} [{STATE_UNITS[s]}]" for s in result.states]
        data.append(result.x)
    w.writerow(cols)
    for row in np.hstack(data):
        w.writerow([f"{v:.10g}" for v in row])
    return buf.getvalue()


def write_csv(result: SimulationResult, path: str | os.PathLike[str], states: bool = False) -> Path:
    """Write `csv_text` to `path` atomically (temporary file, then rename).

    Parameters
    ----------
    result : SimulationResult
        The simulation.
    path : str or path-like
        The CSV file written.
    states : bool
        Also write the states.

    Returns
    -------
    Path
        `path`.
    """
    atomic_write_text(path, csv_text(result, states))
    return Path(path)
