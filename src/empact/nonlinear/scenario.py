"""Simulation scenarios: TOML files naming the model options, the trimmed initial point and
piecewise-linear input signals.

::

    [scenario]
    name = "shift-and-load-step"
    description = "LOW -> OD shift, then a load step"
    duration = 2.0            # [s]
    sample_rate = 1000.0      # output samples per second [Hz]

    [model]                   # empact.nonlinear.model.ModelOptions
    drive = "speed"
    ratio_control = true

    [initial]                 # empact.nonlinear.trim: r_g, omega_p and two of nu, F_s, T_l
    r_g = 0.43
    omega_p = 300.0
    F_s = 15000.0
    T_l = 30.0

    [inputs]                  # [[t, value], ...] in SI; a repeated time is a step
    r_g_ref = [[0.2, 0.43], [1.2, 2.25]]
    T_l = [[1.5, 30.0], [1.5, 60.0]]

    [offsets]                 # [[t, value], ...] added to the input's trimmed value
    T_ms = [[0.3, 0.0], [0.3, 0.5]]

    [solver]                  # optional
    rtol = 1e-4
    max_step = 0.01           # [s]
    omega_min = 1.0           # stop when omega_p falls to this [rad/s]

Input names are the model's (``T_mp`` or ``r_g_ref``, ``T_ms``, ``T_d`` or ``omega_d_ref``,
``T_l`` or ``omega_l_ref``); ``F_s_ref`` [N] may replace ``T_ms`` and is mapped to the static
servo torque ``T_ms = i_e s F_s_ref / i_c``.  An ``[offsets]`` signal is added to the input's
trimmed value (steps of a servo torque around its holding torque, which depends on the
parameters); an input is given absolutely or as an offset, not both.  A signal holds its first
value before its first point and its last value after its last point; inputs not given hold
their trimmed values.
The shipped examples are in ``empact/data/scenarios``.
"""
from __future__ import annotations

import os
import tomllib
from dataclasses import dataclass, field, replace
from importlib import resources
from pathlib import Path
from typing import Any, Mapping

import numpy as np
from numpy.typing import NDArray

from .._validate import check_number
from ..errors import ParameterError
from ..params import read_toml
from .model import ModelOptions

__all__ = ["Scenario", "load_scenario", "scenario_from_dict", "list_examples", "example_path",
           "input_names"]

_SCENARIO_KEYS = {"scenario": {"name", "description", "duration", "sample_rate"},
                  "model": None, "initial": {"r_g", "omega_p", "nu", "F_s", "T_l"},
                  "inputs": None, "offsets": None,
                  "solver": {"rtol", "max_step", "omega_min", "max_steps"}}


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
    offsets : dict name -> array, shape (k, 2)
        Piecewise-linear signals added to the input's trimmed value.
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
    offsets: Mapping[str, NDArray[np.float64]] = field(default_factory=dict)
    rtol: float = 1e-4
    max_step: float = 0.01
    omega_min: float = 1.0
    max_steps: int = 2_000_000

    def with_duration(self, duration: float) -> "Scenario":
        """A copy with another end time [s]."""
        return replace(self, duration=check_number("duration", duration, 0.0, 3600.0,
                                                   lo_open=True, unit="s"))


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


def check_tables(data: Mapping[str, Any], schema: Mapping[str, Any], src: str) -> None:
    """Refuse a table not in `schema` (table -> allowed keys, or None for any), a value where
    a table belongs, and a key not allowed in its table: one line naming `src`."""
    for key, value in data.items():
        if key not in schema:
            raise ParameterError(f"{src}: unknown table [{key}] (allowed: {', '.join(schema)})")
        if not isinstance(value, Mapping):
            raise ParameterError(f"{src}: {key!r} must be a table")
        allowed = schema[key]
        for sub in value:
            if allowed is not None and sub not in allowed:
                raise ParameterError(f"{src}: unknown key {key}.{sub} (allowed: "
                                     f"{', '.join(sorted(allowed))})")


def model_options(table: Mapping[str, Any], src: str,
                  defaults: Mapping[str, Any] | None = None) -> ModelOptions:
    """A scenario file's ``[model]`` table as `ModelOptions` (over `defaults`); a relative
    ``thrust_ratio`` path is read relative to the scenario file."""
    model = {**(defaults or {}), **dict(table)}
    path = model.get("thrust_ratio")
    if isinstance(path, str) and not Path(path).is_absolute() and Path(src).is_file():
        model["thrust_ratio"] = str(Path(src).parent / path)
    try:
        return ModelOptions.from_mapping(model)
    except ParameterError as exc:
        raise ParameterError(f"{src}: [model] {exc}") from None


def scenario_from_dict(data: Mapping[str, Any], src: str = "scenario") -> Scenario:
    """Validate a scenario given as a nested mapping (the parsed TOML)."""
    check_tables(data, _SCENARIO_KEYS, src)
    head = data.get("scenario", {})
    if "duration" not in head:
        raise ParameterError(f"{src}: missing scenario.duration [s]")
    duration = check_number("scenario.duration", head["duration"], 0.0, 3600.0, lo_open=True,
                            unit="s", where=src)
    rate = check_number("scenario.sample_rate", head.get("sample_rate", 1000.0), 0.0, 1e6,
                        lo_open=True, unit="Hz", where=src)
    options = model_options(data.get("model", {}), src)
    initial = dict(data.get("initial", {}))
    for key in ("r_g", "omega_p"):
        if key not in initial:
            raise ParameterError(f"{src}: missing initial.{key}")
    for key, value in initial.items():
        check_number(f"initial.{key}", value, where=src)
    model_inputs = input_names(options)
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
    offsets: dict[str, NDArray[np.float64]] = {}
    for name, pts in data.get("offsets", {}).items():
        if name not in model_inputs:
            raise ParameterError(f"{src}: unknown offset input {name!r} for this model "
                                 f"(allowed: {', '.join(model_inputs)})")
        if name in inputs or (name == "T_ms" and "F_s_ref" in inputs):
            raise ParameterError(f"{src}: input {name!r} given in [inputs] and [offsets]; "
                                 "give one")
        offsets[name] = _signal(f"{src}: offsets.{name}", pts, duration)
    solver = data.get("solver", {})
    rtol = check_number("solver.rtol", solver.get("rtol", 1e-4), 1e-12, 0.1, lo_open=True,
                        where=src)
    max_step = check_number("solver.max_step", solver.get("max_step", 0.01), 0.0, 1.0,
                            lo_open=True, unit="s", where=src)
    omega_min = check_number("solver.omega_min", solver.get("omega_min", 1.0), 0.0, 1e4,
                             lo_open=True, unit="rad/s", where=src)
    max_steps = int(check_number("solver.max_steps", solver.get("max_steps", 2_000_000), 0.0,
                                 1e9, lo_open=True, where=src))
    return Scenario(name=str(head.get("name", Path(src).stem)),
                    description=str(head.get("description", "")), duration=duration,
                    sample_rate=rate, options=options, initial=initial, inputs=inputs,
                    offsets=offsets, rtol=rtol, max_step=max_step, omega_min=omega_min,
                    max_steps=max_steps)


def input_names(options: ModelOptions) -> tuple[str, ...]:
    """The model's four input names under `options` (controllers replace torques by
    references)."""
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


