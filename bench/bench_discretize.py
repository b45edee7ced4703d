"""Benchmark: discretising a controller (issue 23, item 3: command waits), `empact.lti.
cont2discrete` against ``scipy.signal.cont2discrete`` (the library route), cold start
included.

Workload: the shipped slip-load-step PI controller (`empact control design`'s controller at
one point: 4 states, 2 measured inputs, 2 outputs) at 1 kHz, Tustin.
- cold: a fresh interpreter that imports the route and discretises once (what every
  ``empact control`` command paid), median of RUNS interleaved runs;
- warm: one call with everything imported, median of 2000 calls;
and whether the two routes give bitwise the same matrices.

Run: ``.venv/bin/python bench/bench_discretize.py``
"""
from __future__ import annotations

import os
import statistics
import subprocess
import sys
import time

import numpy as np

RUNS = 9
SETUP = ("import numpy as np\n"
         "A = np.array([[0., 0, 0, 0], [0, -50., 0, 0], [1., 0, -200., 0], [0, 1., 0, -200.]])\n"
         "B = np.array([[1., 0], [0, 1.], [0, 0], [0, 0]])\n"
         "C = np.array([[3., 0, 40., 0], [0, 2., 0, 30.]])\n"
         "D = np.zeros((2, 2))\n")
ROUTES = {
    "scipy.signal.cont2discrete": "from scipy.signal import cont2discrete\n"
                                  "cont2discrete((A, B, C, D), 1e-3, method='tustin')\n",
    "empact.lti.cont2discrete": "from empact.lti import cont2discrete\n"
                                "cont2discrete(A, B, C, D, 1e-3, 'tustin')\n",
}


def cold(code: str) -> float:
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-c", SETUP + code], check=True)
    return time.perf_counter() - t0


def main() -> None:
    print(f"load average {os.getloadavg()[0]:.2f}")
    for code in ROUTES.values():  # warm the file cache
        cold(code)
    times = {name: [] for name in ROUTES}
    for _ in range(RUNS):  # interleaved
        for name, code in ROUTES.items():
            times[name].append(cold(code))
    base = statistics.median(times["scipy.signal.cont2discrete"])
    print(f"cold (fresh process, import + one call), median of {RUNS} interleaved runs")
    for name, ts in times.items():
        med = statistics.median(ts)
        print(f"  {name:28s} {med:6.3f} s ({min(ts):.3f} - {max(ts):.3f}), {base / med:5.2f}x")

    from scipy.signal import cont2discrete as scipy_c2d

    from empact.lti import cont2discrete
    ns: dict = {}
    exec(SETUP, ns)
    A, B, C, D = (ns[k] for k in "ABCD")
    warm = {}
    for name, fn in (("scipy.signal.cont2discrete",
                      lambda: scipy_c2d((A, B, C, D), 1e-3, method="tustin")),
                     ("empact.lti.cont2discrete",
                      lambda: cont2discrete(A, B, C, D, 1e-3, "tustin"))):
        ts = []
        for _ in range(2000):
            t0 = time.perf_counter()
            fn()
            ts.append(time.perf_counter() - t0)
        warm[name] = statistics.median(ts)
    base = warm["scipy.signal.cont2discrete"]
    print("warm (one call, imported), median of 2000")
    for name, t in warm.items():
        print(f"  {name:28s} {1e6 * t:8.1f} us, {base / t:5.2f}x")
    same = all(np.array_equal(x, y) for x, y in
               zip(cont2discrete(A, B, C, D, 1e-3, "tustin"),
                   scipy_c2d((A, B, C, D), 1e-3, method="tustin")[:4]))
    print(f"bitwise the same matrices: {same}")


if __name__ == "__main__":
    main()
