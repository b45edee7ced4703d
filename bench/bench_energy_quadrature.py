"""Benchmark: the energy integrals on the integrator's own steps (issue 32 item 6) against the
same runs without them (the route before: the integrator's ``Q`` empty, the balance taken
by Simpson's rule on the output samples).

Workload: every shipped scenario (open loop: `run_scenario`; closed loop:
`run_closed_loop`), Rodas4 at the scenario's rtol, each run with and without the integrals,
alternated, REPEATS times after a warm-up; CPU time (`time.process_time`), the median ratio
with/without, and the energy-balance residual each way (with the integrals; on the output
samples, `energy_balance` of the result without them).

Run: ``.venv/bin/python bench/bench_energy_quadrature.py``
"""
from __future__ import annotations

import os
import statistics
import time
from dataclasses import replace

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

from empact.control.closed_loop import run_closed_loop  # noqa: E402
from empact.nonlinear import _kernel as K  # noqa: E402
from empact.nonlinear.scenario import example_path, list_examples, load_scenario  # noqa: E402
from empact.nonlinear.simulation import run_scenario  # noqa: E402
from empact.params import default_params  # noqa: E402

REPEATS = 5


def _run(sc, params, rates):
    """One run with the energy rates `rates` integrated by the integrator (() for none)."""
    K.ENERGY_RATES = rates  # `simulate` sizes its integrals by it (module attribute)
    t0 = time.process_time()
    res = run_closed_loop(sc, params).result if sc.closed_loop else run_scenario(sc, params)
    return time.process_time() - t0, res


def main() -> None:
    params = default_params()
    full = K.ENERGY_RATES
    print(f"load average {os.getloadavg()[0]:.2f}")
    print(f"{'scenario':22s} {'with [ms]':>9s} {'without [ms]':>12s} {'ratio':>6s} "
          f"{'residual: integrator':>21s} {'output samples':>15s}")
    try:
        for name in list_examples():
            sc = load_scenario(example_path(name))
            _run(sc, params, full)
            cpu = {"with": [], "without": []}
            ratios = []
            for _ in range(REPEATS):
                a, res_a = _run(sc, params, full)
                b, res_b = _run(sc, params, ())
                cpu["with"].append(a)
                cpu["without"].append(b)
                ratios.append(a / b)
            on = res_a.energy_balance()["energy_balance_residual"]
            off = replace(res_b, energy_integrals={}).energy_balance()["energy_balance_residual"]
            print(f"{name:22s} {1e3 * statistics.median(cpu['with']):9.1f} "
                  f"{1e3 * statistics.median(cpu['without']):12.1f} "
                  f"{statistics.median(ratios):6.3f} {on:21.2e} {off:15.2e}")
    finally:
        K.ENERGY_RATES = full


if __name__ == "__main__":
    main()
