"""Benchmark: the dynamic WLTC 3b run (issue 34, item 6; goal: at most 60 s on one core) next
to the same cycle's quasi-static cost, in one process: CPU time (`time.process_time`, the
process's own: one core) of `dynamic_cycle` for each strategy alone (the loop law and the
driver at 1 kHz in the compiled loop, outputs at 100 Hz), after a warm-up run that compiles
or loads numba's cache; the quasi-static cycle of the same strategy (median of 5) as the
baseline.  Wall time beside (the machine is shared); the compiled closed loop's load step
before and after, as `bench_compiled_loop.py` times it on a quiet machine (33 ms), says how
much the other jobs slow this process's CPU time.

Run: ``.venv/bin/python bench/bench_dynamic_cycle.py [STRATEGY ...]``
"""
from __future__ import annotations

import os
import statistics
import sys
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from empact.cycles import Cycle, load_cycle  # noqa: E402
from empact.drive_cycle import DEFAULT_STRATEGIES, quasi_static_cycle  # noqa: E402
from empact.dynamic_cycle import dynamic_cycle  # noqa: E402
from empact.nonlinear.model import nonlinear_model  # noqa: E402
from empact.params import default_params  # noqa: E402


def _calibration(params) -> float:
    """The compiled closed loop's load step (slip-load-step-r1, 2.5 s at 1 kHz: 33 ms of CPU
    on the quiet machine of `bench_compiled_loop.py`), median of 7 [s]: how loaded this
    machine is now, paired in this process."""
    from empact.control.closed_loop import control_example_path, run_closed_loop
    from empact.nonlinear.scenario import load_scenario

    sc = load_scenario(control_example_path("slip-load-step-r1"))
    run_closed_loop(sc, params)
    times = []
    for _ in range(7):
        t = time.process_time()
        run_closed_loop(sc, params)
        times.append(time.process_time() - t)
    return statistics.median(times)


def main(strategies: tuple[str, ...]) -> None:
    params = default_params()
    cyc = load_cycle("wltc3b")
    car = nonlinear_model(params, driveline="vehicle")
    bench = nonlinear_model(params)
    # warm-up: compile or load every routine on a short stretch
    k = cyc.t <= 60
    short = Cycle(cyc.name, cyc.t[k], cyc.v[k], tuple(np.asarray(cyc.phase)[k]))
    dynamic_cycle(params, short, strategies=strategies[:1], model=car)
    print(f"load average at start: {os.getloadavg()[0]:.2f}")
    cal = _calibration(params)
    print(f"calibration: the load step's compiled closed loop {1e3 * cal:.1f} ms CPU "
          "(33 ms on a quiet machine)")
    print(f"{'strategy':16s} {'QS CPU [s]':>10s} {'dyn CPU [s]':>11s} {'dyn wall [s]':>12s} "
          f"{'ratio':>7s} {'steps':>9s} {'dyn [s]':>8s}")
    for s in strategies:
        qs_times = []
        for _ in range(5):
            t = time.process_time()
            qs = quasi_static_cycle(params, cyc, strategies=(s,), model=bench)
            qs_times.append(time.process_time() - t)
        qs_cpu = statistics.median(qs_times)
        t, w = time.process_time(), time.perf_counter()
        res = dynamic_cycle(params, cyc, strategies=(s,), quasi_static=qs, model=car)
        cpu, wall = time.process_time() - t, time.perf_counter() - w
        run = res.runs[s]
        dyn_s = sum(b - a for a, b in res.stretches)
        print(f"{s:16s} {qs_cpu:10.3f} {cpu:11.1f} {wall:12.1f} {cpu / qs_cpu:7.0f} "
              f"{run.n_steps:9d} {dyn_s:8.0f}")
    cal2 = _calibration(params)
    print(f"calibration at end: {1e3 * cal2:.1f} ms CPU")
    print(f"load average at end: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main(tuple(sys.argv[1:]) or DEFAULT_STRATEGIES)
