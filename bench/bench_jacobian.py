"""Benchmark: the exact Jacobian by forward mode against the complex step (issue 23, item 1).

Both routes in one process, side by side, interleaved, one core:

* ``fm``: `empact.nonlinear._kernel._eval_tangent` - hand-derived forward-mode derivatives in
  real arithmetic, all directions in one pass (`_jacobian`, `_state_jacobian`,
  `_input_direction`, `linearize_batch`: what the package now uses);
* ``cs``: the complex step (`_jacobian_cs`, `_state_jacobian_cs`, `_input_direction_cs`,
  `linearize_batch_cs`: the reference, what the package used before).

Measured:

1. time per call in compiled loops on each shipped open-loop scenario's model at its initial
   trim: the RHS (for scale), the integrators' varying columns of A, the full A, B, C, D, the
   input direction (df/du) du;
2. the Jacobian's share of an integrator step: every shipped open-loop scenario at its own
   tolerance with Rodas4 (the default) and with the scenario's own method, run with each route
   (the integrator compiled a second time with the complex-step routines in place of the
   exact ones, as `tests/test_integrators.py` does); share = calls x unit cost / run time
   (one varying-columns Jacobian per accepted step, the full one once per run);
   the outputs of the two routes compared (largest difference over each output's scale);
3. `plant_family` over the 21 x 9 grid of `bench_family.py` and `linearize_batch` alone on
   its trimmed points; a single `EmpactModel.jacobian` and a single `linearize` (which also
   builds a `control.StateSpace`), each with the package's call swapped for the reference.

Ratios: complex-step time / forward-mode time (> 1: forward mode is faster), of the medians
and of the best of 3 x REPEATS interleaved runs (2 and 3; the machine is shared: the best is
the steadier under another job's load), unit costs the best of REPEATS loops.

Run: ``.venv/bin/python bench/bench_jacobian.py`` (about a minute warm; the first run compiles
the complex-step integrator, ~30 s).  ``BENCH_QUICK=1``: fewer repeats.
"""
from __future__ import annotations

import os
import statistics
import sys
import time
import types

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402
from numba import njit  # noqa: E402

from empact.control.family import (  # noqa: E402
    ISSUE21_GRID,
    LOOP_FAMILY_OUTPUTS,
    plant_family,
)
from empact.nonlinear import _kernel as K  # noqa: E402
from empact.nonlinear import _tangent as KT  # noqa: E402
from empact.nonlinear import _batch as KB  # noqa: E402
from empact.nonlinear import _rodas  # noqa: E402
from empact.nonlinear.equilibrium import trim, trim_grid  # noqa: E402
from empact.nonlinear.linearization import linearize  # noqa: E402
from empact.nonlinear.model import nonlinear_model  # noqa: E402
from empact.nonlinear.scenario import example_path, list_examples, load_scenario  # noqa: E402
from empact.nonlinear.simulation import scenario_model, scenario_signals, simulate  # noqa: E402
from empact.params import OperatingPoint, default_params  # noqa: E402

QUICK = os.environ.get("BENCH_QUICK") == "1"
REPEATS = 3 if QUICK else 7
TARGET_SHARE = 0.35      # the Jacobian at most 35 % of a step
TARGET_SPEEDUP = 1.5     # families and linearisation at least 1.5x faster


def timings(fns, repeats=REPEATS):
    """Wall times of the functions, run interleaved `repeats` times after a warm-up."""
    for f in fns:
        f()
    times = [[] for _ in fns]
    for _ in range(repeats):
        for i, f in enumerate(fns):
            t0 = time.perf_counter()
            f()
            times[i].append(time.perf_counter() - t0)
    return times


def medians(fns, repeats=REPEATS):
    """Median wall times of the functions, run interleaved after a warm-up."""
    return [statistics.median(t) for t in timings(fns, repeats)]


# -- 1. unit costs in compiled loops -----------------------------------------------------------
@njit
def _loop_eval(x, u, p, ix, N):
    dx = np.empty(x.shape[0])
    y = np.empty(K.NY)
    for _ in range(N):
        K._eval(x, u, p, ix, dx, y)
    return dx[0]


@njit
def _loop_cols(f, x, u, p, ix, cols, N):
    J = np.empty((x.shape[0], x.shape[0]))
    for _ in range(N):
        f(x, u, p, ix, J, cols)
    return J[0, 0]


@njit
def _loop_full(f, x, u, p, ix, N):
    n = x.shape[0]
    A, B = np.empty((n, n)), np.empty((n, 4))
    C, D = np.empty((K.NY, n)), np.empty((K.NY, 4))
    for _ in range(N):
        f(x, u, p, ix, A, B, C, D)
    return A[0, 0]


@njit
def _loop_dir(f, x, u, du, p, ix, N):
    out = np.empty(x.shape[0])
    for _ in range(N):
        f(x, u, du, p, ix, out)
    return out[0]


def unit_costs(model, x, u, N=20000):
    """Seconds per call: {"f", "cols fm", "cols cs", "full fm", "full cs", "du fm", "du cs"};
    the best of REPEATS loops of N calls each, the two routes interleaved."""
    cols = K.varying_columns(model.ix)
    du = np.array([1.0, 0.5, 0.0, 2.0])
    p, ix = model.p, model.ix
    calls = {"f": lambda n: _loop_eval(x, u, p, ix, n),
             "cols fm": lambda n: _loop_cols(KT._state_jacobian, x, u, p, ix, cols, n),
             "cols cs": lambda n: _loop_cols(K._state_jacobian_cs, x, u, p, ix, cols, n),
             "full fm": lambda n: _loop_full(KT._jacobian, x, u, p, ix, n),
             "full cs": lambda n: _loop_full(K._jacobian_cs, x, u, p, ix, n),
             "du fm": lambda n: _loop_dir(KT._input_direction, x, u, du, p, ix, n),
             "du cs": lambda n: _loop_dir(K._input_direction_cs, x, u, du, p, ix, n)}
    best = {k: np.inf for k in calls}
    for f in calls.values():
        f(10)
    for _ in range(REPEATS):
        for k, f in calls.items():
            t0 = time.perf_counter()
            f(N)
            best[k] = min(best[k], (time.perf_counter() - t0) / N)
    return best


# -- 2. the integrators with the complex-step routines -----------------------------------------
def complex_step_integrators():
    """`_rodas.METHODS` compiled once more with the complex-step Jacobian and input direction
    in place of the exact ones (the stepper's own code, unchanged)."""
    def rebuild(f, **names):
        g = dict(f.__globals__, **names)
        return njit(types.FunctionType(f.__code__, g, f.__name__, f.__defaults__,
                                       f.__closure__))

    run = rebuild(_rodas._run.py_func, _state_jacobian=K._state_jacobian_cs,
                  _input_direction=K._input_direction_cs)
    return {"rodas4": rebuild(_rodas.integrate_rodas4.py_func, _run=run),
            "rodas5p": rebuild(_rodas.integrate.py_func, _run=run)}


def scenarios(params):
    out = []
    for name in sorted(list_examples(closed_loop=False)):
        sc = load_scenario(example_path(name))
        model, op = scenario_model(sc, params)
        out.append((name, sc, model, op, scenario_signals(sc, model, op)))
    return out


def run_with(route, cs_methods, method, sc, model, op, sig):
    """A function running the scenario with `method` on `route` ("fm" or "cs")."""
    kw = dict(u0=op.u, sample_rate=sc.sample_rate, max_step=sc.max_step, rtol=sc.rtol,
              omega_min=sc.omega_min, max_steps=sc.max_steps, method=method)

    def run():
        if route == "fm":
            return simulate(model, op.x, sig, sc.duration, **kw)
        saved = _rodas.METHODS[method]
        _rodas.METHODS[method] = cs_methods[method]
        try:
            return simulate(model, op.x, sig, sc.duration, **kw)
        finally:
            _rodas.METHODS[method] = saved
    return run


class _Start:
    """A start (x, u) in place of a trim result."""

    def __init__(self, x, u):
        self.x, self.u = x, u


def differences(model, a, b):
    """Largest |a.y - b.y| over each output's largest |b.y|: worst of all outputs and worst
    of r_g, nu, F_s."""
    scale = np.abs(b.y).max(axis=0)
    scale[scale == 0] = 1.0
    d = np.abs(a.y - b.y).max(axis=0) / scale
    key = [model.outputs.index(k) for k in ("r_g", "nu", "F_s")]
    return float(d.max()), float(d[key].max())


# -- 3. families and linearisation -------------------------------------------------------------
def with_reference(fn):
    """`fn` run with the package's exact-Jacobian entry points swapped for the complex step."""
    def run():
        saved = KT._jacobian, KB.linearize_batch
        KT._jacobian, KB.linearize_batch = K._jacobian_cs, KB.linearize_batch_cs
        try:
            return fn()
        finally:
            KT._jacobian, KB.linearize_batch = saved
    return run


def main() -> None:
    load0 = os.getloadavg()
    params = default_params()
    print(f"load average at start: {load0[0]:.2f} {load0[1]:.2f} {load0[2]:.2f}; "
          f"{os.cpu_count()} cores; median of {REPEATS} interleaved runs (unit costs: best)")
    work = scenarios(params)

    print("\n1. Time per call [us] (compiled loops; cs / fm = speed-up)")
    print("| scenario | n | RHS | varying cols fm | cs | cs / fm | full A,B,C,D fm | cs | "
          "cs / fm | (df/du) du fm | cs | cs / fm | fm cols / RHS |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    units = {}
    for name, sc, model, op, sig in work:
        c = unit_costs(model, op.x, op.u)
        units[name] = c
        nc = len(K.varying_columns(model.ix))
        print(f"| {name} | {model.n} ({nc} cols) | {1e6 * c['f']:.2f} | "
              f"{1e6 * c['cols fm']:.2f} | {1e6 * c['cols cs']:.2f} | "
              f"**{c['cols cs'] / c['cols fm']:.1f}** | {1e6 * c['full fm']:.2f} | "
              f"{1e6 * c['full cs']:.2f} | **{c['full cs'] / c['full fm']:.1f}** | "
              f"{1e6 * c['du fm']:.2f} | {1e6 * c['du cs']:.2f} | "
              f"{c['du cs'] / c['du fm']:.1f} | {c['cols fm'] / c['f']:.1f} |", flush=True)

    t0 = time.perf_counter()
    cs_methods = complex_step_integrators()
    for method in cs_methods:  # compile (not timed below)
        run_with("cs", cs_methods, method, *work[0][1:])()
    print(f"\n(complex-step integrators compiled in {time.perf_counter() - t0:.0f} s)")

    print("\n2. Integrator runs (each scenario at its own rtol; Jacobian share = (steps x "
          "varying-columns cost + one full) / best run time; median and best of "
          f"{3 * REPEATS} interleaved runs; outputs fm vs cs: the "
          "largest |y_fm - y_cs| over the output's largest |y|, worst of all outputs / worst "
          "of r_g, nu, F_s, at all samples; floor: the same between two fm runs whose initial "
          "states differ by one ulp)")
    print("| scenario | method | rtol | steps + rejected | fm median [ms] | cs median [ms] | "
          "cs / fm | fm best [ms] | cs best [ms] | cs / fm (best) | J share fm | J share cs | "
          "outputs fm vs cs: all / key | floor: all / key |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    shares = []
    for name, sc, model, op, sig in work:
        methods = ["rodas4"] + ([sc.method] if sc.method != "rodas4" else [])
        for method in methods:
            fm = run_with("fm", cs_methods, method, sc, model, op, sig)
            cs = run_with("cs", cs_methods, method, sc, model, op, sig)
            rf, rc = fm(), cs()
            rp = run_with("fm", cs_methods, method, sc, model,
                          _Start(np.nextafter(op.x, np.inf), op.u), sig)()
            assert rf.complete and rc.complete and rp.complete, (rf.message, rc.message)
            d_all, d_key = differences(model, rf, rc)
            f_all, f_key = differences(model, rp, rf)
            t = timings([fm, cs], 3 * REPEATS)
            tf, tc = (statistics.median(v) for v in t)
            bf, bc = (min(v) for v in t)
            ns, nr = rf.stats["n_steps"], rf.stats["n_rejected"]
            nsc = rc.stats["n_steps"]
            c = units[name]
            share_f = (ns * c["cols fm"] + c["full fm"]) / bf
            share_c = (nsc * c["cols cs"] + c["full cs"]) / bc
            shares.append(share_f)
            same = "" if (ns, nr) == (rc.stats["n_steps"], rc.stats["n_rejected"]) else \
                f" (cs: {nsc} + {rc.stats['n_rejected']})"
            print(f"| {name} | {method} | {sc.rtol:.0e} | {ns} + {nr}{same} | {1e3 * tf:.2f} | "
                  f"{1e3 * tc:.2f} | {tc / tf:.2f} | {1e3 * bf:.2f} | {1e3 * bc:.2f} | "
                  f"**{bc / bf:.2f}** | **{100 * share_f:.0f} %** | "
                  f"{100 * share_c:.0f} % | {d_all:.0e} / {d_key:.0e} | "
                  f"{f_all:.0e} / {f_key:.0e} |", flush=True)

    print(f"\n3. Families and linearisation (median and best of {3 * REPEATS} interleaved runs; "
          "cs / fm)")
    r, nu = np.geomspace(0.5, 2, 21), np.geomspace(0.005, 0.02, 9)
    fam = lambda: plant_family(params, r_g=r, nu=nu)  # noqa: E731
    m = nonlinear_model(params, drive="speed", load="torque")
    op = params.operating
    rr, nn = np.meshgrid(r, nu, indexing="ij")
    tg = trim_grid(m, rr.ravel(), np.full(rr.size, op.omega_p), nu=nn.ravel(),
                   F_s=np.full(rr.size, op.F_s))
    X, U = tg.x[tg.ok], tg.u[tg.ok]
    batch = lambda: m.jacobian_many(X, U)  # noqa: E731
    tr = trim(m, OperatingPoint(r_g=1.0, omega_p=op.omega_p, nu=0.01, F_s=op.F_s))
    jac = lambda: [m.jacobian(tr.x, tr.u) for _ in range(100)]  # noqa: E731
    lin = lambda: [linearize(tr) for _ in range(20)]  # noqa: E731
    fa, fb = plant_family(params, r_g=r, nu=nu), with_reference(fam)()
    fdiff = float(np.nanmax(np.abs(fa.A - fb.A)) / np.nanmax(np.abs(fb.A)))
    r2, nu2 = np.geomspace(0.5, 2, 41), np.geomspace(0.005, 0.02, 21)
    fam2 = lambda: plant_family(params, r_g=r2, nu=nu2)  # noqa: E731
    # issue 21's design family (the design family until issue 33), comparable across runs
    dfam = lambda: plant_family(params, **ISSUE21_GRID, outputs=LOOP_FAMILY_OUTPUTS)  # noqa: E731
    rows = [("plant_family, 21 x 9 grid (trim + linearisation)", fam, 1, r.size * nu.size),
            ("plant_family, 41 x 21 grid", fam2, 1, r2.size * nu2.size),
            ("design_family (7 x 3 x 3, the loop outputs)", dfam, 1, 63),
            (f"linearize_batch alone ({X.shape[0]} trimmed points)", batch, 1, X.shape[0]),
            ("EmpactModel.jacobian, one point", jac, 100, 1),
            ("linearize (with control.StateSpace), one point", lin, 20, 1)]
    print("| workload | fm median | cs median | cs / fm (median) | fm best | cs best | "
          "cs / fm (best) |")
    print("|---|---|---|---|---|---|---|")
    speed = {}
    for label, fn, per, pts in rows:
        t = timings([fn, with_reference(fn)], 3 * REPEATS)
        tf, tc = (statistics.median(v) / per for v in t)
        bf, bc = (min(v) / per for v in t)
        unit = "ms" if tf > 1e-3 else "us"
        k = 1e3 if unit == "ms" else 1e6
        speed[label] = tc / tf
        print(f"| {label} | {k * tf:.2f} {unit} | {k * tc:.2f} {unit} | **{tc / tf:.2f}** | "
              f"{k * bf:.2f} {unit} | {k * bc:.2f} {unit} | **{bc / bf:.2f}** |", flush=True)
    print(f"family A, fm vs cs: largest difference {fdiff:.1e} of the largest |A|")

    load1 = os.getloadavg()
    print(f"\ntargets: Jacobian share of a step <= {100 * TARGET_SHARE:.0f} %: largest "
          f"{100 * max(shares):.0f} % ({'met' if max(shares) <= TARGET_SHARE else 'NOT met'}); "
          f"families and linearisation >= {TARGET_SPEEDUP:g}x: "
          + ", ".join(f"{v:.2f}x" for v in speed.values()))
    print(f"load average at the end: {load1[0]:.2f} {load1[1]:.2f} {load1[2]:.2f}")


if __name__ == "__main__":
    sys.exit(main())
