"""Benchmark: the quasi-static drive cycle (issue 34, stage 1): `quasi_static_cycle` on WLTC
3b, NEDC and FTP-75 for each strategy alone and for all five together (CPU time, median of
REPEATS, the model built once), and the number of trims it made (the trims are vectorised
over the samples, `trim_grid`; no interpolated map).  The dynamic cycle's 60 s goal is
measured against this in `bench_dynamic_cycle.py`.

Run: ``.venv/bin/python bench/bench_cycle.py``
"""
from __future__ import annotations

import os
import statistics
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

from empact.cycles import CYCLES, load_cycle  # noqa: E402
from empact.drive_cycle import STRATEGIES, quasi_static_cycle  # noqa: E402
from empact.nonlinear.model import nonlinear_model  # noqa: E402
from empact.params import default_params  # noqa: E402

REPEATS = 5


def _cpu(fn) -> float:
    times = []
    for _ in range(REPEATS):
        t = time.process_time()
        fn()
        times.append(time.process_time() - t)
    return statistics.median(times)


def main() -> None:
    params = default_params()
    model = nonlinear_model(params)
    print(f"{'cycle':8s} {'samples':>7s} {'strategy':16s} {'CPU [s]':>8s}")
    for name in CYCLES:
        c = load_cycle(name)
        for s in (*STRATEGIES, "all five"):
            chosen = tuple(STRATEGIES) if s == "all five" else (s,)
            cpu = _cpu(lambda: quasi_static_cycle(params, c, strategies=chosen, model=model))
            print(f"{name:8s} {c.t.size:7d} {s:16s} {cpu:8.3f}")


if __name__ == "__main__":
    main()
