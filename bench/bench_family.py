"""Benchmark: plant families (issue 13, item 1): the batch route against a plain loop.

Workload: the plant at 21 ratios x 9 slips (189 points; clamping force and speed of
[operating], test bench options), trimmed and exactly linearised.  The batch route
(`empact.control.family.plant_family`: `trim_grid` solves all points at once with vectorised
Newton / bisection, one compiled loop linearises them) against a plain Python loop of
`trim` + `EmpactModel.jacobian` (the fastest per-point route; `plant`, which also builds a
`control.StateSpace`, is ten times slower still), in the same process, warm.

Run: ``.venv/bin/python bench/bench_family.py``
"""
from __future__ import annotations

import os
import statistics
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from empact.control.family import plant_family  # noqa: E402
from empact.nonlinear.equilibrium import trim  # noqa: E402
from empact.nonlinear.model import nonlinear_model  # noqa: E402
from empact.params import default_params  # noqa: E402

REPEATS = 5
TARGET = 2.0


def loop(params, r, nu):
    m = nonlinear_model(params, drive="speed", load="torque")
    op = params.operating
    out = []
    for ri in r:
        for ni in nu:
            tr = trim(m, ri, op.omega_p, nu=ni, F_s=op.F_s)
            out.append(m.jacobian(tr.x, tr.u)[0])
    return out


def timed(fn):
    fn()
    times = []
    for _ in range(REPEATS):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def main() -> None:
    params = default_params()
    r, nu = np.geomspace(0.5, 2, 21), np.geomspace(0.005, 0.02, 9)
    n = r.size * nu.size
    t_batch = timed(lambda: plant_family(params, r_g=r, nu=nu))
    t_loop = timed(lambda: loop(params, r, nu))
    print(f"{n} points, median of {REPEATS}, one core")
    print(f"batch (plant_family): {1e3 * t_batch:.1f} ms = {n / t_batch:.0f} points/s")
    print(f"plain loop (trim + jacobian): {1e3 * t_loop:.1f} ms = {n / t_loop:.0f} points/s")
    print(f"ratio loop / batch = {t_loop / t_batch:.1f} (target >= {TARGET:g})")


if __name__ == "__main__":
    main()
