"""Benchmark: a closed-loop run through the one simulator (issue 19) against the 0.1 runner.

Workload: the shipped closed-loop load steps ``slip-load-step-r0.5``, ``-r1``, ``-r2`` (2.5 s
simulated, the shipped PI controller at 1 kHz with the driveshaft-torque feedforward) and the
shifts.  Both routes run the same trimmed start and the same compiled integrator:

* new: `empact.nonlinear.simulation.run_scenario` (the one simulator) with the 0.1 loop law
  as a sampled controller (the other inputs evaluated once on the sample grid before the
  loop, the Jacobian's constant columns kept between samples), with the 0.1 integrator
  (ros2);
* baseline: the 0.1 runner (`_closed_loop_baseline.py`): its own loop with Python-level
  piecewise-linear interpolation at every sample and a full Jacobian at every sample.

Both run the 0.1 law (frozen in `_closed_loop_baseline.py`; the package's law, rewritten in
issue 21, adds sensors, feedforwards and limits) and must give bitwise equal outputs (checked
here).  The last column times today's `run_closed_loop` (today's law with its sensors, Rodas4)
for information: another law, so no ratio.  Warm timings: median of REPEATS after a
warm-up, one process, alternating the two routes.  Then the 200-run closed-loop Monte Carlo
of the shipped example spread (slip-load-step-r1, serial, in process).

Run: ``.venv/bin/python bench/bench_closed_loop.py [--no-montecarlo]``
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

from dataclasses import replace  # noqa: E402

from _closed_loop_baseline import LoopLaw, run_closed_loop_v01  # noqa: E402
from _montecarlo_workload import shipped_monte_carlo  # noqa: E402
from empact.control.closed_loop import (control_example_path, control_examples,  # noqa: E402
                                        resolve_controller, run_closed_loop)
from empact.nonlinear.scenario import load_scenario  # noqa: E402
from empact.nonlinear.simulation import run_scenario, scenario_model  # noqa: E402
from empact.params import default_params  # noqa: E402

REPEATS = 7


def median_time(fn, repeats=REPEATS):
    fn()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), min(times), max(times)


def main() -> None:
    params = default_params()
    print(f"load average {os.getloadavg()[0]:.2f}")
    print(f"{'scenario':24s} {'0.1 runner [s]':>15s} {'one simulator [s]':>18s} "
          f"{'ratio':>7s}  equal  {'today run_closed_loop [s]':>26s}")
    for name in control_examples():
        sc = replace(load_scenario(control_example_path(name)), method="ros2")
        ctrl = resolve_controller(sc.controller.file)
        model, op = scenario_model(sc, params)

        def one_simulator():
            return run_scenario(sc, params, controller=LoopLaw(ctrl, sc, model, op))

        new = one_simulator()
        t, X, Y, U = run_closed_loop_v01(sc, model, op, ctrl)
        equal = (len(t) == len(new.t) and np.array_equal(X, new.x, equal_nan=True)
                 and np.array_equal(Y, new.y, equal_nan=True)
                 and np.array_equal(U, new.u, equal_nan=True))
        base = median_time(lambda: run_closed_loop_v01(sc, model, op, ctrl))
        ours = median_time(one_simulator)
        today_sc = load_scenario(control_example_path(name))
        today = median_time(lambda: run_closed_loop(today_sc, params), repeats=3)
        print(f"{name:24s} {base[0]:15.4f} {ours[0]:18.4f} {base[0] / ours[0]:7.2f}  "
              f"{str(equal):5s}  {today[0]:26.4f}", flush=True)
    if "--no-montecarlo" in sys.argv:
        return
    wall, res = shipped_monte_carlo(params)
    print(f"Monte Carlo, 200 closed-loop runs of slip-load-step-r1, serial: {wall:.1f} s "
          f"({res.failures} failed)")


if __name__ == "__main__":
    main()
