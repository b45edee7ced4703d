"""A second library baseline for the simulator's work (benchmark only, not shipped): SUNDIALS
CVODE (variable-order BDF, dense direct linear solver) through scikit-sundae, driven by the
SAME compiled right-hand side and exact Jacobian (forward mode) as `empact.nonlinear.simulation`
(the numba wrappers of `_odeint_baseline.py`).

An optional benchmark dependency (``pip install -e '.[bench]'``, i.e. scikit-sundae; `make
bench` tries to install it): `available()` says whether it imports.  As the odeint route: the run is split at the input steps (a fresh CVODE start
each), the other breakpoints are critical times (``tstop``: CVODE does not step across them,
no restart), outputs are evaluated at the output samples from CVODE's interpolated state
(one ``step(t_sample, tstop=...)`` call per sample).  CVODE takes one relative tolerance for
all states: ``rtol``, with the simulator's absolute tolerances (`state_tolerances`); the
simulator gives the positions no relative tolerance, CVODE cannot - the benchmark compares the
routes at equal measured error, so this only moves CVODE along its error-time curve.  Stop
conditions are not checked (the benchmark scenarios complete).

With its default largest order (5) CVODE fails on some of the shipped scenarios at tight
tolerances (error test failures where the slip passes the traction peak: BDF orders 3-5 are
not A-stable and the machine has lightly damped modes; scikit-sundae does not expose CVODE's
stability limit detection), so `max_order` is an argument.
"""
from __future__ import annotations

import time

import numpy as np

from _odeint_baseline import _jac, _outputs, _rhs, signal_pieces
from empact.nonlinear import _kernel as K
from empact.nonlinear.simulation import state_tolerances

try:
    from sksundae.cvode import CVODE
except ImportError:  # the optional benchmark dependency
    CVODE = None


def available() -> bool:
    """True when scikit-sundae (CVODE) imports."""
    return CVODE is not None


def _callbacks(args):
    """CVODE's right-hand side and Jacobian callbacks for one piece of the inputs."""
    def rhs(t, y, yp):
        yp[:] = _rhs(y, t, *args)

    def jac(t, y, yp, JJ):
        JJ[:, :] = _jac(y, t, *args)

    return rhs, jac


def simulate_cvode(model, x0, signals, duration, *, u0, sample_rate=1000.0, rtol=1e-4,
                   max_step=0.01, max_order=5):
    """Outputs (n_t, NY) at the samples and the number of right-hand side evaluations;
    `max_order` the largest BDF order (CVODE's default 5; 3 for problems with lightly damped
    stiff oscillations, where orders 3-5 are not A-stable).  RuntimeError if CVODE fails."""
    sig_t, sig_v, sig_n, steps, kinks, samples = signal_pieces(model, signals, duration, u0,
                                                               sample_rate)
    atol = state_tolerances(model, rtol)[1]
    Y = np.empty((len(samples), K.NY))
    Y[:1] = _outputs(np.asarray(x0, float)[None], samples[:1], model.p, model.ix, sig_t, sig_v,
                     sig_n, 0.0, duration)
    x, filled, nfev = np.asarray(x0, float), 1, 0
    for a, b in zip([0.0] + steps, steps + [duration]):
        piece = samples[(samples > a + 1e-12) & (samples <= b + 1e-12)]
        crit = np.union1d(kinks[(kinks > a) & (kinks < b)], [b])
        args = (model.p, model.ix, sig_t, sig_v, sig_n, a, b)

        rhs, jac = _callbacks(args)
        solver = CVODE(rhs, method="BDF", rtol=rtol, atol=atol, jacfn=jac, max_step=max_step,
                       max_num_steps=10 ** 7, max_order=max_order)
        solver.init_step(a, x)
        times = np.union1d(piece, crit)
        keep = np.isin(times, piece)
        X = np.empty((len(times), len(x)))
        ic = 0
        res = None
        for r, te in enumerate(times):
            while crit[ic] < te:
                ic += 1
            res = solver.step(float(te), tstop=float(crit[ic]))
            if not res.success:
                raise RuntimeError(f"CVODE failed at t = {res.t}: {res.message}")
            X[r] = res.y
        nfev += int(res.nfev)
        Y[filled:filled + keep.sum()] = _outputs(X[keep], times[keep], *args)
        filled += int(keep.sum())
        x = X[-1].copy()
    return Y, nfev


def call_overhead(n_calls: int = 2000) -> float:
    """Seconds per ``step()`` call of scikit-sundae on a one-state problem with steps much
    longer than the output spacing (the wrapper's cost per output sample, not CVODE's)."""
    def rhs(t, y, yp):
        yp[0] = -y[0]

    def jac(t, y, yp, JJ):
        JJ[0, 0] = -1.0

    ts = np.linspace(0.0, 1.0, n_calls + 1)[1:]
    solver = CVODE(rhs, rtol=1e-3, atol=1e-6, jacfn=jac, max_step=0.5)
    solver.init_step(0.0, np.array([1.0]))
    t0 = time.perf_counter()
    for te in ts:
        solver.step(float(te), tstop=1.0)
    return (time.perf_counter() - t0) / n_calls
