"""The sampled loop law's sample, compiled (private; `empact.control.law`).

`sample` is one whole sample of `empact.control.law.LoopLaw` (`update` and `step` wrap it):
the sensor buffers, the counting encoders' means and quantisation, the slip and the tracking
errors, the gain schedule, the clamping feedforward and its filter or the safety-factor
clamping, the decoupler and the shift feedforward with their low-pass, the controller, the
servo limits and the anti-windup; `pre` is the same up to the controller (`preprocess`, what
`empact.control.loop` linearises).  The model's laws come from the compiled kernel
(`empact.nonlinear._batch.mu_max_many`: the traction peak; `empact.nonlinear._kernel`:
``creep_coefficient`` and the creep law ``creep_force``), the secondary radius from the one
belt-geometry law (`empact.variator._laws.secondary_radius`, compiled).

The law is handed over in three named structures (`LawConstants`, `LawTables`, `LawWork`,
built by `LoopLaw`) behind one reference (`Law`): its constants, its per-sample tables
(references, noise, the shift feedforward's geometry) with the controller's matrices and the
model's parameter vector, and its work arrays (the last secondary radius, the measurements,
the servo torques).  Every
operation is the one the law's float form had, in the same order, with the C library's
``log``, ``asin``, ``cos``, ``exp`` (numba contracts no products into fused multiply-adds
without ``fastmath``); the controller's products are summed in index order, and the shift
feedforward's ``tanh`` is the C library's where the Python form had numpy's (which rounds the
last bit differently in about a third of the arguments).
"""
from __future__ import annotations

import math
from typing import NamedTuple, get_type_hints

import numpy as np
from numba import njit, types
from numba.experimental import structref

from ..nonlinear._batch import mu_max_many
from ..nonlinear._kernel import creep_coefficient, creep_force
from ..variator._compiled import secondary_radius


class LawConstants(NamedTuple):
    """The loop law's constants (`empact.control.law.LoopLaw`; SI units)."""

    n_pre: int  #: size of the sensor, feedforward and decoupler state
    n_buf: int  #: samples buffered per raw signal (delay + counting window)
    delay: int  #: sensor delay [samples]
    window: int  #: the counting encoders' window [samples]
    quantise: bool  #: quantise the measurements
    speed_quantum: float  #: [rad/s]
    ratio_quantum: float  #: [-]
    slip_nu: bool  #: the slip signal is ``nu`` (else ``nu_r``, on `r_ref0`)
    r_ref0: float  #: the reference ratio of ``nu_r`` [-]
    log_r: bool  #: the ratio error is of logarithms
    log_s: bool  #: the slip error is of logarithms
    scheduled: bool  #: the controller has a gain schedule
    sign0: float  #: the schedule's gain signs
    sign1: float
    feedforward: bool  #: the clamping feedforward
    ff_t_ds: bool  #: the feedforward's torque is T_ds (else T_l_act)
    F_s0: float  #: the starting clamping force [N]
    bias0: float  #: the servo torques without the controller's and feedforwards' [N m]
    bias1: float
    safety: bool  #: the safety-factor clamping (the slip loop off)
    safety_factor: float  #: [-]
    mu_design: float  #: the safety-factor clamping's traction; NaN: the peak at the ratio
    shift_ff: bool  #: the shift feedforward
    J_s: float  #: secondary inertia [kg m^2] (the bench's; 0 in the car, whose wheels hold it)
    alpha_ff: float  #: the feedforward filter's pole [-]
    tpf: float  #: secondary servo torque per N of clamping force [N m / N]
    ff_gain: float  #: [-]
    ff_den: float  #: 2 traction_error [-]
    cosb: float  #: cos(beta) [-]
    L_belt: float  #: belt length [m]
    a: float  #: centre distance [m]
    alpha_dec: float  #: the decoupler's low-pass pole [-]
    T_ms_start: float  #: the decoupler's zero [N m]
    shift_gain: float  #: primary servo torque per N of primary thrust [N m / N]
    omega_0: float  #: the creep law's speed floor [rad/s]
    xi_sat: float  #: the creep law's saturation [-]
    creep: bool  #: the creep law (else Shafai's: the geometric thrust ratio)
    tau_ref: float  #: the set-point's torque ratio [-]
    mask1: float  #: 0 where the safety-factor clamping replaces the controller's T_ms
    limited: bool  #: servo limits
    T_max: float  #: [N m]
    w_max: float  #: [rad/s]
    S_max: float  #: [N m]
    v_max: float  #: [rad/s]
    band: float  #: the speed limiter's band [-]
    anti_windup: bool
    # the engine-torque estimate (issue 33; `ff_est` False: none, ``n_est`` 0)
    ff_est: bool  #: the feedforward's torque is the torque source's estimate
    n_est: int  #: the estimate's buffer [samples]: its delay + 1 (0 without it)
    est_gain: float  #: the estimate over the truth, ``1 + engine_torque_error`` [-]
    obs: bool  #: the driveshaft-torque observer (state after the estimate's buffer)
    obs_k: float  #: its driveline stiffness times the sample period [N m / rad * s]
    obs_a: float  #: its correction's share per sample, ``1 - exp(-omega_c dt)`` [-]
    # the torque request of a saturating secondary servo (issue 33)
    request: bool  #: compute the torque request
    honour: bool  #: the bench's load torque follows it (the law commands ``T_l``)
    F_cap: float  #: the clamping the secondary servo holds within its margin [N]
    # the reserve ahead and the slip-runaway guard (issue 33; `empact.control.law` notes)
    ahead: bool  #: lower the set-point's torque ratio as the servo's headroom shrinks
    F_max: float  #: the clamping the secondary servo's torque limit holds [N]
    ahead_h0: float  #: the headroom share below which the set-point moves [-]
    guard: bool  #: the slip-runaway guard (its state last of the pre-processing's)
    guard_margin: float  #: the slip's share above its set-point where it acts [-]
    guard_gain: float  #: its clamping (a share of the set-point's) per share of slip beyond
    #: the margin [-]; its state the clamping it adds [N]
    guard_decay: float  #: its release per sample, ``exp(-dt / guard_release)`` [-]
    # the clamping floor (issue 34; `floor` False: none)
    sf_engine: bool  #: the safety-factor clamping's torque is the engine's (raw[6], in the
    #: car) instead of the driveshaft's
    J_e: float  #: the car's engine and primary inertia [kg m^2]: the clamping feedforward and
    #: the safety-factor clamping add its torque of an upshift at the reference's rate (0 on
    #: the bench, whose drive holds the primary's speed)
    alpha_rel: float  #: the safety-factor clamping's release: the pole of its torque's
    #: first-order fall, ``exp(-dt / clamping_release)`` (0: none); it rises at once
    floor: bool  #: hold the secondary servo at or beyond the torque of `min_clamping`
    T_floor: float  #: that torque [N m] (its sign the clamping's: `tpf`'s)


class LawTables(NamedTuple):
    """Per sample (rows ``0 .. n_k - 1``, the last held) the references and noise, the shift
    feedforward's geometry at the reference ratio (where it moves), and the law's matrices
    and the model's parameter vector."""

    r_g: np.ndarray  #: ratio reference [-]
    slip: np.ndarray  #: slip set-point [-]
    mu: np.ndarray  #: its traction coefficient [-]
    slip_lo: np.ndarray  #: the reserve ahead's lowest set-point [-] (its torque ratio's)
    mu_lo: np.ndarray  #: its traction coefficient [-]
    rdot: np.ndarray  #: the ratio reference's rate [1/s]
    decoupling: np.ndarray  #: the decoupler's torque ratio [-]
    mu_max: np.ndarray  #: the traction peak at the reference ratio [-] (scheduled laws)
    R_p: np.ndarray  #: primary radius at the reference ratio [m] (where rdot != 0)
    R_s: np.ndarray  #: secondary radius [m]
    phi: np.ndarray  #: wrap angle offset [rad]
    kappa_geo: np.ndarray  #: the geometric thrust ratio [-]
    noise: np.ndarray  #: (n_k, n_raw) noise of each raw signal
    schedule: np.ndarray  #: the packed schedule (`pack_schedule`)
    A: np.ndarray  #: the discrete controller (n_c, n_c), (n_c, 2), (2, n_c), (2, 2)
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    L: np.ndarray  #: the anti-windup gain (n_c, 2)
    ff_table: np.ndarray  #: (3, n) the feedforward gain table (`ff_table`); n = 0: none
    p: np.ndarray  #: the model's parameter vector (`EmpactModel.p`)
    load: np.ndarray  #: the bench's load-torque demand [N m] (an honoured torque request)


class LawWork(NamedTuple):
    """The law's work arrays: written by every sample."""

    radius: np.ndarray  #: (2,) the last measured ratio and its secondary radius
    meas: np.ndarray  #: (n_raw,) the measurements the controller saw
    u: np.ndarray  #: (2,) the servo torques [N m]
    one: np.ndarray  #: (2,) the traction peak's argument and value
    trace: np.ndarray  #: (n_k, 2) per sample the torque request and the load applied [N m]
    setpoint: np.ndarray  #: (n_k, 2) per sample the set-point run [-] and the guard's
    #: clamping share [-] (the reserve ahead or the guard; NaN until written)


#: each constant's type
_KINDS = get_type_hints(LawConstants)


def constants(**values: object) -> LawConstants:
    """`LawConstants` from `values` (every field by name), each converted to its field's type
    (so that numba compiles the sample once for every law)."""
    return LawConstants(**{k: _KINDS[k](v) for k, v in values.items()})


def tables(**arrays: object) -> LawTables:
    """`LawTables` from `arrays` (every field by name), each as a C-ordered float64 array."""
    return LawTables(**{k: np.ascontiguousarray(v, dtype=np.float64)
                        for k, v in arrays.items()})


def work(n_raw: int, n_cmd: int = 2, n_trace: int = 1, n_setpoint: int = 1) -> LawWork:
    """Fresh work arrays for a law reading `n_raw` signals and commanding `n_cmd` inputs,
    with `n_trace` samples of the torque request's trace and `n_setpoint` of the set-point's
    (NaN until written)."""
    return LawWork(np.full(2, np.nan), np.zeros(n_raw), np.zeros(n_cmd), np.zeros(2),
                   np.full((n_trace, 2), np.nan), np.full((n_setpoint, 2), np.nan))


@structref.register
class LawType(types.StructRef):
    """numba's type of `Law`."""

    def preprocess_fields(self, fields):
        return tuple((name, types.unliteral(t)) for name, t in fields)


class Law(structref.StructRefProxy):
    """The law as the compiled sample takes it: its `LawConstants` ``c``, `LawTables` ``tb``
    and `LawWork` ``wk`` behind one reference (a call hands numba one pointer, where the
    three structures' 70 fields cost about 4 us a call to convert, more than a sample)."""


structref.define_proxy(Law, LawType, ["c", "tb", "wk"])


@njit(cache=True)
def law(c, tb, wk):
    """The `Law` of `c`, `tb`, `wk` (compiled once, cached)."""
    return Law(c, tb, wk)


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
def _radius(r_g, L_belt, a, cache):
    """The secondary radius at the measured ratio (the one law,
    `empact.variator._laws.secondary_radius`; NaN where it finds no belt geometry), the last
    one reused."""
    r = _lo_hi(r_g, 1e-3, 1e3)
    if r != cache[0]:
        cache[0] = r
        cache[1] = secondary_radius(r, L_belt, a, np.nan, 1e-13)
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
def sense(buf, n_raw, c, ideal, m):
    """`LoopLaw.sense`: the measurements into ``m[:n_raw]`` from the buffers ``buf`` (row
    after row, newest first): each signal `delay` samples late, the shaft speeds the mean
    over the counting window (numpy's sum), quantised unless `ideal`."""
    nbuf = c.n_buf
    d = c.delay
    W = c.window
    for i in range(n_raw):
        m[i] = buf[i * nbuf + d]
    if W > 1:
        m[1] = _pairwise_sum(buf, nbuf + d, W) / W
        m[2] = _pairwise_sum(buf, 2 * nbuf + d, W) / W
    if c.quantise and not ideal:
        q = c.speed_quantum
        m[1] = _round(m[1] / q) * q
        m[2] = _round(m[2] / q) * q
        rq = c.ratio_quantum
        if rq != 0.0:
            m[0] = _round(m[0] / rq) * rq


@njit(cache=True)
def safety_torque(T, r_m, c, tb, wk):
    """The safety-factor clamping's secondary servo torque [N m] for the torque `T` [N m] a
    production controller knows (the feedforward's signal: the driveshaft torque, or its
    estimate) at the measured ratio `r_m`:
    ``SF |T| cos(beta) / (2 mu_design R_s)`` (``mu_design`` the peak at `r_m` when NaN)."""
    mu_d = c.mu_design
    if mu_d != mu_d:
        wk.one[0] = r_m
        mu_max_many(wk.one[:1], tb.p, wk.one[1:])
        mu_d = wk.one[1]
    return c.tpf * c.safety_factor * abs(T) * c.cosb / (
        2 * mu_d * _radius(r_m, c.L_belt, c.a, wk.radius))


@njit(cache=True)
def shift_torque(c, tb, kk, w_p, F_s):
    """Primary servo torque [N m] over its holding value against the creep law's resistance
    at sample `kk`'s reference ratio and rate (speed `w_p`, clamping force `F_s`): the thrust
    ratio ``kappa* exp(xi)``, ``xi = xi_sat tanh(rdot / (omega K_c) / xi_sat)``
    (`empact.variator.shift_law`) needs the primary thrust ``kappa* (exp(xi) - 1) F_s``
    more, ``T_mp = -(i_e s / i_w)`` times it."""
    rdot = tb.rdot[kk]
    if rdot == 0.0:
        return 0.0
    r_ref, R_p = tb.r_g[kk], tb.R_p[kk]
    w_eff = math.hypot(w_p, c.omega_0)
    K_c = creep_coefficient(r_ref, R_p, F_s, tb.p)
    if c.creep:
        keq = creep_force(r_ref, R_p, tb.R_s[kk], tb.phi[kk], F_s, c.tau_ref, 0.0, 1.0,
                          tb.p)[2]
    else:
        keq = tb.kappa_geo[kk]
    xi = c.xi_sat * math.tanh(rdot / (w_eff * K_c) / c.xi_sat)
    return c.shift_gain * keq * math.expm1(xi) * F_s


@njit(cache=True)
def pre(law, s, out, raw, k, ideal):
    """`LoopLaw.preprocess` of the `Law` `law`: from the sensor and feedforward state `s`
    (``n_pre``), the raw measurements `raw` and the sample index `k` (its row of the tables,
    the last held), the next state into ``out[:n_pre]`` and the measurements into
    ``wk.meas``; returns ``(status, e0, e1, u0, u1)``: 1 when the clamping finds no belt
    geometry at the measured ratio (``wk.meas[0]``), the controller's errors (times the
    schedule's gains) and the servo torques without the controller's share.  `ideal` drops
    noise and quantisation."""
    c, tb, wk = law.c, law.tb, law.wk
    nb = c.n_pre - 2 - c.n_est - (1 if c.obs else 0) - (1 if c.guard else 0)
    nbuf = c.n_buf
    n_last = tb.r_g.shape[0] - 1
    kk = k if k < n_last else n_last
    n_raw = tb.noise.shape[1]  # the sensors' signals (the observer's wheel speed after them)
    m = wk.meas
    # the buffers, newest first: every row moves on by one, the new samples in front
    for j in range(nb - 1, 0, -1):
        out[j] = s[j - 1]
    for i in range(n_raw):
        out[i * nbuf] = raw[i] if ideal else raw[i] + tb.noise[kk, i]
    if c.n_est:  # the torque estimate's buffer (of the torque source, T_l_act), after
        e0_ = nb + 2  # the filters' state
        for j in range(c.n_est - 1, 0, -1):
            out[e0_ + j] = s[e0_ + j - 1]
        out[e0_] = raw[6]
    sense(out, n_raw, c, ideal, m)
    r_ref, slip_ref, mu_ref, rdot = tb.r_g[kk], tb.slip[kk], tb.mu[kk], tb.rdot[kk]
    r_m, w_p, w_s, T_ds = m[0], m[1], m[2], m[3]
    base = r_m if c.slip_nu else c.r_ref0
    y = 1.0 - w_s / (base * w_p)
    # the torque the clamping is computed for (the feedforward's signal; the safety-factor
    # clamping reads the same, so that every strategy has the same information)
    if c.ff_est:  # the torque source's torque as its controller reports it: late, off
        T_b = c.est_gain * out[nb + 2 + c.n_est - 1]
        if c.obs:  # the driveshaft torque: the twist rate integrated (output speed
            # less wheel speed, raw), pulled slowly to the estimate
            o = nb + 2 + c.n_est
            T_h = s[o]
            T_h = T_h + c.obs_k * (out[2 * nbuf] - raw[n_raw]) + c.obs_a * (T_b - T_h)
            out[o] = T_h
            T_b = T_h
    else:
        T_b = T_ds if c.ff_t_ds else m[6]
    F_full = 0.0  # the clamping that holds the set-point at T_b (feedforward gain 1) [N]
    if c.ahead or c.guard:
        R_s = _radius(r_m, c.L_belt, c.a, wk.radius)
        if R_s != R_s:
            return 1, 0.0, 0.0, c.bias0, c.bias1
        F_full = abs(T_b) * c.cosb / (c.ff_den * mu_ref * R_s)
    if c.ahead:  # the reserve ahead: the set-point moves towards slip_lo as the servo's
        # headroom h (the share of its torque limit the clamping F_full leaves) falls
        # below ahead_h0, never past the clamping the servo holds
        h = 1.0 - F_full / c.F_max
        h = 0.0 if 0.0 > h else h
        w = (c.ahead_h0 - h) / c.ahead_h0
        cap = mu_ref * h / (mu_ref - tb.mu_lo[kk]) if mu_ref > tb.mu_lo[kk] else 0.0
        w = cap if cap < w else w
        w = _lo_hi(w, 0.0, 1.0)
        slip_ref = slip_ref + w * (tb.slip_lo[kk] - slip_ref)
        mu_ref = mu_ref + w * (tb.mu_lo[kk] - mu_ref)
        wk.setpoint[kk, 0] = slip_ref
    if c.log_r:
        e0 = math.log(1e-9 if 1e-9 > r_ref else r_ref) - math.log(1e-9 if 1e-9 > r_m else r_m)
    else:
        e0 = r_ref - r_m
    if c.log_s:
        e1 = math.log(1e-9 if 1e-9 > slip_ref else slip_ref) - \
            math.log(1e-9 if 1e-9 > y else y)
    else:
        e1 = slip_ref - y
    f = s[nb]
    u1 = c.bias1
    if c.safety:
        e1 = 0.0  # the slip loop is replaced by the open-loop clamping strategy
        T_sf = m[6] if c.sf_engine else T_b  # the car: the engine's torque at the secondary
        if c.J_e != 0.0 and rdot > 0.0:  # in the car, upshifting: the engine's inertia
            T_sf = T_sf + c.J_e * w_p * rdot / (r_m * r_m)
        # held: up at once, down at the release's rate (its state the feedforward filter's)
        T_sf = abs(T_sf)
        f = c.alpha_rel * s[nb] + (1.0 - c.alpha_rel) * T_sf
        f = T_sf if T_sf > f else f
        u1 = safety_torque(f, r_m, c, tb, wk)
        if wk.radius[1] != wk.radius[1]:
            return 1, e0, e1, c.bias0, u1
    if c.scheduled:  # at the clamping the law commands (the safety factor's, its floor)
        at = np.empty(3)
        at[0] = r_m
        at[1] = mu_ref / tb.mu_max[kk]
        if c.safety:
            F_at = u1 / c.tpf
            at[2] = c.T_floor / c.tpf if c.floor and c.T_floor / c.tpf > F_at else F_at
        else:
            at[2] = f if c.feedforward else c.F_s0
        lg = np.empty(2)
        schedule_log_gains(tb.schedule, at, True, lg)
        e0 = e0 * (c.sign0 * math.exp(lg[0]))
        e1 = e1 * (c.sign1 * math.exp(lg[1]))
    if c.feedforward and not c.safety:
        if c.shift_ff:  # the secondary pulley's acceleration torque
            T_b = T_b + c.J_s * w_p * rdot
        if c.J_e != 0.0 and rdot > 0.0:  # in the car, upshifting: the engine's
            # deceleration torque (its speed follows the ratio); never less clamping
            T_b = T_b + c.J_e * w_p * rdot / (r_m * r_m)
        a = c.alpha_ff
        R_s = _radius(r_m, c.L_belt, c.a, wk.radius)
        if R_s != R_s:
            return 1, e0, e1, c.bias0, u1
        if tb.ff_table.shape[1]:
            ff = scheduled_ff(tb.ff_table, T_b * c.cosb / (c.ff_den * mu_ref * R_s))
        else:
            ff = c.ff_gain * T_b * c.cosb / (c.ff_den * mu_ref * R_s)
        if c.guard:  # the slip-runaway guard: clamping at once when the measured slip
            # passes its set-point by more than the margin, held as a force (so that the
            # driveshaft torque's swings do not move it) and released slowly
            og = c.n_pre - 1
            x = c.guard_gain * (y / slip_ref - 1.0 - c.guard_margin)
            x = (1.0 if x > 1.0 else x) * F_full  # at most the set-point's clamping more
            g = c.guard_decay * s[og]
            g = x if x > g else g
            # never past the servo: at most the headroom its last torque left (a demand
            # beyond it would unwind the controller through the anti-windup and move the
            # primary through the decoupler, and clamp nothing)
            out[og] = g  # held whole; applied within the headroom
            room = c.F_max - wk.u[1] / c.tpf
            room = 0.0 if 0.0 > room else room
            g = room if g > room else g
            ff += g
            wk.setpoint[kk, 1] = g / F_full if F_full > 0.0 else 0.0
        f = a * f + (1 - a) * ff
        u1 += c.tpf * f
    elif not c.safety:
        f = 0.0
    out[nb] = f
    # the primary servo's feedforward share, low-passed: the decoupler (it follows the
    # feedforward's clamping) and the shift feedforward
    dec = tb.decoupling[kk]
    u0 = c.bias0
    t_mp = dec * (u1 - c.T_ms_start)
    if c.shift_ff:
        t_mp += shift_torque(c, tb, kk, w_p, f if c.feedforward else c.F_s0)
    g = s[nb + 1]
    if dec != 0.0 or c.shift_ff:
        a = c.alpha_dec
        g = a * g + (1 - a) * t_mp
        u0 += g
    else:
        g = 0.0
    out[nb + 1] = g
    return 0, e0, e1, u0, u1


def ff_table(pairs) -> np.ndarray:
    """The feedforward gain table as `scheduled_ff` reads it: rows the forces ``F_i`` [N],
    the gains ``g_i`` [-] and ``H_i = int_0^F_i g dF`` [N] (``g_0`` held below ``F_0``, the
    gain linear between the points); shape (3, 0) without a table (`pairs` None)."""
    if pairs is None:
        return np.zeros((3, 0))
    F = np.array([p[0] for p in pairs], float)
    g = np.array([p[1] for p in pairs], float)
    H = np.empty_like(F)
    H[0] = g[0] * F[0]
    for i in range(1, len(F)):
        H[i] = H[i - 1] + 0.5 * (g[i - 1] + g[i]) * (F[i] - F[i - 1])
    return np.ascontiguousarray(np.stack([F, g, H]))


@njit(cache=True)
def scheduled_ff(tab, F):
    """The feedforward's clamping force [N] of the full force `F` [N] (the clamping at gain
    1) under the gain table `tab` (`ff_table`): ``int_0^F g(x) dx``, ``g`` linear between the
    table's forces and held beyond them."""
    n = tab.shape[1]
    if F <= tab[0, 0]:
        return tab[1, 0] * F
    if F >= tab[0, n - 1]:
        return tab[2, n - 1] + tab[1, n - 1] * (F - tab[0, n - 1])
    i = 0
    while tab[0, i + 1] < F:
        i += 1
    d = F - tab[0, i]
    slope = (tab[1, i + 1] - tab[1, i]) / (tab[0, i + 1] - tab[0, i])
    return tab[2, i] + tab[1, i] * d + 0.5 * slope * d * d


@njit(cache=True)
def servo_limited(T, w, T_max, w_max, band):
    """The torque servo `T` [N m] delivers at speed `w`: within +-T_max, and the torque that
    would drive it faster falls to zero over the last `band` of its speed limit `w_max`
    (``min(max(x, 0), 1)`` as Python evaluates it, NaN passing)."""
    T = -T_max if -T_max > T else T
    T = T_max if T_max < T else T
    if T * w > 0:
        v = (w_max - abs(w)) / (band * w_max)
        v = 0.0 if 0.0 > v else v
        v = 1.0 if 1.0 < v else v
        T *= v
    return T


@njit(cache=True)
def sample(law, z, z_next, raw, k, ideal):
    """One sample of the `Law` `law` (`LoopLaw.update`): from the state `z` (`pre`'s, then the
    controller's), the raw measurements `raw` and the sample index `k`, the next state into
    `z_next` and the servo torques into ``wk.u``; returns 1 when the clamping finds no belt
    geometry at the measured ratio (``wk.meas[0]``), else 0.  `ideal` drops noise,
    quantisation and limits (the linear model's law)."""
    c, tb, wk = law.c, law.tb, law.wk
    n = c.n_pre
    status, e0, e1, u0, u1 = pre(law, z, z_next, raw, k, ideal)
    if status:
        return status
    A, B, C, D, L = tb.A, tb.B, tb.C, tb.D, tb.L
    nc = z.shape[0] - n
    du0 = 0.0
    du1 = 0.0
    for j in range(nc):
        du0 += C[0, j] * z[n + j]
        du1 += C[1, j] * z[n + j]
    du0 = du0 + (D[0, 0] * e0 + D[0, 1] * e1)
    du1 = du1 + (D[1, 0] * e0 + D[1, 1] * e1)
    if c.safety:  # the controller's T_ms does not reach its servo
        du1 = du1 * c.mask1
    for i in range(nc):
        acc = 0.0
        for j in range(nc):
            acc += A[i, j] * z[n + j]
        z_next[n + i] = acc + (B[i, 0] * e0 + B[i, 1] * e1)
    u0 = u0 + du0
    u1 = u1 + du1
    if c.limited and not ideal:
        w0, w1 = wk.meas[4], wk.meas[5]
        s0 = servo_limited(u0, w0, c.T_max, c.w_max, c.band)
        s1 = servo_limited(u1, w1, c.S_max, c.v_max, c.band)
        if c.anti_windup and (s0 != u0 or s1 != u1):
            d0 = s0 - u0
            d1 = (s1 - u1) * c.mask1 if c.safety else s1 - u1
            for i in range(nc):
                z_next[n + i] = z_next[n + i] + (L[i, 0] * d0 + L[i, 1] * d1)
        u0, u1 = s0, s1
    if c.floor and not ideal:
        u1 = clamp_floor(c, tb, z_next, u1)
    wk.u[0] = u0
    wk.u[1] = u1
    if c.request:
        torque_request(c, tb, wk, k)
    return 0


@njit(cache=True)
def clamp_floor(c, tb, z_next, u1):
    """The clamping floor (`ControllerSpec.min_clamping`): the secondary servo torque `u1`
    [N m] held at or beyond ``T_floor`` in the clamping's sense (the sign of ``tpf``), the
    difference fed back to the controller's state as the servo limits' (observer-form
    anti-windup, `sample`; none where the safety-factor clamping replaces the controller's
    torque); returns the torque."""
    s1 = u1
    if c.tpf * (u1 - c.T_floor) < 0.0:
        s1 = c.T_floor
        if c.anti_windup and not c.safety:
            n = c.n_pre
            L = tb.L
            for i in range(z_next.shape[0] - n):
                z_next[n + i] = z_next[n + i] + L[i, 1] * (s1 - u1)
    return s1


@njit(cache=True)
def torque_request(c, tb, wk, k):
    """The torque request of sample `k` (``wk.trace[k, 0]``) [N m]: the secondary-shaft
    torque the clamping ``F_cap`` (the secondary servo's torque limit less its margin)
    holds at the set-point's traction coefficient (the feedforward's estimate) and the
    measured ratio's radius, ``F_cap 2 mu_hat R_s / cos(beta)``; honoured, the bench's
    load torque ``T_l`` (``wk.u[2]``, ``wk.trace[k, 1]``): its demand, its size at most the
    request."""
    n_last = tb.r_g.shape[0] - 1
    kk = k if k < n_last else n_last
    R_s = _radius(wk.meas[0], c.L_belt, c.a, wk.radius)
    T_req = c.F_cap * c.ff_den * tb.mu[kk] * R_s / c.cosb
    wk.trace[kk, 0] = T_req
    if c.honour:
        T_dem = tb.load[kk]
        T_app = T_dem
        if abs(T_dem) > T_req:
            T_app = math.copysign(T_req, T_dem)
        wk.u[2] = T_app
        wk.trace[kk, 1] = T_app
