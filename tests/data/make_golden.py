"""Make the golden closed-loop trajectories (`tests/data/golden_loop.npz`) that
`tests/test_loop.py` compares today's loop law against.

What: every shipped closed-loop scenario (`empact.control.closed_loop.control_examples`), run
by `run_closed_loop` on the shipped parameters, and a closed-loop Monte Carlo of the shipped
example spread (`empact/data/montecarlo/example-spread.toml`, slip-load-step-r1, seed 1,
`MC_RUNS` runs, serial; as the report and `bench/_montecarlo_workload.py` build it).  Per
scenario: the signals the law reads (`empact.control.law.RAW_SIGNALS`), the slip ``nu``, the
clamping force ``F_s`` and the servo torques ``T_mp``, ``T_ms`` as applied, every
`DECIMATE`-th output sample (full float64: the test compares them bitwise), the whole state at
the last sample, the run's length, its integrator statistics and its scalar metrics; the
Monte Carlo's drawn parameters and metric table; the law's pre-processing linearised
(`empact.control.loop.linear_preprocess`, ideal law) on a load step and a shift.  About 1 MB
compressed.

How: from a checkout of the commit whose law is the reference (the file's ``commit`` entry
records it; the shipped file was made from main at ``89f6a97``, the law before its one
compiled sample, issue 31 item 2; its runs and Monte Carlo are bitwise those of ``9bddc97``;
remade at issue 33 item 1, ``cf367a5``, for the new shipped PI and the feedforward's gain
table: the shipped runs changed on purpose; remade at issue 33 item 2 for the shipped PI
retuned by `empact control tune`, on the lossless machine the tests run; remade at issue 34,
``4ca10a6``, for the safety-factor clamping's gain schedule at its own clamping: only
shift-low-od-sf13 moved, the other runs within 3.1e-11 of the last golden)::

    PYTHONPATH=<that checkout>/src python tests/data/make_golden.py tests/data/golden_loop.npz

It takes about 10 s after compilation.  Regenerate only for an intended change of the
law's numbers, and say why in the commit.
"""
from __future__ import annotations

import subprocess
import sys
from importlib import resources
from pathlib import Path

import numpy as np

import empact
from empact.control.closed_loop import (
    build_law,
    control_example_path,
    control_examples,
    resolve_controller,
    run_closed_loop,
)
from empact.control.law import RAW_SIGNALS
from empact.control.loop import linear_preprocess
from empact.montecarlo import load_spread, monte_carlo
from empact.nonlinear.scenario import load_scenario

#: every DECIMATE-th output sample is kept (4 ms at the scenarios' 1 kHz)
DECIMATE = 4
#: the Monte Carlo's runs
MC_RUNS = 6
#: the signals kept per scenario: what the law reads, then what its loop acts on
SIGNALS = tuple(RAW_SIGNALS) + ("nu", "F_s", "T_mp", "T_ms")


def scenario_runs(params) -> dict[str, np.ndarray]:
    """Each shipped closed-loop scenario's golden arrays, keyed ``<scenario>/<what>``."""
    out: dict[str, np.ndarray] = {}
    for name in sorted(control_examples()):
        run = run_closed_loop(load_scenario(control_example_path(name)), params)
        res = run.result
        out[f"{name}/n_t"] = np.asarray(res.t.size)
        out[f"{name}/complete"] = np.asarray(res.complete)
        out[f"{name}/n_steps"] = np.asarray(res.stats["n_steps"])
        out[f"{name}/x_end"] = res.x[-1]
        for s in SIGNALS:
            out[f"{name}/{s}"] = res.output(s)[::DECIMATE]
        for k, v in sorted(run.metrics.items()):
            if isinstance(v, (bool, int, float, np.floating, np.integer)):
                out[f"{name}/metric/{k}"] = np.asarray(float(v))
    return out


def monte_carlo_runs(params) -> dict[str, np.ndarray]:
    """The shipped spread's closed-loop Monte Carlo (`MC_RUNS` runs, seed 1)."""
    path = resources.files("empact.data").joinpath("montecarlo", "example-spread.toml")
    sc = load_scenario(control_example_path("slip-load-step-r1"))
    res = monte_carlo(params, load_spread(str(path), params), MC_RUNS, "closed-loop", seed=1,
                      scenario=sc, controller=resolve_controller(sc.controller.file))
    return {"montecarlo/samples": res.samples, "montecarlo/values": res.values,
            "montecarlo/ok": res.ok, "montecarlo/outputs": np.array(res.outputs)}


#: the scenarios whose law's linearisation is kept
LINEARISED = ("slip-load-step-r1", "shift-low-od")


def linearised(params) -> dict[str, np.ndarray]:
    """`linear_preprocess` of the ideal law of each of `LINEARISED`."""
    out = {}
    for name in LINEARISED:
        law = build_law(load_scenario(control_example_path(name)), params, ideal=True)
        out |= {f"linear/{name}/{k}": v for k, v in linear_preprocess(law).items()}
    return out


def main(path: str) -> None:
    src = Path(empact.__file__).resolve().parents[2]
    commit = subprocess.run(["git", "-C", str(src), "rev-parse", "--short", "HEAD"],
                            capture_output=True, text=True).stdout.strip()
    # the machine without the variator's losses, as `tests/test_loop.py`'s `_lossless` (the
    # goldens pin the law's implementation, not the physics)
    params = empact.load_params().from_dotted({"losses.lambda_F": 0.0, "losses.k_T": 0.0,
                                               "losses.c_v": 0.0, "losses.c_q": 0.0})
    out = scenario_runs(params) | monte_carlo_runs(params) | linearised(params)
    out["commit"] = np.array(commit)
    out["decimate"] = np.asarray(DECIMATE)
    out["signals"] = np.array(SIGNALS)
    np.savez_compressed(path, **out)
    print(f"{len(out)} arrays from {src} at {commit} -> {path}")


if __name__ == "__main__":
    main(sys.argv[1])
