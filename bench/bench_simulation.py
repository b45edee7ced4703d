"""Benchmark: the 2 s shift-and-load-step scenario (issue 4, item 9).

The compiled route (numba right-hand side, exact complex-step Jacobian, compiled L-stable
Rosenbrock integrator, `empact.simulate`) against the same model run by
`scipy.integrate.solve_ivp` (BDF, finite-difference Jacobian) with a plain Python right-hand
side (the pure-Python source of the same kernel, ``_eval.py_func``), in one process, one core.
The baseline integrates piece by piece between the input breakpoints, like the compiled route.
Run: `.venv/bin/python bench/bench_simulation.py`.
"""
import os

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import platform  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402
from scipy.integrate import solve_ivp  # noqa: E402

from empact import _nonlinear_kernel as K  # noqa: E402
from empact.params import default_params  # noqa: E402
from empact.simulate import (_inputs_at, example_path, load_scenario, run_scenario,  # noqa: E402
                             scenario_model, state_tolerances)


def baseline(scenario, params):
    """solve_ivp(BDF) with the plain-Python right-hand side; returns (t, final x, wall time)."""
    model, op = scenario_model(scenario, params)
    a = params.actuation
    signals = dict(scenario.inputs)
    arr = np.array(signals.pop("F_s_ref"), float)
    arr[:, 1] = a.i_e * a.s * model.p[K.P_SIG] * arr[:, 1] / a.i_c
    signals["T_ms"] = arr
    kmax = max(len(v) for v in signals.values())
    sig_t, sig_v = np.zeros((4, kmax)), np.zeros((4, kmax))
    sig_n = np.ones(4, dtype=np.int64)
    sig_v[:, 0] = op.u
    brk = {scenario.duration}
    for j, name in enumerate(model.inputs):
        if name in signals:
            v = signals[name]
            sig_n[j] = len(v)
            sig_t[j, :len(v)], sig_v[j, :len(v)] = v[:, 0], v[:, 1]
            brk |= {float(t) for t in v[:, 0] if 0 < t <= scenario.duration}
    f = K._eval.py_func
    dx, y = np.empty(model.n), np.empty(K.NY)

    def rhs(t, x, u_left):
        u = _inputs_at(t, sig_t, sig_v, sig_n) if u_left is None else u_left(t)
        f(x, u, model.p, model.ix, dx, y)
        return dx.copy()

    _, atol = state_tolerances(model, scenario.rtol)
    x, t0 = op.x.copy(), 0.0
    ts = []
    wall = time.perf_counter()
    for t1 in sorted(brk):
        # inputs of this piece, evaluated at the piece's midpoint segment (steps are right-
        # continuous at t0, so use the value just after t0 and the slope inside the piece)
        tm = 0.5 * (t0 + t1)
        ua, ub = _inputs_at(t0 + 1e-12 * (t1 - t0), sig_t, sig_v, sig_n), \
            _inputs_at(tm, sig_t, sig_v, sig_n)
        slope = (ub - ua) / (tm - t0)
        sol = solve_ivp(rhs, (t0, t1), x, method="BDF", rtol=scenario.rtol,
                        atol=atol, max_step=scenario.max_step,
                        args=(lambda t, ua=ua, slope=slope, t0=t0: ua + slope * (t - t0),))
        if not sol.success:
            raise RuntimeError(sol.message)
        x, t0 = sol.y[:, -1], t1
        ts.append(sol.t)
    return np.concatenate(ts), x, time.perf_counter() - wall


def main():
    params = default_params()
    sc = load_scenario(example_path("shift-and-load-step"))
    run_scenario(sc.with_duration(0.01), params)  # compile (or load the numba cache)
    walls = []
    for _ in range(5):
        t0 = time.perf_counter()
        res = run_scenario(sc, params)
        walls.append(time.perf_counter() - t0)
    assert res.complete, res.message
    wall = min(walls)
    print(f"machine: {platform.machine()}, {platform.processor() or 'cpu'}, python "
          f"{platform.python_version()}, numpy {np.__version__}, one core")
    print(f"scenario {sc.name}: {sc.duration:g} s simulated, {res.stats['n_steps']} steps "
          f"({res.stats['n_rejected']} rejected), {len(res.t)} output samples")
    print(f"compiled (numba + Rosenbrock, trim included, best of 5): {1e3 * wall:8.1f} ms   "
          f"real-time factor {sc.duration / wall:6.1f}")
    t_b, x_b, wall_b = baseline(sc, params)
    v, tb = params.variator, np.tan(params.variator.beta)
    r_b = (v.R_min + x_b[4] / tb) / (v.R_max - x_b[5] / tb)  # final ratio of the baseline
    dr = abs(res.output("r_g")[-1] - r_b)
    print(f"plain Python rhs + solve_ivp(BDF, FD Jacobian):          {1e3 * wall_b:8.1f} ms   "
          f"real-time factor {sc.duration / wall_b:6.2f}   ({len(t_b)} steps)")
    print(f"speed-up: {wall_b / wall:.1f}x;  |r_g(2 s) compiled - baseline| = {dr:.2e}")


if __name__ == "__main__":
    main()
