"""The strongest library route for the simulator's work (benchmark baseline, not shipped):
`scipy.integrate.odeint` (LSODA) driven by the SAME compiled right-hand side and exact
Jacobian (forward mode since issue 23) as `empact.nonlinear.simulation`, through numba wrappers.

Inputs are the same piecewise-linear signals; the run is split at their steps (a fresh LSODA
start each), the other breakpoints are passed as ``tcrit``; outputs are evaluated at the
output samples.  Stop conditions are not checked (the benchmark scenarios complete).
"""
from __future__ import annotations

import numpy as np
from numba import njit
from scipy.integrate import odeint

from empact.nonlinear import _kernel as K
from empact.nonlinear import _tangent as KT
from empact.nonlinear.simulation import state_tolerances

#: LSODA's counters of the last `simulate_odeint` run: steps, f and Jacobian evaluations
COUNTS = {"nst": 0, "nfe": 0, "nje": 0}


@njit(cache=True)
def _inputs(t, t_a, t_b, sig_t, sig_v, sig_n, u):
    tq = min(max(t, t_a), t_b)
    right = tq < 0.5 * (t_a + t_b)  # right limit near the piece start, left near its end
    for k in range(sig_n.shape[0]):
        n = sig_n[k]
        ts = sig_t[k, :n]
        vs = sig_v[k, :n]
        i = (np.searchsorted(ts, tq, side="right") if right
             else np.searchsorted(ts, tq, side="left")) - 1
        if i < 0:
            u[k] = vs[0]
        elif i >= n - 1:
            u[k] = vs[n - 1]
        else:
            u[k] = vs[i] + (vs[i + 1] - vs[i]) * (tq - ts[i]) / (ts[i + 1] - ts[i])


@njit(cache=True)
def _rhs(x, t, p, ix, sig_t, sig_v, sig_n, t_a, t_b):
    u = np.empty(sig_n.shape[0])
    _inputs(t, t_a, t_b, sig_t, sig_v, sig_n, u)
    dx = np.empty(x.shape[0])
    y = np.empty(K.NY)
    K._eval(x, u, p, ix, dx, y)
    return dx


@njit(cache=True)
def _jac(x, t, p, ix, sig_t, sig_v, sig_n, t_a, t_b):
    u = np.empty(sig_n.shape[0])
    _inputs(t, t_a, t_b, sig_t, sig_v, sig_n, u)
    A = np.empty((x.shape[0], x.shape[0]))
    KT._state_jacobian(x, u, p, ix, A, np.arange(x.shape[0]))
    return A


@njit(cache=True)
def _outputs(X, T, p, ix, sig_t, sig_v, sig_n, t_a, t_b):
    Y = np.empty((X.shape[0], K.NY))
    u = np.empty(sig_n.shape[0])
    dx = np.empty(X.shape[1])
    for r in range(X.shape[0]):
        _inputs(T[r], t_a, t_b, sig_t, sig_v, sig_n, u)
        K._eval(X[r], u, p, ix, dx, Y[r])
    return Y


def signal_pieces(model, signals, duration, u0, sample_rate):
    """The inputs as compiled tables (``sig_t, sig_v, sig_n``), the input steps in
    (0, duration) (where a route restarts), the other breakpoints (kinks, passed as critical
    times) and the output sample times."""
    kmax = max([2] + [len(v) for v in signals.values()])
    sig_t, sig_v = np.zeros((4, kmax)), np.zeros((4, kmax))
    sig_n = np.ones(4, dtype=np.int64)
    steps, kinks = set(), set()
    for j, name in enumerate(model.inputs):
        if name in signals:
            arr = np.asarray(signals[name], float)
            sig_n[j] = len(arr)
            sig_t[j, :len(arr)], sig_v[j, :len(arr)] = arr[:, 0], arr[:, 1]
            steps |= set(arr[np.flatnonzero(np.diff(arr[:, 0]) == 0), 0].tolist())
            kinks |= set(arr[:, 0].tolist())
        else:
            sig_v[j, 0] = u0[j]
    steps = sorted(s for s in steps if 0 < s < duration)
    kinks = np.array(sorted(k for k in kinks if 0 < k < duration and k not in steps))
    samples = np.arange(int(np.floor(duration * sample_rate + 1e-9)) + 1) / sample_rate
    return sig_t, sig_v, sig_n, steps, kinks, samples


def simulate_odeint(model, x0, signals, duration, *, u0, sample_rate=1000.0, rtol=1e-4,
                    max_step=0.01, atol_rtol=None):
    """Outputs (n_t, NY) at the samples and the number of LSODA steps.

    Tolerances as the simulator's (`state_tolerances`); `atol_rtol` sets the absolute ones
    from another rtol (a reference run: LSODA refuses absolute tolerances near rounding)."""
    sig_t, sig_v, sig_n, steps, kinks, samples = signal_pieces(model, signals, duration, u0,
                                                               sample_rate)
    rel, atol = state_tolerances(model, rtol)
    if atol_rtol is not None:
        atol = state_tolerances(model, atol_rtol)[1]
    Y = np.empty((len(samples), K.NY))
    Y[:1] = _outputs(np.asarray(x0, float)[None], samples[:1], model.p, model.ix, sig_t, sig_v,
                     sig_n, 0.0, duration)
    x, filled, n_steps = np.asarray(x0, float), 1, 0
    COUNTS.update(nst=0, nfe=0, nje=0)
    for a, b in zip([0.0] + steps, steps + [duration]):
        piece = samples[(samples > a + 1e-12) & (samples <= b + 1e-12)]
        grid = np.union1d(np.concatenate([[a], piece]), [b])
        crit = np.union1d(kinks[(kinks > a) & (kinks < b)], [b])
        args = (model.p, model.ix, sig_t, sig_v, sig_n, a, b)
        sol, info = odeint(_rhs, x, grid, args=args, Dfun=_jac, rtol=rel, atol=atol,
                           tcrit=crit, hmax=max_step, mxstep=10**6, full_output=True)
        n_steps += int(info["nst"][-1])
        for k in COUNTS:
            COUNTS[k] += int(info[k][-1])
        keep = np.isin(grid, piece)
        Y[filled:filled + keep.sum()] = _outputs(sol[keep], grid[keep], *args)
        filled += int(keep.sum())
        x = sol[-1]
    return Y, n_steps
