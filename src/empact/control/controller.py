"""The controller record: a named state space from tracking errors to servo torques, and its
files.

A controller maps the errors ``e = reference - measured`` of the measured outputs (``r_g`` and
a slip signal) to deviations of the servo torques (``T_mp``, ``T_ms``) from their holding
values::

    dx_c/dt = A x_c + B e,   du = C x_c + D e          (continuous, dt = 0)
    x_c[k+1] = A x_c[k] + B e[k],   du[k] = C x_c[k] + D e[k]   (discrete, sample time dt)

A gain-scheduled controller carries a `Schedule`: gains on its error inputs that depend on
the operating point (``e -> g(sigma) e``, then the fixed state space), interpolated over a
grid of the ratio, the set-point's torque ratio and the clamping force.  Scaling the errors
before the dynamics keeps the integrators' states continuous when the gains move (no bump).

Files: JSON (schema ``empact.controller``, version 2; version 1 files read the same) with A,
B, C, D, the names, units, ``dt``, the schedule with its interpolation rule and the design
data (with the whole loop specification, ``design["loop"]``:
`empact.control.loop.loop_specification`); ``.mat`` with the same fields (the schedule as
``schedule_axes`` names, ``schedule_<axis>`` grids, ``schedule_gains`` and
``schedule_interpolation``; the design as ``design_json``).

A scheduled controller's A, B, C, D are the unit-gain dynamics: closing them alone is not the
loop that runs.  ``empact control discretize pi.json --at r_g=1,tau=0.9,F_s=10000 --out
k.mat`` (`empact.control.loop.controller_at`) writes the controller folded at an operating
point, discrete at the loop's rate, with the loop it closes there (``loop_plant_A``, ``_B``,
``_C``: the sampled machine with the loop law's sensors and feedforwards, from the servo
torques to the errors).  In MATLAB::

    k = load('k.mat');
    K = ss(k.A, k.B, k.C, k.D, k.dt);                          % errors -> servo torques
    P = ss(k.loop_plant_A, k.loop_plant_B, k.loop_plant_C, 0, k.dt);  % servo torques -> errors
    pole(feedback(K, P, +1))       % du = K e, e = P du: the poles `control check` computes
"""
from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any, Mapping

import numpy as np
from numpy.typing import NDArray

from .._deprecate import warn_renamed
from .._io import atomic_file, atomic_write_text, parse_json
from .._lazy import lazy_module
from .._validate import check_number
from ..errors import ParameterError
from ..export import jsonable
from ..lti import DISCRETIZATIONS, cont2discrete, statespace
from ..nonlinear.model import INPUT_UNITS, OUTPUT_UNITS

_core = lazy_module("empact.control._law_core")  # (numba, on first use)
sio = lazy_module("scipy.io")

__all__ = ["Controller", "Schedule", "load_controller", "SCHEDULE_VARIABLES"]

SCHEMA = {"name": "empact.controller", "version": 2}
#: the schema versions `load_controller` reads (1: no interpolation rule, no loop record)
READABLE_VERSIONS = (1, 2)

#: how a schedule is read (written with it: `Schedule.to_dict`)
INTERPOLATION = {
    "rule": "multilinear in ln|gain| over the axes, ln r_g, tau and ln F_s; held at the "
            "grid's edges; each gain keeps its sign",
    "log_axes": ["r_g", "F_s"],
    "applies": "e -> gain * e on each error input, before A, B, C, D (no bump when the "
               "gains move)",
    "variables": {"r_g": "the measured ratio [-]",
                  "tau": "the set-point's mu(nu*, r_g*) / mu_max(r_g*) [-]",
                  "F_s": "the clamping feedforward's filtered force [N] (under the "
                         "safety-factor clamping its force, at least min_clamping; the "
                         "start's clamping force with neither)"}}

#: the signals a controller may measure (a slip or ratio, or its logarithm ``ln_...``)
MEASURABLE = ("r_g", "nu", "nu_r", "ln_r_g", "ln_nu", "ln_nu_r")

#: what a schedule may depend on: the measured ratio, the slip set-point's torque ratio
#: ``mu / mu_max``, the clamping force [N] the loop commands; interpolated in ``ln r_g``,
#: ``tau`` and ``ln F_s``
SCHEDULE_VARIABLES = ("r_g", "tau", "F_s")
_LOG_AXES = ("r_g", "F_s")


@dataclass(frozen=True, eq=False)
class Schedule:
    """Gains on a controller's error inputs over a grid of operating points.

    Attributes
    ----------
    axes : dict name -> array
        Increasing grid values of `SCHEDULE_VARIABLES` (SI).
    gains : array, shape ``grid + (n_e,)``
        The gain on each error input at each grid point (non-zero, one sign per input).

    Calling it with a mapping of the variables gives the gains there (multilinear in
    ``ln |gain|`` over ``ln r_g``, ``tau``, ``ln F_s``; held at the grid's edges).
    """

    axes: Mapping[str, NDArray[np.float64]]
    gains: NDArray[np.float64]

    def __post_init__(self) -> None:
        axes = {}
        for name, grid in self.axes.items():
            if name not in SCHEDULE_VARIABLES:
                raise ParameterError(f"schedule axis {name!r}: choose from "
                                     f"{', '.join(SCHEDULE_VARIABLES)}")
            g = np.asarray(grid, float).ravel()
            if g.size < 1 or not np.all(np.isfinite(g)) or np.any(np.diff(g) <= 0) or \
                    (name in _LOG_AXES and np.any(g <= 0)):
                raise ParameterError(f"schedule axis {name!r}: must be finite and increasing"
                                     + (" and positive" if name in _LOG_AXES else ""))
            axes[name] = g
        gains = np.asarray(self.gains, float)
        shape = tuple(len(g) for g in axes.values())
        if gains.shape[:-1] != shape or not np.all(np.isfinite(gains)):
            raise ParameterError(f"schedule gains: shape {gains.shape}, expected "
                                 f"{shape} + (inputs,) of finite numbers")
        sign = np.sign(gains.reshape(-1, gains.shape[-1]))
        if np.any(sign == 0) or np.any(sign != sign[:1]):
            raise ParameterError("schedule gains: each input's gain must keep one sign, "
                                 "never zero")
        object.__setattr__(self, "axes", axes)
        object.__setattr__(self, "gains", gains)
        object.__setattr__(self, "_sign", sign[0])
        object.__setattr__(self, "_log", np.log(np.abs(gains)))
        object.__setattr__(self, "_q", [np.log(g) if n in _LOG_AXES else g
                                        for n, g in axes.items()])
        object.__setattr__(self, "_qlist", [q.tolist() for q in self._q])
        # the packed table of `gains_at` (`empact.control._law_core.pack_schedule`)
        table = np.ascontiguousarray(self._log)
        object.__setattr__(self, "_packed", _core.pack_schedule(
            self._qlist, [n in _LOG_AXES for n in axes],
            [s // table.itemsize for s in table.strides[:-1]],
            [SCHEDULE_VARIABLES.index(n) for n in axes], table.ravel().tolist(),
            gains.shape[-1]))
        object.__setattr__(self, "_n_e", gains.shape[-1])
        object.__setattr__(self, "_sign_list", sign[0].tolist())
        object.__setattr__(self, "_positive", bool(np.all(sign[0] > 0)))

    def __call__(self, point: Mapping[str, float]) -> NDArray[np.float64]:
        """The gains at an operating point (``{name: value}`` for every axis)."""
        return np.array(self.gains_at([float(point[name]) for name in self.axes]))

    def gains_at(self, values: list[float]) -> list[float]:
        """The gains at the operating point `values` (one per axis, in the order of `axes`),
        as floats (what a sampled law calls at every sample): the interpolation compiled
        (`empact.control._law_core.schedule_log_gains`), each value rounded as the array
        form's elementwise arithmetic would, then `exp_gains`.

        Parameters
        ----------
        values : list of float
            The operating point: one value per axis, in the order of `axes` (SI units).
        """
        out = np.empty(self._n_e)
        _core.schedule_log_gains(self._packed, np.array(values, float), False, out)
        return self.exp_gains(out.tolist())

    def exp_gains(self, log_gains: list[float]) -> list[float]:
        """The gains of the log-gains ``ln |gain|`` (numpy's ``exp``, with the signs).

        Parameters
        ----------
        log_gains : list of float
            ``ln |gain|`` of each scheduled gain, in the schedule's order.
        """
        gains = np.exp(np.array(log_gains)).tolist()
        return gains if self._positive else [s * x for s, x in zip(self._sign_list, gains)]

    def to_dict(self) -> dict[str, Any]:
        """Plain data (the file layout)."""
        return {"axes": {k: v.tolist() for k, v in self.axes.items()},
                "gains": self.gains.tolist(), "interpolation": INTERPOLATION}


@dataclass(frozen=True, eq=False)
class Controller:
    """A linear controller from tracking errors to servo-torque deviations.

    Attributes
    ----------
    A, B, C, D : arrays, shapes (n_c, n_c), (n_c, n_e), (n_u, n_c), (n_u, n_e)
    measured : tuple of str
        The measured outputs whose errors are the inputs (e.g. ``("r_g", "nu")``).
    outputs : tuple of str
        The servo torques driven (``("T_mp", "T_ms")``), deviations [N m].
    dt : float
        Sample time [s]; 0 for a continuous controller.
    method : str
        How it was designed (``"pi"``, ``"hinf"``, ...).
    design : dict
        Design data (gains, weights, margins, the family's grid, the nominal point).
    schedule : Schedule or None
        Gains on the error inputs by operating point (a gain-scheduled controller).
    """

    A: NDArray[np.float64]
    B: NDArray[np.float64]
    C: NDArray[np.float64]
    D: NDArray[np.float64]
    measured: tuple[str, ...]
    outputs: tuple[str, ...]
    dt: float = 0.0
    method: str = ""
    design: Mapping[str, Any] = field(default_factory=dict)
    schedule: Schedule | None = None

    def __post_init__(self) -> None:
        A, B, C, D = (np.atleast_2d(np.asarray(M, float)) for M in (self.A, self.B, self.C,
                                                                      self.D))
        n = A.shape[0] if A.size else 0
        A = A.reshape(n, n)
        B = B.reshape(n, len(self.measured))
        C = C.reshape(len(self.outputs), n)
        D = D.reshape(len(self.outputs), len(self.measured))
        for name, M in (("A", A), ("B", B), ("C", C), ("D", D)):
            if not np.all(np.isfinite(M)):
                raise ParameterError(f"controller {name}: entries must be finite")
        for name, M in (("A", A), ("B", B), ("C", C), ("D", D)):
            object.__setattr__(self, name, M)
        object.__setattr__(self, "measured", tuple(self.measured))
        object.__setattr__(self, "outputs", tuple(self.outputs))
        object.__setattr__(self, "dt", check_number("dt", self.dt, 0.0, unit="s"))
        object.__setattr__(self, "_discrete", {})  # `discretize`'s results, by (dt, method)
        if self.schedule is not None and self.schedule.gains.shape[-1] != len(self.measured):
            raise ParameterError(f"controller schedule: {self.schedule.gains.shape[-1]} gains "
                                 f"per point for {len(self.measured)} inputs")

    def at(self, point: Mapping[str, float]) -> "Controller":
        """The controller frozen at an operating point: its schedule's gains folded into B
        and D (an LTI controller; itself when it has no schedule).

        Parameters
        ----------
        point : mapping of str to float
            The operating point: a value for each of the schedule's axes (e.g. ``r_g``) in
            their SI units.
        """
        if self.schedule is None:
            return self
        g = self.schedule(point)
        return Controller(self.A, self.B * g, self.C, self.D * g, self.measured, self.outputs,
                          self.dt, self.method, self.design)

    @property
    def inputs(self) -> tuple[str, ...]:
        """Input names: ``e_<measured>`` (reference minus measurement)."""
        return tuple(f"e_{m}" for m in self.measured)

    @property
    def n(self) -> int:
        """Number of controller states."""
        return self.A.shape[0]

    def state_space(self):
        """The controller as a named `control.StateSpace`."""
        return statespace(self.A, self.B, self.C, self.D, inputs=self.inputs,
                          outputs=self.outputs, states=[f"xc{i}" for i in range(self.n)],
                          name=f"controller_{self.method}", dt=self.dt or None)

    def statespace(self):
        """Deprecated: `state_space`."""
        warn_renamed("Controller.statespace", "state_space")
        return self.state_space()

    def discretize(self, dt: float, method: str = "tustin") -> "Controller":
        """The controller at sample time `dt` [s] by `method` (one of
        `empact.lti.DISCRETIZATIONS`, Tustin by default; ``scipy.signal.cont2discrete``'s
        formulas, `empact.lti.cont2discrete`); computed once per `dt` and `method` (a loop law
        built at every point of a family discretizes the same controller each time).

        Parameters
        ----------
        dt : float
            Sample time [s], > 0.
        method : str, optional
            One of `empact.lti.DISCRETIZATIONS` (default ``"tustin"``).
        """
        if self.dt:
            raise ParameterError(f"controller is already discrete (dt = {self.dt:g} s)")
        dt = check_number("dt", dt, 0.0, 1.0, lo_open=True, unit="s")
        if method not in DISCRETIZATIONS:
            raise ParameterError(f"discretization method {method!r}: one of "
                                 f"{', '.join(DISCRETIZATIONS)}")
        done = self._discrete.get((dt, method))
        if done is not None:
            return done
        if self.n == 0:
            done = Controller(self.A, self.B, self.C, self.D, self.measured, self.outputs,
                              dt, self.method, self.design, self.schedule)
        else:
            Ad, Bd, Cd, Dd = cont2discrete(self.A, self.B, self.C, self.D, dt, method)
            done = Controller(Ad, Bd, Cd, Dd, self.measured, self.outputs, dt, self.method,
                              {**self.design, "discretized": method}, self.schedule)
        self._discrete[(dt, method)] = done
        return done

    def to_dict(self) -> dict[str, Any]:
        """The controller as plain JSON types (the file layout of `save`'s JSON: matrices
        as nested lists, NaN as None).

        Returns
        -------
        dict
            ``A``, ``B``, ``C``, ``D``, the names and units, ``dt`` [s], ``method``,
            ``design`` and ``schedule``.
        """
        return jsonable(self._layout())

    def _layout(self) -> dict[str, Any]:
        """Arrays and names (the file layout: `save` writes it)."""
        return {"A": self.A, "B": self.B, "C": self.C, "D": self.D,
                "inputs": list(self.inputs), "measured": list(self.measured),
                "outputs": list(self.outputs), "dt": self.dt, "method": self.method,
                "inputs_units": [OUTPUT_UNITS.get(m, "-") for m in self.measured],
                "outputs_units": [INPUT_UNITS[o] for o in self.outputs],
                "design": dict(self.design),
                "schedule": None if self.schedule is None else self.schedule.to_dict()}

    def save(self, path: str | os.PathLike[str]) -> Path:
        """Write JSON or ``.mat`` (by the suffix) atomically.

        Parameters
        ----------
        path : str or path-like
            The file: ``.json`` or ``.mat``.
        """
        suffix = Path(path).suffix.lower()
        data = self._layout()
        if suffix == ".json":
            atomic_write_text(path, json.dumps(jsonable({"schema": SCHEMA, **data}),
                                               indent=1) + "\n")
        elif suffix == ".mat":
            flat = {k: v for k, v in data.items() if k not in ("design", "schedule")}
            for k in ("inputs", "measured", "outputs", "inputs_units", "outputs_units"):
                flat[k] = np.array(flat[k], dtype=object)
            if self.schedule is not None:
                flat["schedule_axes"] = np.array(list(self.schedule.axes), dtype=object)
                for name, grid in self.schedule.axes.items():
                    flat[f"schedule_{name}"] = grid
                flat["schedule_gains"] = self.schedule.gains
                flat["schedule_interpolation"] = json.dumps(INTERPOLATION)
            plant = data["design"].get("loop_plant")
            if isinstance(plant, Mapping):  # the loop at a point (`controller_at`)
                for key in ("A", "B", "C"):
                    flat[f"loop_plant_{key}"] = np.asarray(plant[key], float)
            flat["design_json"] = json.dumps(jsonable(data["design"]))
            with atomic_file(path) as tmp:
                sio.savemat(tmp, flat)
        else:
            raise ParameterError(f"{path}: a controller is written as .json or .mat, not "
                                 f"{suffix or 'no suffix'!r}")
        return Path(path)


def _names(doc: Mapping[str, Any], key: str, src: Path, allowed: tuple[str, ...]
           ) -> tuple[str, ...]:
    """A list of distinct signal names of a controller file, each one of `allowed`."""
    names = doc.get(key)
    if not isinstance(names, list) or not names or \
            not all(isinstance(n, str) for n in names):
        raise ParameterError(f"{src}: {key} = {names!r}: must be a list of signal names "
                             f"({', '.join(allowed)})")
    for n in names:
        if n not in allowed:
            raise ParameterError(f"{src}: {key} names {n!r}; allowed: {', '.join(allowed)}")
    if len(set(names)) < len(names):
        raise ParameterError(f"{src}: {key} = {names!r}: a signal named twice")
    return tuple(names)


def _units(doc: Mapping[str, Any], key: str, expected: list[str], of: str, src: Path) -> None:
    """Check the optional unit list `key` of a controller file: one unit per signal of `of`,
    each the SI unit empact uses for that signal (a controller is read in SI only)."""
    units = doc.get(key)
    if units is None:
        return
    if not isinstance(units, list) or not all(isinstance(u, str) for u in units):
        raise ParameterError(f"{src}: {key} must be a list of unit names, one per {of} signal")
    if len(units) != len(expected):
        raise ParameterError(f"{src}: {key} has {len(units)} units for {len(expected)} {of} "
                             f"signals ({', '.join(expected)})")
    for u, e in zip(units, expected):
        if u != e:
            raise ParameterError(f"{src}: {key} gives {u!r} where the signal's unit is "
                                 f"{e!r}; a controller file is in SI ({', '.join(expected)})")


def _matrix(doc: Mapping[str, Any], key: str, shape: tuple[int, int], what: str,
            src: Path) -> NDArray[np.float64]:
    """Matrix `key` of a controller file: rows of finite JSON numbers, of `shape`."""
    rows = doc.get(key)
    expected = f"{shape[0]} x {shape[1]} ({what})"
    if rows is None:
        raise ParameterError(f"{src}: no {key} matrix (expected {expected})")
    if shape[0] == 0 or shape[1] == 0:  # an empty matrix: [] or rows of []
        if isinstance(rows, list) and all(r == [] for r in rows) and len(rows) in (0, shape[0]):
            return np.zeros(shape)
    if not isinstance(rows, list) or not all(isinstance(r, list) for r in rows):
        raise ParameterError(f"{src}: {key} must be a list of rows (expected {expected})")
    got = (len(rows), len(rows[0]) if rows else 0)
    if got != shape or any(len(r) != shape[1] for r in rows):
        lengths = sorted({len(r) for r in rows})
        raise ParameterError(f"{src}: {key} has {len(rows)} rows of "
                             f"{', '.join(map(str, lengths)) or 0} entries; expected "
                             f"{expected}")
    for i, r in enumerate(rows):
        for j, x in enumerate(r):
            if isinstance(x, bool) or not isinstance(x, (int, float)):
                raise ParameterError(f"{src}: {key}[{i}][{j}] = {x!r}: must be a number")
            if not np.isfinite(x):
                raise ParameterError(f"{src}: {key}[{i}][{j}] = {x!r}: must be finite")
    return np.array(rows, float).reshape(shape)


def _schedule(doc: Any, src: Path) -> Schedule:
    """A controller file's ``schedule``: ``{"axes": {name: [values]}, "gains": nested
    rows}``."""
    if not isinstance(doc, dict) or not isinstance(doc.get("axes"), dict) \
            or "gains" not in doc:
        raise ParameterError(f"{src}: schedule must be a table with axes (name -> values) and "
                             "gains")
    try:
        axes = {str(k): np.array(v, float) for k, v in doc["axes"].items()}
        gains = np.array(doc["gains"], float)
    except (TypeError, ValueError):
        raise ParameterError(f"{src}: schedule axes and gains must be numbers") from None
    return Schedule(axes=axes, gains=gains)


#: a controller named by this prefix is a shipped one: ``shipped:pi`` is
#: ``empact/data/control/pi.json``
SHIPPED = "shipped:"


def shipped_controllers() -> tuple[str, ...]:
    """The names of the shipped controllers (``pi``, ``hinf``), for ``shipped:NAME``.

    Returns
    -------
    tuple of str
        Sorted names.
    """
    folder = resources.files("empact.data").joinpath("control")
    return tuple(sorted(p.name[:-5] for p in folder.iterdir()
                        if p.name.endswith(".json")))


def controller_path(ref: str | os.PathLike[str]) -> Path:
    """The file a controller reference names: the path itself, or for ``shipped:NAME`` the
    shipped file (``empact/data/control/NAME.json``).

    Parameters
    ----------
    ref : str or path-like
        A controller file or ``shipped:NAME`` (one of `shipped_controllers`).

    Returns
    -------
    pathlib.Path
        The file.

    Raises
    ------
    ParameterError
        For an unknown shipped name.
    """
    if not str(ref).startswith(SHIPPED):
        return Path(ref)
    name = str(ref)[len(SHIPPED):]
    if name not in shipped_controllers():
        raise ParameterError(f"controller {str(ref)!r}: no shipped controller {name!r} "
                             f"(shipped: {', '.join(shipped_controllers())})")
    return Path(str(resources.files("empact.data").joinpath("control", f"{name}.json")))


def load_controller(path: str | os.PathLike[str]) -> Controller:
    """Read a controller JSON file (`Controller.save`), or a shipped one (``shipped:pi``);
    one-line errors for bad files, naming the key, its value and what is allowed.

    Parameters
    ----------
    path : str or path-like
        A JSON file of schema ``empact.controller``, or ``shipped:NAME`` (`SHIPPED`, one of
        `shipped_controllers`): every command and function that reads a controller takes
        both.

    Returns
    -------
    Controller
        From the measured errors (``r_g`` and a slip signal, or their logarithms) to the
        servo torques ``(T_mp, T_ms)`` [N m]: A, B, C, D, the sample time ``dt`` [s] (0:
        continuous), the design data and the schedule, if any.

    Raises
    ------
    ParameterError
        For a missing file, a file that is not JSON of the schema, or a bad key (names,
        matrix shapes, ``dt``, ``design``, ``schedule``).
    """
    p = controller_path(path)
    doc = parse_json(p, "controller")
    if not isinstance(doc, dict) or not isinstance(doc.get("schema"), dict) \
            or doc["schema"].get("name") != SCHEMA["name"]:
        raise ParameterError(f"{p}: not a controller file (schema {SCHEMA['name']!r} "
                             "expected)")
    version = doc["schema"].get("version", 1)
    if isinstance(version, bool) or not isinstance(version, int) or version < 1:
        raise ParameterError(f"{p}: schema version {version!r}: must be a whole number >= 1")
    newest = max(READABLE_VERSIONS)
    if version > newest:
        raise ParameterError(f"{p}: controller schema version {version} is newer than this "
                             f"empact reads (up to {newest}); update empact")
    if version not in READABLE_VERSIONS:
        raise ParameterError(f"{p}: schema version {version}: this empact reads "
                             f"{', '.join(map(str, READABLE_VERSIONS))}")
    measured = _names(doc, "measured", p, MEASURABLE)
    outputs = _names(doc, "outputs", p, ("T_mp", "T_ms"))
    _units(doc, "inputs_units", [OUTPUT_UNITS.get(m, "-") for m in measured], "measured", p)
    _units(doc, "outputs_units", [INPUT_UNITS[o] for o in outputs], "outputs", p)
    a = doc.get("A")
    n = len(a) if isinstance(a, list) else 0
    ne, nu = len(measured), len(outputs)
    A = _matrix(doc, "A", (n, n), "states x states", p)
    B = _matrix(doc, "B", (n, ne), "states x measured", p)
    C = _matrix(doc, "C", (nu, n), "outputs x states", p)
    D = _matrix(doc, "D", (nu, ne), "outputs x measured", p)
    dt = doc.get("dt", 0.0)
    if isinstance(dt, bool) or not isinstance(dt, (int, float)):
        raise ParameterError(f"{p}: dt = {dt!r}: must be a number of seconds (0: continuous)")
    design = doc.get("design", {})
    if not isinstance(design, dict):
        raise ParameterError(f"{p}: design = {design!r}: must be a table")
    try:
        sched = doc.get("schedule")
        schedule = None if sched is None else _schedule(sched, p)
        return Controller(A=A, B=B, C=C, D=D, measured=measured, outputs=outputs,
                          dt=float(dt), method=str(doc.get("method", "")), design=design,
                          schedule=schedule)
    except ParameterError as exc:
        raise ParameterError(f"{p}: {exc}") from None
