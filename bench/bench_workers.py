"""Benchmark: a closed-loop Monte Carlo on forked workers against serial (issue 36, item 4).

Workload: the report's closed-loop Monte Carlo (`_montecarlo_workload.py`: slip-load-step-r1,
the shipped PI controller and example spread, seed 1), serial in process (the baseline)
against ``SweepOptions(workers=N)`` (forked worker processes on this machine, the CLI's
default: the first chunk runs here, the workers inherit what it loaded).  Both in this one
process, serial first, then alternated ``--pairs`` times; each pair's tables are checked
bitwise equal.  Wall time is what a user waits for; the CPU times (this process and its
workers) and the machine's load average are printed beside it, since on a shared machine
the wall-time ratio is only as good as the cores that were free.

Run: ``.venv/bin/python bench/bench_workers.py [--runs 200] [--workers 2] [--pairs 2]``
"""
from __future__ import annotations

import argparse
import os
import resource
import time

import numpy as np

from empact.control.closed_loop import control_example_path, resolve_controller
from empact.montecarlo import load_spread, monte_carlo
from empact.nonlinear.scenario import load_scenario
from empact.params import default_params
from empact.sweep import SweepOptions

TARGET = 1.7


def cpu() -> float:
    """CPU seconds of this process and its (waited-for) children."""
    s, c = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return s.ru_utime + s.ru_stime + c.ru_utime + c.ru_stime


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--runs", type=int, default=200)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--pairs", type=int, default=2)
    a = ap.parse_args()
    params = default_params()
    path = os.path.join(os.path.dirname(__file__), "..", "src", "empact", "data", "montecarlo",
                        "example-spread.toml")
    spread = load_spread(path, params)
    sc = load_scenario(control_example_path("slip-load-step-r1"))
    ctrl = resolve_controller(sc.controller.file)

    def study(sweep):
        t0, c0 = time.perf_counter(), cpu()
        res = monte_carlo(params, spread, a.runs, "closed-loop", seed=1, scenario=sc,
                          controller=ctrl, sweep=sweep)
        return time.perf_counter() - t0, cpu() - c0, res

    study(None)  # warm: imports, numba's cache, the lazy tables
    print(f"{os.cpu_count()} cores; load average before {os.getloadavg()}")
    ratios = []
    for _ in range(a.pairs):
        ts, cs, serial = study(None)
        tp, cp, forked = study(SweepOptions(workers=a.workers))
        equal = (np.array_equal(serial.values, forked.values, equal_nan=True)
                 and np.array_equal(serial.samples, forked.samples)
                 and np.array_equal(serial.ok, forked.ok) and serial.reasons == forked.reasons)
        ratios.append(ts / tp)
        print(f"Monte Carlo {a.runs} closed-loop runs: serial {ts:7.2f} s ({cs:6.2f} s CPU), "
              f"{a.workers} forked workers {tp:7.2f} s ({cp:6.2f} s CPU): "
              f"{ts / tp:4.2f}x; bitwise equal: {equal}")
        assert equal
    print(f"load average after {os.getloadavg()}")
    best = max(ratios)
    print(f"speed-up median {np.median(ratios):.2f}x, best {best:.2f}x (target >= {TARGET}x "
          f"on {a.workers} free cores)")


if __name__ == "__main__":
    main()
