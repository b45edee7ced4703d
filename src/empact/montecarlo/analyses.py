"""What one Monte Carlo run evaluates on its parameter set.

``"plant"``
    The exact plant of Fig. 2 (servo torques -> ratio and slip) at the parameter set's
    operating point (``[operating]``, so a spread of ``operating.*`` moves it): the trimmed
    servo torques and load, the largest pole real part, the slowest resonant mode
    (``f_slow_hz``, ``zeta_slow``: the lowest-frequency pole pair with damping ratio below
    ``1/sqrt(2)``, so that it shows a resonance peak; heavily damped pairs, which appear
    with some spreads, are skipped rather than mixed into the quantiles) and the
    right-half-plane zeros of ``T_mp -> nu`` (the non-minimum-phase behaviour of Sec. 2.3).
    Model options as `empact.nonlinear.nmp.nmp_zeros`: moderate damping, torque-controlled
    drive and load.
``"slip"``
    The slip model (Sec. 2.2) at the operating point: largest real part and smallest damping
    ratio of its poles, the belt damper ``c_b`` and the traction coefficient.
``"closed-loop"``
    A closed-loop scenario with a controller on the nonlinear machine
    (`empact.control.closed_loop`): its metrics, slips as fractions (``slip_error``,
    ``peak_slip`` [-]).  The scenario sets its own operating point, so
    ``operating.*`` spreads do not act here; ``scenario.*`` spreads
    (`empact.montecarlo.spread.SCENARIO_VARIABLES`) move its initial point and load step.
    Each run carries its verdicts (`output_units`): ``belt_slack`` (1 when the clamping force
    reached zero), ``macro_slip`` and ``met.NAME`` (1 met, 0 missed) per scenario target
    (`empact.control.closed_loop.check_targets`).  A run whose simulation stops early fails
    with the solver's message (a slack belt stops it: ``clamping force F_s fell to zero``).
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from ..control.closed_loop import check_targets, run_closed_loop
from ..errors import ParameterError
from ..lti import channel_zeros, oscillatory
from ..nonlinear.linearization import plant
from ..params import Params
from ..slip.coupling import linearize_belt
from ..slip.stability import stability_map
from .spread import Spread, apply_scenario, resolve_peak_slips

__all__ = ["ANALYSES", "OUTPUTS", "AnalysisContext", "RunFailed", "evaluate", "output_units",
           "prepare", "TARGET_PREFIX"]

ANALYSES = ("plant", "slip", "closed-loop")

#: output name -> unit, per analysis (table columns, in this order)
OUTPUTS: dict[str, dict[str, str]] = {
    "plant": {"T_mp": "N m", "T_ms": "N m", "T_l": "N m", "max_real_pole": "1/s",
              "f_slow_hz": "Hz", "zeta_slow": "-", "n_rhp_zeros": "-",
              "rhp_zero_hz": "Hz"},
    "slip": {"max_real": "1/s", "min_damping": "-", "c_b": "N m s/rad", "mu": "-"},
    "closed-loop": {"slip_error": "-", "peak_slip_error": "-", "peak_slip": "-",
                    "slip_reserve": "-", "macro_slip": "-", "ratio_error": "-",
                    "peak_T_mp": "N m", "peak_T_ms": "N m",
                    "mean_clamping_force": "N", "mean_slip_power": "W",
                    "mean_actuation_power": "W", "mean_losses": "W", "belt_slack": "-"},
}

#: a closed-loop run's verdict on scenario target NAME is output ``met.NAME`` (1 met, 0 missed)
TARGET_PREFIX = "met."

#: measured wall time of one run [s] (sizes the sweep's chunks)
SECONDS_PER_RUN = {"plant": 0.03, "slip": 2e-3, "closed-loop": 0.08}

#: a pole pair resonates (its frequency response peaks) below this damping ratio
ZETA_RESONANT = 1.0 / np.sqrt(2.0)

#: zeros of T_mp -> nu above this are not reported [Hz] (as `empact nmp`)
F_MAX_ZEROS = 100.0


class RunFailed(RuntimeError):
    """A run that produced no result (the message says why)."""


@dataclass(frozen=True)
class AnalysisContext:
    """What an analysis needs besides the parameters (picklable: it travels to workers).

    Attributes
    ----------
    kind : one of `ANALYSES`
    scenario : a closed-loop `empact.nonlinear.scenario.Scenario` (closed loop only)
    controller : `empact.control.controller.Controller` (closed loop only)
    nominal : the nominal `empact.params.Params` the controller knows (closed loop: its
        traction curve, geometry and holding torques; each run's machine differs from it)
    traction : measured traction curves (`empact.variator.traction.TabulatedTraction`) of
        the plant analysis's model (the closed loop's are in its scenario's options); None:
        the analytic curve
    """

    kind: str
    scenario: Any = None
    controller: Any = None
    nominal: Any = None
    traction: Any = None

    def __post_init__(self) -> None:
        if self.kind not in ANALYSES:
            raise ParameterError(f"analysis {self.kind!r}: choose one of {', '.join(ANALYSES)}")
        if self.kind == "closed-loop" and self.scenario is None:
            raise ParameterError("the closed-loop analysis needs a scenario")
        if self.kind == "slip" and self.traction is not None:
            raise ParameterError("traction: the slip analysis draws the analytic curve's "
                                 "coefficients; a measured table serves the plant and "
                                 "closed-loop analyses")


def output_units(context: AnalysisContext) -> dict[str, str]:
    """The outputs of a run of `context` -> unit: `OUTPUTS` and, for the closed loop, one
    verdict ``met.NAME`` [-] per scenario target (in the scenario's order).

    Parameters
    ----------
    context : AnalysisContext
        The study's analysis and its scenario.

    Returns
    -------
    dict of str to str
        Output name -> unit, in the order of a run's record.
    """
    out = dict(OUTPUTS[context.kind])
    if context.kind == "closed-loop":
        out.update({TARGET_PREFIX + t: "-" for t in context.scenario.targets})
    return out


def prepare(params: Params, spread: Spread, row: Any,
            context: AnalysisContext) -> tuple[Params, AnalysisContext]:
    """One run's parameter set and context: the spread's parameters replace the nominal
    values, its ``scenario.*`` variables the scenario's (validated, `apply_scenario`).

    Parameters
    ----------
    params : Params
        The nominal set.
    spread : Spread
    row : sequence of float
        The run's values (`Spread.sample`'s row), in the order of ``spread.names``.
    context : AnalysisContext
        The study's context (scenario, controller, traction).

    Returns
    -------
    tuple of (Params, AnalysisContext)
        The run's parameter set and its context with its own scenario.
    """
    values, scen = spread.split(row)
    p = params.from_dotted(resolve_peak_slips(values, params))
    if scen:
        context = replace(context, scenario=apply_scenario(context.scenario, scen, params))
    return p, context


def evaluate(params: Params, context: AnalysisContext) -> dict[str, float]:
    """The outputs (`OUTPUTS`) of one run; raises on failure (the caller records why).

    Parameters
    ----------
    params : Params
        The run's (spread) parameter set.
    context : AnalysisContext
        The analysis (``kind``) and, for the closed loop, its scenario, controller and
        nominal parameters.

    Returns
    -------
    dict of str to float
        ``OUTPUTS[context.kind]``'s names -> values in the units `OUTPUTS` gives (slips as
        fractions [-]; NaN for a plant output that does not exist, e.g. no resonant mode).

    Raises
    ------
    RunFailed
        When a closed-loop simulation stops early (the solver's message).
    """
    return _EVALUATE[context.kind](params, context)


def _plant(params: Params, context: AnalysisContext) -> dict[str, float]:
    tables = {} if context.traction is None else {"traction": context.traction}
    pl = plant(params, params.operating, disturbance=False, **tables)
    sys, op = pl.system, pl.trim
    assert op is not None  # `plant` trims
    poles = np.linalg.eigvals(sys.A)
    f, zeta = oscillatory(poles)
    resonant = zeta < ZETA_RESONANT
    f, zeta = f[resonant], zeta[resonant]
    z = channel_zeros(sys, "T_mp", "nu", max_abs=1e7)
    z = z[np.abs(z) < 2 * np.pi * F_MAX_ZEROS]
    rhp = z[(z.real > 1e-3 * np.abs(z)) & (np.abs(z) > 1e-3)]
    return {"T_mp": op.T_mp, "T_ms": op.T_ms, "T_l": op.T_l,
            "max_real_pole": float(poles.real.max()),
            "f_slow_hz": float(f[0]) if f.size else np.nan,
            "zeta_slow": float(zeta[0]) if f.size else np.nan,
            "n_rhp_zeros": float(rhp.size),
            "rhp_zero_hz": float(np.abs(rhp).min() / (2 * np.pi)) if rhp.size else np.nan}


def _slip(params: Params, context: AnalysisContext) -> dict[str, float]:
    op = params.operating.resolve(params)  # (a point given by tau or T_l)
    sm = stability_map(params, "nu", [op.nu], "r_g", [op.r_g], base=op, workers=1)
    belt = linearize_belt(params, op)
    return {"max_real": float(sm.max_real[0, 0]), "min_damping": float(sm.min_damping[0, 0]),
            "c_b": belt.c_b, "mu": belt.mu}


def _closed_loop(params: Params, context: AnalysisContext) -> dict[str, float]:
    run = run_closed_loop(context.scenario, params, context.controller,
                          nominal=context.nominal)
    m = run.metrics
    if not m["complete"]:
        raise RunFailed(m["message"])
    out = {k: float(m[k]) for k in OUTPUTS["closed-loop"] if k != "belt_slack"}
    out["belt_slack"] = float(m["min_clamping_force"] <= 0.0)
    out.update({TARGET_PREFIX + c.name: float(c.met)
                for c in check_targets(m, context.scenario.targets)})
    return out


_EVALUATE = {"plant": _plant, "slip": _slip, "closed-loop": _closed_loop}
