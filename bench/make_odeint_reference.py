"""Make the tight reference run of `tests/test_integrators.py`
(`tests/data/odeint_servo_torque_steps.npz`): the shipped servo-torque-steps scenario by
`scipy.integrate.odeint` (LSODA) at rtol 1e-11 with the simulator's compiled right-hand side
and exact Jacobian (`_odeint_baseline.py`); kept: ``r_g``, ``nu`` and ``F_s`` at the 1001
output samples, and the commit it was made from.  The shipped file was made from ``db7a78a``
(with the variator's losses of issue 32).

Run: ``PYTHONPATH=<checkout>/src .venv/bin/python bench/make_odeint_reference.py
tests/data/odeint_servo_torque_steps.npz`` (a few seconds after compilation).
"""
from __future__ import annotations

import os
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import numpy as np  # noqa: E402

import empact  # noqa: E402
from _odeint_baseline import simulate_odeint  # noqa: E402
from empact.nonlinear.scenario import example_path, load_scenario  # noqa: E402
from empact.nonlinear.simulation import scenario_model, scenario_signals  # noqa: E402

SIGNALS = ("r_g", "nu", "F_s")


def main(path: str) -> None:
    params = empact.load_params()
    sc = load_scenario(example_path("servo-torque-steps"))
    model, op = scenario_model(sc, params)
    sig = scenario_signals(sc, model, op)
    Y, _ = simulate_odeint(model, op.x, sig, sc.duration, rtol=1e-11, atol_rtol=1e-9,
                           u0=op.u, sample_rate=sc.sample_rate, max_step=sc.max_step)
    src = os.path.dirname(os.path.dirname(os.path.abspath(empact.__file__)))
    commit = subprocess.run(["git", "-C", src, "rev-parse", "--short", "HEAD"],
                            capture_output=True, text=True).stdout.strip()
    np.savez_compressed(path, commit=np.array(commit), signals=np.array(SIGNALS),
                        y=Y[:, [model.outputs.index(s) for s in SIGNALS]])
    print(f"{Y.shape[0]} samples from {src} at {commit} -> {path}")


if __name__ == "__main__":
    main(sys.argv[1])
