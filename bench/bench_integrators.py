"""Benchmark: the simulator's integrators against the library routes at equal accuracy
(the higher-order Rosenbrock issue).

Workloads: every shipped open-loop scenario (``empact/data/scenarios``: clamping-ramp,
servo-torque-steps, shift-and-load-step) and a rig record (`bench_rig_odeint.workload`: the
rig's multisine on T_mp at r_g = 0.5 with Coulomb friction and the creep law, 4.096 s, an
input kink every millisecond).  Routes, all driven by the SAME compiled right-hand side and
exact Jacobian (forward mode since issue 23; complex step before), one core:

* ``ros2``: the order-2 Rosenbrock method (ode23s) of `empact.nonlinear._rosenbrock`, the
  default ("old");
* ``rodas5p``, ``rodas4``: the stiffly accurate Rodas5P (order 5) and Rodas4 (order 4) of
  `empact.nonlinear._rodas` ("new");
* ``odeint``: `scipy.integrate.odeint` (LSODA) with the Jacobian as ``Dfun``
  (`_odeint_baseline.py`);
* ``cvode``: SUNDIALS CVODE (BDF, dense) through scikit-sundae (`_cvode_baseline.py`), an
  optional dependency (skipped with a note when absent), at largest BDF orders 5 (its
  default) and 3 - the cheaper of the two counts.

Accuracy: the largest error of the key outputs at the output samples against odeint at rtol
1e-11 (absolute tolerances of rtol 1e-9), each normalised by its signal's range: r_g, nu, F_s
for the scenarios, the rig's measured theta_mp, theta_ms, nu for the rig record.

Equal accuracy: for each workload the baseline is odeint at rtol 1e-4 and at 1e-6; every
other route is run over a grid of tolerances (10^(-k/8)), refined by three tolerances between
its loosest qualifying one and the next looser, and represented by its cheapest run at least
as accurate as the baseline run (the two loosest qualifying tolerances are timed, the faster
counts).  Timings: median of REPEATS warm runs, interleaved with the baseline's in
the same process; ratios are baseline time / route time (> 1: the route is faster).  The
numba compile (cold start) is excluded from these and timed separately in fresh processes.

Run: ``.venv/bin/python bench/bench_integrators.py`` (a few minutes).
"""
from __future__ import annotations

import os
import statistics
import subprocess
import sys
import tempfile
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import numpy as np  # noqa: E402

import _cvode_baseline as CV  # noqa: E402
import _odeint_baseline as OB  # noqa: E402
from _odeint_baseline import simulate_odeint  # noqa: E402
from bench_rig_odeint import workload  # noqa: E402
from numba import njit  # noqa: E402

from empact.nonlinear import _kernel as K  # noqa: E402
from empact.nonlinear import _tangent as KT  # noqa: E402
from empact.nonlinear._rosenbrock import _lu, _lu_solve  # noqa: E402
from empact.nonlinear.scenario import example_path, list_examples, load_scenario  # noqa: E402
from empact.nonlinear.simulation import scenario_model, scenario_signals, simulate  # noqa: E402
from empact.params import default_params  # noqa: E402

QUICK = os.environ.get("BENCH_QUICK") == "1"  # a smoke test: coarse grid, one repeat
REPEATS = 1 if QUICK else 7
TARGETS = (1e-4, 1e-6)
GRID = [10 ** (-k / 8) for k in range(24, 65, 8 if QUICK else 1)]  # 1e-3 ... 1e-8
OURS = ("ros2", "rodas5p", "rodas4")
NEW = ("rodas4", "rodas5p")  # the default first


def workloads(params):
    """(name, model, x0, signals, duration, simulate keywords, error output indices)."""
    out = []
    for name in sorted(list_examples(closed_loop=False)):
        sc = load_scenario(example_path(name))
        model, op = scenario_model(sc, params)
        out.append((name, model, op.x, scenario_signals(sc, model, op), sc.duration,
                    dict(u0=op.u, sample_rate=sc.sample_rate, max_step=sc.max_step),
                    (K.Y_RG, K.Y_NU, K.Y_FS)))
    model, op, sig, end, fs = workload(params, 4.096)
    out.append(("rig record 4.096 s", model, op.x, sig, end, dict(u0=op.u, sample_rate=fs),
                tuple(model.outputs.index(k) for k in ("theta_mp", "theta_ms", "nu"))))
    return out


def runner(route, model, x0, sig, duration, kw, rtol):
    """A function running `route` at `rtol`, returning (outputs, steps or evaluations)."""
    if route in OURS:
        def run():
            r = simulate(model, x0, sig, duration, rtol=rtol, method=route, **kw)
            return r.y, r.stats["n_steps"]
    elif route == "odeint":
        def run():
            return simulate_odeint(model, x0, sig, duration, rtol=rtol, **kw)
    else:  # cvode5, cvode3
        def run():
            return CV.simulate_cvode(model, x0, sig, duration, rtol=rtol,
                                     max_order=int(route[-1]), **kw)
    return run


def medians(fns):
    """Median wall times of the functions, run interleaved REPEATS times after a warm-up."""
    for f in fns:
        f()
    times = [[] for _ in fns]
    for _ in range(REPEATS):
        for i, f in enumerate(fns):
            t0 = time.perf_counter()
            f()
            times[i].append(time.perf_counter() - t0)
    return [statistics.median(t) for t in times]


def unit_costs(model, x, u):
    """Seconds per call of the integrators' parts, each timed in a compiled loop: the RHS
    evaluation, the Jacobian's varying columns, the input direction (df/du) du, the LU
    factorisation, one solve."""
    cols = K.varying_columns(model.ix)
    du = np.zeros(4)
    du[0] = 1.0
    N = 20000
    res = {}
    for name, fn in (("f", _loop_eval), ("J", _loop_jac), ("df/du", _loop_dir), ("LU", _loop_lu),
                     ("solve", _loop_solve)):
        fn(x.copy(), u, du, model.p, model.ix, cols, 10)
        t0 = time.perf_counter()
        fn(x.copy(), u, du, model.p, model.ix, cols, N)
        res[name] = (time.perf_counter() - t0) / N
    return res


@njit(cache=True)
def _loop_eval(x, u, du, p, ix, cols, N):
    dx = np.empty(x.shape[0])
    y = np.empty(K.NY)
    for _ in range(N):
        K._eval(x, u, p, ix, dx, y)
    return dx[0]


@njit(cache=True)
def _loop_jac(x, u, du, p, ix, cols, N):
    J = np.empty((x.shape[0], x.shape[0]))
    for _ in range(N):
        KT._state_jacobian(x, u, p, ix, J, cols)
    return J[0, 0]


@njit(cache=True)
def _loop_dir(x, u, du, p, ix, cols, N):
    out = np.empty(x.shape[0])
    for _ in range(N):
        KT._input_direction(x, u, du, p, ix, out)
    return out[0]


@njit(cache=True)
def _loop_lu(x, u, du, p, ix, cols, N):
    n = x.shape[0]
    J = np.empty((n, n))
    KT._state_jacobian(x, u, p, ix, J, np.arange(n))
    W = np.empty((n, n))
    piv = np.empty(n, dtype=np.int64)
    for _ in range(N):
        for i in range(n):
            for j in range(n):
                W[i, j] = -1e-4 * J[i, j]
            W[i, i] += 1.0
        _lu(W, piv)
    return W[0, 0]


@njit(cache=True)
def _loop_solve(x, u, du, p, ix, cols, N):
    n = x.shape[0]
    J = np.empty((n, n))
    KT._state_jacobian(x, u, p, ix, J, np.arange(n))
    W = np.eye(n) - 1e-4 * J
    piv = np.empty(n, dtype=np.int64)
    _lu(W, piv)
    b = np.ones(n)
    for _ in range(N):
        _lu_solve(W, piv, b)
    return b[0]


def breakdown(params, picks):
    """Where the time goes on shift-and-load-step at equal accuracy: calls x unit costs
    (`unit_costs`) for ros2 and rodas5p, LSODA's counters for odeint."""
    sc = load_scenario(example_path("shift-and-load-step"))
    model, op = scenario_model(sc, params)
    sig = scenario_signals(sc, model, op)
    kw = dict(u0=op.u, sample_rate=sc.sample_rate, max_step=sc.max_step)
    c = unit_costs(model, op.x, op.u)
    n_samp = int(sc.duration * sc.sample_rate)
    print("\nwhere the time goes, shift-and-load-step (unit costs in compiled loops: "
          + ", ".join(f"{k} {1e6 * v:.2f} us" for k, v in c.items()) + "):")
    # calls per accepted step / per rejected attempt / per output sample
    per = {"ros2": ({"J": 1, "f": 3, "df/du": 1, "LU": 1, "solve": 3},
                    {"f": 2, "LU": 1, "solve": 3}),
           "rodas5p": ({"J": 1, "f": 8, "df/du": 1, "LU": 1, "solve": 8},
                       {"f": 7, "LU": 1, "solve": 8}),
           "rodas4": ({"J": 1, "f": 6, "df/du": 1, "LU": 1, "solve": 6},
                      {"f": 5, "LU": 1, "solve": 6})}
    for target, routes in picks.items():
        for route, rtol in routes.items():
            if route == "odeint":
                t, _ = medians([runner("odeint", model, op.x, sig, sc.duration, kw, rtol)])[0], 0
                cnt = dict(OB.COUNTS)
                print(f"  target {target:.0e}, odeint rtol {rtol:.1e}: {1e3 * t:.2f} ms, "
                      f"{cnt['nst']} steps, {cnt['nfe']} f and {cnt['nje']} Jacobian "
                      f"evaluations ({1e6 * t / cnt['nst']:.2f} us per step)")
                continue
            t = medians([runner(route, model, op.x, sig, sc.duration, kw, rtol)])[0]
            r = simulate(model, op.x, sig, sc.duration, rtol=rtol, method=route, **kw)
            ns, nr = r.stats["n_steps"], r.stats["n_rejected"]
            acc, rej = per[route]
            parts = {k: c[k] * (acc.get(k, 0) * ns + rej.get(k, 0) * nr) for k in c}
            parts["f"] += c["f"] * n_samp  # the outputs at the samples
            rest = t - sum(parts.values())
            # df/du: an upper bound (no cost on constant input pieces)
            print(f"  target {target:.0e}, {route} rtol {rtol:.1e}: {1e3 * t:.2f} ms, {ns} steps "
                  f"+ {nr} rejected ({1e6 * t / (ns + nr):.2f} us per attempt): "
                  + ", ".join(f"{k} {100 * v / t:.0f} %" for k, v in parts.items())
                  + f", the rest (stage sums, dense output, controller, calls) "
                    f"{100 * rest / t:.0f} %")


COLD = """
import os, sys, time
t0 = time.perf_counter()
from empact.params import default_params
from empact.nonlinear.scenario import example_path, load_scenario
from empact.nonlinear.simulation import run_scenario
from dataclasses import replace
sc = replace(load_scenario(example_path("shift-and-load-step")), method=sys.argv[1])
params = default_params()
t1 = time.perf_counter()
run_scenario(sc, params)
t2 = time.perf_counter()
run_scenario(sc, params)
t3 = time.perf_counter()
print(t1 - t0, t2 - t1, t3 - t2)
"""


def cold_start():
    """Fresh processes: (imports, first run, second run) [s] with an empty numba cache (every
    compiled function compiled: kernel, trim, integrator) and with the cache present."""
    rows = []
    for method in ("ros2",) + NEW:
        with tempfile.TemporaryDirectory() as cache:
            env = dict(os.environ, NUMBA_CACHE_DIR=cache)
            empty = subprocess.run([sys.executable, "-c", COLD, method], env=env,
                                   capture_output=True, text=True, check=True).stdout.split()
            warm = [subprocess.run([sys.executable, "-c", COLD, method], env=env,
                                   capture_output=True, text=True,
                                   check=True).stdout.split() for _ in range(3)]
        rows.append((method, [float(v) for v in empty],
                     [statistics.median(float(w[i]) for w in warm) for i in range(3)]))
    return rows


def main() -> None:
    load0 = os.getloadavg()
    params = default_params()
    routes = list(OURS) + ["odeint"] + (["cvode5", "cvode3"] if CV.available() else [])
    print(f"load average at start: {load0[0]:.2f} {load0[1]:.2f} {load0[2]:.2f}; "
          f"{os.cpu_count()} cores; median of {REPEATS}")
    if not CV.available():
        print("note: scikit-sundae is not installed: CVODE skipped (pip install scikit-sundae)")
    else:
        print(f"scikit-sundae step() call overhead: {1e6 * CV.call_overhead():.1f} us per "
              "output sample (the wrapper's, included in the CVODE times)")
    same, equal = [], []
    for name, model, x0, sig, duration, kw, idx in workloads(params):
        t0 = time.perf_counter()
        ref, _ = simulate_odeint(model, x0, sig, duration, rtol=1e-11, atol_rtol=1e-9, **kw)

        def err(Y):
            return max(float(np.max(np.abs(Y[:, k] - ref[:, k])) / np.ptp(ref[:, k]))
                       for k in idx)

        sweep = {}  # route -> [(rtol, error, single time, steps)]
        for route in routes:
            sweep[route] = []
            for rtol in GRID:
                if route == "ros2" and rtol < 1e-7:
                    continue  # order 2: minutes per run below this, never the cheapest
                run = runner(route, model, x0, sig, duration, kw, rtol)
                try:
                    ts = time.perf_counter()
                    Y, n = run()
                    sweep[route].append((rtol, err(Y), time.perf_counter() - ts, n))
                except RuntimeError:
                    sweep[route].append((rtol, np.inf, np.inf, 0))  # CVODE failure
        # the same tolerance: every route at 1e-4 and 1e-6
        for rtol in TARGETS:
            rs = [r for r in routes]
            ok = [r for r in rs if np.isfinite(dict((a, b) for a, b, _, _ in sweep[r])[rtol])]
            t = medians([runner(r, model, x0, sig, duration, kw, rtol) for r in ok])
            for r, tr in zip(ok, t):
                e = dict((a, b) for a, b, _, _ in sweep[r])[rtol]
                same.append((name, rtol, r, e, tr))
            for r in set(rs) - set(ok):
                same.append((name, rtol, r, np.inf, np.inf))
        # equal accuracy: odeint at the target against each route's cheapest run as accurate
        for target in TARGETS:
            e_base = [e for r, e, _, _ in sweep["odeint"] if r == target][0]
            picks = {}
            for route in routes:
                if route == "odeint":
                    continue
                ok = [c for c in sweep[route] if c[1] <= e_base]
                if ok:  # refine towards the next looser grid tolerance (not as accurate)
                    r_ok = max(c[0] for c in ok)
                    looser = [c[0] for c in sweep[route] if c[0] > r_ok]
                    if looser:
                        r_bad = min(looser)
                        for j in (1, 2, 3):
                            rtol = r_ok * (r_bad / r_ok) ** (j / 4)
                            try:
                                Y, n = runner(route, model, x0, sig, duration, kw, rtol)()
                                if err(Y) <= e_base:
                                    ok.append((rtol, err(Y), 0.0, n))
                            except RuntimeError:
                                pass
                ok = sorted(ok, key=lambda c: -c[0])[:2]  # the two loosest
                picks[route] = ok
            fns = [runner("odeint", model, x0, sig, duration, kw, target)]
            keys = [("odeint", target, e_base)]
            for route, ok in picks.items():
                for rtol, e, _, _ in ok:
                    fns.append(runner(route, model, x0, sig, duration, kw, rtol))
                    keys.append((route, rtol, e))
            t = medians(fns)
            best = {}
            for (route, rtol, e), tr in zip(keys, t):
                if route not in best or tr < best[route][2]:
                    best[route] = (rtol, e, tr)
            if "cvode5" in best or "cvode3" in best:
                cv = [best[k] + (k,) for k in ("cvode5", "cvode3") if k in best]
                best["cvode"] = min(cv, key=lambda c: c[2])
            equal.append((name, target, best))
        print(f"  {name}: done in {time.perf_counter() - t0:.0f} s", flush=True)

    print("\nThe same tolerance (error of r_g, nu, F_s or of the rig's signals vs odeint at "
          "rtol 1e-11; time [ms])")
    print("| workload | rtol | " + " | ".join(routes) + " |")
    print("|---|---|" + "---|" * len(routes))
    for name in dict.fromkeys(r[0] for r in same):
        for rtol in TARGETS:
            cells = {r: (e, t) for n, rt, r, e, t in same if n == name and rt == rtol}
            row = " | ".join("failed" if not np.isfinite(cells[r][0]) else
                             f"{cells[r][0]:.1e}, {1e3 * cells[r][1]:.2f}" for r in routes)
            print(f"| {name} | {rtol:.0e} | {row} |")

    print("\nEqual accuracy: odeint at rtol 1e-4 / 1e-6 against each route's cheapest run at "
          "least as accurate (its rtol, error, time [ms]); speed-ups = time of the other route "
          "/ time of the new method")
    cols = [r for r in routes if r not in ("odeint", "cvode5", "cvode3")] + \
        (["cvode"] if CV.available() else [])
    ratio_cols = [(b, n) for n in NEW for b in ("odeint", "cvode", "ros2")]
    print("| workload | odeint rtol (error, time) | " + " | ".join(cols) + " | "
          + " | ".join(f"{b} / {n}" for b, n in ratio_cols) + " |")
    print("|---|---|" + "---|" * (len(cols) + len(ratio_cols)))
    for name, target, best in equal:
        base = best["odeint"]
        cells = []
        for r in cols:
            if r not in best:
                cells.append("none as accurate")
                continue
            rt, e, tr = best[r][:3]
            tag = f" [{best[r][3]}]" if r == "cvode" else ""
            cells.append(f"{rt:.1e}{tag}: {e:.1e}, {1e3 * tr:.2f}")
        def ratio(k, n):
            return f"{best[k][2] / best[n][2]:.2f}" if k in best and n in best else "-"

        print(f"| {name} | {target:.0e} ({base[1]:.1e}, {1e3 * base[2]:.2f}) | "
              + " | ".join(cells) + " | "
              + " | ".join(ratio(b, n) for b, n in ratio_cols) + " |")

    picks = {tg: {"odeint": tg, **{r: b[0] for r, b in best.items() if r in OURS}}
             for name, tg, best in equal if name == "shift-and-load-step"}
    breakdown(params, picks)
    if QUICK:
        return
    print("\ncold start, fresh processes (imports / first run / second run [s], "
          "shift-and-load-step):")
    for method, empty, warm in cold_start():
        print(f"  {method}: empty numba cache {empty[0]:.2f} / {empty[1]:.2f} / {empty[2]:.3f}; "
              f"cache present {warm[0]:.2f} / {warm[1]:.2f} / {warm[2]:.3f}")
    load1 = os.getloadavg()
    print(f"load average at the end: {load1[0]:.2f} {load1[1]:.2f} {load1[2]:.2f}")


if __name__ == "__main__":
    main()
