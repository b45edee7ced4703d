"""The sampled loop law's arithmetic, compiled (private; `empact.control.law`).

`pre_core` is the part of `LoopLaw.preprocess` that is arithmetic on floats: the sensor
buffers, the counting encoders' means and quantisation, the slip and the tracking errors, the
gain schedule's interpolation (in ``ln |gain|``; the ``exp`` is numpy's, in the caller), the
clamping feedforward and its filter.  Every operation is the one the law's array form had, in
the same order, with the same library functions (``log``, ``asin``, ``cos`` of the C
library; numba contracts no products into fused multiply-adds without ``fastmath``), so the
results are the same to the last bit.  What needs numpy's own vectorised ``exp``, ``tanh``,
``expm1`` or its BLAS (the schedule's gains, the shift feedforward, the controller's matrix
products) stays with the caller.

Packing (`LoopLaw._pack`): ``P`` the law's constants (the ``_P_*`` indices), ``T`` one row per
sample (the references ``r_g, slip, mu, dr_g/dt``, the decoupler's ratio, the traction peak
at the reference ratio, then the noise of each raw signal), ``S`` the schedule
(`pack_schedule`), ``cache`` the last ratio and its secondary radius.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..variator._compiled import secondary_radius

# P: the law's constants
(_P_NB, _P_NBUF, _P_DELAY, _P_WINDOW, _P_QUANTISE, _P_SPEED_Q, _P_RATIO_Q, _P_SLIP_NU,
 _P_R_REF0, _P_LOG_R, _P_LOG_S, _P_SCHED, _P_FEEDFORWARD, _P_F_S0, _P_BIAS0, _P_BIAS1,
 _P_SAFETY, _P_FF_T_DS, _P_SHIFT_FF, _P_J_S, _P_ALPHA_FF, _P_TPF, _P_FF_GAIN, _P_FF_DEN,
 _P_COSB, _P_L_BELT, _P_A, _P_N_LAST) = range(28)
N_P = 28
# T: the columns of a sample's row
T_R, T_SLIP, T_MU, T_RDOT, T_DEC, T_MU_MAX, T_NOISE = range(7)
# the result vector: errors, log-gains, servo torques (without the controller's share and
# the primary's low-passed share), the feedforward force, the secondary radius at the
# measured ratio, the measurements
(R_E0, R_E1, R_L0, R_L1, R_U0, R_U1, R_F, R_RS) = range(8)
R_M = 8
N_RES = R_M + 7


def pack_schedule(qs: list[list[float]], log_axis: list[bool], strides: list[int],
                  variables: list[int], flat: list[float], n_e: int) -> np.ndarray:
    """A schedule for `schedule_log_gains`: ``[n_axes, n_e, then per axis: length, log,
    stride, variable (its index in SCHEDULE_VARIABLES), the grid values, then the table of
    ln |gain| in C order]``."""
    out = [float(len(qs)), float(n_e)]
    for q, lg, st, var in zip(qs, log_axis, strides, variables):
        out += [float(len(q)), 1.0 if lg else 0.0, float(st), float(var)] + list(q)
    return np.array(out + list(flat))


@njit(cache=True)
def _lo_hi(x, lo, hi):
    """``min(max(x, lo), hi)`` as Python evaluates it (NaN passes)."""
    y = lo if lo > x else x
    return hi if hi < y else y


@njit(cache=True)
def schedule_log_gains(S, values, by_variable, out):
    """The schedule's ln |gain| at `values` (one per axis; with `by_variable` one per
    SCHEDULE_VARIABLES) into ``out[:n_e]``: per axis its
    grid cell ``i`` and fraction ``f`` (held at the edges; ``ln`` of the value on a log
    axis), then ``(1 - f) L[i] + f L[i + 1]`` axis after axis on the cell's corners."""
    n_axes = int(S[0])
    n_e = int(S[1])
    pos = 2
    offset = 0
    m = 0
    fs = np.empty(n_axes)
    strides = np.empty(n_axes, np.int64)
    for a in range(n_axes):
        n = int(S[pos])
        lg = S[pos + 1]
        st = int(S[pos + 2])
        var = int(S[pos + 3])
        q0 = pos + 4
        pos = q0 + n
        v = values[var] if by_variable else values[a]
        if lg != 0.0:
            v = math.log(1e-12 if 1e-12 > v else v)
        if n == 1:
            continue
        lo, hi = 0, n  # bisect_left
        while lo < hi:
            mid = (lo + hi) // 2
            if S[q0 + mid] < v:
                lo = mid + 1
            else:
                hi = mid
        i = lo - 1
        i = 0 if 0 > i else i
        i = n - 2 if n - 2 < i else i
        fs[m] = _lo_hi((v - S[q0 + i]) / (S[q0 + i + 1] - S[q0 + i]), 0.0, 1.0)
        strides[m] = st
        m += 1
        offset += i * st
    n_c = 1 << m
    cur = np.empty((n_c, n_e))
    for c in range(n_c):  # corner c: bit (m - 1 - j) of c is axis j's upper side
        o = offset
        for j in range(m):
            if (c >> (m - 1 - j)) & 1:
                o += strides[j]
        for e in range(n_e):
            cur[c, e] = S[pos + o + e]
    h = n_c
    for j in range(m):
        h //= 2
        f = fs[j]
        g = 1 - f
        for c in range(h):
            for e in range(n_e):
                cur[c, e] = g * cur[c, e] + f * cur[c + h, e]
    for e in range(n_e):
        out[e] = cur[0, e]


@njit(cache=True)
def _radius(r_g, P, cache):
    """`LoopLaw._R_s`: the secondary radius at the measured ratio (the law,
    `empact.variator._laws.secondary_radius`; NaN where it finds no belt geometry), the last
    one reused."""
    r = _lo_hi(r_g, 1e-3, 1e3)
    if r != cache[0]:
        cache[0] = r
        cache[1] = secondary_radius(r, P[_P_L_BELT], P[_P_A], np.nan, 1e-13)
    return cache[1]


@njit(cache=True)
def _pairwise_sum(a, lo, n):
    """The sum of ``a[lo:lo + n]`` in numpy's order (its pairwise summation: eight partial
    sums over blocks of up to 128, halves above), so that a window summed here equals
    ``ndarray.sum`` of it to the last bit."""
    if n < 8:
        res = 0.0
        for i in range(n):
            res += a[lo + i]
        return res
    if n <= 128:
        r = np.empty(8)
        for j in range(8):
            r[j] = a[lo + j]
        i = 8
        top = n - n % 8
        while i < top:
            for j in range(8):
                r[j] += a[lo + i + j]
            i += 8
        res = ((r[0] + r[1]) + (r[2] + r[3])) + ((r[4] + r[5]) + (r[6] + r[7]))
        while i < n:
            res += a[lo + i]
            i += 1
        return res
    h = n // 2
    h -= h % 8
    return _pairwise_sum(a, lo, h) + _pairwise_sum(a, lo + h, n - h)


@njit(cache=True)
def _round(x):
    """Python's ``round(x)`` (to the nearest integer, ties to even) as a float."""
    return np.rint(x)


@njit(cache=True)
def sense(buf, n_raw, P, ideal, m):
    """`LoopLaw.sense`: the measurements into ``m[:n_raw]`` from the buffers ``buf`` (row
    after row, newest first): each signal `delay` samples late, the shaft speeds the mean
    over the counting window (numpy's sum), quantised unless `ideal`."""
    nbuf = int(P[_P_NBUF])
    d = int(P[_P_DELAY])
    W = int(P[_P_WINDOW])
    for i in range(n_raw):
        m[i] = buf[i * nbuf + d]
    if W > 1:
        m[1] = _pairwise_sum(buf, nbuf + d, W) / W
        m[2] = _pairwise_sum(buf, 2 * nbuf + d, W) / W
    if P[_P_QUANTISE] != 0.0 and not ideal:
        q = P[_P_SPEED_Q]
        m[1] = _round(m[1] / q) * q
        m[2] = _round(m[2] / q) * q
        rq = P[_P_RATIO_Q]
        if rq != 0.0:
            m[0] = _round(m[0] / rq) * rq


@njit(cache=True)
def pre_core(s, out, raw, k, ideal, ref, P, T, S, cache, res):
    """`LoopLaw.preprocess` up to the schedule's ``exp``, the safety-factor clamping and the
    primary servo's low-passed share: the next buffers and feedforward force into
    ``out[:n_pre - 1]``, the results (``R_*``) into `res`.  `ref` (4) replaces the sample's
    references when its first entry is not NaN; `ideal` drops noise and quantisation."""
    nb = int(P[_P_NB])
    nbuf = int(P[_P_NBUF])
    n_last = int(P[_P_N_LAST])
    kk = k if k < n_last else n_last
    n_raw = raw.shape[0]
    # the buffers, newest first: every row moves on by one, the new samples in front
    for j in range(nb - 1, 0, -1):
        out[j] = s[j - 1]
    for i in range(n_raw):
        out[i * nbuf] = raw[i] if ideal else raw[i] + T[kk, T_NOISE + i]
    sense(out, n_raw, P, ideal, res[R_M:])
    if np.isnan(ref[0]):
        r_ref, slip_ref, mu_ref, rdot = T[kk, T_R], T[kk, T_SLIP], T[kk, T_MU], T[kk, T_RDOT]
    else:
        r_ref, slip_ref, mu_ref, rdot = ref[0], ref[1], ref[2], ref[3]
    r_m, w_p, w_s, T_ds = res[R_M], res[R_M + 1], res[R_M + 2], res[R_M + 3]
    base = r_m if P[_P_SLIP_NU] != 0.0 else P[_P_R_REF0]
    y = 1.0 - w_s / (base * w_p)
    if P[_P_LOG_R] != 0.0:
        res[R_E0] = math.log(1e-9 if 1e-9 > r_ref else r_ref) - \
            math.log(1e-9 if 1e-9 > r_m else r_m)
    else:
        res[R_E0] = r_ref - r_m
    if P[_P_LOG_S] != 0.0:
        res[R_E1] = math.log(1e-9 if 1e-9 > slip_ref else slip_ref) - \
            math.log(1e-9 if 1e-9 > y else y)
    else:
        res[R_E1] = slip_ref - y
    f = s[nb]
    if P[_P_SCHED] != 0.0:
        mu_max = T[kk, T_MU_MAX] if np.isnan(ref[0]) else ref[4]
        at = np.empty(3)
        at[0] = r_m
        at[1] = mu_ref / mu_max
        at[2] = f if P[_P_FEEDFORWARD] != 0.0 else P[_P_F_S0]
        schedule_log_gains(S, at, True, res[R_L0:R_L1 + 1])
    u1 = P[_P_BIAS1]
    if P[_P_SAFETY] != 0.0:
        res[R_E1] = 0.0  # the slip loop is replaced by the open-loop clamping strategy
        f = 0.0  # (the clamping: the caller's)
    elif P[_P_FEEDFORWARD] != 0.0:
        T_b = T_ds if P[_P_FF_T_DS] != 0.0 else res[R_M + 6]
        if P[_P_SHIFT_FF] != 0.0:  # the secondary pulley's acceleration torque
            T_b = T_b + P[_P_J_S] * w_p * rdot
        a = P[_P_ALPHA_FF]
        R_s = _radius(r_m, P, cache)
        res[R_RS] = R_s
        ff = P[_P_FF_GAIN] * T_b * P[_P_COSB] / (P[_P_FF_DEN] * mu_ref * R_s)
        f = a * f + (1 - a) * ff
        u1 += P[_P_TPF] * f
    else:
        f = 0.0
    res[R_U0] = P[_P_BIAS0]
    res[R_U1] = u1
    res[R_F] = f
    out[nb] = f


# Q: the constants of a whole sample (`step_core`)
(_Q_N_PRE, _Q_SCHED, _Q_SIGN0, _Q_SIGN1, _Q_ALPHA_DEC, _Q_T_MS_START, _Q_SHIFT_FF,
 _Q_LIMITED, _Q_T_MAX, _Q_W_MAX, _Q_S_MAX, _Q_V_MAX, _Q_BAND, _Q_ANTI_WINDUP) = range(14)
N_Q = 14


@njit(cache=True)
def servo_limited(T, w, T_max, w_max, band):
    """The torque servo `T` [N m] delivers at speed `w`: within +-T_max, and the torque that
    would drive it faster falls to zero over the last `band` of its speed limit `w_max`
    (``min(max(x, 0), 1)`` as Python evaluates it, NaN passing; `LoopLaw._limit_f` calls
    this too)."""
    T = -T_max if -T_max > T else T
    T = T_max if T_max < T else T
    if T * w > 0:
        v = (w_max - abs(w)) / (band * w_max)
        v = 0.0 if 0.0 > v else v
        v = 1.0 if 1.0 < v else v
        T *= v
    return T


@njit(cache=True)
def step_core(z, z_next, raw, k, no_ref, P, T, S, cache, res, Q, A, B, C, D, L, u):
    """`LoopLaw.update` at sample `k` (its references, noise and limits, not ideal) for a law
    whose samples need no model call (no safety-factor clamping, so every controller output
    reaches its servo; a shift feedforward only where the reference ratio stands still, so
    that its torque is zero): the next state into
    `z_next`, the servo torques into ``u[:2]``; returns 1 when the clamping feedforward finds
    no belt geometry at the measured ratio (``res[R_M]``), else 0.

    The same operations as `LoopLaw.update` in the same order, but the schedule's ``exp``
    (the C library's here, numpy's SIMD loop there) and the controller's products (summed
    here in index order, by BLAS there) may round differently in the last bit."""
    n = int(Q[_Q_N_PRE])
    nb = n - 2
    pre_core(z, z_next, raw, k, False, no_ref, P, T, S, cache, res)
    e0, e1, u0, u1 = res[R_E0], res[R_E1], res[R_U0], res[R_U1]
    if Q[_Q_SCHED] != 0.0:
        e0 = e0 * (Q[_Q_SIGN0] * math.exp(res[R_L0]))
        e1 = e1 * (Q[_Q_SIGN1] * math.exp(res[R_L1]))
    if P[_P_FEEDFORWARD] != 0.0 and res[R_RS] != res[R_RS]:
        return 1
    n_last = int(P[_P_N_LAST])
    kk = k if k < n_last else n_last
    dec = T[kk, T_DEC]
    t_mp = dec * (u1 - Q[_Q_T_MS_START])
    g = z[nb + 1]
    if dec != 0.0 or Q[_Q_SHIFT_FF] != 0.0:
        a = Q[_Q_ALPHA_DEC]
        g = a * g + (1 - a) * t_mp
        u0 += g
    else:
        g = 0.0
    z_next[nb + 1] = g
    nc = z.shape[0] - n
    du0 = 0.0
    du1 = 0.0
    for j in range(nc):
        du0 += C[0, j] * z[n + j]
        du1 += C[1, j] * z[n + j]
    du0 = du0 + (D[0, 0] * e0 + D[0, 1] * e1)
    du1 = du1 + (D[1, 0] * e0 + D[1, 1] * e1)
    for i in range(nc):
        acc = 0.0
        for j in range(nc):
            acc += A[i, j] * z[n + j]
        z_next[n + i] = acc + (B[i, 0] * e0 + B[i, 1] * e1)
    u0 = u0 + du0
    u1 = u1 + du1
    if Q[_Q_LIMITED] != 0.0:
        w0, w1 = res[R_M + 4], res[R_M + 5]
        s0 = servo_limited(u0, w0, Q[_Q_T_MAX], Q[_Q_W_MAX], Q[_Q_BAND])
        s1 = servo_limited(u1, w1, Q[_Q_S_MAX], Q[_Q_V_MAX], Q[_Q_BAND])
        if Q[_Q_ANTI_WINDUP] != 0.0 and (s0 != u0 or s1 != u1):
            d0 = s0 - u0
            d1 = s1 - u1
            for i in range(nc):
                z_next[n + i] = z_next[n + i] + (L[i, 0] * d0 + L[i, 1] * d1)
        u0, u1 = s0, s1
    u[0] = u0
    u[1] = u1
    return 0
