"""Benchmark: the sampled loop law's cost per sample, this tree against another (paired).

Workload: every shipped closed-loop scenario, run by the one simulator (`run_scenario`,
Rodas4) with the scenario's `empact.control.law.LoopLaw`; per scenario the law's own cost per
1 ms sample (the time inside ``step``, the law wrapped so that the simulator's Python loop
calls it) and the whole run's wall time with the law itself in the loop (compiled with the
integrator where the law offers `run_compiled`); the compiled loop's CPU time per sample
(issue 36: a shift's within 1.5x a load step's), the law's construction (`build_law`, CPU)
and its share of the whole `run_closed_loop` (issue 36: at most 10 % on a shift); a
process's *first* law of each shift (`FIRST_BUILD`: a fresh process per scenario, numba's
cache warm from the runs before, so that the references are not cached: `build_law`, then
`run_closed_loop`, CPU, and the build's share of the two); then,
unless ``--no-montecarlo``, the
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

import inspect
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
#: the shipped shifts (a moving ratio reference) whose first law `first_build` times
FIRST_BUILD = ("shift-low-od", "shift-low-od-sf13", "shift-low-od-slow", "vehicle-kickdown",
               "vehicle-upshift")
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
    from empact.control.closed_loop import (build_law, control_example_path, control_examples,
                                            run_closed_loop)
    from empact.nonlinear.scenario import load_scenario
    from empact.nonlinear.simulation import run_scenario, scenario_model
    from empact.params import default_params

    params = default_params()
    out: dict = {}
    # (a tree from before run_scenario took the caller's trim trims again: not timed)
    has_start = "start" in inspect.signature(run_scenario).parameters

    def start(model, op):
        return {"start": (model, op)} if has_start else {}

    for name in sorted(control_examples()):
        sc = load_scenario(control_example_path(name))
        model, op = scenario_model(sc, params)
        run_scenario(sc, params, controller=build_law(sc, params, None, model, op))  # warm
        per, wall, build, sample, whole = [], [], [], [], []
        for _ in range(3):
            timed = _Timed(build_law(sc, params, None, model, op))
            run_scenario(sc, params, controller=timed)
            per.append(timed.spent / timed.calls)
            c0 = time.process_time()
            law = build_law(sc, params, None, model, op)
            c1 = time.process_time()
            t0 = time.perf_counter()
            run_scenario(sc, params, controller=law, **start(model, op))
            wall.append(time.perf_counter() - t0)
            c2 = time.process_time()
            if not has_start:  # that run trimmed again: less a trim's CPU
                c_t = time.process_time()
                scenario_model(sc, params)
                c2 -= time.process_time() - c_t
            build.append(c1 - c0)
            sample.append((c2 - c1) / law._k)  # the compiled loop's CPU a 1 ms sample
            c3 = time.process_time()
            run_closed_loop(sc, params)
            whole.append(time.process_time() - c3)
        out[name] = (statistics.median(per), statistics.median(wall), statistics.median(build),
                     statistics.median(sample), statistics.median(whole))
    if montecarlo:
        from _montecarlo_workload import shipped_monte_carlo

        out["montecarlo"] = shipped_monte_carlo(params)[0]
    print(json.dumps(out))


def first_build(name: str) -> None:
    """A process's first law of the scenario `name`, as JSON on stdout: the CPU time [s] of
    `build_law` (the references computed, not cached) and of the `run_closed_loop` after it
    (which builds the law again from the cached references, trims and runs)."""
    from empact.control.closed_loop import build_law, control_example_path, run_closed_loop
    from empact.nonlinear.scenario import load_scenario
    from empact.nonlinear.simulation import scenario_model
    from empact.params import default_params

    params = default_params()
    sc = load_scenario(control_example_path(name))
    model, op = scenario_model(sc, params)
    c0 = time.process_time()
    build_law(sc, params, None, model, op)
    c1 = time.process_time()
    run_closed_loop(sc, params)
    print(json.dumps([c1 - c0, time.process_time() - c1]))


def _first(src: Path, name: str) -> list[float]:
    env = dict(os.environ, PYTHONPATH=str(src))
    res = subprocess.run([sys.executable, __file__, "--first-build", name], env=env,
                         capture_output=True, text=True)
    if res.returncode:
        sys.exit(f"the first build of {name} on {src} failed:\n{res.stderr}")
    return json.loads(res.stdout.splitlines()[-1])


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
    if "--first-build" in sys.argv:
        first_build(sys.argv[sys.argv.index("--first-build") + 1])
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
    med = {key: {name: [statistics.median(r[name][i] for r in runs)
                        for i in range(len(runs[0][name]))]
                 for name in runs[0] if name != "montecarlo"} for key, runs in got.items()}
    other = "against" if "against" in trees else "this"
    print(f"{'scenario':22s} {'law [us/sample]':>16s} {'against':>8s} {'ratio':>6s}  "
          f"{'run [s]':>8s} {'against':>8s} {'ratio':>6s}")
    for name in med["this"]:
        (pn, wn), (po, wo) = med["this"][name][:2], med[other][name][:2]
        print(f"{name:22s} {1e6 * pn:16.2f} {1e6 * po:8.2f} {pn / po:6.3f}  {wn:8.3f} "
              f"{wo:8.3f} {wn / wo:6.3f}")
    load = [v[0] for k, v in med["this"].items() if k.startswith("slip-load-step")]
    shift = [v[0] for k, v in med["this"].items() if k.startswith("shift")]
    print(f"a shift's sample over a load step's: {max(shift) / statistics.median(load):.2f} "
          f"(largest shift over the load steps' median)")
    # the compiled loop (`run_compiled`: law and integrator in one numba loop) and the law's
    # set-up, CPU time: per 1 ms sample, and the build's share of the whole run_closed_loop
    print(f"{'scenario':22s} {'sample [us]':>11s} {'against':>8s}  {'build [ms]':>10s} "
          f"{'against':>8s} {'ratio':>6s}  {'run [ms]':>9s} {'against':>8s}  "
          f"{'build share':>11s} {'against':>8s}")
    for name in med["this"]:
        _, _, bn, sn, rn = med["this"][name]
        _, _, bo, so, ro = med[other][name]
        print(f"{name:22s} {1e6 * sn:11.1f} {1e6 * so:8.1f}  {1e3 * bn:10.1f} {1e3 * bo:8.1f} "
              f"{bn / bo:6.3f}  {1e3 * rn:9.1f} {1e3 * ro:8.1f}  {bn / rn:11.2f} {bo / ro:8.2f}")
    for key in ("this", other):
        cl = [v[3] for k, v in med[key].items() if k.startswith("slip-load-step")]
        cs = [v[3] for k, v in med[key].items() if k.startswith("shift")]
        print(f"{key}: compiled shift sample over the load steps': "
              f"{max(cs) / statistics.median(cl):.2f} (largest shift); law build share of a "
              f"shift's run_closed_loop: {max(v[2] / v[4] for k, v in med[key].items() if k.startswith('shift')):.2f} (largest)")
    # a process's first law of each shift (fresh processes, alternated; medians of REPEATS)
    first: dict[str, dict[str, list[list[float]]]] = {k: {n: [] for n in FIRST_BUILD}
                                                       for k in trees}
    for _ in range(REPEATS):
        for name in FIRST_BUILD:
            for key, src in trees.items():
                first[key][name].append(_first(src, name))
    print(f"{'first law':22s} {'build [ms]':>10s} {'against':>8s} {'ratio':>6s}  "
          f"{'then run [ms]':>13s} {'against':>8s}  {'build share':>11s} {'against':>8s}")
    for name in FIRST_BUILD:
        (bn, rn), (bo, ro) = ([statistics.median(x[i] for x in first[key][name])
                               for i in (0, 1)] for key in ("this", other))
        print(f"{name:22s} {1e3 * bn:10.1f} {1e3 * bo:8.1f} {bn / bo:6.3f}  {1e3 * rn:13.1f} "
              f"{1e3 * ro:8.1f}  {bn / (bn + rn):11.2f} {bo / (bo + ro):8.2f}")
    if montecarlo:
        mc = {k: statistics.median(r["montecarlo"] for r in runs) for k, runs in got.items()}
        print(f"Monte Carlo, 200 closed-loop runs of slip-load-step-r1, serial: this "
              f"{mc['this']:.1f} s, against {mc[other]:.1f} s, ratio "
              f"{mc['this'] / mc[other]:.3f}")
    print(f"load average {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
