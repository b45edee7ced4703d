"""Benchmark: sweeps on Dask (issue 14, item 5): in process against a local cluster of two
worker processes, in one script.

Workloads
  * a 400-point plant family (20 ratios x 20 slips, test bench options), and a 40,000-point one
    (200 x 200) to show where a cluster starts to pay for a family;
  * a 200-run Monte Carlo of the closed-loop analysis (the shipped slip-load-step-r1 scenario,
    2.5 s of machine time, shipped PI controller) over the shipped example spread.

Timings
  * start-up: `LocalCluster(n_workers=2)` + `Client`, then the first (4-run) sweep on it,
    which includes each worker's imports and compiled-kernel cache load;
  * serial (``scheduler="none"``) against the warm cluster (by its address), and against
    ``scheduler="local"`` end to end (a cluster started and closed inside the call, as the
    CLI's ``--scheduler local --workers 2`` does);
  * every parallel result is checked bitwise equal to the serial one.

Run: ``.venv/bin/python bench/bench_sweep.py`` (about 4 minutes on 2 cores)
"""
from __future__ import annotations

import os
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from empact.control.closed_loop import (control_example_path,  # noqa: E402
                                        load_control_scenario)
from empact.control.family import plant_family  # noqa: E402
from empact.montecarlo import load_spread, monte_carlo  # noqa: E402
from empact.params import default_params  # noqa: E402
from empact.sweep import LOCAL_CONFIG, SweepOptions  # noqa: E402

TARGET = 1.7
SPREAD = os.path.join(os.path.dirname(__file__), "..", "src", "empact", "data", "montecarlo",
                      "example-spread.toml")


def timed(fn):
    t0 = time.perf_counter()
    out = fn()
    return time.perf_counter() - t0, out


def same_family(a, b) -> bool:
    return all(np.array_equal(x, y, equal_nan=True) for x, y in
               ((a.A, b.A), (a.B, b.B), (a.C, b.C), (a.D, b.D)))


def same_mc(a, b) -> bool:
    return (np.array_equal(a.values, b.values, equal_nan=True)
            and np.array_equal(a.samples, b.samples) and a.reasons == b.reasons)


def line(name, serial, parallel, equal):
    print(f"{name:44s} serial {serial:8.3f} s   parallel {parallel:8.3f} s   "
          f"speed-up {serial / parallel:5.2f}x   bitwise equal: {equal}")


def main() -> None:
    import dask
    import distributed

    params = default_params()
    sc = load_control_scenario(control_example_path("slip-load-step-r1"))
    spread = load_spread(SPREAD, params)
    local = SweepOptions(scheduler="local", workers=2)
    print(f"{os.cpu_count()} cores; local cluster: 2 single-threaded worker processes")

    # serial first, with no cluster alive in this process (its threads would take CPU)
    grids = {n: dict(r_g=np.geomspace(0.5, 2.0, n), nu=np.linspace(0.004, 0.012, n))
             for n in (20, 200)}
    serial_family = {}
    for n, kw in grids.items():
        plant_family(params, **kw)  # warm in process
        serial_family[n] = timed(lambda: plant_family(params, **kw))
    runs = 200
    ts, ms = timed(lambda: monte_carlo(params, spread, runs, "closed-loop", scenario=sc,
                                       seed=1))

    t0 = time.perf_counter()
    with dask.config.set(LOCAL_CONFIG):  # as `scheduler="local"` starts its clusters
        cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                           dashboard_address=":0", silence_logs=50)
    client = distributed.Client(cluster)
    t_start = time.perf_counter() - t0
    warm = SweepOptions(scheduler=cluster.scheduler_address)
    t_first, _ = timed(lambda: monte_carlo(params, spread, 4, "plant", sweep=warm))
    print(f"cluster start-up {t_start:.2f} s; first sweep on it (worker imports, kernel "
          f"cache) {t_first:.2f} s")
    for n, kw in grids.items():
        t_s, f_s = serial_family[n]
        tw, fw = timed(lambda: plant_family(params, sweep=warm, **kw))
        line(f"family {n * n} points (warm cluster)", t_s, tw, same_family(f_s, fw))
    tw, mw = timed(lambda: monte_carlo(params, spread, runs, "closed-loop", scenario=sc,
                                       seed=1, sweep=warm))
    line(f"Monte Carlo {runs} closed-loop runs (warm cluster)", ts, tw, same_mc(ms, mw))
    client.close()
    cluster.close()
    t_s, f_s = serial_family[20]
    tl, fl = timed(lambda: plant_family(params, sweep=local, **grids[20]))
    line("family 400 points (--scheduler local, end to end)", t_s, tl, same_family(f_s, fl))
    tl, ml = timed(lambda: monte_carlo(params, spread, runs, "closed-loop", scenario=sc,
                                       seed=1, sweep=local))
    line(f"Monte Carlo {runs} runs (--scheduler local, end to end)", ts, tl, same_mc(ms, ml))
    print(f"target speed-up >= {TARGET}x for the Monte Carlo: "
          f"{'met' if ts / tl >= TARGET else 'NOT met'} end to end ({ts / tl:.2f}x)")
    s = ms.summary()
    print(f"summary: {s['succeeded']} ok, {s['failures']} failed; slip error [pp] q05/q50/q95 "
          + "/".join(f"{100 * s['outputs']['slip_error'][q]:.3g}" for q in ("q05", "q50", "q95")))


if __name__ == "__main__":
    main()
