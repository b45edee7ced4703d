"""Benchmark: the sampled loop law on floats (issue 23, item 4) against the law before it.

Workload: every shipped closed-loop scenario, run by the one simulator (`run_scenario`,
Rodas4) with today's `empact.control.law.LoopLaw` and with the law as it was before
(`_loop_law_baseline.py`, frozen), each built from the same controller, model, point and
configuration; then the 200-run closed-loop Monte Carlo of the shipped example spread
(slip-load-step-r1, serial, in process), once with each law.  Per scenario: the law's own
cost per 1 ms sample (the time inside ``step``), the whole run's wall time, and whether the
two runs' states, outputs and inputs are bitwise equal (else their largest difference over
each signal's largest magnitude: the compiled sample, `LoopLaw.compiled`, rounds the last bit
differently).  Warm timings: median of REPEATS
after a warm-up, one process, the two laws alternated.

Run: ``.venv/bin/python bench/bench_loop_law.py [--no-montecarlo]``
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

import _loop_law_baseline as frozen  # noqa: E402
from _montecarlo_workload import shipped_monte_carlo  # noqa: E402
from empact.control.closed_loop import (build_law, control_example_path,  # noqa: E402
                                        control_examples)
from empact.control.law import LoopLaw  # noqa: E402
from empact.nonlinear.scenario import load_scenario  # noqa: E402
from empact.nonlinear.simulation import run_scenario, scenario_model  # noqa: E402
from empact.params import default_params  # noqa: E402

REPEATS = 5


class _Timed:
    """A law whose ``step`` adds its time to ``spent``."""

    def __init__(self, law):
        self.law, self.spent, self.calls = law, 0.0, 0
        self.commands, self.measured, self.dt = law.commands, law.measured, law.dt

    def step(self, t, measured):
        t0 = time.perf_counter()
        u = self.law.step(t, measured)
        self.spent += time.perf_counter() - t0
        self.calls += 1
        return u


def main() -> None:
    params = default_params()
    print(f"load average {os.getloadavg()[0]:.2f}")
    print(f"{'scenario':22s} {'frozen law [us/sample]':>23s} {'law [us/sample]':>16s} "
          f"{'ratio':>6s}  {'frozen run [s]':>14s} {'run [s]':>8s} {'ratio':>6s}  bitwise")
    for name in control_examples():
        sc = load_scenario(control_example_path(name))
        model, op = scenario_model(sc, params)

        def laws():
            law = build_law(sc, params, None, model, op)
            return law, frozen.LoopLaw(law.controller, law.model, law.point, law.u0,
                                       law.config, sc.references, sc.duration)

        new, old = laws()
        a, b = run_scenario(sc, params, controller=new), run_scenario(sc, params, controller=old)
        equal = all(np.array_equal(getattr(a, k), getattr(b, k), equal_nan=True)
                    for k in ("x", "y", "u"))
        dev = max(float(np.nanmax(np.abs(getattr(a, k) - getattr(b, k)) / np.maximum(
            np.nanmax(np.abs(getattr(b, k)), axis=0), 1e-300))) for k in ("x", "y", "u"))
        per = {"new": [], "old": []}
        wall = {"new": [], "old": []}
        for _ in range(REPEATS):
            pair = laws()
            for key, law in zip(("new", "old"), pair):
                timed = _Timed(law)
                t0 = time.perf_counter()
                run_scenario(sc, params, controller=timed)
                wall[key].append(time.perf_counter() - t0)
                per[key].append(timed.spent / timed.calls)
        pn, po = statistics.median(per["new"]), statistics.median(per["old"])
        wn, wo = statistics.median(wall["new"]), statistics.median(wall["old"])
        print(f"{name:22s} {1e6 * po:23.1f} {1e6 * pn:16.1f} {po / pn:6.2f}  {wo:14.3f} "
              f"{wn:8.3f} {wo / wn:6.2f}  {equal} ({dev:.1e}; compiled: {new.compiled})",
              flush=True)
    if "--no-montecarlo" in sys.argv:
        return
    out = {key: shipped_monte_carlo(params, cls)
           for key, cls in (("frozen", frozen.LoopLaw), ("law", LoopLaw))}
    (to, ro), (tn, rn) = out["frozen"], out["law"]
    same = np.array_equal(ro.values, rn.values, equal_nan=True)
    rel = float(np.nanmax(np.abs(ro.values - rn.values) / np.maximum(np.abs(ro.values),
                                                                      1e-300)))
    print(f"Monte Carlo, 200 closed-loop runs of slip-load-step-r1, serial: frozen law "
          f"{to:.1f} s, law {tn:.1f} s, ratio {to / tn:.2f} ({rn.failures} failed; metrics "
          f"bitwise equal: {same}, largest relative difference {rel:.1e}); load average {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
