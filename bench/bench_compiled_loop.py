"""Benchmark: the compiled closed loop (issue 23, items 3 and 4): a compiled loop law
(`LoopLaw.compiled`) and the integrator in one numba loop (`LoopLaw.run_compiled`,
`empact.control._loop_core`) against the same law stepped by the simulator's Python loop
(the route before it: `step` at every sample between the integrator's calls).

Workload: every shipped closed-loop scenario whose law runs compiled (the six load steps),
run by `run_scenario` (Rodas4) both ways, median of REPEATS, alternated, after a warm-up;
whether the two runs are bitwise equal; then the report's 200-run closed-loop Monte Carlo of
the shipped example spread (slip-load-step-r1, serial, in process), once each way.

Run: ``.venv/bin/python bench/bench_compiled_loop.py [--no-montecarlo]``
"""
from __future__ import annotations

import os
import statistics
import sys
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import numpy as np  # noqa: E402
from _montecarlo_workload import shipped_monte_carlo  # noqa: E402

from empact.control import closed_loop  # noqa: E402
from empact.control.closed_loop import (build_law, control_example_path,  # noqa: E402
                                        control_examples)
from empact.control.law import LoopLaw  # noqa: E402
from empact.nonlinear.scenario import load_scenario  # noqa: E402
from empact.nonlinear.simulation import run_scenario, scenario_model  # noqa: E402
from empact.params import default_params  # noqa: E402

REPEATS = 7


class PythonLoopLaw(LoopLaw):
    """The same law, stepped by the simulator's Python loop (the route before)."""

    @property
    def compiled(self) -> bool:
        return False


def main() -> None:
    params = default_params()
    print(f"load average {os.getloadavg()[0]:.2f}")
    print(f"{'scenario':22s} {'Python loop [ms]':>16s} {'compiled loop [ms]':>18s} "
          f"{'ratio':>6s}  bitwise")
    for name in control_examples():
        sc = load_scenario(control_example_path(name))
        model, op = scenario_model(sc, params)
        if not build_law(sc, params, None, model, op).compiled:
            continue
        runs, wall = {}, {"python": [], "compiled": []}
        for rep in range(REPEATS + 1):
            for key, cls in (("python", PythonLoopLaw), ("compiled", LoopLaw)):
                closed_loop.LoopLaw = cls
                try:
                    law = build_law(sc, params, None, model, op)
                finally:
                    closed_loop.LoopLaw = LoopLaw
                t0 = time.perf_counter()
                runs[key] = run_scenario(sc, params, controller=law)
                if rep:  # the first is a warm-up
                    wall[key].append(time.perf_counter() - t0)
        same = all(np.array_equal(getattr(runs["python"], k), getattr(runs["compiled"], k))
                   for k in ("t", "x", "y", "u"))
        wp, wc = statistics.median(wall["python"]), statistics.median(wall["compiled"])
        print(f"{name:22s} {1e3 * wp:16.1f} {1e3 * wc:18.1f} {wp / wc:6.2f}  {same}",
              flush=True)
    if "--no-montecarlo" in sys.argv:
        return
    out = {key: shipped_monte_carlo(params, cls)
           for key, cls in (("python", PythonLoopLaw), ("compiled", LoopLaw))}
    (tp, rp), (tc, rc) = out["python"], out["compiled"]
    same = np.array_equal(rp.values, rc.values, equal_nan=True)
    print(f"Monte Carlo, 200 closed-loop runs of slip-load-step-r1, serial: Python loop "
          f"{tp:.1f} s, compiled loop {tc:.1f} s, ratio {tp / tc:.2f} ({rc.failures} failed; "
          f"metrics bitwise equal: {same}); load average {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
