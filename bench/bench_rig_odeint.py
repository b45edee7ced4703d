"""Benchmark: the simulator's integrator against odeint on the rig's workload (issues 9, 12).

The rig's records (`empact.experiments.rig`, multisine on T_mp sampled at 1 kHz: an input
breakpoint every millisecond; r_g = 0.5, spindle Coulomb friction, the creep law), simulated
by empact's compiled order-2 Rosenbrock method (``method="ros2"``; the higher-order methods
are in `bench_integrators.py`) and by `scipy.integrate.odeint` (LSODA) with the SAME
compiled right-hand side and exact Jacobian (`_odeint_baseline.py`), warm, one core.  Errors:
largest deviation of theta_mp, theta_ms and nu from odeint at rtol 1e-9, normalised by each
signal's range.

Run: ``.venv/bin/python bench/bench_rig_odeint.py``
"""
from __future__ import annotations

import os
import sys
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import numpy as np  # noqa: E402

from _odeint_baseline import simulate_odeint  # noqa: E402
from empact.experiments.rig import RigSettings, excitation_signal  # noqa: E402
from empact.nonlinear import nonlinear_model, simulate, trim  # noqa: E402
from empact.params import default_params  # noqa: E402


def workload(params, duration):
    s = RigSettings(duration=duration, settle=0.0, period=min(2048, int(duration * 1000)))
    model = nonlinear_model(params, coulomb_sp=float(s.coulomb[0]),
                            coulomb_ss=float(s.coulomb[1]))
    op = trim(model, s.r_g, s.omega_p, nu=s.nu, F_s=s.F_s)
    n = int(round(s.duration * s.sample_rate))
    t = np.arange(n) / s.sample_rate
    x = excitation_signal(s.excitation, n, s.sample_rate, s.band_hz, s.rms, seed=s.seed,
                          period=s.period)
    j = model.inputs.index(s.excite)
    return model, op, {s.excite: np.column_stack([t, op.u[j] + x])}, t[-1], s.sample_rate


def warm(fn):
    fn()
    t0 = time.perf_counter()
    out = fn()
    return time.perf_counter() - t0, out


def main() -> None:
    params = default_params()
    print(f"{'record [s]':>10s} {'rtol':>6s} {'empact [s]':>10s} {'error':>8s} "
          f"{'odeint [s]':>10s} {'error':>8s}")
    for duration in (4.096, 16.384):
        model, op, sig, end, fs = workload(params, duration)
        kw = dict(u0=op.u, sample_rate=fs)
        ref, _ = simulate_odeint(model, op.x, sig, end, rtol=1e-9, atol_rtol=1e-8, **kw)
        idx = [model.outputs.index(k) for k in ("theta_mp", "theta_ms", "nu")]

        def err(Y):
            return max(float(np.max(np.abs(Y[:, k] - ref[:, k])) / np.ptp(ref[:, k]))
                       for k in idx)

        rows = []
        for rtol in (1e-4, 1e-5, 1e-6):
            te, res = warm(lambda r=rtol: simulate(model, op.x, sig, end, rtol=r,
                                                   method="ros2", **kw))
            to, (Y, _) = warm(lambda r=rtol: simulate_odeint(model, op.x, sig, end, rtol=r,
                                                              **kw))
            rows.append((rtol, te, err(res.y), to, err(Y)))
            print(f"{duration:10.3f} {rtol:6.0e} {te:10.3f} {err(res.y):8.1e} {to:10.3f} "
                  f"{err(Y):8.1e}")
        for rtol, te, ee, _, _ in rows:
            ok = [(to, eo) for _, _, _, to, eo in rows if eo <= ee]
            if ok:
                to, eo = min(ok)
                print(f"  empact rtol {rtol:.0e} ({te:.3f} s, {ee:.1e}) vs the cheapest odeint "
                      f"at least as accurate ({to:.3f} s, {eo:.1e}): odeint / empact = "
                      f"{to / te:.1f}")


if __name__ == "__main__":
    main()
