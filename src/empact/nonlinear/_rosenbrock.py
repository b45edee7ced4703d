"""Compiled stiff integrator for the nonlinear model (private; used by
`empact.nonlinear.simulation`).

A linearly implicit (Rosenbrock) method of order 2 with an embedded order-3 error estimate:
the modified Rosenbrock formula of Shampine & Reichelt (MATLAB's ``ode23s``), L-stable, one
LU factorisation per step, with its continuous extension for output between steps.  The
Jacobian is exact (forward-mode derivatives of the compiled right-hand side,
`_tangent._state_jacobian`), the
explicit time dependence through the inputs is included (``df/dt = B du/dt``).

Inputs are piecewise linear in time (a repeated time is a step); the integrator never steps
across a breakpoint, so every step sees smooth inputs.  Breakpoints and input pieces are found
by running indices (O(1) per step, whatever the number of breakpoints behind), and the
Jacobian is evaluated in full once per run and afterwards only in its state-dependent
columns (`_kernel.varying_columns`, 8 or 9 of 18-22); it is kept between calls (a sampled
controller's run calls `integrate` once per sample period).

Numba caches this module's compiled code with `_kernel._eval` inlined and re-checks only this
file's time stamp: after editing `_kernel.py` in a source checkout delete the ``*.nbi`` /
``*.nbc`` files under ``nonlinear/__pycache__`` (an installed upgrade replaces both files).

Status codes returned by `integrate`: 0 reached the end; 1 omega_p at or below omega_min (slip
undefined); 2 clamping force F_s at or below zero (slack belt); 3 a running radius left
[R_min, R_max]; 4 non-finite state; 5 step size below hmin; 6 too many steps; 7 singular
iteration matrix.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from ._kernel import NY, _eval, stop_status
from ._tangent import _input_direction, _state_jacobian

D_GAMMA = 1.0 / (2.0 + np.sqrt(2.0))
E32 = 6.0 + np.sqrt(2.0)

STATUS = {0: "completed", 1: "omega_p reached omega_min: slip (eq. 2) undefined",
          2: "clamping force F_s fell to zero: belt slack", 3: "a running radius left "
          "[R_min, R_max]: ratio outside the variator's range", 4: "non-finite state",
          5: "step size below the minimum (solver failure)", 6: "too many steps",
          7: "singular iteration matrix (solver failure)"}


@njit(cache=True)
def _lu(A, piv):
    """In-place LU factorisation with partial pivoting; False if singular."""
    n = A.shape[0]
    for k in range(n):
        m = k
        big = abs(A[k, k])
        for i in range(k + 1, n):
            if abs(A[i, k]) > big:
                big = abs(A[i, k])
                m = i
        if big == 0.0 or not np.isfinite(big):
            return False
        piv[k] = m
        if m != k:
            for j in range(n):
                tmp = A[k, j]
                A[k, j] = A[m, j]
                A[m, j] = tmp
        inv = 1.0 / A[k, k]
        for i in range(k + 1, n):
            A[i, k] *= inv
            f = A[i, k]
            if f != 0.0:
                for j in range(k + 1, n):
                    A[i, j] -= f * A[k, j]
    return True


@njit(cache=True)
def _lu_solve(LU, piv, b):
    """Solve in place with the factors of `_lu`."""
    n = LU.shape[0]
    for k in range(n):
        m = piv[k]
        if m != k:
            tmp = b[k]
            b[k] = b[m]
            b[m] = tmp
    for i in range(n):
        s = b[i]
        for j in range(i):
            s -= LU[i, j] * b[j]
        b[i] = s
    for i in range(n - 1, -1, -1):
        s = b[i]
        for j in range(i + 1, n):
            s -= LU[i, j] * b[j]
        b[i] = s / LU[i, i]


@njit(cache=True)
def _segment_inputs(t_mid, sig_t, sig_v, sig_n, u0, slope, tref, hint):
    """Linear piece of every input signal that contains `t_mid`: u(t) = u0 + slope (t - tref).

    `hint` holds each signal's piece index of the last call and is updated: time only moves
    forward, so the search starts there (O(1) amortised)."""
    for k in range(sig_n.shape[0]):
        n = sig_n[k]
        tref[k] = t_mid
        slope[k] = 0.0
        if t_mid < sig_t[k, 0]:
            u0[k] = sig_v[k, 0]
            continue
        if t_mid >= sig_t[k, n - 1]:
            u0[k] = sig_v[k, n - 1]
            continue
        i = hint[k]
        if i > n - 2 or sig_t[k, i] > t_mid:
            i = 0
        while i + 1 < n and sig_t[k, i + 1] <= t_mid:
            i += 1
        hint[k] = i
        dt = sig_t[k, i + 1] - sig_t[k, i]
        tref[k] = sig_t[k, i]
        u0[k] = sig_v[k, i]
        if dt > 0.0:
            slope[k] = (sig_v[k, i + 1] - sig_v[k, i]) / dt


@njit(cache=True)
def _u_at(t, u0, slope, tref, u):
    for k in range(u.shape[0]):
        u[k] = u0[k] + slope[k] * (t - tref[k])


@njit(cache=True)
def integrate(x, t, t_end, h, samples, p, ix, sig_t, sig_v, sig_n, brk, rtol, atol,
              hmin, hmax, omega_min, max_steps, X, Y, cols, J, full):
    """Integrate from `t` to `t_end` in place on `x`; fill `X`, `Y` at `samples` in (t, t_end].

    `cols` are the Jacobian columns that change (`_kernel.varying_columns`); `J` (n, n) holds
    the Jacobian between calls: with `full` every column is evaluated at the first step (the
    first call of a run), otherwise only `cols` (the others are constant over a run).

    Returns ``(status, t, h, n_filled, n_steps, n_rejected)``; on a stop, `x` holds the last
    accepted state at time `t`.
    """
    n = x.shape[0]
    m = sig_n.shape[0]
    W = np.empty((n, n))
    piv = np.empty(n, dtype=np.int64)
    F0 = np.empty(n)
    F1 = np.empty(n)
    F2 = np.empty(n)
    T = np.empty(n)
    k1 = np.empty(n)
    k2 = np.empty(n)
    k3 = np.empty(n)
    xs = np.empty(n)
    xn = np.empty(n)
    y = np.empty(NY)
    u = np.empty(m)
    u0 = np.empty(m)
    slope = np.empty(m)
    tref = np.empty(m)
    hint = np.zeros(m, dtype=np.int64)
    all_cols = np.arange(n)
    ib = 0
    n_samp = samples.shape[0]
    js = 0
    while js < n_samp and samples[js] <= t:
        js += 1
    n_filled = js
    n_steps = 0
    n_rej = 0
    d = D_GAMMA
    eps = 1e-12 * max(1.0, abs(t_end))
    while t_end - t > eps:
        if n_steps >= max_steps:
            return 6, t, h, n_filled, n_steps, n_rej
        # next breakpoint after t (breakpoints closer than eps count as passed); brk is sorted
        while ib < brk.shape[0] and brk[ib] - t <= eps:
            ib += 1
        t_stop = t_end
        if ib < brk.shape[0] and brk[ib] < t_stop:
            t_stop = brk[ib]
        h = min(h, hmax)
        last = False
        if t + h >= t_stop - eps:
            h = t_stop - t
            last = True
        _segment_inputs(t + 0.5 * h, sig_t, sig_v, sig_n, u0, slope, tref, hint)
        _u_at(t, u0, slope, tref, u)
        _eval(x, u, p, ix, F0, y)
        _state_jacobian(x, u, p, ix, J, all_cols if full else cols)
        full = False
        _input_direction(x, u, slope, p, ix, T)
        accepted = False
        while not accepted:
            if h < hmin:
                return 5, t, h, n_filled, n_steps, n_rej
            for i in range(n):
                for j in range(n):
                    W[i, j] = -h * d * J[i, j]
                W[i, i] += 1.0
            if not _lu(W, piv):
                return 7, t, h, n_filled, n_steps, n_rej
            for i in range(n):
                k1[i] = F0[i] + h * d * T[i]
            _lu_solve(W, piv, k1)
            for i in range(n):
                xs[i] = x[i] + 0.5 * h * k1[i]
            _u_at(t + 0.5 * h, u0, slope, tref, u)
            _eval(xs, u, p, ix, F1, y)
            for i in range(n):
                k2[i] = F1[i] - k1[i]
            _lu_solve(W, piv, k2)
            for i in range(n):
                k2[i] += k1[i]
                xn[i] = x[i] + h * k2[i]
            _u_at(t + h, u0, slope, tref, u)
            _eval(xn, u, p, ix, F2, y)
            for i in range(n):
                k3[i] = F2[i] - E32 * (k2[i] - F1[i]) - 2.0 * (k1[i] - F0[i]) + h * d * T[i]
            _lu_solve(W, piv, k3)
            err = 0.0
            for i in range(n):
                sc = atol[i] + rtol[i] * max(abs(x[i]), abs(xn[i]))
                e = h / 6.0 * (k1[i] - 2.0 * k2[i] + k3[i]) / sc
                err += e * e
            err = np.sqrt(err / n)
            if not np.isfinite(err):
                h *= 0.25
                last = False
                n_rej += 1
                continue
            if err <= 1.0:
                accepted = True
            else:
                h *= max(0.1, 0.8 * err ** (-1.0 / 3.0))
                last = False
                n_rej += 1
        n_steps += 1
        t_new = t_stop if last else t + h
        # dense output at the samples inside (t, t_new]
        while js < n_samp and samples[js] <= t_new * (1.0 + 1e-14):
            sfrac = (samples[js] - t) / h
            c1 = sfrac * (1.0 - sfrac) / (1.0 - 2.0 * d)
            c2 = sfrac * (sfrac - 2.0 * d) / (1.0 - 2.0 * d)
            for i in range(n):
                xs[i] = x[i] + h * (c1 * k1[i] + c2 * k2[i])
                X[js, i] = xs[i]
            _u_at(samples[js], u0, slope, tref, u)
            _eval(xs, u, p, ix, F1, Y[js])
            js += 1
            n_filled = js
        for i in range(n):
            x[i] = xn[i]
        t = t_new
        status = stop_status(y, p, omega_min)
        if status != 0:
            return status, t, h, n_filled, n_steps, n_rej
        fac = 5.0 if err == 0.0 else min(5.0, max(0.2, 0.8 * err ** (-1.0 / 3.0)))
        h = h * fac
    t = max(t, t_end)
    return 0, t, h, n_filled, n_steps, n_rej
