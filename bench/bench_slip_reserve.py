"""Benchmark: the closed-loop metrics' slip reserve (issue 23, item 4) against the traction
peak searched at every sample (the route before it).

Workload: every shipped closed-loop scenario, run once with the shipped PI; then, on each
run's true ratio and slip records, `smallest_slip_reserve` (129 interpolated + 16 exact
golden-section searches) and the per-sample search (`traction_peak` at every sample, as
`empact.control.closed_loop.metrics` did), alternated, median of REPEATS; whether the two
give the same reserve at the same sample (bitwise); and the whole `metrics` call with the new
route.  Then `run_closed_loop` of slip-load-step-r1 (the Monte Carlo's scenario) for its
share.

Run: ``.venv/bin/python bench/bench_slip_reserve.py``
"""
from __future__ import annotations

import os
import statistics
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from empact.control.closed_loop import (control_example_path, control_examples,  # noqa: E402
                                        metrics, run_closed_loop)
from empact.nonlinear.equilibrium import smallest_slip_reserve, traction_peak  # noqa: E402
from empact.nonlinear.scenario import load_scenario  # noqa: E402
from empact.params import default_params  # noqa: E402

REPEATS = 15


def _per_sample(model, r, nu):
    full = np.asarray(traction_peak(model, r)[0]) - nu
    return float(full.min()), int(full.argmin())


def _median(fn, *args):
    times = []
    for _ in range(REPEATS):
        t0 = time.perf_counter()
        fn(*args)
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def main() -> None:
    params = default_params()
    print(f"load average {os.getloadavg()[0]:.2f}")
    print(f"{'scenario':22s} {'samples':>7s} {'per sample [ms]':>15s} {'new [ms]':>9s} "
          f"{'ratio':>6s}  {'metrics [ms]':>12s}  same")
    for name in control_examples():
        run = run_closed_loop(load_scenario(control_example_path(name)), params)
        model, res = run.op.model, run.result
        r, nu = np.clip(res.output("r_g"), 0.3, 3.0), res.output("nu")
        same = smallest_slip_reserve(model, r, nu) == _per_sample(model, r, nu)
        old, new = [], []
        for _ in range(3):  # alternated
            old.append(_median(_per_sample, model, r, nu))
            new.append(_median(smallest_slip_reserve, model, r, nu))
        o, n = min(old), min(new)
        m = _median(metrics, run)
        print(f"{name:22s} {r.size:7d} {1e3 * o:15.2f} {1e3 * n:9.3f} {o / n:6.1f}  "
              f"{1e3 * m:12.2f}  {same}")
    sc = load_scenario(control_example_path("slip-load-step-r1"))
    w = _median(run_closed_loop, sc, params)
    print(f"run_closed_loop slip-load-step-r1: {1e3 * w:.1f} ms a run (median of {REPEATS})")


if __name__ == "__main__":
    main()
