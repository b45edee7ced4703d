"""Benchmark: command start-up (issue 9, item 4): ``empact --help`` and ``empact params show``
against ``python -c "import numpy"``, whole processes, in one run.

Target: both commands within 0.5 s on this machine (about 5x the start of numpy).

Run: ``.venv/bin/python bench/bench_startup.py``
"""
from __future__ import annotations

import statistics
import subprocess
import sys
import time
from pathlib import Path

RUNS = 9
TARGET = 0.5
EMPACT = str(Path(sys.executable).with_name("empact"))
COMMANDS = {
    'python -c "import numpy"': [sys.executable, "-c", "import numpy"],
    "empact --help": [EMPACT, "--help"],
    "empact params show": [EMPACT, "params", "show"],
    "empact modes driveline (for scale)": [EMPACT, "modes", "driveline"],
}


def wall(cmd: list[str]) -> float:
    t0 = time.perf_counter()
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
    return time.perf_counter() - t0


def main() -> None:
    for cmd in COMMANDS.values():  # warm the file cache
        wall(cmd)
    times = {name: [] for name in COMMANDS}
    for _ in range(RUNS):  # interleaved, so drift of the machine hits all alike
        for name, cmd in COMMANDS.items():
            times[name].append(wall(cmd))
    base = statistics.median(times['python -c "import numpy"'])
    print(f"whole-process wall time, median of {RUNS} interleaved runs (min - max)")
    for name, ts in times.items():
        med = statistics.median(ts)
        mark = ""
        if name in ("empact --help", "empact params show"):
            mark = f"  target <= {TARGET:g} s: {'met' if med <= TARGET else 'NOT met'}"
        print(f"  {name:36s} {med:6.3f} s ({min(ts):.3f} - {max(ts):.3f}), "
              f"{med / base:4.1f}x numpy{mark}")


if __name__ == "__main__":
    main()
