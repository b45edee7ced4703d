"""Benchmark: ``empact identify --ratios 0.5,1,2`` with default settings (issue 11, item 2),
whole processes, against the same command with one BLAS thread forced from outside
(``OPENBLAS_NUM_THREADS=1``, the old route's best case) in one run.

Target: <= 2 s on this machine.

Run: ``.venv/bin/python bench/bench_identify.py``
"""
from __future__ import annotations

import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

RUNS = 5
TARGET = 2.0
CMD = [str(Path(sys.executable).with_name("empact")), "identify", "--ratios", "0.5,1,2"]


def wall(env: dict) -> float:
    t0 = time.perf_counter()
    subprocess.run(CMD, check=True, stdout=subprocess.DEVNULL, env=env)
    return time.perf_counter() - t0


def main() -> None:
    default = dict(os.environ)
    for k in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        default.pop(k, None)
    one = {**default, "OPENBLAS_NUM_THREADS": "1"}
    wall(default)
    a, b = [], []
    for _ in range(RUNS):
        a.append(wall(default))
        b.append(wall(one))
    ma, mb = statistics.median(a), statistics.median(b)
    print(f"{' '.join(CMD[1:])}: median of {RUNS} whole-process runs")
    print(f"  default settings      {ma:6.2f} s ({min(a):.2f} - {max(a):.2f})  target <= "
          f"{TARGET:g} s: {'met' if ma <= TARGET else 'NOT met'}")
    print(f"  OPENBLAS_NUM_THREADS=1 {mb:5.2f} s ({min(b):.2f} - {max(b):.2f}); default / one "
          f"thread = {ma / mb:.2f}")


if __name__ == "__main__":
    main()
