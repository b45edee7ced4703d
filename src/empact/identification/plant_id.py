"""Fig. 2 of the paper: the (T_mp, T_ms) -> (r_g, nu) plant by approximate realisation.

As in the paper (Sec. 3, after Klaassen et al.), the nonlinear model is trimmed at an
operating point, each servo torque is stepped by a small amount on its own, and the step
responses of ratio and slip (deviations, divided by the step size) are realised as a
continuous state-space model with `realize_steps`.  The exact linearisation at the same point
(`empact.linearize.plant`) is the reference the identified model is compared with.

The slip responds strongly to the servo torques: at the default point a 1e-3 N m step already
makes the slip response about 10 % nonlinear, so the default steps are 1e-4 N m and the model
is integrated with a tight tolerance.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from .realization import RealizationResult, realize_steps

__all__ = ["StepExperiment", "PlantIdentification", "step_experiment", "identify_plant"]

INPUTS = ("T_mp", "T_ms")
OUTPUTS = ("r_g", "nu")


@dataclass(frozen=True, eq=False)
class StepExperiment:
    """Step responses of the nonlinear model around a trimmed point.

    Attributes
    ----------
    t : sample times [s], shape (n_t,)
    steps : responses per unit step, shape (n_t, 2, 2): outputs (r_g [-], nu [-]) per input
        (T_mp, T_ms) [1/(N m)]
    amplitudes : step sizes [N m], shape (2,)
    op : the trimmed operating point (`empact.trim.TrimResult`)
    """

    t: np.ndarray
    steps: np.ndarray
    amplitudes: np.ndarray
    op: object


@dataclass(frozen=True, eq=False)
class PlantIdentification:
    """Identified and exact plant at one operating point.

    Attributes
    ----------
    experiment : the step experiment
    realization : `RealizationResult` (identified model ``realization.sys``)
    exact : the exact linearisation, a named `control.StateSpace`
    """

    experiment: StepExperiment
    realization: RealizationResult
    exact: object

    @property
    def r_g(self) -> float:
        """Ratio of the operating point [-]."""
        return float(self.experiment.op.r_g)


def step_experiment(params, r_g: float, nu: float, F_s: float, omega_p: float, *,
                    amplitudes: Sequence[float] = (1e-4, 1e-4), duration: float = 6.0,
                    sample_rate: float = 500.0, rtol: float = 1e-8, model=None
                    ) -> StepExperiment:
    """Step each servo torque by its amplitude [N m] and record r_g and nu.

    Parameters
    ----------
    params : Params
    r_g, nu, F_s, omega_p : operating point: ratio [-], slip [-], clamping force [N], primary
        speed [rad/s]
    amplitudes : step sizes of T_mp and T_ms [N m], non-zero
    duration : record length [s]
    sample_rate : [Hz]
    rtol : integrator tolerance (see `empact.simulate.simulate`)
    model : an `EmpactModel` with torque inputs (default: `nonlinear_model(params)`)
    """
    from ..nonlinear import nonlinear_model
    from ..simulate import simulate
    from ..trim import trim

    amps = np.asarray(amplitudes, float)
    if amps.shape != (2,) or np.any(~np.isfinite(amps)) or np.any(amps == 0):
        raise ValueError(f"amplitudes = {list(amplitudes)!r}: need two non-zero step sizes [N m]")
    if not (duration > 0 and sample_rate > 0):
        raise ValueError(f"duration = {duration!r} s, sample_rate = {sample_rate!r} Hz: must be "
                         "> 0")
    model = nonlinear_model(params) if model is None else model
    op = trim(model, r_g, omega_p, nu=nu, F_s=F_s)
    cols = []
    for j, name in enumerate(INPUTS):
        u = op.u.copy()
        u[model.inputs.index(name)] += amps[j]
        res = simulate(model, op.x, {}, duration, u0=u, sample_rate=sample_rate, rtol=rtol,
                       name=f"step {name}")
        if not res.complete:
            raise ValueError(f"step in {name} at r_g = {r_g:g}: {res.message}")
        cols.append(np.column_stack([res.output(o) - getattr(op, o) for o in OUTPUTS])
                    / amps[j])
    return StepExperiment(t=res.t, steps=np.stack(cols, axis=-1), amplitudes=amps, op=op)


def identify_plant(params, r_g: float, nu: float = 0.004, F_s: float = 10e3,
                   omega_p: float = 300.0, *, order: int | None = None, min_fit: float = 98.0,
                   n_block_rows: int = 100, n_block_cols: int = 1200, **experiment
                   ) -> PlantIdentification:
    """Identify the (T_mp, T_ms) -> (r_g, nu) plant at one point (Fig. 2).

    Parameters
    ----------
    params : Params
    r_g, nu, F_s, omega_p : operating point (defaults: 0.4 % slip, 10 kN, 300 rad/s)
    order : model order (default: the smallest reaching `min_fit`)
    min_fit : worst-channel step fit to reach [%] when `order` is None
    n_block_rows, n_block_cols : Hankel size
    **experiment : passed to `step_experiment`
    """
    from ..linearize import plant

    exp = step_experiment(params, r_g, nu, F_s, omega_p, **experiment)
    real = realize_steps(exp.t, exp.steps, order, n_block_rows=n_block_rows,
                         n_block_cols=min(n_block_cols, len(exp.t) - n_block_rows),
                         min_fit=None if order is not None else min_fit,
                         inputs=INPUTS, outputs=OUTPUTS)
    exact, _ = plant(params, r_g, nu, F_s, omega_p)
    return PlantIdentification(experiment=exp, realization=real, exact=exact)
