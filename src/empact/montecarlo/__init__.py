"""Monte Carlo over parameter spread.

Modules
-------
spread
    Distributions of parameters (normal, uniform, log-normal, with bounds) from TOML, sampled
    by run index from the study's seed.
analyses
    What a run evaluates: the plant at an operating point, the slip model's stability, or the
    metrics of a closed-loop scenario.
study
    `monte_carlo` (runs in chunks on the sweep layer, failures recorded with their reason),
    `MonteCarloResult` (table, summary) and `save_montecarlo` (CSV, JSON).
"""
from .analyses import ANALYSES, OUTPUTS, AnalysisContext, evaluate
from .spread import DISTRIBUTIONS, Distribution, Spread, load_spread, spread_from_dict
from .study import MonteCarloResult, monte_carlo, save_montecarlo

__all__ = ["ANALYSES", "OUTPUTS", "AnalysisContext", "evaluate", "DISTRIBUTIONS",
           "Distribution", "Spread", "load_spread", "spread_from_dict", "MonteCarloResult",
           "monte_carlo", "save_montecarlo"]
