"""Fig. 2 of the paper: the (T_mp, T_ms) -> (r_g, nu, nu_r) plant by approximate realisation.

As in the paper (Sec. 3, after Klaassen et al.), the nonlinear model is trimmed at an
operating point, each servo torque is stepped by a small amount on its own, and the step
responses of ratio and slip (deviations, divided by the step size; both slip signals: ``nu``
of eq. 2 on the current radii and ``nu_r = 1 - omega_s / (r_g0 omega_p)`` at the operating
ratio ``r_g0``) are realised as a
continuous state-space model with `realize_steps`.  The exact linearisation at the same point
(`empact.nonlinear.linearization.plant`) is the reference the identified model is compared with.

The slip responds strongly to the primary servo (with equal translation its torque presses
both sheaves), so the default steps are small (1e-5 N m: the response stays linear) and the
model is integrated with a tight tolerance.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Sequence

import numpy as np

from .._results import Result
from .._validate import check_number
from ..errors import ParameterError
from ..identification.realization import RealizationResult, realize_steps
from ..nonlinear.equilibrium import TrimResult, trim
from ..nonlinear.linearization import plant
from ..nonlinear.model import nonlinear_model
from ..nonlinear.simulation import simulate
from ..params import OperatingPoint, Params

__all__ = ["StepExperiment", "PlantIdentification", "step_experiment", "identify_plant"]

INPUTS = ("T_mp", "T_ms")
OUTPUTS = ("r_g", "nu", "nu_r")


@dataclass(frozen=True, eq=False)
class StepExperiment(Result):
    """Step responses of the nonlinear model around a trimmed point.

    Attributes
    ----------
    t : sample times [s], shape (n_t,)
    steps : responses per unit step, shape (n_t, 3, 2): outputs (r_g, nu, nu_r [-]) per input
        (T_mp, T_ms) [1/(N m)]
    amplitudes : step sizes [N m], shape (2,)
    op : the trimmed operating point (`empact.nonlinear.equilibrium.TrimResult`)
    """

    t: np.ndarray
    steps: np.ndarray
    amplitudes: np.ndarray
    op: TrimResult


@dataclass(frozen=True, eq=False)
class PlantIdentification(Result):
    """Identified and exact plant at one operating point.

    Attributes
    ----------
    experiment : the step experiment
    realization : `RealizationResult` (identified model ``realization.sys``)
    params : the parameter set
    point : the requested operating point

    `exact`, the exact linearisation at the same point (a named `control.StateSpace`), is
    computed on first use.
    """

    experiment: StepExperiment
    realization: RealizationResult
    params: Params
    point: OperatingPoint

    @cached_property
    def exact(self):
        """The exact (T_mp, T_ms) -> (r_g, nu, nu_r) linearisation at the same point."""
        return plant(self.params, self.point, model=self.experiment.op.model,
                     disturbance=False).system

    @property
    def r_g(self) -> float:
        """Ratio of the operating point [-]."""
        return float(self.experiment.op.r_g)


def step_experiment(params, op: OperatingPoint | None = None, *,
                    amplitudes: Sequence[float] = (1e-5, 1e-5), duration: float = 6.0,
                    sample_rate: float = 500.0, rtol: float = 1e-9, model=None
                    ) -> StepExperiment:
    """Step each servo torque by its amplitude [N m] and record r_g, nu and nu_r.

    Parameters
    ----------
    params : Params
    op : operating point (ratio [-], slip [-], clamping force [N], primary speed [rad/s];
        default ``params.operating``)
    amplitudes : step sizes of T_mp and T_ms [N m], non-zero
    duration : record length [s]
    sample_rate : [Hz]
    rtol : integrator tolerance (see `empact.nonlinear.simulation.simulate`)
    model : an `EmpactModel` with torque inputs (default: `nonlinear_model(params)`)

    Returns
    -------
    StepExperiment
        ``t`` shape (n_t,) [s]; ``steps`` shape (n_t, 3, 2), the deviations of ``(r_g, nu,
        nu_r)`` [-] from the trimmed point divided by the step size of ``(T_mp, T_ms)``
        [1/(N m)]; the ``amplitudes`` [N m] and the trimmed point ``op``.

    Raises
    ------
    ParameterError
        For amplitudes that are not two non-zero numbers, a non-positive duration or sample
        rate, or a step simulation that does not complete.
    """
    amps = np.asarray(amplitudes, float)
    if amps.shape != (2,) or np.any(~np.isfinite(amps)) or np.any(amps == 0):
        raise ParameterError(f"amplitudes = {list(amplitudes)!r}: need two non-zero step sizes "
                             "[N m]")
    duration = check_number("duration", duration, 0.0, lo_open=True, unit="s")
    sample_rate = check_number("sample_rate", sample_rate, 0.0, lo_open=True, unit="Hz")
    op = params.operating if op is None else op
    model = nonlinear_model(params) if model is None else model
    trimmed = trim(model, op)
    cols = []
    for j, name in enumerate(INPUTS):
        u = trimmed.u.copy()
        u[model.inputs.index(name)] += amps[j]
        res = simulate(model, trimmed.x, {}, duration, u0=u, sample_rate=sample_rate, rtol=rtol,
                       name=f"step {name}")
        if not res.complete:
            raise ParameterError(f"step in {name} at r_g = {op.r_g:g}: {res.message}")
        nu_r = 1 - res.output("omega_s") / (trimmed.r_g * res.output("omega_p"))
        cols.append(np.column_stack([res.output("r_g") - trimmed.r_g,
                                     res.output("nu") - trimmed.nu, nu_r - trimmed.nu])
                    / amps[j])
    return StepExperiment(t=res.t, steps=np.stack(cols, axis=-1), amplitudes=amps, op=trimmed)


def identify_plant(params, op: OperatingPoint | None = None, *, order: int | None = None,
                   min_fit: float = 98.0, n_block_rows: int = 100, n_block_cols: int = 1200,
                   **experiment) -> PlantIdentification:
    """Identify the (T_mp, T_ms) -> (r_g, nu, nu_r) plant at one point (Fig. 2).

    Parameters
    ----------
    params : Params
    op : operating point (default ``params.operating``)
    order : model order (default: the smallest reaching `min_fit`)
    min_fit : worst-channel step fit to reach [%] when `order` is None
    n_block_rows, n_block_cols : Hankel size
    **experiment : passed to `step_experiment`

    Returns
    -------
    PlantIdentification
        The step ``experiment``, the ``realization`` (its ``sys``: the identified model, a
        named ``control.StateSpace``) and, computed on first use, the ``exact`` linearisation.
    """
    op = params.operating if op is None else op
    exp = step_experiment(params, op, **experiment)
    real = realize_steps(exp.t, exp.steps, order, n_block_rows=n_block_rows,
                         n_block_cols=min(n_block_cols, len(exp.t) - n_block_rows),
                         min_fit=None if order is not None else min_fit,
                         inputs=INPUTS, outputs=OUTPUTS)
    return PlantIdentification(experiment=exp, realization=real, params=params, point=op)
