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

__all__ = ["linearize", "plant", "trim_point", "PLANT_INPUTS", "PLANT_OUTPUTS",
           "disturbance_input"]

#: the plant's control inputs (servo torques) and outputs (ratio and the two slip signals:
#: eq. 2 on the current radii, and at the operating ratio)
PLANT_INPUTS = ("T_mp", "T_ms")
PLANT_OUTPUTS = ("r_g", "nu", "nu_r")


def disturbance_input(model: EmpactModel) -> str:
    """The plant's disturbance input: the load torque ``T_l`` (torque-controlled load motor)
    or the load speed reference ``omega_l_ref`` (speed-controlled)."""
    return model.inputs[3]


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
        ``op.model.states``.  Units: SI, as in `empact.nonlinear.model`.  The output
        ``nu_r`` is linearised at the trimmed ratio (the slip of eq. 3 and Fig. 12).
    """
    m = op.model
    A, B, C, D = m.jacobian(op.x, op.u)
    # nu_r = 1 - omega_s / (r_g0 omega_p) at the trimmed ratio r_g0, whatever the model's
    # reference: d nu_r = d nu - (1 - nu0) d r_g / r_g0 (eq. 2 without its ratio term)
    i_nu, i_r, i_nur = (m.outputs.index(k) for k in ("nu", "r_g", "nu_r"))
    w = (1 - op.nu) / op.r_g
    C[i_nur], D[i_nur] = C[i_nu] - w * C[i_r], D[i_nu] - w * D[i_r]
    ii = _select(m.inputs, inputs, "input")
    oo = _select(m.outputs, outputs, "output")
    return statespace(A, B[:, ii], C[oo], D[np.ix_(oo, ii)], states=m.states,
                      inputs=[m.inputs[i] for i in ii], outputs=[m.outputs[o] for o in oo],
                      name=name)


def trim_point(model: EmpactModel, op: OperatingPoint) -> TrimResult:
    """`trim` at an operating point given by ratio, speed, slip and clamping force."""
    return trim(model, op.r_g, op.omega_p, nu=op.nu, F_s=op.F_s)


def plant(params: Params, op: OperatingPoint | None = None, *,
          model: EmpactModel | None = None, disturbance: bool = True, **options):
    """The exact plant of Fig. 2 at one operating point: servo torques (and the load as a
    disturbance) to ratio and slip.

    Parameters
    ----------
    params : Params
    op : OperatingPoint, optional
        Ratio, slip, clamping force and primary speed (default: ``params.operating``).
    model : EmpactModel, optional
        A built model (then `options` must be empty); default ``nonlinear_model(params,
        **options)``.
    disturbance : bool
        Include the load input (``T_l``, or ``omega_l_ref`` with a speed-controlled load) as
        a third input, the plant's disturbance.
    **options
        `empact.nonlinear.model.ModelOptions` fields.

    Returns
    -------
    (control.StateSpace, TrimResult)
        Inputs ``T_mp, T_ms`` [N m] (+ the disturbance), outputs ``r_g, nu, nu_r`` [-].
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
    inputs = PLANT_INPUTS + ((disturbance_input(model),) if disturbance else ())
    return linearize(trimmed, inputs, PLANT_OUTPUTS, name=name), trimmed
