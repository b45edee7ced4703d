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

from .nonlinear import EmpactModel, nonlinear_model
from .params import Params
from .trim import TrimResult, trim

__all__ = ["linearize", "plant", "transmission_zeros", "frequency_response", "PLANT_INPUTS",
           "PLANT_OUTPUTS"]

PLANT_INPUTS = ("T_mp", "T_ms")
PLANT_OUTPUTS = ("r_g", "nu")


def _select(names: Sequence[str], wanted: Sequence[str] | None, what: str) -> list[int]:
    if wanted is None:
        return list(range(len(names)))
    idx = []
    for w in wanted:
        if w not in names:
            raise ValueError(f"unknown {what} {w!r}: choose from {', '.join(names)}")
        idx.append(list(names).index(w))
    return idx


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
        ``op.model.states``.  Units: SI, as in `empact.nonlinear`.
    """
    import control

    m = op.model
    A, B, C, D = m.jacobian(op.x, op.u)
    ii = _select(m.inputs, inputs, "input")
    oo = _select(m.outputs, outputs, "output")
    return control.ss(A, B[:, ii], C[oo], D[np.ix_(oo, ii)], states=list(m.states),
                      inputs=[m.inputs[i] for i in ii], outputs=[m.outputs[o] for o in oo],
                      name=name)


def plant(params: Params, r_g: float, nu: float, F_s: float, omega_p: float,
          model: EmpactModel | None = None, **options):
    """The exact (T_mp, T_ms) -> (r_g, nu) plant of Fig. 2 at one operating point.

    Parameters
    ----------
    params : Params
    r_g : float
        Ratio [-].
    nu : float
        Slip [-].
    F_s : float
        Secondary clamping force [N].
    omega_p : float
        Primary speed [rad/s].
    model : EmpactModel, optional
        A built model (then `options` must be empty); default ``nonlinear_model(params,
        **options)``.

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
    op = trim(model, r_g, omega_p, nu=nu, F_s=F_s)
    return linearize(op, PLANT_INPUTS, PLANT_OUTPUTS, name=f"plant_rg_{r_g:g}".replace(".", "p")), op


def transmission_zeros(sys, input: str, output: str, scale: np.ndarray | None = None,
                       max_abs: float = 1e7) -> np.ndarray:
    """Finite zeros of one SISO channel [rad/s, complex], sorted by magnitude.

    Solved as the finite generalised eigenvalues of the Rosenbrock pencil
    ``([[A, b], [c, d]], [[I, 0], [0, 0]])`` after diagonal state scaling ``x = S x~`` (states
    of very different units); zeros above `max_abs` [rad/s] are treated as infinite.
    """
    from scipy.linalg import eig

    i = list(sys.input_labels).index(input)
    o = list(sys.output_labels).index(output)
    A, b, c, d = sys.A, sys.B[:, [i]], sys.C[[o]], sys.D[o, i]
    n = A.shape[0]
    S = np.ones(n) if scale is None else np.asarray(scale, float)
    A = A * S[None, :] / S[:, None]
    b = b / S[:, None]
    c = c * S[None, :]
    cs = np.max(np.abs(c))
    bs = np.max(np.abs(b))
    M = np.block([[A, b / bs], [c / cs, np.array([[d / (bs * cs)]])]])
    N = np.zeros((n + 1, n + 1))
    N[:n, :n] = np.eye(n)
    w, beta = eig(M, N, right=False, homogeneous_eigvals=True)
    finite = np.abs(beta) > 1e-12 * np.abs(w)
    z = w[finite] / beta[finite]
    z = z[np.abs(z) < max_abs]
    return z[np.argsort(np.abs(z))]


def frequency_response(sys, omega: np.ndarray, label: str = ""):
    """Exact frequency response ``C (j w I - A)^-1 B + D`` of a `control.StateSpace`.

    Parameters
    ----------
    sys : control.StateSpace
    omega : array, shape (n_f,)
        Frequencies [rad/s].
    label : str

    Returns
    -------
    empact.lumped.FrequencyResponse
        ``H`` of shape (n_out, n_in, n_f).
    """
    from .lumped import FrequencyResponse

    w = np.atleast_1d(np.asarray(omega, float))
    n = sys.A.shape[0]
    Z = 1j * w[:, None, None] * np.eye(n)[None] - sys.A[None]
    X = np.linalg.solve(Z, np.broadcast_to(sys.B, (len(w),) + sys.B.shape))
    H = np.einsum("on,fni->oif", sys.C, X) + sys.D[:, :, None]
    return FrequencyResponse(omega=w, H=H, inputs=tuple(sys.input_labels),
                             outputs=tuple(sys.output_labels), label=label)
