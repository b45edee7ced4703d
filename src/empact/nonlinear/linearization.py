"""Exact linearisation of the nonlinear model at a trimmed operating point.

The Jacobians are computed by the complex step on the compiled right-hand side
(``df/dx_j = Im f(x + i h e_j) / h`` with ``h = 1e-30``): no subtraction, so no truncation or
cancellation error - exact to rounding, unlike a fixed-step difference.

The linear model's states are deviations from the trimmed state.  The driveline is in the
rotating frame (twists and speeds), so the shaft angles, which grow without bound at speed,
never appear; with torque-controlled drive and load motors the common speed of the shafts is a
pole at the origin (the driveline's rigid-body mode).
"""
from __future__ import annotations

from typing import Sequence

import numpy as np

from ..lti import index, statespace
from ..params import OperatingPoint, Params
from .model import EmpactModel, nonlinear_model
from .equilibrium import TrimResult, trim

__all__ = ["linearize", "plant", "trim_point", "PLANT_INPUTS", "PLANT_OUTPUTS"]

PLANT_INPUTS = ("T_mp", "T_ms")
PLANT_OUTPUTS = ("r_g", "nu")


def _select(names: Sequence[str], wanted: Sequence[str] | None, what: str) -> list[int]:
    if wanted is None:
        return list(range(len(names)))
    return [index(names, w, what) for w in wanted]


def linearize(op: TrimResult, inputs: Sequence[str] | None = None,
              outputs: Sequence[str] | None = None, name: str = "empact_linear"):
    """Named `control.StateSpace` of the model linearised at `op`.

    Parameters
    ----------
    op : TrimResult
        The operating point (its ``model`` is linearised).
    inputs, outputs : sequence of str, optional
        Subsets of ``op.model.inputs`` / ``op.model.outputs`` (default: all).
    name : str
        System name.

    Returns
    -------
    control.StateSpace
        ``dx = A x + B u``, ``y = C x + D u`` in deviations from `op`; states named as
        ``op.model.states``.  Units: SI, as in `empact.nonlinear.model`.
    """
    m = op.model
    A, B, C, D = m.jacobian(op.x, op.u)
    ii = _select(m.inputs, inputs, "input")
    oo = _select(m.outputs, outputs, "output")
    return statespace(A, B[:, ii], C[oo], D[np.ix_(oo, ii)], states=m.states,
                      inputs=[m.inputs[i] for i in ii], outputs=[m.outputs[o] for o in oo],
                      name=name)


def trim_point(model: EmpactModel, op: OperatingPoint) -> TrimResult:
    """`trim` at an operating point given by ratio, speed, slip and clamping force."""
    return trim(model, op.r_g, op.omega_p, nu=op.nu, F_s=op.F_s)


def plant(params: Params, op: OperatingPoint | None = None, *,
          model: EmpactModel | None = None, **options):
    """The exact (T_mp, T_ms) -> (r_g, nu) plant of Fig. 2 at one operating point.

    Parameters
    ----------
    params : Params
    op : OperatingPoint, optional
        Ratio, slip, clamping force and primary speed (default: ``params.operating``).
    model : EmpactModel, optional
        A built model (then `options` must be empty); default ``nonlinear_model(params,
        **options)``.
    **options
        `empact.nonlinear.model.ModelOptions` fields.

    Returns
    -------
    (control.StateSpace, TrimResult)
    """
    if model is None:
        model = nonlinear_model(params, **options)
    elif options:
        raise ValueError("give either model or options, not both")
    if "T_mp" not in model.inputs:
        raise ValueError("the (T_mp, T_ms) plant needs ratio_control = false")
    op = params.operating if op is None else op
    trimmed = trim_point(model, op)
    name = f"plant_rg_{op.r_g:g}".replace(".", "p")
    return linearize(trimmed, PLANT_INPUTS, PLANT_OUTPUTS, name=name), trimmed
