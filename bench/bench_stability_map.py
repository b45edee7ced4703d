"""Benchmark: batched stability map vs a per-point python-control loop (issue 3, item 10).

Problem: a 200 x 200 map over slip nu in [0.05 %, 6 %] and ratio r_g in [0.43, 2.25] at
F_s0 = 10 kN, omega_p0 = 300 rad/s (the shipped parameters and traction curve): 40 000
operating points, eight states each.

Timed, in this process (best of `REPEATS` for the batched paths):

* ``stability_map(method="full")``: per chunk of 4096 points the stacked 8 x 8 state matrices
  and ONE `numpy.linalg.eigvals` call; the three structural zeros dropped by magnitude.
* ``stability_map(method="reduced")``: the same with the exact 5 x 5 reduction
  (structural zeros removed analytically), one thread and ``os.cpu_count()`` threads.
  (The compiled polynomial-root path of issue 3 was removed in issue 9: a cold process, which
  is how the CLI and the report use the map, paid 1.3-4.2 s for it against 0.8 s for this
  path; see RESULTS.md.)
* the loop: for every point ``control.ss(A, B, C, D).poles()`` on the *same* 8 x 8 matrices
  (built beforehand by `state_matrices`, not timed), then the same stability measures.  The
  batched timings include building the matrices; the loop's do not.

Both give the same largest real part and smallest damping (checked, printed).

Run: ``.venv/bin/python bench/bench_stability_map.py``
"""
from __future__ import annotations

import os
import time

import control
import numpy as np

from empact.params import OperatingPoint, default_params
from empact.slip import stability_map, stability_measures, state_matrices

N_SIDE, REPEATS = 200, 3


def best_time(fn, repeats: int = REPEATS):
    best, out = np.inf, None
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def main() -> None:
    params = default_params()
    base = OperatingPoint(r_g=1.0, nu=0.01, F_s=1e4, omega_p=300.0)
    nu = np.linspace(0.0005, 0.06, N_SIDE)
    r_g = np.linspace(0.43, 2.25, N_SIDE)
    n = nu.size * r_g.size
    cpus = os.cpu_count() or 1

    runs = {
        "batched full 8x8, 1 thread": dict(method="full"),
        "batched reduced 5x5, 1 thread": dict(method="reduced"),
        f"batched reduced 5x5, {cpus} threads": dict(method="reduced", workers=cpus),
    }
    timings, maps = {}, {}
    for label, kw in runs.items():
        timings[label], maps[label] = best_time(
            lambda kw=kw: stability_map(params, "nu", nu, "r_g", r_g, base=base, **kw))

    # the loop, on the same 8 x 8 matrices (grid order: row = r_g, column = nu)
    R, NU = np.meshgrid(r_g, nu, indexing="ij")
    A, B, C, D = state_matrices(params, R.ravel(), NU.ravel(), base.F_s, base.omega_p)
    max_real = np.empty(n)
    min_damp = np.empty(n)
    t0 = time.perf_counter()
    for k in range(n):
        p = control.ss(A[k], B[k], C[k], D[k]).poles()
        max_real[k], min_damp[k] = stability_measures(p)
    t_loop = time.perf_counter() - t0
    loop_rate = n / t_loop

    print(f"stability map {N_SIDE} x {N_SIDE} = {n} points (nu x r_g), control "
          f"{control.__version__}, numpy {np.__version__}, {cpus} CPUs")
    print(f"{'path':38s} {'time [s]':>9s} {'points/s':>11s} {'vs loop':>8s}  agreement")
    print(f"{'loop: control.ss(...).poles() per point':38s} {t_loop:9.3f} {loop_rate:11.0f} "
          f"{1.0:7.1f}x  (reference, full loop, matrices prebuilt)")
    for label, t in timings.items():
        sm = maps[label]
        scale = np.abs(max_real).max()
        d_re = np.abs(sm.max_real.ravel() - max_real).max() / scale
        d_z = np.abs(sm.min_damping.ravel() - min_damp).max()
        same = np.array_equal(sm.unstable.ravel(), max_real > sm.tol)
        print(f"{label:38s} {t:9.3f} {n / t:11.0f} {t_loop / t:7.1f}x  max |d max_real| / "
              f"max |max_real| = {d_re:.1e}, max |d min_damping| = {d_z:.1e}, same unstable "
              f"set: {same}")


if __name__ == "__main__":
    main()
