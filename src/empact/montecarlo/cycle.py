"""A drive cycle over a parameter spread (issue 34, item 6): each run's fuel by strategy and
its saving against the reference, quasi-static or dynamic, on the sweep layer (in process,
forked workers, or Dask: `empact.sweep`).

Run ``i`` draws its parameters from the spread's stream ``SeedSequence(seed, (i,))``
(`empact.montecarlo.spread.Spread.sample`): its values do not depend on which other runs are
drawn with it or on the chunking, so one worker, two forked workers and a cluster give
bitwise the same table.  A spread of ``scenario.*`` variables is refused (a cycle has no
scenario).
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._results import TableResult
from .._validate import check_int
from ..cycles import Cycle
from ..drive_cycle import DEFAULT_STRATEGIES, REFERENCE, quasi_static_cycle
from ..dynamic_cycle import dynamic_cycle
from ..errors import ParameterError
from ..params import Params
from ..sweep import SweepOptions, plan_chunks, run_chunks
from .spread import Spread, resolve_peak_slips

__all__ = ["CycleStudy", "cycle_monte_carlo"]

#: measured cost of one run (quasi-static WLTC 3b, four strategies; the dynamic one is about
#: a hundred times more), for sizing chunks [s]
SECONDS_PER_RUN = {False: 2.0, True: 200.0}


@dataclass(frozen=True, eq=False)
class CycleStudy(TableResult):
    """A drive cycle's Monte Carlo (`cycle_monte_carlo`).

    Attributes
    ----------
    cycle : str
        The cycle's name.
    dynamic : bool
        Dynamic runs (`empact.dynamic_cycle.dynamic_cycle`), else quasi-static.
    names : tuple of str
        The spread's parameters (dotted names).
    values : array, shape (runs, len(names))
        Each run's parameter values (SI).
    strategies : tuple of str
    fuel_g : dict str -> array, shape (runs,)
        By strategy: the cycle's fuel [g].
    saving : dict str -> array, shape (runs,)
        By strategy: ``1 - fuel / fuel of REFERENCE`` [-] (NaN without the reference).
    macro_slip : dict str -> array of bool, shape (runs,)
        By strategy (dynamic runs; False for quasi-static ones).
    seed : int
    """

    cycle: str
    dynamic: bool
    names: tuple[str, ...]
    values: NDArray[np.float64]
    strategies: tuple[str, ...]
    fuel_g: dict[str, NDArray[np.float64]]
    saving: dict[str, NDArray[np.float64]]
    macro_slip: dict[str, NDArray[np.bool_]]
    seed: int

    def _columns(self) -> dict[str, Any]:
        """The parameters, then per strategy ``fuel_g.<s>``, ``saving.<s>`` and
        ``macro_slip.<s>``."""
        cols: dict[str, Any] = {n: self.values[:, j] for j, n in enumerate(self.names)}
        for s in self.strategies:
            cols[f"fuel_g.{s}"] = self.fuel_g[s]
            cols[f"saving.{s}"] = self.saving[s]
            cols[f"macro_slip.{s}"] = self.macro_slip[s]
        return cols


def _runs_chunk(task: tuple) -> dict[str, Any]:
    """One chunk of runs (`run_chunks` task): the parameter set, the spread's names, the
    runs' values, the cycle, the strategies, dynamic or not."""
    params, names, rows, cycle, strategies, dynamic = task
    fuel = {s: np.empty(len(rows)) for s in strategies}
    macro = {s: np.zeros(len(rows), dtype=bool) for s in strategies}
    for i, row in enumerate(rows):
        p = params.from_dotted(resolve_peak_slips(dict(zip(names, map(float, row))), params))
        if dynamic:
            res = dynamic_cycle(p, cycle, strategies=strategies)
            for s in strategies:
                fuel[s][i] = res.runs[s].fuel_g
                macro[s][i] = res.runs[s].macro_slip
        else:
            d = quasi_static_cycle(p, cycle, strategies=strategies).to_dict()["strategies"]
            for s in strategies:
                fuel[s][i] = d[s]["fuel_g"]
    return {"fuel": fuel, "macro": macro}


def cycle_monte_carlo(params: Params, spread: Spread, runs: int, *, cycle: Cycle,
                      strategies: Sequence[str] = DEFAULT_STRATEGIES, seed: int = 0,
                      dynamic: bool = False,
                      sweep: SweepOptions | None = None) -> CycleStudy:
    """The cycle's fuel by strategy over `runs` draws of `spread` (module notes).

    Parameters
    ----------
    params : Params
        The nominal parameter set (the spread's parameters replace its values).
    spread : Spread
        The parameter spread (`empact.montecarlo.spread.load_spread`); no ``scenario.*``.
    runs : int
        Number of runs, >= 1.
    cycle : Cycle
        The speed trace.
    strategies : sequence of str, optional
        `empact.drive_cycle.STRATEGIES` names (default its `DEFAULT_STRATEGIES`).
    seed : int, optional
        The study's seed.
    dynamic : bool, optional
        Dynamic runs (minutes each) instead of quasi-static ones (seconds).
    sweep : SweepOptions, optional
        Where the runs go (default: in process; ``SweepOptions(workers=2)``: forked).

    Returns
    -------
    CycleStudy

    Raises
    ------
    ParameterError
        For a spread with ``scenario.*`` variables or a bad run count (before any work).
    """
    runs = check_int("runs", runs, 1, 1_000_000)
    bad = [n for n in spread.names if n.startswith("scenario.")]
    if bad:
        raise ParameterError(f"spread variable {bad[0]!r}: a drive cycle has no scenario")
    strategies = tuple(strategies)
    values = spread.sample(seed, np.arange(runs))
    tasks = [(params, spread.names, values[s], cycle, strategies, bool(dynamic))
             for s in plan_chunks(runs, SECONDS_PER_RUN[bool(dynamic)], sweep)]
    parts = run_chunks(_runs_chunk, tasks, sweep, desc="cycle Monte Carlo")
    fuel = {s: np.concatenate([p["fuel"][s] for p in parts]) for s in strategies}
    macro = {s: np.concatenate([p["macro"][s] for p in parts]) for s in strategies}
    ref = fuel.get(REFERENCE)
    saving = {s: (1 - fuel[s] / ref) if ref is not None else np.full(runs, np.nan)
              for s in strategies}
    return CycleStudy(cycle=cycle.name, dynamic=bool(dynamic), names=spread.names,
                      values=values, strategies=strategies, fuel_g=fuel, saving=saving,
                      macro_slip=macro, seed=int(seed))
