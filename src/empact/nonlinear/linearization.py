"""Exact linearisation of the nonlinear model at a trimmed operating point.

The Jacobians are exact: forward-mode (tangent) derivatives of the compiled right-hand side,
hand derived and propagated along all state and input directions in one pass
(`empact.nonlinear._tangent._eval_tangent`) - no truncation or cancellation error, unlike a
fixed-step difference; equal to the complex step (``df/dx_j = Im f(x + i h e_j) / h``,
``h = 1e-30``, kept as the reference) to rounding.

The linear model's states are deviations from the trimmed state.  The driveline is in the
rotating frame (twists and speeds), so the shaft angles, which grow without bound at speed,
never appear; with torque-controlled drive and load motors the common speed of the shafts is a
pole at the origin (the driveline's rigid-body mode).

The plant of Fig. 2 (`plant`) is taken on the test bench by default (`BENCH_OPTIONS`: the
drive motor speed-controlled, the load motor torque-controlled, as in the paper's Secs. 3-4):
the same bench as a plant family (`empact.control.family.plant_family`), so that a family's
point and the single-point plant are the same system.
"""
from __future__ import annotations

import functools
from dataclasses import dataclass, field
from typing import Any, Iterator, Sequence

import numpy as np
from numpy.typing import NDArray

from .._deprecate import warn_renamed
from .._results import Result
from ..lti import index, statespace
from ..params import OperatingPoint, Params
from .equilibrium import TrimResult, trim
from .model import EmpactModel, nonlinear_model
from .options import VEHICLE_OPTIONS

__all__ = ["linearize", "linearized_plant", "linearize_many", "plant", "Plant",
           "PLANT_INPUTS", "PLANT_OUTPUTS", "BENCH_OPTIONS", "disturbance_input",
           "plant_options"]

#: the plant's control inputs (servo torques) and outputs (ratio and the two slip signals:
#: eq. 2 on the current radii, and at the operating ratio)
PLANT_INPUTS = ("T_mp", "T_ms")
PLANT_OUTPUTS = ("r_g", "nu", "nu_r")

#: model options of a plant by default: the test bench of the paper's Secs. 3 and 4
#: (speed-controlled drive motor, torque-controlled load motor)
BENCH_OPTIONS: dict[str, Any] = {"drive": "speed", "load": "torque"}


def plant_options(options: dict[str, Any]) -> dict[str, Any]:
    """The model options of a plant: `options` over the test bench's (`BENCH_OPTIONS`), or
    over the car's (`empact.nonlinear.options.VEHICLE_OPTIONS`: the engine and the road as
    torques) when they name ``driveline = "vehicle"``.

    Parameters
    ----------
    options : dict
        `empact.nonlinear.model.ModelOptions` fields given.

    Returns
    -------
    dict
        The fields the plant's model is built with.
    """
    base = VEHICLE_OPTIONS if options.get("driveline") == "vehicle" else BENCH_OPTIONS
    return {**base, **options}


def disturbance_input(model: EmpactModel) -> str:
    """The plant's disturbance input: the load torque ``T_l`` (torque-controlled load motor)
    or the load speed reference ``omega_l_ref`` (speed-controlled).

    Parameters
    ----------
    model : EmpactModel
        The nonlinear model (its ``load`` option decides).

    Returns
    -------
    str
        ``"T_l"`` [N m] or ``"omega_l_ref"`` [rad/s]: ``model.inputs[3]``.
    """
    return model.inputs[3]


def _select(names: Sequence[str], wanted: Sequence[str] | None, what: str) -> list[int]:
    if wanted is None:
        return list(range(len(names)))
    return [index(names, w, what) for w in wanted]


def _refer_nu_r(model: EmpactModel, C: NDArray, D: NDArray, r_g0, nu0) -> None:
    """``nu_r = 1 - omega_s / (r_g0 omega_p)`` at the trimmed ratio ``r_g0``, whatever the
    model's reference: ``d nu_r = d nu - (1 - nu0) d r_g / r_g0`` (eq. 2 without its ratio
    term); in place on the rows of `C`, `D` (stacked over the last two axes)."""
    i_nu, i_r, i_nur = (model.output_index(k) for k in ("nu", "r_g", "nu_r"))
    w = np.asarray((1 - np.asarray(nu0)) / np.asarray(r_g0))[..., None]
    C[..., i_nur, :] = C[..., i_nu, :] - w * C[..., i_r, :]
    D[..., i_nur, :] = D[..., i_nu, :] - w * D[..., i_r, :]


def linearize(op: TrimResult, inputs: Sequence[str] | None = None,
              outputs: Sequence[str] | None = None, name: str = "empact_linear"):
    """Named `control.StateSpace` of the model linearised at `op`.

    Parameters
    ----------
    op : TrimResult
        The trimmed point to linearise at (and its ``model``).
    inputs, outputs : sequence of str, optional
        The signals to keep, of ``op.model.inputs`` / ``op.model.outputs`` (default: all).
    name : str
        The system's name.

    Returns
    -------
    control.StateSpace
        ``dx = A x + B u``, ``y = C x + D u`` in deviations from `op`; states named as
        ``op.model.states``.  Units: SI, as in `empact.nonlinear.model`.  The output
        ``nu_r`` is linearised at the trimmed ratio (the slip of eq. 3 and Fig. 12).
        `linearized_plant` gives the same matrices without python-control.
    """
    return linearized_plant(op, inputs, outputs, name).system


def linearized_plant(op: TrimResult, inputs: Sequence[str] | None = None,
                     outputs: Sequence[str] | None = None, name: str = "empact_linear",
                     operating: dict[str, float] | None = None) -> "Plant":
    """`linearize` as a `Plant`: the matrices and signal names, the python-control object
    built only when asked (``Plant.system``; importing python-control takes ~1.5 s).

    Parameters
    ----------
    op : TrimResult
        The operating point (its ``model`` is linearised).
    inputs, outputs : sequence of str, optional
        Subsets of ``op.model.inputs`` / ``op.model.outputs`` (default: all).
    name : str
        System name.
    operating : dict, optional
        The plant's operating variables (default: none).

    Returns
    -------
    Plant
        ``dx = A x + B u``, ``y = C x + D u`` in deviations from `op` (SI), `trim` = `op`.
    """
    m = op.model
    A, B, C, D = m.jacobian(op.x, op.u)
    _refer_nu_r(m, C, D, op.r_g, op.nu)
    ii = _select(m.inputs, inputs, "input")
    oo = _select(m.outputs, outputs, "output")
    return Plant(A, B[:, ii], C[oo], D[np.ix_(oo, ii)], inputs=tuple(m.inputs[i] for i in ii),
                 outputs=tuple(m.outputs[o] for o in oo), states=tuple(m.states), name=name,
                 operating=dict(operating or {}), trim=op)


def linearize_many(model: EmpactModel, X: NDArray, U: NDArray, r_g0: NDArray,
                   nu0: NDArray) -> tuple[NDArray, NDArray, NDArray, NDArray]:
    """`linearize` at many trimmed points in one compiled loop: states `X` (N, n), inputs
    `U` (N, 4), their ratios and slips (N,) -> ``A`` (N, n, n), ``B`` (N, n, 4), ``C`` (N, ny,
    n), ``D`` (N, ny, 4) over all inputs and outputs, ``nu_r`` at each point's ratio.

    Parameters
    ----------
    model : EmpactModel
        The nonlinear model.
    X : array, shape (N, n)
        Trimmed states, ordered as ``model.states``.
    U : array, shape (N, 4)
        Their inputs, ordered as ``model.inputs``.
    r_g0 : array, shape (N,)
        Trimmed ratios [-] (the reference of ``nu_r``).
    nu0 : array, shape (N,)
        Trimmed slips [-].

    Returns
    -------
    A : ndarray, shape (N, n, n)
    B : ndarray, shape (N, n, 4)
    C : ndarray, shape (N, ny, n)
    D : ndarray, shape (N, ny, 4)
        ``dx = A x + B u``, ``y = C x + D u`` in deviations at each point, states, inputs
        and outputs ordered as ``model.states``, ``model.inputs`` and ``model.outputs``
        (``ny = len(model.outputs)``; SI units).
    """
    A, B, C, D = model.jacobian_many(X, U)
    _refer_nu_r(model, C, D, r_g0, nu0)
    return A, B, C, D


@dataclass(frozen=True, eq=False)
class Plant(Result):
    """An exact linear plant at one operating point: what `plant` and
    `empact.control.family.PlantFamily.plant` return.

    Attributes
    ----------
    A, B, C, D : ndarray, shapes (n, n), (n, m), (p, n), (p, m)
        ``dx = A x + B u``, ``y = C x + D u`` in deviations from the operating point (SI).
    inputs : tuple of str
        Input names (``T_mp, T_ms`` [N m] and the disturbance), m of them.
    outputs : tuple of str
        Output names (``r_g, nu, nu_r`` [-]), p of them.
    states : tuple of str
        State names (SI), n of them.
    name : str
        System name.
    operating : dict
        The operating variables of the point (``r_g, nu, F_s, omega_p, T_l``, SI).
    trim : TrimResult or None
        The trimmed point (None for a point of a stored family).
    """

    A: NDArray[np.float64]
    B: NDArray[np.float64]
    C: NDArray[np.float64]
    D: NDArray[np.float64]
    inputs: tuple[str, ...]
    outputs: tuple[str, ...]
    states: tuple[str, ...]
    name: str = "plant"
    operating: dict[str, float] = field(default_factory=dict)
    trim: TrimResult | None = None

    @functools.cached_property
    def system(self) -> Any:
        """The plant as a named `control.StateSpace` (built on first use: python-control
        is imported then)."""
        return statespace(self.A, self.B, self.C, self.D, inputs=self.inputs,
                          outputs=self.outputs, states=self.states, name=self.name)

    def state_space(self):
        """The plant as a named `control.StateSpace`."""
        return self.system

    # the names as python-control spells them: a Plant goes wherever a named system does
    # (`empact.export.system_dict`, `empact.lti.channel_zeros`)
    @property
    def input_labels(self) -> list[str]:
        """`inputs` as a list (python-control's name)."""
        return list(self.inputs)

    @property
    def output_labels(self) -> list[str]:
        """`outputs` as a list (python-control's name)."""
        return list(self.outputs)

    @property
    def state_labels(self) -> list[str]:
        """`states` as a list (python-control's name)."""
        return list(self.states)

    def __iter__(self) -> Iterator[Any]:
        """Deprecated: ``sys, trimmed = plant(...)`` (empact 0.1); use ``.state_space()``
        and ``.trim``."""
        warn_renamed("unpacking plant() as (system, trim)", ".state_space() and .trim of the "
                     "Plant it returns")
        return iter((self.system, self.trim))


def trim_point(model: EmpactModel, op: OperatingPoint) -> TrimResult:
    """Deprecated: `empact.nonlinear.equilibrium.trim` takes the `OperatingPoint` itself.

    Parameters
    ----------
    model : EmpactModel
        The nonlinear model.
    op : OperatingPoint
        The trim request.

    Returns
    -------
    TrimResult
        ``trim(model, op)`` (with a `DeprecationWarning`).
    """
    warn_renamed("trim_point(model, op)", "trim(model, op)")
    return trim(model, op)


def plant(params: Params, op: OperatingPoint | None = None, *,
          model: EmpactModel | None = None, disturbance: bool = True, **options) -> Plant:
    """The exact plant of Fig. 2 at one operating point: servo torques (and the load as a
    disturbance) to ratio and slip.

    Parameters
    ----------
    params : Params
    op : OperatingPoint, optional
        The operating point: ratio, speed and two of slip (or torque ratio), clamping force,
        load (default: ``params.operating``).
    model : EmpactModel, optional
        A built model (then `options` must be empty); default ``nonlinear_model(params,
        **BENCH_OPTIONS, **options)``: the test bench.
    disturbance : bool
        Include the load input (``T_l``, or ``omega_l_ref`` with a speed-controlled load) as
        a third input, the plant's disturbance.
    **options
        `empact.nonlinear.model.ModelOptions` fields.

    Returns
    -------
    Plant
        Inputs ``T_mp, T_ms`` [N m] (+ the disturbance), outputs ``r_g, nu, nu_r`` [-].

    Examples
    --------
    >>> from empact import default_params
    >>> p = plant(default_params())
    >>> p.inputs, p.outputs
    (('T_mp', 'T_ms', 'T_l'), ('r_g', 'nu', 'nu_r'))
    """
    if model is None:
        model = nonlinear_model(params, **plant_options(options))
    elif options:
        raise ValueError("give either model or options, not both")
    if "T_mp" not in model.inputs:
        raise ValueError("the (T_mp, T_ms) plant needs ratio_control = false")
    op = params.operating if op is None else op
    trimmed = trim(model, op)
    name = f"plant_rg_{op.r_g:g}".replace(".", "p")
    inputs = PLANT_INPUTS + ((disturbance_input(model),) if disturbance else ())
    operating = {k: getattr(trimmed, k) for k in ("r_g", "nu", "F_s", "omega_p", "T_l")}
    return linearized_plant(trimmed, inputs, PLANT_OUTPUTS, name, operating)
