"""The compiled stiff integrators' shared pieces (private; the driver and the tableaus are
`empact.nonlinear._rodas`): the status codes, the LU factorisation with partial pivoting and
its solve, and the piecewise-linear inputs found by running indices (O(1) per step, whatever
the number of breakpoints behind).

Status codes the integrators return: 0 reached the end; 1 omega_p at or below omega_min (slip
undefined); 2 clamping force F_s at or below zero (slack belt); 3 a running radius left
[R_min, R_max]; 4 non-finite state; 5 step size below hmin; 6 too many steps; 7 singular
iteration matrix.
"""
from __future__ import annotations

import numpy as np
from numba import njit

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
