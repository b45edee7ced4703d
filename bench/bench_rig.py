"""Benchmark: virtual-rig records of 1-60 s (issue 11, item 3): cost linear in the length.

The rig (`empact.experiments.rig.run_rig`, multisine on T_mp sampled at 1 kHz: an input
breakpoint every millisecond) against the old route in the same process: the integrator of
commit b9157d2 (each step scanned every breakpoint from the start and evaluated all Jacobian
columns), loaded from git history and run through the same simulator.  The exponent is the
slope of log(time) over log(record length) from 1 to 60 s.

Run: ``.venv/bin/python bench/bench_rig.py`` (needs the git history for the old route).
"""
from __future__ import annotations

import os
import subprocess
import sys
import time
import types
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from empact.experiments.rig import RigSettings, run_rig  # noqa: E402
import importlib

S = importlib.import_module("empact.nonlinear.simulation")  # noqa: E402
from empact.params import default_params  # noqa: E402

DURATIONS = (1.024, 4.096, 16.384, 60.0)
TARGET_60S, TARGET_EXPONENT = 3.0, 1.1
OLD_COMMIT = "b9157d2"


def old_integrator():
    """The integrate() of OLD_COMMIT, compiled against today's kernel (all columns)."""
    root = Path(__file__).resolve().parents[1]
    src = subprocess.run(["git", "-C", str(root), "show",
                          f"{OLD_COMMIT}:src/empact/_rosenbrock.py"],
                         capture_output=True, text=True, check=True).stdout
    src = src.replace("from ._nonlinear_kernel import", "from empact.nonlinear._kernel import")
    src = src.replace("_state_jacobian(x, u, p, ix, J)", "_state_jacobian(x, u, p, ix, J, ALL)")
    src = src.replace("D_GAMMA = ", "ALL = np.arange(18)\nD_GAMMA = ")
    src = src.replace("@njit(cache=True)", "@njit")
    mod = types.ModuleType("old_rosenbrock")
    exec(compile(src, "old_rosenbrock", "exec"), mod.__dict__)
    integrate = mod.integrate
    return lambda *a: integrate(*a[:19])  # the old signature has no `cols`, `J`, `full`


def run(duration, params, integrate=None):
    # the order-2 integrator: this benchmark compares its versions (the rig's default is now
    # Rodas5P, see bench_integrators.py)
    s = RigSettings(duration=duration, settle=0.0, period=min(2048, int(duration * 1000)),
                    method="ros2")
    orig = S.integrate
    if integrate is not None:
        S.integrate = integrate
    try:
        t0 = time.perf_counter()
        rec = run_rig(params, s)
        wall = time.perf_counter() - t0
    finally:
        S.integrate = orig
    assert rec.complete, rec.message
    return wall, rec


def main() -> None:
    params = default_params()
    old = old_integrator()
    run(1.024, params)
    run(1.024, params, old)  # compile both
    new_t, old_t = [], []
    print(f"{'record [s]':>10s} {'empact [s]':>11s} {'us/sample':>10s} {'old [s]':>9s} "
          f"{'us/sample':>10s} {'old / empact':>12s}")
    for d in DURATIONS:
        tn, rec = run(d, params)
        to, rec_o = run(d, params, old) if d <= 16.384 or "--old-60" in sys.argv else (np.nan,
                                                                                       None)
        new_t.append(tn)
        old_t.append(to)
        n = len(rec.t)
        if rec_o is not None:  # same integrator steps: the records agree to rounding
            diff = max(np.max(np.abs(rec.signals[k] - rec_o.signals[k])) for k in rec.signals)
            assert diff < 1e-9, diff
        print(f"{d:10.3f} {tn:11.3f} {1e6 * tn / n:10.1f} {to:9.3f} {1e6 * to / n:10.1f} "
              f"{to / tn:12.1f}")
    slope = np.polyfit(np.log(DURATIONS), np.log(new_t), 1)[0]
    print(f"60 s record: {new_t[-1]:.2f} s (target <= {TARGET_60S:g} s); cost exponent over "
          f"1-60 s: {slope:.3f} (target <= {TARGET_EXPONENT:g})")
    ok = np.isfinite(old_t)
    if ok.sum() >= 2:
        so = np.polyfit(np.log(np.array(DURATIONS)[ok]), np.log(np.array(old_t)[ok]), 1)[0]
        print(f"old route exponent over the lengths it ran: {so:.3f}")


if __name__ == "__main__":
    main()
