"""Benchmark: a closed-loop Monte Carlo on forked workers against serial (issue 36, item 4).

Workload: the report's closed-loop Monte Carlo (`_montecarlo_workload.py`: slip-load-step-r1,
the shipped PI controller and example spread, seed 1), serial in process (the baseline)
against ``SweepOptions(workers=N)`` (forked worker processes on this machine, the CLI's
default: the first chunk runs here, the workers inherit what it loaded).  Both in this one
process, serial first, then alternated ``--pairs`` times; each pair's tables are checked
bitwise equal.  Wall time is what a user waits for; on a shared machine the wall-time ratio
is only as good as the cores that were free, so the CPU times are printed beside it (this
process's and the workers'), with the speed-up they bound on free cores: the serial CPU over
this process's CPU plus one worker's share, and the load average.

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


def cpu() -> tuple[float, float]:
    """CPU seconds of this process, and of its (waited-for) children."""
    s, c = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return s.ru_utime + s.ru_stime, c.ru_utime + c.ru_stime


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
        t0, (p0, c0) = time.perf_counter(), cpu()
        res = monte_carlo(params, spread, a.runs, "closed-loop", seed=1, scenario=sc,
                          controller=ctrl, sweep=sweep)
        p1, c1 = cpu()
        return time.perf_counter() - t0, p1 - p0, c1 - c0, res

    study(None)  # warm: imports, numba's cache, the lazy tables
    print(f"{os.cpu_count()} cores; load average before {os.getloadavg()}")
    ratios, bound = [], []
    for _ in range(a.pairs):
        ts, cs, _, serial = study(None)
        tp, cp, cw, forked = study(SweepOptions(workers=a.workers))
        equal = (np.array_equal(serial.values, forked.values, equal_nan=True)
                 and np.array_equal(serial.samples, forked.samples)
                 and np.array_equal(serial.ok, forked.ok) and serial.reasons == forked.reasons)
        ratios.append(ts / tp)
        # on free cores the forked run takes this process's CPU (the first chunk, the
        # collection) plus one worker's share (the chunks are dealt one at a time)
        bound.append(cs / (cp + cw / a.workers))
        print(f"Monte Carlo {a.runs} closed-loop runs: serial {ts:7.2f} s ({cs:6.2f} s CPU), "
              f"{a.workers} forked workers {tp:7.2f} s ({cp:5.2f} s CPU here + {cw:6.2f} s in "
              f"the workers): wall {ts / tp:4.2f}x, CPU-bound {bound[-1]:4.2f}x; "
              f"bitwise equal: {equal}")
        assert equal
    print(f"load average after {os.getloadavg()}")
    print(f"speed-up: wall median {np.median(ratios):.2f}x, best {max(ratios):.2f}x; CPU-bound "
          f"(free cores) median {np.median(bound):.2f}x (target >= {TARGET}x)")


if __name__ == "__main__":
    main()
