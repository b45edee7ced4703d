"""Benchmark: the simulator's integrator against the strongest library route (issues 4, 9, 11).

Workload: the shipped ``shift-and-load-step`` scenario (LOW -> OD in 1.3 s under ratio
control, then a load step; 2 s simulated), one core, on the machine with the creep law (issue
12: eigenvalues down to about -7e6 1/s from the belt's shift resistance).  Both routes are
driven by the SAME compiled right-hand side and exact Jacobian (forward mode since issue 23):

* empact: the compiled L-stable Rosenbrock method of `empact.nonlinear._rosenbrock`
  (running breakpoint indices, Jacobian columns that cannot change reused; ``method="ros2"``,
  the default up to 0.1 - the higher-order methods are in `bench_integrators.py`; the
  shipped-setting line runs the scenario's own method);
* baseline: `scipy.integrate.odeint` (LSODA) with numba wrappers (`_odeint_baseline.py`);
  the helper's comparison of solve_ivp's LSODA, BDF and Radau found them 2-10x slower still.

Accuracy: the largest error of r_g, nu and F_s at the 2001 output samples against a tight
reference (odeint at rtol 1e-11), each normalised by its signal's range.  The table pairs
each empact tolerance with the cheapest baseline run that is at least as accurate ("equal
accuracy").  Warm timings: median of REPEATS after a warm-up; numba compile or cache load is
timed separately, in fresh processes.

Run: ``.venv/bin/python bench/bench_simulation.py``
"""
from __future__ import annotations

import os
import statistics
import subprocess
import sys
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import numpy as np  # noqa: E402

from _odeint_baseline import simulate_odeint  # noqa: E402
from empact.nonlinear import _kernel as K  # noqa: E402
from empact.nonlinear.scenario import example_path, load_scenario  # noqa: E402
from empact.nonlinear.simulation import (run_scenario, scenario_model,  # noqa: E402
                                         scenario_signals, simulate)
from empact.params import default_params  # noqa: E402

REPEATS = 5
SIGNALS = (K.Y_RG, K.Y_NU, K.Y_FS)
TARGET_RTF = 20.0


def setup():
    params = default_params()
    sc = load_scenario(example_path("shift-and-load-step"))
    model, op = scenario_model(sc, params)
    return params, sc, model, op, scenario_signals(sc, model, op)


def timed(fn):
    fn()
    times = []
    for _ in range(REPEATS):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), out


def error(Y, ref):
    return max(float(np.max(np.abs(Y[:, k] - ref[:, k])) / np.ptp(ref[:, k])) for k in SIGNALS)


COLD = """
import time, sys
t0 = time.perf_counter()
from empact.params import default_params
from empact.nonlinear.scenario import example_path, load_scenario
from empact.nonlinear.simulation import run_scenario
params = default_params()
sc = load_scenario(example_path("shift-and-load-step"))
t1 = time.perf_counter()
run_scenario(sc, params)
t2 = time.perf_counter()
print(t1 - t0, t2 - t1)
"""


def main() -> None:
    params, sc, model, op, signals = setup()
    kw = dict(u0=op.u, sample_rate=sc.sample_rate, max_step=sc.max_step)
    ref, _ = simulate_odeint(model, op.x, signals, sc.duration, rtol=1e-11, atol_rtol=1e-9, **kw)
    rows = []
    for rtol in (1e-3, 1e-4, 1e-5, 1e-6):
        t, res = timed(lambda r=rtol: simulate(model, op.x, signals, sc.duration, rtol=r,
                                               method="ros2", **kw))
        rows.append(("empact Rosenbrock", rtol, t, error(res.y, ref), res.stats["n_steps"]))
    base = []
    for rtol in (1e-3, 1e-4, 1e-5, 1e-6, 1e-7):
        t, (Y, n) = timed(lambda r=rtol: simulate_odeint(model, op.x, signals, sc.duration,
                                                          rtol=r, **kw))
        base.append(("odeint LSODA", rtol, t, error(Y, ref), n))
    print(f"shift-and-load-step, {sc.duration:g} s simulated, one core; median of {REPEATS}; "
          f"errors normalised by each signal's range (r_g, nu, F_s), vs odeint rtol 1e-11"
          f" (atol of rtol 1e-9)")
    print(f"{'route':20s} {'rtol':>7s} {'time [ms]':>10s} {'RTF':>7s} {'error':>9s} {'steps':>7s}")
    for name, rtol, t, err, n in rows + base:
        print(f"{name:20s} {rtol:7.0e} {1e3 * t:10.2f} {sc.duration / t:7.1f} {err:9.1e} {n:7d}")
    print("equal accuracy (cheapest baseline run at least as accurate as each empact run):")
    for name, rtol, t, err, _ in rows:
        ok = [b for b in base if b[3] <= err]
        if not ok:
            print(f"  empact rtol {rtol:.0e} (error {err:.1e}): no baseline run this accurate")
            continue
        b = min(ok, key=lambda b: b[2])
        print(f"  empact rtol {rtol:.0e} ({1e3 * t:.2f} ms, error {err:.1e}) vs odeint rtol "
              f"{b[1]:.0e} ({1e3 * b[2]:.2f} ms, error {b[3]:.1e}): ratio baseline / empact = "
              f"{b[2] / t:.2f}")
    t_default = [r for r in rows if r[1] == sc.rtol][0][2]
    t_run, _ = timed(lambda: run_scenario(sc, params))
    print(f"shipped setting (rtol {sc.rtol:g}, trim included): {1e3 * t_run:.1f} ms, real-time "
          f"factor {sc.duration / t_run:.1f} (target >= {TARGET_RTF:g}, method {sc.method}); "
          f"ros2 alone {1e3 * t_default:.1f} ms")
    cold = [subprocess.run([sys.executable, "-c", COLD], capture_output=True, text=True,
                           check=True).stdout.split() for _ in range(3)]
    imp, first = zip(*[(float(a), float(b)) for a, b in cold])
    print(f"cold process (numba cache present): imports {statistics.median(imp):.2f} s, first "
          f"run (cache load + run) {statistics.median(first):.2f} s")


if __name__ == "__main__":
    main()
