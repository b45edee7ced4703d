"""The nonlinear machine as an FMI 2.0 co-simulation unit (FMU): `export_fmu` and the unit
that runs inside it.

`export_fmu` writes an FMU (``empact fmu export``) of `empact.nonlinear` for a parameter set,
model options (drive and load motors, damping, kinematics, shift law, a measured traction
table) and the operating point it starts at, with empact's own Rosenbrock integrator
inside (`empact.nonlinear.simulation.Stepper`: the state, step size and Jacobian carry
over from one communication point to the next, any communication step is accepted) and,
with a controller file, the sampled loop law of `empact.control.law` (sensors, references,
controller, feedforwards, servo limits) in front of the servos.

The unit (`CoSimulation`, pure Python; `EmpactSlave` its pythonfmu face):

* **inputs**: open loop the model's four (``T_mp``, ``T_ms``, the drive input
  ``omega_d_ref`` or ``T_d``, the load input ``T_l`` or ``omega_l_ref``), held over each
  communication step; closed loop the references ``r_g_ref`` [-] and ``tau_ref`` [-] (the
  torque ratio ``mu / mu_max`` of the slip set-point) and the drive and load inputs; their
  start values hold the starting point (the trim).
* **outputs**: every output of the model by its name (`empact.nonlinear.OUTPUT_UNITS`: ratio,
  slips ``nu`` and ``nu_r``, forces, shaft and servo speeds, powers), the holding inputs of
  the starting point (``trim.<input>``) and, closed loop, the servo torques ``T_mp``,
  ``T_ms`` the law commands.
* **parameters** (fixed: set them before initialisation): the physical parameters of
  `PARAMETER_SECTIONS` by dotted name (``driveline.J_p``) and the starting point
  (``initial.r_g``, ``initial.omega_p`` and the two that fix it), with units and ranges from
  the parameter blocks' field metadata (`empact._section.param`); the unit validates the
  changed set as `empact.params` does and trims the new start.

A run of communication steps is bitwise `empact.nonlinear.simulation.simulate` with a
sampled controller of that period (open loop: one that holds; closed loop: the loop law at
its rate, when the communication points are its samples): the integrator is restarted at
every point in both.  The shipped scenarios run without such a grid differ from it by the
integrator's tolerance (``tests/test_fmu.py``).

The FMU's binary is pythonfmu's: it loads the Python of the importing process, or the host's
shared libpython, which must have empact (with numba) installed; see the docs page "The
machine as an FMU".
"""
from __future__ import annotations

import json
import math
import shutil
import sys
import tempfile
import uuid
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any, Callable, Mapping
from xml.etree.ElementTree import Element, SubElement

import numpy as np
from pythonfmu import (
    DefaultExperiment,
    Fmi2Causality,
    Fmi2Initial,
    Fmi2Slave,
    Fmi2Variability,
    FmuBuilder,
    Real,
)
from pythonfmu.enums import Fmi2Status

from ._io import atomic_file
from ._validate import check_choice, check_int, check_number
from .control.controller import Controller, controller_path, load_controller
from .control.law import RAW_SIGNALS, SHIPPED_LOOP, LoopConfig, LoopLaw
from .errors import ParameterError
from .nonlinear.equilibrium import trim
from .nonlinear.model import (
    INPUT_UNITS,
    OUTPUT_DESCRIPTIONS,
    OUTPUT_UNITS,
    EmpactModel,
    nonlinear_model,
)
from .nonlinear.options import ModelOptions
from .nonlinear.scenario import DEFAULT_METHOD, METHODS
from .nonlinear.simulation import Stepper
from .operating import OperatingPoint
from .params import Params, dumps_params, load_params
from .variator.losses import load_loss_map
from .variator.shift_law import load_creep_map
from .variator.thrust_ratio import load_thrust_ratio
from .variator.traction import load_traction

__all__ = ["export_fmu", "FmuConfig", "CoSimulation", "FmuVariable", "MODEL_IDENTIFIER",
           "PARAMETER_SECTIONS", "EXPORTED_OPTIONS", "REFERENCE_INPUTS"]

#: the FMU's model identifier (its binary's name and the slave class)
MODEL_IDENTIFIER = "EmpactCVT"
#: the parameter blocks whose fields are the FMU's parameters
PARAMETER_SECTIONS = ("variator", "actuation", "driveline", "traction", "shift")
#: the model options an FMU is exported with (`ModelOptions`)
EXPORTED_OPTIONS = ("drive", "load", "damping", "kinematics", "shift_law", "traction",
                    "thrust_ratio", "creep_map", "loss_map")
#: the measured tables among them, each with its reader (copied into the FMU)
_TABLES: dict[str, Callable[[Path], Any]] = {"traction": load_traction,
                                             "thrust_ratio": load_thrust_ratio,
                                             "creep_map": load_creep_map,
                                             "loss_map": load_loss_map}
#: the closed loop's reference inputs (ratio, and the slip set-point by its torque ratio)
REFERENCE_INPUTS = ("r_g_ref", "tau_ref")
_SPEC = "empact_fmu.json"
_PARAMS = "params.toml"
_CONTROLLER = "controller.json"


@dataclass(frozen=True)
class FmuConfig:
    """What an FMU is exported from (validated by `CoSimulation`, which builds it).

    Attributes
    ----------
    params : Params
        The parameter set.
    options : dict
        Model options (`EXPORTED_OPTIONS`; a measured table as its reader returns it).
    point : OperatingPoint
        The starting point (trimmed at initialisation).
    controller : Controller or None
        The loop law's controller (None: open loop).
    rate : float
        The loop law's sample rate [Hz].
    method : str
        The integrator (`empact.nonlinear.simulation.METHODS`).
    rtol, max_step, omega_min : float
        The integrator's relative tolerance [-], largest step [s] and the primary speed that
        stops the run [rad/s] (`empact.nonlinear.simulation.simulate`).
    max_steps : int
        The integrator's step budget over a run.
    duration : float
        Closed loop: the longest run [s] (the loop law's per-sample tables of references and
        sensor noise are made for it; pythonfmu's binary does not pass the stop time).
    """

    params: Params
    options: Mapping[str, Any] = field(default_factory=dict)
    point: OperatingPoint | None = None
    controller: Controller | None = None
    rate: float = 1000.0
    method: str = DEFAULT_METHOD
    rtol: float = 1e-4
    max_step: float = 0.01
    omega_min: float = 1.0
    max_steps: int = 2_000_000
    duration: float = 60.0

    def __post_init__(self) -> None:
        for key in self.options:
            if key not in EXPORTED_OPTIONS:
                raise ParameterError(f"model option {key!r}: an FMU is exported with "
                                     f"{', '.join(EXPORTED_OPTIONS)}")
        ModelOptions.from_mapping(dict(self.options))
        check_choice("method", self.method, METHODS)
        check_number("rtol", self.rtol, 1e-12, 0.1)
        check_number("max_step", self.max_step, 0.0, 10.0, lo_open=True, unit="s")
        check_number("omega_min", self.omega_min, 0.0, unit="rad/s")
        check_int("max_steps", self.max_steps, 1, 10**9)
        check_number("rate", self.rate, 1.0, 1e5, unit="Hz")
        check_number("duration", self.duration, 0.0, 3600.0, lo_open=True, unit="s")
        if self.point is None:
            object.__setattr__(self, "point", self.params.operating)


@dataclass(frozen=True)
class FmuVariable:
    """One variable of the FMU's model description.

    Attributes
    ----------
    name : str
        Its name (dotted for parameters: ``driveline.J_p``).
    causality : {"parameter", "input", "output"}
    unit : str
        SI unit (``"-"`` or empty: dimensionless).
    lo, hi : float
        Allowed range (parameters; -inf / inf: open).
    description : str
    get : callable
        Its value now.
    set : callable or None
        Sets it (parameters and inputs).
    """

    name: str
    causality: str
    unit: str
    lo: float
    hi: float
    description: str
    get: Callable[[], float]
    set: Callable[[float], None] | None = None


def _parameter_fields(params: Params, point: OperatingPoint) -> list[tuple[str, Any, Any]]:
    """(dotted name, field, value) of every FMU parameter: the float fields of
    `PARAMETER_SECTIONS` and the starting point's ``r_g``, ``omega_p`` and the two that fix
    it (the blocks' `param` metadata gives unit, range and description)."""
    out = []
    for sec in PARAMETER_SECTIONS:
        block = getattr(params, sec)
        for f in fields(block):
            value = getattr(block, f.name)
            if "unit" in f.metadata and isinstance(value, float):
                out.append((f"{sec}.{f.name}", f, value))
    meta = {f.name: f for f in fields(point)}
    for name in ("r_g", "omega_p") + point.given:
        out.append((f"initial.{name}", meta[name], float(getattr(point, name))))
    return out


class CoSimulation:
    """The machine the FMU runs: the model stepped from point to point with its inputs held,
    and with a controller the loop law at its rate in front of the servos.

    Parameters
    ----------
    config : FmuConfig
        What it was exported from.

    Attributes
    ----------
    variables : list of FmuVariable
        The FMU's variables (parameters, inputs, outputs), in the model description's order.
    model : EmpactModel
        The model (rebuilt when a parameter changes).
    stepper : Stepper
        The integration (after `initialize`).
    law : LoopLaw or None
        The loop law (closed loop, after `initialize`).

    Raises
    ------
    ParameterError, TrimError
        When the configuration does not build a model, trim its start or build the law.
    """

    def __init__(self, config: FmuConfig) -> None:
        self.config = config
        self.closed = config.controller is not None
        assert config.point is not None
        self._fields = _parameter_fields(config.params, config.point)
        self.values = {name: value for name, _, value in self._fields}
        self._built_from = dict(self.values)
        self.model, self.op = self._build(config.params, config.point)
        m = self.model
        self.inputs: dict[str, float] = {}
        if self.closed:
            tau0 = config.point.tau if config.point.tau is not None else self.op.tau
            self.inputs.update(r_g_ref=float(self.op.r_g), tau_ref=float(tau0))
            self._free = [2, 3]
        else:
            self._free = [0, 1, 2, 3]
        self.inputs.update({m.inputs[j]: float(self.op.u[j]) for j in self._free})
        self.start: float = 0.0
        self.stop: float | None = None
        self.stepper = Stepper(m, self.op.x, self.op.u, rtol=config.rtol,
                               max_step=config.max_step, omega_min=config.omega_min,
                               max_steps=config.max_steps, method=config.method)
        self.law: LoopLaw | None = None
        self._k = 0  # the law's samples taken
        self._y = self.stepper.outputs()
        if self.closed:  # the law builds (controller against the loop) before any export
            self._make_law(2.0 / config.rate)
        self.variables = self._variables()

    # -- set-up ----------------------------------------------------------------------------
    def _build(self, params: Params, point: OperatingPoint) -> tuple[EmpactModel, Any]:
        opts = dict(self.config.options)
        # nu_r refers to the starting ratio, as in a scenario (`scenario_model`)
        model = nonlinear_model(params, reference_ratio=point.r_g, **opts)
        return model, trim(model, point)

    def _make_law(self, duration: float) -> LoopLaw:
        cfg = LoopConfig.of(self.model.params, rate=self.config.rate, **SHIPPED_LOOP)
        op = self.op
        point = {"r_g": op.r_g, "nu": op.nu, "omega_p": op.omega_p, "T_l": op.T_l,
                 "F_s": op.F_s}
        refs = {"r_g": np.array([[0.0, self.inputs["r_g_ref"]]]),
                "tau": np.array([[0.0, self.inputs["tau_ref"]]])}
        assert self.config.controller is not None
        law = LoopLaw(self.config.controller, self.model, point, op.u[:2], cfg, refs,
                      duration)
        self._ref_now = (self.inputs["r_g_ref"], self.inputs["tau_ref"])
        self._out_idx = np.array([self.model.outputs.index(s) for s in RAW_SIGNALS])
        return law

    def _variables(self) -> list[FmuVariable]:
        m = self.model
        out: list[FmuVariable] = []
        for name, f, _ in self._fields:
            meta = f.metadata
            out.append(FmuVariable(name, "parameter", meta["unit"], meta["lo"], meta["hi"],
                                   meta["doc"], self._getter(self.values, name),
                                   self._setter(self.values, name)))
        for name in self.inputs:
            unit = INPUT_UNITS.get(name, "-")
            what = {"r_g_ref": "ratio reference", "tau_ref": "slip set-point by its torque "
                    "ratio mu / mu_max (0.9: an 11 % torque reserve)"}.get(name, "input "
                                                                           "held over a step")
            out.append(FmuVariable(name, "input", unit, -math.inf, math.inf, what,
                                   self._getter(self.inputs, name),
                                   self._setter(self.inputs, name)))
        for k, name in enumerate(m.outputs):
            out.append(FmuVariable(name, "output", OUTPUT_UNITS.get(name, ""), -math.inf,
                                   math.inf, OUTPUT_DESCRIPTIONS.get(name, name),
                                   self._output(k)))
        for j, name in enumerate(m.inputs):
            out.append(FmuVariable(f"trim.{name}", "output", INPUT_UNITS.get(name, ""),
                                   -math.inf, math.inf, "the input that holds the starting "
                                   "point (the trim)", self._trim(j)))
        if self.closed:
            for j, name in enumerate(("T_mp", "T_ms")):
                out.append(FmuVariable(name, "output", "N m", -math.inf, math.inf,
                                       "servo torque the loop law commands (held over its "
                                       "sample)", self._command(j)))
        return out

    @staticmethod
    def _getter(table: dict[str, float], name: str) -> Callable[[], float]:
        return lambda: table[name]

    @staticmethod
    def _setter(table: dict[str, float], name: str) -> Callable[[float], None]:
        def set_(value: float) -> None:
            table[name] = float(value)
        return set_

    def _output(self, k: int) -> Callable[[], float]:
        return lambda: float(self._y[k])

    def _trim(self, j: int) -> Callable[[], float]:
        return lambda: float(self.op.u[j])

    def _command(self, j: int) -> Callable[[], float]:
        return lambda: float(self.stepper.u[j])

    # -- the run ---------------------------------------------------------------------------
    def initialize(self, start: float = 0.0, stop: float | None = None) -> None:
        """Start the run at `start` [s]: with changed parameters the model is rebuilt and the
        start trimmed again; closed loop, the law's tables are sized for ``stop - start``
        (the exported `FmuConfig.duration` without a stop time).

        Parameters
        ----------
        start : float
            Start time [s].
        stop : float, optional
            Stop time [s], if the importer gives one.

        Raises
        ------
        ParameterError, TrimError
            A changed parameter out of its range, or a start that does not trim.
        """
        self.start, self.stop = float(start), stop
        if self.values != self._built_from:
            changed = {k: v for k, v in self.values.items() if v != self._built_from[k]}
            params = self.config.params.from_dotted(
                {k: v for k, v in changed.items() if not k.startswith("initial.")})
            assert self.config.point is not None
            point = self.config.point.replace(**{k.removeprefix("initial."): v
                                                 for k, v in self.values.items()
                                                 if k.startswith("initial.")})
            self.model, self.op = self._build(params, point)
            self._built_from = dict(self.values)
        c = self.config
        self.stepper = Stepper(self.model, self.op.x, self.op.u, t0=self.start, rtol=c.rtol,
                               max_step=c.max_step, omega_min=c.omega_min,
                               max_steps=c.max_steps, method=c.method)
        self._k = 0
        if self.closed:
            span = (stop - start) if stop is not None and stop > start else \
                self.config.duration
            self.law = self._make_law(span)
            self._set_free()
        else:
            self._set_open()
        self._y = self.stepper.outputs()

    def _set_open(self) -> None:
        for j, name in enumerate(self.model.inputs):
            self.stepper.u[j] = self.inputs[name]

    def _set_free(self) -> None:
        for j in self._free:
            self.stepper.u[j] = self.inputs[self.model.inputs[j]]

    def do_step(self, t: float, step: float) -> str:
        """One communication step from `t` [s] over `step` [s] with the inputs held
        (closed loop: the law's samples that fall in it, each with the inputs of the step).

        Parameters
        ----------
        t : float
            The communication point [s] (the importer's; the run continues from its own).
        step : float
            The communication step [s], > 0.

        Returns
        -------
        str
            Empty when the step completed, else why the run stopped.
        """
        target = float(t) + float(step)
        st = self.stepper
        if not self.closed:
            self._set_open()
            status = st.advance(max(target, st.t))
            self._y = st.outputs()
            return st.message if status else ""
        assert self.law is not None
        dt = self.law.dt
        eps = 1e-9 * dt
        self._set_free()
        while target > st.t + eps:
            ts = self.start + self._k * dt
            if ts <= st.t + eps:
                if self._k >= self.law.n_k - 1:
                    return (f"t = {st.t:.6g} s: past the loop law's tables (sized for the "
                            "run's stop time; set one)")
                self._sample(ts)
                continue
            status = st.advance(ts if ts <= target + eps else target)
            if status:
                self._y = st.outputs()
                return st.message
        self._y = st.outputs()
        return ""

    def _sample(self, ts: float) -> None:
        """The law's sample at `ts`: the references, the measurements at the state and
        inputs now, the servo torques held to the next sample."""
        assert self.law is not None
        ref = (self.inputs["r_g_ref"], self.inputs["tau_ref"])
        if ref != self._ref_now:
            self._retarget(self._k, *ref)
        y = self.stepper.outputs()
        c = self.law.step(ts, y[self._out_idx])
        self.stepper.u[:2] = c
        self._k += 1

    def _retarget(self, k: int, r_g: float, tau: float) -> None:
        """New references from sample `k` on: the law's own reference tables
        (`LoopLaw._references`: the slip set-point of the torque ratio, its traction
        coefficient, the decoupler's ratio) for a constant (r_g, tau), written into its
        tables in place (the ratio reference's rate stays zero: the law sees a reference
        input's change as a step)."""
        law = self.law
        assert law is not None
        keep = law._tau_ref
        refs = law._references({"r_g": np.array([[0.0, r_g]]), "tau": np.array([[0.0, tau]])})
        law._tau_ref = keep
        tb = law._tb
        for name in ("r_g", "slip", "mu", "decoupling"):
            getattr(tb, name)[k:] = getattr(refs, name)[k:]
        if law.controller.schedule is not None:
            tb.mu_max[k:] = law.model.mu_max(refs.r_g[k:])
        self._ref_now = (r_g, tau)

    # -- state -----------------------------------------------------------------------------
    def snapshot(self) -> dict[str, Any]:
        """The run's state as plain JSON types (`restore` returns to it bitwise).

        Returns
        -------
        dict
            The integration (`Stepper.snapshot`), the inputs, the outputs and, closed loop,
            the law's state, sample count and reference tables.
        """
        snap: dict[str, Any] = {"stepper": self.stepper.snapshot(), "k": self._k,
                                "inputs": dict(self.inputs), "y": self._y.tolist()}
        if self.law is not None:
            tb = self.law._tb
            snap["law"] = {"z": self.law._z.tolist(), "k": self.law._k,
                           "ref": list(self._ref_now),
                           **{n: getattr(tb, n).tolist()
                              for n in ("r_g", "slip", "mu", "decoupling", "mu_max")}}
        return snap

    def restore(self, snap: Mapping[str, Any]) -> None:
        """Back to a `snapshot` of this run.

        Parameters
        ----------
        snap : mapping
            What `snapshot` returned.
        """
        self.stepper.restore(snap["stepper"])
        self._k = int(snap["k"])
        self.inputs.update(snap["inputs"])
        self._y = np.array(snap["y"], float)
        if self.law is not None and "law" in snap:
            s = snap["law"]
            self.law._z = np.array(s["z"], float)
            self.law._z_spare = np.empty_like(self.law._z)
            self.law._k = int(s["k"])
            self._ref_now = (float(s["ref"][0]), float(s["ref"][1]))
            for n in ("r_g", "slip", "mu", "decoupling", "mu_max"):
                getattr(self.law._tb, n)[:] = s[n]

    # -- files -----------------------------------------------------------------------------
    @classmethod
    def from_folder(cls, folder: str | Path) -> "CoSimulation":
        """The unit of an FMU's resources folder (what `export_fmu` wrote there).

        Parameters
        ----------
        folder : str or Path
            The resources folder.

        Returns
        -------
        CoSimulation
        """
        folder = Path(folder)
        spec = json.loads((folder / _SPEC).read_text())
        options = dict(spec["options"])
        for key, read in _TABLES.items():
            if key in options:
                options[key] = read(folder / options[key])
        point = OperatingPoint(**spec["point"])
        ctrl = load_controller(folder / _CONTROLLER) if spec["controller"] else None
        return cls(FmuConfig(load_params(folder / _PARAMS), options, point, ctrl,
                             **spec["solver"]))

    def write_folder(self, folder: Path, controller_file: str | Path | None) -> list[Path]:
        """Write what `from_folder` reads into `folder`.

        Parameters
        ----------
        folder : Path
            An existing folder.
        controller_file : str or Path, optional
            The controller JSON file (copied).

        Returns
        -------
        list of Path
            The files written.
        """
        c = self.config
        params = c.params
        options = dict(c.options)
        files = []
        if options.get("traction") is None and params.traction_table is not None:
            options["traction"] = params.traction_table  # the file's table, as an option
        if options.get("loss_map") is None and params.loss_map is not None:
            options["loss_map"] = params.loss_map  # likewise the file's loss map
        data = params.to_dict()
        data.get("traction", {}).pop("table", None)
        data.get("losses", {}).pop("table", None)
        for key in _TABLES:
            if options.get(key) is not None:
                src = Path(options[key].source)
                name = key + src.suffix
                shutil.copyfile(src, folder / name)
                files.append(folder / name)
                options[key] = name
        (folder / _PARAMS).write_text(dumps_params(Params.from_dict(data),
                                                   "parameters of the FMU (empact fmu export)"))
        files.append(folder / _PARAMS)
        if controller_file is not None:
            shutil.copyfile(controller_path(controller_file), folder / _CONTROLLER)
            files.append(folder / _CONTROLLER)
        assert c.point is not None
        spec = {"options": options,
                "point": {k: getattr(c.point, k) for k in ("r_g", "omega_p") + c.point.given},
                "controller": controller_file is not None,
                "solver": {"rate": c.rate, "method": c.method, "rtol": c.rtol,
                           "max_step": c.max_step, "omega_min": c.omega_min,
                           "max_steps": c.max_steps, "duration": c.duration}}
        (folder / _SPEC).write_text(json.dumps(spec, indent=1))
        files.append(folder / _SPEC)
        return files


class _Real(Real):
    """pythonfmu's Real with the unit and range FMI 2.0 allows on it."""

    def __init__(self, name: str, unit: str = "", lo: float = -math.inf,
                 hi: float = math.inf, **kwargs: Any) -> None:
        super().__init__(name, **kwargs)
        self._extra = {"unit": unit if unit not in ("", "-") else ""}
        if math.isfinite(lo):
            self._extra["min"] = f"{lo:.16g}"
        if math.isfinite(hi):
            self._extra["max"] = f"{hi:.16g}"

    def to_xml(self) -> Element:
        """The variable's XML node with its unit and range.

        Returns
        -------
        xml.etree.ElementTree.Element
        """
        node = super().to_xml()
        real = node.find("Real")
        assert real is not None
        for key, value in self._extra.items():
            if value:
                real.set(key, value)
        return node


#: the slave modules' namespaces, once per instance made in this process (`EmpactSlave`)
_NAMESPACES: list[Any] = []
_CAUSALITY = {"parameter": Fmi2Causality.parameter, "input": Fmi2Causality.input,
              "output": Fmi2Causality.output}


class EmpactSlave(Fmi2Slave):
    """The FMU's pythonfmu slave: `CoSimulation` of the resources folder behind the FMI
    calls (the exported script subclasses it as `MODEL_IDENTIFIER`).

    Parameters
    ----------
    **kwargs : Any
        pythonfmu's (``instance_name``, ``resources``: the FMU's resources folder).
    """

    author = "empact"
    description = ("empact: the nonlinear electromechanically actuated pushbelt CVT (slip "
                   "dynamics, creep shifting, actuation) with its Rosenbrock integrator")

    def __init__(self, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        # pythonfmu 0.7's binary releases a reference to the slave module's namespace that
        # it does not own at every instance it makes (``findClass``: ``Py_DECREF`` of the
        # borrowed ``PyModule_GetDict``): the third instance of an FMU in one process found
        # the namespace freed ("module has no attribute 'EmpactCVT'", or a crash); one
        # reference kept per instance balances it
        _NAMESPACES.append(vars(sys.modules[type(self).__module__]))
        self.unit = CoSimulation.from_folder(self.resources)
        step = 1.0 / self.unit.config.rate if self.unit.closed else 1e-3
        self.default_experiment = DefaultExperiment(0.0, 1.0, step)
        self._units: set[str] = set()
        for v in self.unit.variables:
            kw: dict[str, Any] = {"causality": _CAUSALITY[v.causality],
                                  "description": v.description, "getter": v.get}
            if v.causality == "parameter":
                kw.update(variability=Fmi2Variability.fixed, initial=Fmi2Initial.exact)
            else:
                kw.update(variability=Fmi2Variability.continuous)
            if v.set is not None:
                kw["setter"] = v.set
            lo, hi = (v.lo, v.hi) if v.causality == "parameter" else (-math.inf, math.inf)
            self.register_variable(_Real(v.name, v.unit, lo, hi, **kw), nested=False)
            if v.unit not in ("", "-"):
                self._units.add(v.unit)

    def to_xml(self, model_options: dict[str, str] | None = None) -> Element:
        """pythonfmu's model description with the units the variables use.

        Parameters
        ----------
        model_options : dict, optional
            pythonfmu's FMU options.

        Returns
        -------
        xml.etree.ElementTree.Element
        """
        root = super().to_xml(model_options or {})
        units = Element("UnitDefinitions")
        for u in sorted(self._units):
            SubElement(units, "Unit", {"name": u})
        root.insert(1, units)  # after CoSimulation, before the log categories (FMI 2.0)
        # every output is an initial unknown (calculated at initialisation; FMI 2.0 asks
        # the ModelStructure to list them after the outputs)
        structure = root.find("ModelStructure")
        assert structure is not None
        initial = SubElement(structure, "InitialUnknowns")
        for i, v in enumerate(self.vars.values()):
            if v.causality == Fmi2Causality.output:
                SubElement(initial, "Unknown", {"index": str(i + 1)})
        return root

    def setup_experiment(self, start_time: float, stop_time: float | None = None,
                         tolerance: float | None = None) -> None:
        """Keep the experiment's start and stop time.

        Parameters
        ----------
        start_time : float
            [s]
        stop_time : float or None
            [s]
        tolerance : float or None
            Ignored (the integrator runs at the exported tolerance).
        """
        self._times = (float(start_time), stop_time)

    def exit_initialization_mode(self) -> None:
        """Build and trim the start (`CoSimulation.initialize`); an error is logged."""
        start, stop = getattr(self, "_times", (0.0, None))  # (pythonfmu passes no stop)
        try:
            self.unit.initialize(start, stop)
        except Exception as exc:
            self.log(f"empact: {exc}", Fmi2Status.error)
            raise

    def do_step(self, current_time: float, step_size: float) -> bool:
        """One communication step (`CoSimulation.do_step`).

        Parameters
        ----------
        current_time : float
            [s]
        step_size : float
            [s]

        Returns
        -------
        bool
            False (with a logged message) when the run stopped.
        """
        why = self.unit.do_step(current_time, step_size)
        if why:
            self.log(f"empact: {why}", Fmi2Status.error)
            return False
        return True

    def _get_fmu_state(self) -> dict[str, Any]:
        return {"unit": self.unit.snapshot()}

    def _set_fmu_state(self, state: dict[str, Any]) -> None:
        self.unit.restore(state["unit"])


_SLAVE_SCRIPT = f'''"""The FMU's slave class (written by empact fmu export)."""
from empact.fmu import EmpactSlave


class {MODEL_IDENTIFIER}(EmpactSlave):
    """empact's nonlinear CVT (its configuration: empact_fmu.json beside this file)."""


# a reference to this namespace for as long as the process runs (see EmpactSlave)
_NAMESPACE = [globals()]
'''


def export_fmu(path: str | Path, params: Params, *, options: Mapping[str, Any] | None = None,
               point: OperatingPoint | None = None,
               controller: str | Path | None = None, rate: float = 1000.0,
               method: str = DEFAULT_METHOD, rtol: float = 1e-4, max_step: float = 0.01,
               omega_min: float = 1.0, duration: float = 60.0) -> Path:
    """Write an FMI 2.0 co-simulation FMU of the nonlinear machine (open loop, or with the
    loop law of a controller file); everything is checked before the file is written,
    atomically.

    Parameters
    ----------
    path : str or Path
        The FMU file (``.fmu``; replaced if it exists).
    params : Params
        The parameter set.
    options : mapping, optional
        Model options (`EXPORTED_OPTIONS`: ``drive``, ``load``, ``damping``, ``kinematics``,
        ``shift_law``; the measured ``traction``, ``thrust_ratio``, ``creep_map``,
        ``loss_map`` as their readers return them, copied into the FMU from their files).
    point : OperatingPoint, optional
        The starting point (default ``params.operating``).
    controller : str or Path, optional
        A controller JSON file (`empact.control.controller.load_controller`): the loop law
        (the shipped loop, `empact.control.law.SHIPPED_LOOP`, at `rate`) goes inside.
    rate : float
        The loop law's sample rate [Hz].
    method : str
        The integrator (`empact.nonlinear.simulation.METHODS`).
    rtol, max_step, omega_min : float
        As `empact.nonlinear.simulation.simulate`'s.
    duration : float
        Closed loop: the longest run [s] (`FmuConfig.duration`).

    Returns
    -------
    Path
        `path`.

    Raises
    ------
    ParameterError, TrimError
        A bad option, controller or starting point (nothing written).
    """
    path = Path(path)
    if path.suffix != ".fmu":
        raise ParameterError(f"{path}: an FMU file ends in .fmu")
    ctrl = load_controller(controller) if controller is not None else None
    unit = CoSimulation(FmuConfig(params, dict(options or {}), point, ctrl, rate, method,
                                  rtol, max_step, omega_min, duration=duration))
    with tempfile.TemporaryDirectory(prefix="empact-fmu-") as tmp:
        folder = Path(tmp)
        files = unit.write_folder(folder, controller)
        # a module name of its own for each FMU: an importer that loads two of them in one
        # process imports each slave from its own resources (pythonfmu imports it by name)
        script = folder / "script" / f"empact_fmu_{uuid.uuid4().hex}.py"
        script.parent.mkdir()
        script.write_text(_SLAVE_SCRIPT)
        with atomic_file(path) as dest:
            FmuBuilder.build_FMU(script, dest=dest, project_files=files,
                                 canGetAndSetFMUstate=True, canSerializeFMUstate=True)
    return path
