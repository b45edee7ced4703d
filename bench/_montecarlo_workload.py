"""The report's closed-loop Monte Carlo as a benchmark workload (shared by the benchmarks of
the closed loop): 200 runs of slip-load-step-r1 on the shipped example spread, seed 1,
serial, in process."""
from __future__ import annotations

import time
from importlib import resources

from empact.control import closed_loop
from empact.control.closed_loop import control_example_path, resolve_controller
from empact.montecarlo import load_spread, monte_carlo
from empact.nonlinear.scenario import load_scenario


def shipped_monte_carlo(params, law=None, runs: int = 200):
    """``(seconds, MonteCarloResult)`` of the workload, every run's loop law built as `law`
    (a `LoopLaw` class; default today's)."""
    path = resources.files("empact.data").joinpath("montecarlo", "example-spread.toml")
    spread = load_spread(str(path), params)
    sc = load_scenario(control_example_path("slip-load-step-r1"))
    ctrl = resolve_controller(sc.controller.file)
    today = closed_loop.LoopLaw
    closed_loop.LoopLaw = today if law is None else law  # what build_law builds
    try:
        t0 = time.perf_counter()
        res = monte_carlo(params, spread, runs, "closed-loop", seed=1, scenario=sc,
                          controller=ctrl)
        return time.perf_counter() - t0, res
    finally:
        closed_loop.LoopLaw = today
