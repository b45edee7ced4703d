"""Compiled (numba) right-hand side of the nonlinear Empact model; see `empact.nonlinear.model`.

Private: the public interface, the state ordering and the sign conventions are documented in
`empact.nonlinear`.  Everything here works on flat arrays:

* ``x`` state, shape (n,); ``u`` inputs, shape (4,);
* ``p`` float parameters, shape (NP,), laid out by the ``P_*`` indices below;
* ``ix`` int64, shape (4,): positions in ``x`` of the optional states (belt stretch, drive and
  load speed-loop integrators, ratio-controller integrator), -1 when absent.

`_eval` is written once for real and complex arguments, so that `_jacobian` can differentiate
it by the complex step (exact to rounding: no subtraction, step 1e-30).  Comparisons use the
real part; ``abs`` is written as a sign flip so that it stays analytic.
"""
from __future__ import annotations

import numpy as np
from numba import njit

# -- parameter vector layout ---------------------------------------------------------------
(P_A, P_TB, P_COSB, P_RMIN, P_RMAX, P_L0,
 P_JMP, P_JMS, P_JSP, P_JSS, P_MP, P_MS, P_IW, P_IC, P_IE, P_S,
 P_KW, P_KC, P_KBELT, P_KTP, P_KTS,
 P_ALPHA, P_CMP, P_CMS, P_CSP, P_CSS, P_CSH,
 P_TCSP, P_TCSS, P_WC,
 P_JD, P_JP, P_JS, P_JL, P_KTC, P_KDS, P_KBD,
 P_LLOW, P_LMED, P_LOD,
 P_B0, P_B1, P_B2, P_C0, P_C1, P_C2, P_D0, P_D1, P_D2, P_E0, P_E1, P_E2,
 P_DKP, P_DKI, P_LKP, P_LKI, P_RKP, P_RKD, P_RKI, P_SIG, P_RS0) = range(61)
NP = 61

#: number of base states (actuation 12, driveline 6)
NX_BASE = 18

OUTPUTS = ("r_g", "nu", "theta_mp", "theta_ms", "F_p", "F_s", "omega_p", "omega_s",
           "omega_d", "omega_l", "omega_mp", "omega_ms", "T_b", "mu", "R_p", "R_s", "phi",
           "x_p", "x_s", "belt_elongation", "T_mp_act", "T_d_act", "T_l_act", "E", "P_in",
           "P_diss")
NY = len(OUTPUTS)
(Y_RG, Y_NU, Y_THMP, Y_THMS, Y_FP, Y_FS, Y_WP, Y_WS, Y_WD, Y_WL, Y_WMP, Y_WMS, Y_TB, Y_MU,
 Y_RP, Y_RS, Y_PHI, Y_XP, Y_XS, Y_E, Y_TMP, Y_TD, Y_TL, Y_EN, Y_PIN, Y_PDISS) = range(NY)


@njit(cache=True)
def _interp3(lr, l0, l1, l2, c0, c1, c2):
    """Coefficient at log-ratio `lr`: linear in log(r_g) between three knots, constant outside."""
    if lr.real <= l0:
        return c0 + 0.0 * lr
    if lr.real <= l1:
        return c0 + (lr - l0) / (l1 - l0) * (c1 - c0)
    if lr.real <= l2:
        return c1 + (lr - l1) / (l2 - l1) * (c2 - c1)
    return c2 + 0.0 * lr


@njit(cache=True)
def traction_mu(nu, r_g, p):
    """Magic-formula traction coefficient mu(nu, r_g) (scalar; real or complex)."""
    lr = np.log(r_g)
    B = _interp3(lr, p[P_LLOW], p[P_LMED], p[P_LOD], p[P_B0], p[P_B1], p[P_B2])
    C = _interp3(lr, p[P_LLOW], p[P_LMED], p[P_LOD], p[P_C0], p[P_C1], p[P_C2])
    D = _interp3(lr, p[P_LLOW], p[P_LMED], p[P_LOD], p[P_D0], p[P_D1], p[P_D2])
    E = _interp3(lr, p[P_LLOW], p[P_LMED], p[P_LOD], p[P_E0], p[P_E1], p[P_E2])
    Bn = B * nu
    return D * np.sin(C * np.arctan(Bn - E * (Bn - np.arctan(Bn))))


@njit(cache=True)
def belt_geometry(R_p, R_s, a):
    """``(phi, L)``: wrap angle (eq. 4) and belt length (eq. 6), real or complex.

    The numba twin of `empact.geometry.wrap_angle` and `empact.geometry.belt_length`
    (tested equal).
    """
    phi = np.arcsin((R_p - R_s) / a)
    return phi, 2.0 * a * np.cos(phi) + (np.pi + 2.0 * phi) * R_p + (np.pi - 2.0 * phi) * R_s


@njit(cache=True)
def _sabs(w):
    """|w| for real w, analytic continuation (sign flip) for the complex step."""
    if w.real < 0:
        return -w
    return w


@njit(cache=True)
def _eval(x, u, p, ix, dx, y):
    """Fill ``dx`` (shape (n,)) and ``y`` (shape (NY,)) at state x and inputs u."""
    zero = 0.0 * x[0]
    a = p[P_A]
    tb = p[P_TB]
    pi = np.pi
    # actuation coordinates and velocities
    q1 = x[0]
    q2 = x[1]
    q3 = x[2]
    q4 = x[3]
    q5 = x[4]
    q6 = x[5]
    w1 = x[6]
    w2 = x[7]
    w3 = x[8]
    w4 = x[9]
    v5 = x[10]
    v6 = x[11]
    tw_tc = x[12]
    tw_ds = x[13]
    wd = x[14]
    wp = x[15]
    ws = x[16]
    wl = x[17]

    # belt on the full geometry (eqs. 4 and 6)
    R_p = p[P_RMIN] + q5 / tb
    sig = p[P_SIG]
    R_s = p[P_RS0] - sig * q6 / tb
    phi, L = belt_geometry(R_p, R_s, a)
    e = L - p[P_L0]
    g5 = (pi + 2.0 * phi) / tb          # dL/dq5
    g6 = -sig * (pi - 2.0 * phi) / tb   # dL/dq6
    edot = g5 * v5 + g6 * v6
    alpha = p[P_ALPHA]
    N = p[P_KBELT] * (e + alpha * edot)  # belt element force [N], elastic + proportional damping
    F_p = N * g5
    F_s = N * (pi - 2.0 * phi) / tb

    # actuation springs (sign conventions of empact.linear.actuation)
    i_w = p[P_IW]
    i_c = p[P_IC]
    i_e = p[P_IE]
    s = p[P_S]
    e_w = q1 / i_w - q3 / i_e
    ed_w = w1 / i_w - w3 / i_e
    e_c = q2 / i_c - q4 / i_e
    ed_c = w2 / i_c - w4 / i_e
    d_p = s * q3 + q5
    dd_p = s * w3 + v5
    d_s = s * (q4 - q3) + q6
    dd_s = s * (w4 - w3) + v6
    T_w = p[P_KW] * (e_w + alpha * ed_w)
    T_c = p[P_KC] * (e_c + alpha * ed_c)
    F_tp = p[P_KTP] * (d_p + alpha * dd_p)
    F_ts = p[P_KTS] * (d_s + alpha * dd_s)

    # Shafai pulley damping with the current pulley speeds
    c_p = zero
    c_s = zero
    if p[P_CSH] != 0.0:
        c_p = p[P_CSH] / _sabs(wp)
        c_s = p[P_CSH] / _sabs(ws)
    # smooth Coulomb friction in the spindles (screw rotations q3 and q4 - q3)
    w43 = w4 - w3
    Tf_sp = zero
    Tf_ss = zero
    if p[P_TCSP] != 0.0:
        Tf_sp = p[P_TCSP] * np.tanh(w3 / p[P_WC])
    if p[P_TCSS] != 0.0:
        Tf_ss = p[P_TCSS] * np.tanh(w43 / p[P_WC])

    # ratio, slip (eq. 2), traction
    r_g = R_p / R_s
    nu = 1.0 - ws / (r_g * wp)
    mu = traction_mu(nu, r_g, p)
    if ix[0] >= 0:  # belt locked: elastic chain element R_p theta_p - R_s theta_s
        F_b = p[P_KBD] * x[ix[0]]
        T_on_p = -R_p * F_b
        T_b = R_s * F_b
        P_slip = zero
        dx[ix[0]] = R_p * wp - R_s * ws
    else:  # traction torque, eq. 1
        T_b = 2.0 * mu * F_s * R_s / p[P_COSB]
        T_on_p = -r_g * T_b
        P_slip = T_b * (r_g * wp - ws)

    # servo torques: direct, or the ratio controller (PID on the shift coordinate; the integral
    # carries the holding torque)
    if ix[3] >= 0:
        G = (-s * i_e / (i_w * tb)) * (R_s + R_p * (pi + 2.0 * phi) / (pi - 2.0 * phi)) \
            / (R_s * R_s)
        err = (u[0] - r_g) / G
        T_mp = x[ix[3]] + p[P_RKP] * err - p[P_RKD] * w1
        dx[ix[3]] = p[P_RKI] * err
    else:
        T_mp = u[0]
    T_ms = u[1]
    if ix[1] >= 0:
        T_d = x[ix[1]] + p[P_DKP] * (u[2] - wd)
        dx[ix[1]] = p[P_DKI] * (u[2] - wd)
    else:
        T_d = u[2]
    if ix[2] >= 0:
        T_l = x[ix[2]] - p[P_LKP] * (u[3] - wl)
        dx[ix[2]] = -p[P_LKI] * (u[3] - wl)
    else:
        T_l = u[3]

    # actuation equations of motion
    Q1 = T_mp - T_w / i_w - p[P_CMP] * w1
    Q2 = T_ms - T_c / i_c - p[P_CMS] * w2
    Q3 = T_w / i_e - s * F_tp + s * F_ts - p[P_CSP] * w3 - Tf_sp + p[P_CSS] * w43 + Tf_ss
    Q4 = T_c / i_e - s * F_ts - p[P_CSS] * w43 - Tf_ss
    Q5 = -N * g5 - F_tp - c_p * v5
    Q6 = -N * g6 - F_ts - c_s * v6
    dx[0] = w1
    dx[1] = w2
    dx[2] = w3
    dx[3] = w4
    dx[4] = v5
    dx[5] = v6
    dx[6] = Q1 / p[P_JMP]
    dx[7] = Q2 / p[P_JMS]
    dx[8] = Q3 / p[P_JSP]
    dx[9] = Q4 / p[P_JSS]
    dx[10] = Q5 / p[P_MP]
    dx[11] = Q6 / p[P_MS]
    # driveline (rotating frame: twists and speeds)
    T_tc = p[P_KTC] * tw_tc
    T_ds = p[P_KDS] * tw_ds
    dx[12] = wd - wp
    dx[13] = ws - wl
    dx[14] = (T_d - T_tc) / p[P_JD]
    dx[15] = (T_tc + T_on_p) / p[P_JP]
    dx[16] = (T_b - T_ds) / p[P_JS]
    dx[17] = (T_ds - T_l) / p[P_JL]

    # outputs, energy and power
    E = 0.5 * (p[P_JMP] * w1 * w1 + p[P_JMS] * w2 * w2 + p[P_JSP] * w3 * w3
               + p[P_JSS] * w4 * w4 + p[P_MP] * v5 * v5 + p[P_MS] * v6 * v6
               + p[P_KW] * e_w * e_w + p[P_KC] * e_c * e_c + p[P_KBELT] * e * e
               + p[P_KTP] * d_p * d_p + p[P_KTS] * d_s * d_s
               + p[P_JD] * wd * wd + p[P_JP] * wp * wp + p[P_JS] * ws * ws + p[P_JL] * wl * wl
               + p[P_KTC] * tw_tc * tw_tc + p[P_KDS] * tw_ds * tw_ds)
    if ix[0] >= 0:
        E += 0.5 * p[P_KBD] * x[ix[0]] * x[ix[0]]
    P_in = T_mp * w1 + T_ms * w2 + T_d * wd - T_l * wl
    P_diss = (p[P_CMP] * w1 * w1 + p[P_CMS] * w2 * w2 + p[P_CSP] * w3 * w3
              + p[P_CSS] * w43 * w43 + c_p * v5 * v5 + c_s * v6 * v6
              + alpha * (p[P_KW] * ed_w * ed_w + p[P_KC] * ed_c * ed_c
                         + p[P_KBELT] * edot * edot + p[P_KTP] * dd_p * dd_p
                         + p[P_KTS] * dd_s * dd_s)
              + Tf_sp * w3 + Tf_ss * w43 + P_slip)
    y[Y_RG] = r_g
    y[Y_NU] = nu
    y[Y_THMP] = q1
    y[Y_THMS] = q2
    y[Y_FP] = F_p
    y[Y_FS] = F_s
    y[Y_WP] = wp
    y[Y_WS] = ws
    y[Y_WD] = wd
    y[Y_WL] = wl
    y[Y_WMP] = w1
    y[Y_WMS] = w2
    y[Y_TB] = T_b
    y[Y_MU] = mu
    y[Y_RP] = R_p
    y[Y_RS] = R_s
    y[Y_PHI] = phi
    y[Y_XP] = q5
    y[Y_XS] = q6
    y[Y_E] = e
    y[Y_TMP] = T_mp
    y[Y_TD] = T_d
    y[Y_TL] = T_l
    y[Y_EN] = E
    y[Y_PIN] = P_in
    y[Y_PDISS] = P_diss


@njit(cache=True)
def _jacobian(x, u, p, ix, A, B, C, D):
    """Exact A = df/dx, B = df/du, C = dy/dx, D = dy/du by the complex step (h = 1e-30)."""
    n = x.shape[0]
    m = u.shape[0]
    h = 1e-30
    xc = x.astype(np.complex128)
    uc = u.astype(np.complex128)
    dx = np.zeros(n, dtype=np.complex128)
    y = np.zeros(C.shape[0], dtype=np.complex128)
    for j in range(n):
        xc[j] += 1j * h
        _eval(xc, uc, p, ix, dx, y)
        xc[j] = x[j]
        for i in range(n):
            A[i, j] = dx[i].imag / h
        for i in range(C.shape[0]):
            C[i, j] = y[i].imag / h
    for j in range(m):
        uc[j] += 1j * h
        _eval(xc, uc, p, ix, dx, y)
        uc[j] = u[j]
        for i in range(n):
            B[i, j] = dx[i].imag / h
        for i in range(C.shape[0]):
            D[i, j] = y[i].imag / h


#: Base-state columns of df/dx that depend on the state or the inputs (the rest are constant
#: over a run): sheave positions and velocities (belt geometry, belt damping, Shafai damping),
#: spindle speeds (Coulomb friction), pulley speeds (traction).
VARYING_BASE_COLUMNS = (4, 5, 8, 9, 10, 11, 15, 16)


def varying_columns(ix: np.ndarray) -> np.ndarray:
    """The columns of df/dx that change during a run of a model with optional states `ix`:
    `VARYING_BASE_COLUMNS` and, with the locked belt, its stretch (its force acts at the
    current radius).  `tests/test_nonlinear.py` checks every other column is constant."""
    cols = list(VARYING_BASE_COLUMNS) + ([int(ix[0])] if ix[0] >= 0 else [])
    return np.array(cols, dtype=np.int64)


@njit(cache=True)
def _state_jacobian(x, u, p, ix, A, cols):
    """Columns `cols` of A = df/dx (complex step), for the implicit integrator."""
    n = x.shape[0]
    h = 1e-30
    xc = x.astype(np.complex128)
    uc = u.astype(np.complex128)
    dx = np.zeros(n, dtype=np.complex128)
    y = np.zeros(NY, dtype=np.complex128)
    for j in cols:
        xc[j] += 1j * h
        _eval(xc, uc, p, ix, dx, y)
        xc[j] = x[j]
        for i in range(n):
            A[i, j] = dx[i].imag / h


@njit(cache=True)
def _input_direction(x, u, du, p, ix, out):
    """out = (df/du) du by one complex step (the explicit time derivative for Rosenbrock)."""
    n = x.shape[0]
    if not np.any(du != 0.0):  # inputs constant on this piece (the common case)
        out[:] = 0.0
        return
    h = 1e-30
    xc = x.astype(np.complex128)
    uc = u.astype(np.complex128) + 1j * h * du
    dx = np.zeros(n, dtype=np.complex128)
    y = np.zeros(NY, dtype=np.complex128)
    _eval(xc, uc, p, ix, dx, y)
    for i in range(n):
        out[i] = dx[i].imag / h
