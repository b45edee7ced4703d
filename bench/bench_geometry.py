"""Benchmark: the variator geometry's home-made Newton iterations (`empact.geometry`) against
scipy's root finders on the same equations, in one run (guideline: home-made numerics stay
only where they win, cold start included).

* `radii` (eq. 6 solved for the radii at N ratios, vectorised Newton with the exact
  derivative) against `scipy.optimize.newton` on the same arrays (vectorised secant/Newton)
  and against a loop of `scipy.optimize.brentq`;
* `ratio_range` (two bracketed Newton solves) against `scipy.optimize.brentq`;
* cold: a fresh process that loads a parameter file (which checks the ratio range) with each
  route: scipy.optimize's import is the price ``empact params show`` would pay.

Run: ``.venv/bin/python bench/bench_geometry.py``
"""
from __future__ import annotations

import statistics
import subprocess
import sys
import time

import numpy as np
from scipy.optimize import brentq, newton

from empact.variator.geometry import belt_length, radii, ratio_range, wrap_angle
from empact.params import default_params

REPEATS = 20


def timed(fn):
    fn()
    ts = []
    for _ in range(REPEATS):
        t0 = time.perf_counter()
        out = fn()
        ts.append(time.perf_counter() - t0)
    return statistics.median(ts), out


def main() -> None:
    v = default_params().variator
    r = np.linspace(0.43, 2.25, 10_000)

    def scipy_newton():
        f = lambda R_s: belt_length(r * R_s, R_s, v.a) - v.L_belt  # noqa: E731
        fp = lambda R_s: r * (np.pi + 2 * wrap_angle(r * R_s, R_s, v.a)) \
            + (np.pi - 2 * wrap_angle(r * R_s, R_s, v.a))  # noqa: E731
        R_s = newton(f, (v.L_belt - 2 * v.a) / (np.pi * (1 + r)), fprime=fp, tol=1e-15)
        return r * R_s, R_s

    def brentq_loop(n=200):
        out = []
        for rk in r[:n]:
            out.append(brentq(lambda R_s: float(belt_length(rk * R_s, R_s, v.a)) - v.L_belt,
                              1e-4, 0.2, xtol=1e-15))
        return np.array(out)

    t_ours, (_, Rs) = timed(lambda: radii(r, v.L_belt, v.a))
    t_sn, (_, Rs_sn) = timed(scipy_newton)
    t_bq, Rs_bq = timed(brentq_loop)
    print(f"radii at {r.size} ratios: empact Newton {1e3 * t_ours:.2f} ms; scipy.optimize.newton "
          f"(vectorised) {1e3 * t_sn:.2f} ms -> {t_sn / t_ours:.1f}x; brentq loop "
          f"{1e3 * t_bq * r.size / 200:.0f} ms (extrapolated from 200) -> "
          f"{t_bq * r.size / 200 / t_ours:.0f}x; largest |dR_s| {np.abs(Rs - Rs_sn).max():.1e} m "
          f"and {np.abs(Rs[:200] - Rs_bq).max():.1e} m")
    ratio_range.cache_clear()
    t_rr, rr = timed(lambda: (ratio_range.cache_clear(), ratio_range(v))[1])

    def brentq_range():
        R_med = (v.L_belt - 2 * v.a) / (2 * np.pi)
        R_p = brentq(lambda x: float(belt_length(x, v.R_min, v.a)) - v.L_belt, R_med,
                     v.R_min + v.a * (1 - 1e-12), xtol=1e-16)
        return R_p / v.R_min

    t_bq2, hi = timed(brentq_range)
    print(f"ratio_range: empact {1e6 * t_rr:.0f} us, brentq {1e6 * t_bq2:.0f} us; r_max "
          f"{rr[1]:.12f} vs {hi:.12f}")
    code = {"empact (no scipy.optimize import)":
            "from empact.params import load_params; load_params()",
            "with the scipy.optimize import the brentq route needs":
            "import scipy.optimize; from empact.params import load_params; load_params()"}
    for label, c in code.items():
        ts = []
        for _ in range(7):
            t0 = time.perf_counter()
            subprocess.run([sys.executable, "-c", c], check=True)
            ts.append(time.perf_counter() - t0)
        print(f"cold process, load the shipped parameters, {label}: "
              f"{statistics.median(ts):.3f} s")


if __name__ == "__main__":
    main()
