"""Simulation scenarios: one TOML format for open-loop and closed-loop runs.

A scenario names the model options, the trimmed initial point, piecewise-linear input signals
and, optionally, a controller and its references::

    [scenario]
    name = "shift-and-load-step"
    description = "LOW -> OD shift, then a load step"
    duration = 2.0            # [s]
    sample_rate = 1000.0      # output samples per second [Hz]
    load_step_time = 0.5      # optional, [s]: the closed-loop metrics' window starts 0.3 s later
    load_step = 0.5           # optional: the load torque steps at load_step_time by this
                              # fraction of the torque capacity at the initial point
    shift_window = [0.5, 2.0] # optional, [s]: the window of the shift metrics

    [model]                   # empact.nonlinear.model.ModelOptions
    drive = "speed"
    ratio_control = true

    [initial]                 # an OperatingPoint: r_g, omega_p and two of nu (or tau), F_s, T_l
    r_g = 0.43                # (with driveline = "vehicle", T_l = "road" and one of nu (or
                              # tau), F_s: the car's steady cruise, empact.operating.CruisePoint)
    omega_p = 300.0
    F_s = 15000.0
    T_l = 30.0

    [inputs]                  # [[t, value], ...] in SI; a repeated time is a step
    r_g_ref = [[0.2, 0.43], [1.2, 2.25]]
    T_l = [[1.5, 30.0], [1.5, 60.0]]

    [offsets]                 # [[t, value], ...] added to the input's trimmed value
    T_ms = [[0.3, 0.0], [0.3, 0.5]]

    [controller]              # optional: a sampled controller drives the servo torques
    file = "shipped:pi"       # a controller file (relative to this file) or a shipped one
    rate = 1000.0             # sample rate [Hz]; zero-order hold between samples
    feedforward = true        # clamping feedforward of a measured torque:
    feedforward_signal = "T_ds"   # the driveshaft torque, "T_l_act" (the load motor's), or
                              # "T_e_est" (an engine-torque estimate: no torque sensor)
                              # or "T_ds_est" (observed from it and the twist rate)
    observer_hz = 0.1         # the observer's correction by the estimate [Hz]
    feedforward_gain = 0.9    # the share of it clamped for
    feedforward_gain_table = [[0.0, 0.5], [4000.0, 0.5], [8000.0, 0.9]]  # optional: the
                              # gain of a change over the full feedforward force [N, -]
    feedforward_filter_hz = 100.0 # its low-pass corner [Hz]
    traction_error = 1.0      # factor on the feedforward's traction coefficient
    clamping = "feedback"     # or "safety-factor" (open-loop clamping, the slip loop off)
    safety_factor = 1.3
    mu_design = "ratio-blind" # the safety-factor strategy's mu: or "ratio-aware"
    decoupling = true         # the primary servo follows the feedforward's clamping
    decoupling_filter_hz = 5.0    # its low-pass corner [Hz] (also the shift feedforward's)
    shift_feedforward = false # coordinated shifting: feedforward of the ratio reference's rate
    torque_request = "off"    # a saturating secondary servo: "requested" (T_request computed
                              # and reported) or "honoured" (the bench's load torque follows it)
    torque_request_margin = 0.25  # share of the servo's torque limit kept for the slip loop
    anti_windup = true
    sensors = true            # false: ideal sensors (no delay, quantisation, noise)
    limits = true             # false: no servo limits
    seed = 0                  # of the sensor noise

    [sensors]                 # optional: overrides of the parameter set's [sensors]
    delay = 1
    engine_torque_delay = 0.02    # the engine-torque estimate's delay [s] and error [-]
    engine_torque_error = 0.15

    [limits]                  # optional: overrides of the parameter set's [servo]
    T_ms_max = 15.0

    [references]              # [[t, value], ...]: set-points of the controller's signals
    r_g = [[0.0, 1.0]]
    tau = [[0.0, 0.9]]        # or nu / nu_r: tau is the slip where mu = tau mu_max

    [targets]                 # optional: what a closed-loop run must meet (metric names of
    peak_slip_error = 0.006   # empact.control.closed_loop.metrics, in their units: slips
    ratio_rate = [1.0, inf]   # as fractions): a number is an upper bound, [lo, hi] a band,
    macro_slip = false        # a boolean the value

    [solver]                  # optional
    rtol = 1e-4
    max_step = 0.01           # [s]
    omega_min = 1.0           # stop when omega_p falls to this [rad/s]
    max_steps = 2000000
    method = "rodas4"         # the integrator: "rodas4" (default), "rodas5p" or "ros2"

Input names are the model's (``T_mp`` or ``r_g_ref``, ``T_ms``, ``T_d`` or ``omega_d_ref``,
``T_l`` or ``omega_l_ref``); ``F_s_ref`` [N] may replace ``T_ms`` and is mapped to the static
servo torque ``T_ms = i_e s F_s_ref / i_c``.  An ``[offsets]`` signal is added to the input's
trimmed value (steps of a servo torque around its holding torque, which depends on the
parameters); an input is given absolutely or as an offset, not both.  A signal holds its first
value before its first point and its last value after its last point; inputs not given hold
their trimmed values.  With a ``[controller]`` the servo torques are the controller's
(``ratio_control`` false, no ``T_mp``/``T_ms``/``F_s_ref`` signal); it runs with
`empact.control.closed_loop.run_closed_loop`.  The shipped examples are in
``empact/data/scenarios`` (open loop) and ``empact/data/control`` (closed loop).

One loader (`load_scenario`), one validator (`scenario_from_dict`); every problem is one
``ParameterError`` line naming the file, the key, the value and what is allowed.  A file in
the layout of empact 0.1's closed-loop scenarios (controller keys in ``[scenario]``) is
refused with the key to use instead.
"""
from __future__ import annotations

import os
import tomllib
from dataclasses import dataclass, field, fields, replace
from importlib import resources
from pathlib import Path
from typing import Any, Mapping

import numpy as np
from numpy.typing import NDArray

from .._deprecate import REMOVAL, warn_renamed
from .._validate import check_choice, check_int, check_number, check_values
from ..errors import ParameterError
from ..hardware import SensorParams, ServoLimits
from ..operating import CruisePoint, curve_peak
from ..params import OPERATING_VARIABLES, OperatingPoint, Params, check_clamping, read_toml
from ..variator.geometry import check_ratio
from ..variator.traction import traction_from_params
from .controller_spec import CLAMPING, ControllerSpec
from .model import ModelOptions

__all__ = ["Scenario", "ControllerSpec", "load_scenario", "scenario_from_dict", "list_examples",
           "example_path", "input_names", "signal", "check_tables", "model_options",
           "check_references", "check_reference_names",
           "CLAMPING", "METHODS", "DEFAULT_METHOD"]



#: integration methods (``[solver] method``, `empact.nonlinear.simulation.simulate`'s
#: ``method``): the compiled order-2 Rosenbrock method (ode23s) and the stiffly accurate
#: Rodas5P (order 5) and Rodas4 (order 4, the default: `DEFAULT_METHOD`)
METHODS = ("ros2", "rodas5p", "rodas4")

#: the integrator when none is named: Rodas4, at least as fast as odeint (LSODA) at equal
#: accuracy on every shipped scenario at rtol 1e-4 and 1e-6, and faster than the order-2
#: method ("ros2", the default up to 0.1) everywhere at equal accuracy (``bench/RESULTS.md``)
DEFAULT_METHOD = "rodas4"

#: the signals a controller's references may name (``tau``: the slip set-point given by its
#: torque ratio mu / mu_max on the traction curve at the reference ratio)
REFERENCES = ("r_g", "nu", "nu_r", "tau")

_SCENARIO_KEYS = {"scenario": {"name", "description", "duration", "sample_rate",
                               "load_step_time", "load_step", "shift_window"},
                  "model": None, "initial": set(OPERATING_VARIABLES),
                  "inputs": None, "offsets": None,
                  "controller": set(),  # ControllerSpec's fields (set below)
                  "sensors": {f.name for f in fields(SensorParams)},
                  "limits": {f.name for f in fields(ServoLimits)},
                  "references": set(REFERENCES), "targets": None,
                  "solver": {"rtol", "max_step", "omega_min", "max_steps", "method"}}

#: keys of the 0.1 closed-loop layout -> where they live now
_MOVED = {"controller": "[controller] file", "controller_rate": "[controller] rate",
          "feedforward": "[controller] feedforward", "clamping": "[controller] clamping",
          "safety_factor": "[controller] safety_factor", "rtol": "[solver] rtol",
          "max_step": "[solver] max_step"}

#: places of the shipped scenarios: open loop, closed loop
_EXAMPLE_FOLDERS = ("scenarios", "control")


_SCENARIO_KEYS["controller"] = {f.name for f in fields(ControllerSpec)}


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
    initial : OperatingPoint
        The trim request of the initial point.
    inputs : dict name -> array, shape (k, 2)
        Piecewise-linear signals ``[[t, value], ...]``.
    offsets : dict name -> array, shape (k, 2)
        Piecewise-linear signals added to the input's trimmed value.
    controller : ControllerSpec or None
        The sampled controller of a closed-loop scenario.
    sensors, limits : dict
        Overrides of the parameter set's ``[sensors]`` and ``[servo]`` for the loop.
    targets : dict name -> (lo, hi) or bool
        What a closed-loop run must meet (`empact.control.closed_loop.check_targets`).
    references : dict name -> array, shape (k, 2)
        Set-points of the controller's signals (``r_g``, ``nu``, ``nu_r``).
    load_step_time : float or None
        [s]; the closed-loop metrics' window starts 0.3 s after it.
    load_step : float or None
        The load torque steps at `load_step_time` by this fraction of the torque capacity
        ``2 mu_max F_s R_s / cos(beta)`` at the initial point.
    shift_window : (float, float) or None
        [s]; the window of the shift metrics.
    rtol : float
        Relative tolerance of the integrator.
    max_step : float
        Largest step [s].
    omega_min : float
        Stop when omega_p falls to this [rad/s].
    max_steps : int
        Give up (incomplete result) after this many integration steps.
    method : str
        The integrator (`empact.nonlinear.simulation.METHODS`).
    source : str
        The file it was read from ('' when built from a mapping).
    """

    name: str
    description: str
    duration: float
    sample_rate: float
    options: ModelOptions
    initial: OperatingPoint
    inputs: Mapping[str, NDArray[np.float64]]
    offsets: Mapping[str, NDArray[np.float64]] = field(default_factory=dict)
    controller: ControllerSpec | None = None
    references: Mapping[str, NDArray[np.float64]] = field(default_factory=dict)
    sensors: Mapping[str, float] = field(default_factory=dict)
    limits: Mapping[str, float] = field(default_factory=dict)
    targets: Mapping[str, Any] = field(default_factory=dict)
    load_step_time: float | None = None
    load_step: float | None = None
    shift_window: tuple[float, float] | None = None
    rtol: float = 1e-4
    max_step: float = 0.01
    omega_min: float = 1.0
    max_steps: int = 2_000_000
    method: str = DEFAULT_METHOD
    source: str = ""

    @property
    def closed_loop(self) -> bool:
        """True when a controller drives the servo torques."""
        return self.controller is not None

    def with_duration(self, duration: float) -> "Scenario":
        """A copy with another end time [s].

        Parameters
        ----------
        duration : float
            The end time [s], > 0.
        """
        return replace(self, duration=check_number("duration", duration, 0.0, 3600.0,
                                                   lo_open=True, unit="s"))

    def with_options(self, **changes: Any) -> "Scenario":
        """A copy whose model options have the `changes` (`ModelOptions` fields, e.g.
        ``traction=load_traction("curves.csv")``), validated.

        Parameters
        ----------
        **changes
            `ModelOptions` fields by name and their new values.

        Returns
        -------
        Scenario
            The scenario with the changed options (`ModelOptions.from_mapping` validates them).
        """
        values = {f.name: getattr(self.options, f.name) for f in fields(self.options)}
        return replace(self, options=ModelOptions.from_mapping({**values, **changes}))

    def with_controller(self, file: str) -> "Scenario":
        """A copy whose controller is read from `file` (a path or ``"shipped:NAME"``).

        Parameters
        ----------
        file : str
            A controller file (JSON or ``.mat``) or ``"shipped:NAME"``.
        """
        if self.controller is None:
            raise ParameterError(f"scenario {self.name!r} has no [controller] table")
        return replace(self, controller=replace(self.controller, file=str(file)))


def load_scenario(path: str | os.PathLike[str], params: Params | None = None) -> Scenario:
    """Read and validate a scenario file.

    Parameters
    ----------
    path : str or path-like
        A scenario TOML file (open loop, or closed loop with a ``[controller]`` table).
    params : Params, optional
        The machine the scenario will run on: its references are then checked against the
        model's ranges (`check_references`) here, before any integration.

    Returns
    -------
    Scenario
        Duration [s], sample rate [Hz], model options, initial point, input signals, and for a
        closed loop the controller, references, sensors, limits and targets.

    Raises
    ------
    ParameterError
        One line naming the file, the key, the bad value and what is allowed.
    """
    src = str(path)
    data = read_toml(path, "scenario")
    return scenario_from_dict(data, src, params)


def check_tables(data: Mapping[str, Any], schema: Mapping[str, Any], src: str) -> None:
    """Refuse a table not in `schema` (table -> allowed keys, or None for any), a value where
    a table belongs, and a key not allowed in its table: one line naming `src`.

    Parameters
    ----------
    data : mapping
        The parsed TOML document: table name -> table.
    schema : mapping
        Table name -> the set of allowed keys, or None for any key.
    src : str
        The file it came from (named in the message).

    Raises
    ------
    ParameterError
        For an unknown table or key, or a value where a table belongs (a key of empact
        0.1's closed-loop layout is named with where it belongs now).
    """
    for key, value in data.items():
        if key not in schema:
            raise ParameterError(f"{src}: unknown table [{key}] (allowed: {', '.join(schema)})")
        if not isinstance(value, Mapping):
            raise ParameterError(f"{src}: {key!r} must be a table")
        allowed = schema[key]
        for sub in value:
            if allowed is not None and sub not in allowed:
                if key == "scenario" and sub in _MOVED:
                    raise ParameterError(f"{src}: scenario.{sub} belongs in {_MOVED[sub]} "
                                         "now (one scenario format for open and closed loop)")
                raise ParameterError(f"{src}: unknown key {key}.{sub} (allowed: "
                                     f"{', '.join(sorted(allowed))})")


def model_options(table: Mapping[str, Any], src: str,
                  defaults: Mapping[str, Any] | None = None) -> ModelOptions:
    """A scenario file's ``[model]`` table as `ModelOptions` (over `defaults`); a relative
    ``thrust_ratio``, ``creep_map``, ``traction`` or ``loss_map`` path is read relative to
    the scenario file.

    Parameters
    ----------
    table : mapping
        The ``[model]`` table: `ModelOptions` field -> value.
    src : str
        The scenario file (relative paths are taken from its folder; named in messages).
    defaults : mapping, optional
        Option values the table overrides.

    Returns
    -------
    ModelOptions
        The validated options.

    Raises
    ------
    ParameterError
        One line naming `src` and the bad option.
    """
    model = {**(defaults or {}), **dict(table)}
    for key in ("thrust_ratio", "creep_map", "traction", "loss_map"):
        path = model.get(key)
        if isinstance(path, str) and not Path(path).is_absolute() and Path(src).is_file():
            model[key] = str(Path(src).parent / path)
    try:
        return ModelOptions.from_mapping(model)
    except ParameterError as exc:
        raise ParameterError(f"{src}: [model] {exc}") from None


def _initial(table: Mapping[str, Any], src: str, options: ModelOptions) -> OperatingPoint:
    """The ``[initial]`` point: an `OperatingPoint`, or with ``T_l = "road"`` (the vehicle
    driveline only) the car's steady cruise (`CruisePoint`: the road load sets T_l)."""
    for key in ("r_g", "omega_p"):
        if key not in table:
            raise ParameterError(f"{src}: missing initial.{key}")
    cruise = table.get("T_l") == "road"
    if cruise and options.driveline != "vehicle":
        raise ParameterError(f"{src}: initial.T_l = 'road' needs [model] driveline = "
                             "'vehicle' (the bench has no road load)")
    values = {k: check_number(f"initial.{k}", v, where=src) for k, v in table.items()
              if not (cruise and k == "T_l")}
    try:
        return CruisePoint(**values) if cruise else OperatingPoint(**values)
    except ParameterError as exc:
        raise ParameterError(f"{src}: [initial] {exc}") from None


def _controller(table: Mapping[str, Any], src: str) -> ControllerSpec:
    if "file" not in table:
        raise ParameterError(f"{src}: missing controller.file (a controller file or "
                             "'shipped:NAME')")
    file = table["file"]
    if not isinstance(file, str) or not file:
        raise ParameterError(f"{src}: controller.file = {file!r}: must be a file name or "
                             "'shipped:NAME'")
    if not file.startswith("shipped:") and not Path(file).is_absolute() and Path(src).is_file():
        file = str(Path(src).parent / file)
    try:
        return ControllerSpec(**{**table, "file": file})
    except ParameterError as exc:
        raise ParameterError(f"{src}: {exc}") from None


#: The release that stops reading a ``[targets]`` key in percentage points or % (``_pp``).
PP_TARGETS_REMOVAL = REMOVAL


def _targets(table: Mapping[str, Any], src: str) -> dict[str, Any]:
    """A scenario's ``[targets]``: name -> upper bound (number), band ``[lo, hi]`` or a
    boolean; the names are checked against the metrics when the run is judged.  A key in
    percentage points or % (``peak_slip_error_pp = 0.6``, before 0.2.0) is read as the
    fraction under the key without ``_pp`` (``peak_slip_error = 0.006``), with a
    deprecation warning (`warn_renamed`), until `PP_TARGETS_REMOVAL`."""
    out: dict[str, Any] = {}
    for key, given in table.items():
        name, value = key, given
        if key.endswith("_pp") and not isinstance(given, bool):
            name = key[:-3]
            warn_renamed(f"{src}: targets.{key} (percentage points)",
                         f"targets.{name} as a fraction [-] ({name} = {given!r} / 100)",
                         removal=PP_TARGETS_REMOVAL, stacklevel=4)
            if isinstance(given, (int, float)):
                value = given / 100
            elif isinstance(given, list):
                value = [v / 100 if isinstance(v, (int, float)) and not isinstance(v, bool)
                         else v for v in given]
            if name in table:
                raise ParameterError(f"{src}: targets.{key} and targets.{name}: give one "
                                     f"({name}, a fraction [-])")
        where = f"{src}: targets.{name}"
        if isinstance(value, bool):
            out[name] = value
        elif isinstance(value, (int, float)):
            out[name] = (-np.inf, check_number(f"targets.{name}", value, where=src,
                                               lo=-np.inf, lo_open=True))
        elif isinstance(value, list) and len(value) == 2 and all(
                isinstance(v, (int, float)) and not isinstance(v, bool) for v in value):
            lo, hi = float(value[0]), float(value[1])
            if np.isnan(lo) or np.isnan(hi) or not lo <= hi:
                raise ParameterError(f"{where} = {value!r}: a band [lo, hi] with lo <= hi")
            out[name] = (lo, hi)
        else:
            raise ParameterError(f"{where} = {value!r}: give an upper bound (a number), a "
                                 "band [lo, hi] or true/false")
    return out


def _overrides(table: Mapping[str, Any], kind: type, name: str, src: str) -> dict[str, float]:
    """A scenario's ``[sensors]`` / ``[limits]`` table, checked against the section it
    overrides (its defaults stand in for the parameter set's values)."""
    try:
        kind(**table)
    except ParameterError as exc:
        raise ParameterError(f"{src}: [{name}] {exc}") from None
    return {k: float(v) for k, v in table.items()}


def scenario_from_dict(data: Mapping[str, Any], src: str = "scenario",
                       params: Params | None = None) -> Scenario:
    """Validate a scenario given as a nested mapping (the parsed TOML).

    Parameters
    ----------
    data : mapping
        The parsed scenario document (tables as in the module docstring; SI units).
    src : str
        Where it came from: named in every message; relative file names of the ``[model]``
        and ``[controller]`` tables are taken from its folder when it is a file.
    params : Params, optional
        The machine the scenario will run on: its references are then checked against the
        model's ranges (`check_references`).

    Returns
    -------
    Scenario
        The validated scenario (its ``source`` is `src`).

    Raises
    ------
    ParameterError
        One line naming `src`, the key, the bad value and what is allowed.
    """
    check_tables(data, _SCENARIO_KEYS, src)
    head = data.get("scenario", {})
    if "duration" not in head:
        raise ParameterError(f"{src}: missing scenario.duration [s]")
    duration = check_number("scenario.duration", head["duration"], 0.0, 3600.0, lo_open=True,
                            unit="s", where=src)
    rate = check_number("scenario.sample_rate", head.get("sample_rate", 1000.0), 0.0, 1e6,
                        lo_open=True, unit="Hz", where=src)
    options = model_options(data.get("model", {}), src)
    initial = _initial(data.get("initial", {}), src, options)
    model_inputs = input_names(options)
    controller = _controller(data["controller"], src) if "controller" in data else None
    driven = ("T_mp", "T_ms", "F_s_ref") if controller else ()
    if controller and options.ratio_control:
        raise ParameterError(f"{src}: [model] ratio_control must be false with a "
                             "[controller]: the controller drives the servo torques")
    inputs: dict[str, NDArray[np.float64]] = {}
    for name, pts in data.get("inputs", {}).items():
        allowed = [k for k in model_inputs + ("F_s_ref",) if k not in driven]
        if name not in allowed:
            why = " (the [controller] drives the servos)" if name in driven else ""
            raise ParameterError(f"{src}: unknown input {name!r} for this model{why} "
                                 f"(allowed: {', '.join(allowed)})")
        inputs[name] = signal(f"{src}: inputs.{name}", pts)
    if "F_s_ref" in inputs and "T_ms" in inputs:
        raise ParameterError(f"{src}: give inputs.T_ms or inputs.F_s_ref, not both")
    offsets: dict[str, NDArray[np.float64]] = {}
    for name, pts in data.get("offsets", {}).items():
        allowed = [k for k in model_inputs if k not in driven]
        if name not in allowed:
            raise ParameterError(f"{src}: unknown offset input {name!r} for this model "
                                 f"(allowed: {', '.join(allowed)})")
        if name in inputs or (name == "T_ms" and "F_s_ref" in inputs):
            raise ParameterError(f"{src}: input {name!r} given in [inputs] and [offsets]; "
                                 "give one")
        offsets[name] = signal(f"{src}: offsets.{name}", pts)
    references = {k: signal(f"{src}: references.{k}", v)
                  for k, v in data.get("references", {}).items()}
    for table in ("references", "sensors", "limits"):
        if table in data and controller is None:
            raise ParameterError(f"{src}: [{table}] needs a [controller] table")
    check_reference_names(references, src)
    if "tau" in references:
        tau = references["tau"][:, 1]
        if np.any(~((tau > 0) & (tau < 1))):
            raise ParameterError(f"{src}: references.tau = {tau.tolist()}: a torque ratio "
                                 "mu / mu_max lies in (0, 1)")
    sensors = _overrides(data.get("sensors", {}), SensorParams, "sensors", src)
    targets = _targets(data.get("targets", {}), src)
    if targets and controller is None:
        raise ParameterError(f"{src}: [targets] needs a [controller] table")
    limits = _overrides(data.get("limits", {}), ServoLimits, "limits", src)
    t_step = head.get("load_step_time")
    load_step = head.get("load_step")
    if load_step is not None:
        if t_step is None:
            raise ParameterError(f"{src}: scenario.load_step needs scenario.load_step_time")
        load_step = check_number("scenario.load_step", load_step, -1.0, 2.0, where=src,
                                 note="a fraction of the torque capacity")
        if "T_l" in inputs or "T_l" in offsets or options.load != "torque":
            raise ParameterError(f"{src}: scenario.load_step steps the load torque T_l: it "
                                 "needs a torque-controlled load ([model] load = \"torque\") "
                                 "and no T_l signal")
    window = head.get("shift_window")
    if window is not None:
        if not (isinstance(window, list) and len(window) == 2):
            raise ParameterError(f"{src}: scenario.shift_window = {window!r}: must be [start, "
                                 "end] [s]")
        w0 = check_number("scenario.shift_window[0]", window[0], 0.0, duration, unit="s",
                          where=src)
        w1 = check_number("scenario.shift_window[1]", window[1], w0, duration, lo_open=True,
                          unit="s", where=src)
        window = (w0, w1)
    solver = data.get("solver", {})
    rtol = check_number("solver.rtol", solver.get("rtol", 1e-4), 1e-12, 0.1, lo_open=True,
                        where=src)
    max_step = check_number("solver.max_step", solver.get("max_step", 0.01), 0.0, 1.0,
                            lo_open=True, unit="s", where=src)
    omega_min = check_number("solver.omega_min", solver.get("omega_min", 1.0), 0.0, 1e4,
                             lo_open=True, unit="rad/s", where=src)
    max_steps = check_int("solver.max_steps", solver.get("max_steps", 2_000_000), 1, 10**9,
                          where=src)
    method = check_choice("solver.method", solver.get("method", DEFAULT_METHOD), METHODS,
                          where=src)
    sc = Scenario(name=str(head.get("name", Path(src).stem)),
                  description=str(head.get("description", "")), duration=duration,
                  sample_rate=rate, options=options, initial=initial, inputs=inputs,
                  offsets=offsets, controller=controller, references=references,
                  sensors=sensors, limits=limits, targets=targets,
                  load_step_time=None if t_step is None else check_number(
                      "scenario.load_step_time", t_step, 0.0, duration, unit="s", where=src),
                  load_step=load_step,
                  shift_window=window, rtol=rtol, max_step=max_step, omega_min=omega_min,
                  max_steps=max_steps, method=method, source=src)
    if params is not None:
        check_references(sc, params)
    return sc


def check_reference_names(references: Mapping[str, Any], where: str = "") -> None:
    """The one rule on a controller's reference names (the scenario loader and
    `empact.control.law.LoopLaw` call it): each one of `REFERENCES`, and one slip set-point
    (``nu``, ``nu_r`` or ``tau``) at most.

    Parameters
    ----------
    references : mapping
        The references by name (their values are not looked at).
    where : str
        The scenario file, named in the message ('' for none).

    Raises
    ------
    ParameterError
        One line naming `where` and the reference.
    """
    head = f"{where}: " if where else ""
    for key in references:
        if key not in REFERENCES:
            raise ParameterError(f"{head}reference {key!r}: choose from {', '.join(REFERENCES)}")
    slips = [k for k in ("nu", "nu_r", "tau") if k in references]
    if len(slips) > 1:
        raise ParameterError(f"{head}give one slip set-point (references.nu, nu_r or tau), "
                             f"not {' and '.join(slips)}")


def check_references(scenario: Scenario, params: Params) -> None:
    """A scenario's references within what the machine of `params` can follow, checked once,
    when the scenario is loaded (not found out when the simulation stops).

    A ratio (``references.r_g``, ``inputs.r_g_ref``) within the variator's geometric range
    (`empact.variator.geometry.check_ratio`); a clamping force (``inputs.F_s_ref``) > 0
    (`empact.params.check_clamping`); a slip (``references.nu``, ``nu_r``, a fraction)
    within the traction curve's valid range and on its rising branch (0 up to the peak at
    the reference ratio of that time).  A torque ratio ``references.tau`` is in (0, 1) by
    `scenario_from_dict`.

    Parameters
    ----------
    scenario : Scenario
    params : Params
        The machine (its variator geometry and traction curve).

    Raises
    ------
    ParameterError
        One line naming the scenario file, the field, the value and the allowed range.
    """
    src = scenario.source or scenario.name
    tables = (("references", scenario.references), ("inputs", scenario.inputs))
    for group, signals in tables:
        for name in ("r_g", "r_g_ref"):
            if name in signals:
                key = f"{group}.{name}"
                try:
                    check_ratio(signals[name][:, 1], params.variator, key)
                except ParameterError as exc:
                    raise ParameterError(f"{src}: {exc}") from None
    if "F_s_ref" in scenario.inputs:
        check_clamping("inputs.F_s_ref", scenario.inputs["F_s_ref"][:, 1], where=src)
    slip = next((k for k in ("nu", "nu_r") if k in scenario.references), None)
    if slip is None:
        return
    tr = scenario.options.traction if scenario.options.traction is not None \
        else params.traction_table if params.traction_table is not None \
        else traction_from_params(params)
    lo, hi = tr.nu_range
    key = f"references.{slip}"
    table = scenario.references[slip]
    check_values(key, table[:, 1], lo, hi, where=src,
                 note="a slip fraction: 0.01 is 1 %; the traction curve's valid range")
    ratio = scenario.references.get("r_g")
    if ratio is None:  # the ratio the run holds: the initial point's
        ratio = np.array([[0.0, scenario.initial.r_g]])
    # the (slip, ratio) pairs at every corner of either signal (both are piecewise linear)
    pairs = [(nu, float(np.interp(t, ratio[:, 0], ratio[:, 1]))) for t, nu in table] + \
        [(float(np.interp(t, table[:, 0], table[:, 1])), r) for t, r in ratio]
    for nu, r in pairs:
        nu_pk = min(curve_peak(tr, r, refine=True)[0], hi)
        check_number(key, nu, 0.0, nu_pk, lo_open=True, hi_open=True, where=src,
                     note=f"a slip on the rising branch of the traction curve at r_g = {r:g}")


def input_names(options: ModelOptions) -> tuple[str, ...]:
    """The model's four input names under `options` (controllers replace torques by
    references).

    Parameters
    ----------
    options : ModelOptions
        The model options (``ratio_control``, ``drive``, ``load``).

    Returns
    -------
    tuple of str, length 4
        ``T_mp`` or ``r_g_ref``, ``T_ms``, ``T_d`` or ``omega_d_ref``, ``T_l`` or
        ``omega_l_ref``, in the model's input order.
    """
    return ("r_g_ref" if options.ratio_control else "T_mp", "T_ms",
            "omega_d_ref" if options.drive == "speed" else "T_d",
            "omega_l_ref" if options.load == "speed" else "T_l")


def signal(where: str, pts: Any) -> NDArray[np.float64]:
    """A piecewise-linear signal ``[[t, value], ...]`` as an array of shape (k, 2): times
    non-decreasing from 0, each repeated at most once (a step), values finite.

    Parameters
    ----------
    where : str
        What the signal is, for the messages (``"file.toml: inputs.T_l"``).
    pts : sequence of [t, value] pairs
        The points: times [s] and values in the signal's SI unit.

    Returns
    -------
    ndarray, shape (k, 2)
        The points as floats, column 0 the times [s].

    Raises
    ------
    ParameterError
        When the points are not a non-empty list of pairs, not finite, or their times are
        negative, decreasing or repeated more than once.
    """
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


def _example_files() -> dict[str, Path]:
    out: dict[str, Path] = {}
    for folder in _EXAMPLE_FOLDERS:
        for res in sorted(resources.files("empact.data").joinpath(folder).iterdir(),
                          key=lambda r: r.name):
            if res.name.endswith(".toml"):
                out[res.name[:-5]] = Path(str(res))
    return out


def list_examples(closed_loop: bool | None = None) -> dict[str, str]:
    """Shipped example scenarios: name -> description (all, or only the open-loop or the
    closed-loop ones).

    Parameters
    ----------
    closed_loop : bool, optional
        True: only the closed-loop scenarios (with a ``[controller]`` table); False: only
        the open-loop ones; None: all.

    Returns
    -------
    dict of str to str
        Example name (the file name without ``.toml``) -> its description; the open-loop
        examples first, each folder by name.
    """
    out = {}
    for name, path in _example_files().items():
        data = tomllib.loads(path.read_text())
        if closed_loop is None or ("controller" in data) == closed_loop:
            out[name] = data.get("scenario", {}).get("description", "")
    return out


def example_path(name: str) -> Path:
    """Path of a shipped example scenario (`list_examples` names).

    Parameters
    ----------
    name : str
        The example's name (its file name without ``.toml``).

    Returns
    -------
    Path
        The shipped TOML file.

    Raises
    ------
    ParameterError
        For an unknown name (the message lists the names).
    """
    files = _example_files()
    if name not in files:
        raise ParameterError(f"example {name!r}: choose from {', '.join(files)}")
    return files[name]
