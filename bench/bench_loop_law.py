"""Benchmark: the sampled loop law's cost per sample, this tree against another (paired).

Workload: every shipped closed-loop scenario, run by the one simulator (`run_scenario`,
Rodas4) with the scenario's `empact.control.law.LoopLaw`; per scenario the law's own cost per
1 ms sample (the time inside ``step``, the law wrapped so that the simulator's Python loop
calls it) and the whole run's wall time with the law itself in the loop (compiled with the
integrator where the law offers `run_compiled`); then, unless ``--no-montecarlo``, the
200-run closed-loop Monte Carlo of the shipped example spread (slip-load-step-r1, serial, in
process; `_montecarlo_workload.py`).

Paired: each tree (this one, and the one given by ``--against SRC``, e.g. today's main's
``src``) runs in its own process (``PYTHONPATH=SRC``), the two alternated REPEATS times;
each number is the median over the repeats of each process's median.  Warm: every process
runs each scenario once before timing.  The runs' outputs are checked against the golden
runs (`tests/data/golden_loop.npz`) by the tests, not here.

Run: ``.venv/bin/python bench/bench_loop_law.py [--against /path/to/other/src]
[--no-montecarlo]``
"""
from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

REPEATS = 3
HERE = Path(__file__).resolve().parent
OWN_SRC = HERE.parent / "src"


class _Timed:
    """A law whose ``step`` adds its time to ``spent`` (the simulator's Python loop calls
    it: it offers only the `SampledController` protocol)."""

    def __init__(self, law):
        self.law, self.spent, self.calls = law, 0.0, 0
        self.commands, self.measured, self.dt = law.commands, law.measured, law.dt

    def step(self, t, measured):
        t0 = time.perf_counter()
        u = self.law.step(t, measured)
        self.spent += time.perf_counter() - t0
        self.calls += 1
        return u


def worker(montecarlo: bool) -> None:
    """One process's numbers, as JSON on stdout: per scenario the law's median cost per
    sample [s] and the median run [s]; the Monte Carlo's time [s]."""
    sys.path.insert(0, str(HERE))
    from empact.control.closed_loop import build_law, control_example_path, control_examples
    from empact.nonlinear.scenario import load_scenario
    from empact.nonlinear.simulation import run_scenario, scenario_model
    from empact.params import default_params

    params = default_params()
    out: dict = {}
    for name in sorted(control_examples()):
        sc = load_scenario(control_example_path(name))
        model, op = scenario_model(sc, params)
        run_scenario(sc, params, controller=build_law(sc, params, None, model, op))  # warm
        per, wall = [], []
        for _ in range(3):
            timed = _Timed(build_law(sc, params, None, model, op))
            run_scenario(sc, params, controller=timed)
            per.append(timed.spent / timed.calls)
            law = build_law(sc, params, None, model, op)
            t0 = time.perf_counter()
            run_scenario(sc, params, controller=law)
            wall.append(time.perf_counter() - t0)
        out[name] = (statistics.median(per), statistics.median(wall))
    if montecarlo:
        from _montecarlo_workload import shipped_monte_carlo

        out["montecarlo"] = shipped_monte_carlo(params)[0]
    print(json.dumps(out))


def _run(src: Path, montecarlo: bool) -> dict:
    env = dict(os.environ, PYTHONPATH=str(src))
    cmd = [sys.executable, __file__, "--worker"] + ([] if montecarlo else ["--no-montecarlo"])
    res = subprocess.run(cmd, env=env, capture_output=True, text=True)
    if res.returncode:
        sys.exit(f"the worker on {src} failed:\n{res.stderr}")
    return json.loads(res.stdout.splitlines()[-1])


def main() -> None:
    montecarlo = "--no-montecarlo" not in sys.argv
    if "--worker" in sys.argv:
        worker(montecarlo)
        return
    trees = {"this": OWN_SRC}
    if "--against" in sys.argv:
        trees["against"] = Path(sys.argv[sys.argv.index("--against") + 1]).resolve()
    print(f"load average {os.getloadavg()[0]:.2f}; trees: "
          + ", ".join(f"{k} = {v}" for k, v in trees.items()), flush=True)
    got: dict[str, list[dict]] = {k: [] for k in trees}
    for _ in range(REPEATS):
        for key, src in trees.items():
            got[key].append(_run(src, montecarlo))
    med = {key: {name: [statistics.median(r[name][i] for r in runs) for i in (0, 1)]
                 for name in runs[0] if name != "montecarlo"} for key, runs in got.items()}
    other = "against" if "against" in trees else "this"
    print(f"{'scenario':22s} {'law [us/sample]':>16s} {'against':>8s} {'ratio':>6s}  "
          f"{'run [s]':>8s} {'against':>8s} {'ratio':>6s}")
    for name in med["this"]:
        (pn, wn), (po, wo) = med["this"][name], med[other][name]
        print(f"{name:22s} {1e6 * pn:16.2f} {1e6 * po:8.2f} {pn / po:6.3f}  {wn:8.3f} "
              f"{wo:8.3f} {wn / wo:6.3f}")
    load = [v[0] for k, v in med["this"].items() if k.startswith("slip-load-step")]
    shift = [v[0] for k, v in med["this"].items() if k.startswith("shift")]
    print(f"a shift's sample over a load step's: {max(shift) / statistics.median(load):.2f} "
          f"(largest shift over the load steps' median)")
    if montecarlo:
        mc = {k: statistics.median(r["montecarlo"] for r in runs) for k, runs in got.items()}
        print(f"Monte Carlo, 200 closed-loop runs of slip-load-step-r1, serial: this "
              f"{mc['this']:.1f} s, against {mc[other]:.1f} s, ratio "
              f"{mc['this'] / mc[other]:.3f}")
    print(f"load average {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
