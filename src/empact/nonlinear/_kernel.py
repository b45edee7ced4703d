"""Compiled (numba) right-hand side of the nonlinear Empact model; see `empact.nonlinear.model`.

Private: the public interface, the state ordering and the sign conventions are documented in
`empact.nonlinear`.  Everything here works on flat arrays:

* ``x`` state, shape (n,); ``u`` inputs, shape (4,);
* ``p`` float parameters, shape (NP + n_tables,), laid out by the ``P_*`` indices below and
  followed by the optional tabulated maps (a measured thrust-ratio map and a measured
  shift-speed map, `empact.variator._tables.encode_curves`; measured traction curves,
  `empact.variator._traction_table`), each found at the offset that ``p[P_TAB]`` /
  ``p[P_CTAB]`` / ``p[P_MTAB]`` holds (0: the analytic law);
* ``ix`` int64, shape (4,): positions in ``x`` of the optional states (belt stretch, drive and
  load speed-loop integrators, ratio-controller integrator), -1 when absent.

The Jacobians are exact: `_eval_tangent` is `_eval` with hand-derived forward-mode (tangent)
derivatives in real arithmetic, any number of directions in one pass (`_jacobian`: A, B, C, D
for the linearisation and the families; `_state_jacobian`, `_input_direction`: the
integrators' columns and df/du du).  `_eval` itself is written once for real and complex
arguments, so that the complex step differentiates it too (`_jacobian_cs`,
`_state_jacobian_cs`, `_input_direction_cs`, `linearize_batch_cs`; exact to rounding: no
subtraction, step 1e-30), kept as the reference the forward mode is tested and benchmarked
against.  Comparisons use the real part; ``abs`` is written as a sign flip so that it stays
analytic; the forward mode takes the same branch at every comparison.

This module owns the layout of ``p``, ``x`` and ``y``: every index has a name here
(`PARAMETER_NAMES`, `BASE_STATES` and `OPTIONAL_STATES`, `OUTPUTS`), the model packs its
parameters by name (`pack_parameters`) and reads them back by name (`KernelConstants`), and
no other module spells an index.
"""
from __future__ import annotations

from typing import Mapping

import numpy as np
from numba import njit

from ..variator._traction_table import table_mu, table_mu_d, table_mu_max, table_peak
from ._constants import KernelConstants

# -- parameter vector layout ---------------------------------------------------------------
(P_A, P_TB, P_COSB, P_RMIN, P_RMAX, P_L0,
 P_JMP, P_JMS, P_JSP, P_JSS, P_MP, P_MS, P_IW, P_IC, P_IE, P_S,
 P_KW, P_KC, P_KBELT, P_KTP, P_KTS,
 P_ALPHA, P_CMP, P_CMS, P_CSP, P_CSS, P_CSH,
 P_TCSP, P_TCSS, P_WC,
 P_JD, P_JP, P_JS, P_JL, P_KTC, P_KDS, P_KBD,
 P_LLOW, P_LMED, P_LOD,
 P_B0, P_B1, P_B2, P_C0, P_C1, P_C2, P_D0, P_D1, P_D2, P_E0, P_E1, P_E2,
 P_DKP, P_DKI, P_LKP, P_LKI, P_RKP, P_RKD, P_RKI, P_SIG, P_RS0,
 P_LAW, P_DREF, P_FREF, P_KD, P_A1, P_A2, P_GAIN, P_W0, P_XSAT, P_GBETA,
 P_KP0, P_KB0, P_KB1, P_RREF, P_TAB, P_CTAB, P_MTAB) = range(78)
NP = 78

#: names of the parameter vector's entries, in the order of the ``P_*`` indices
PARAMETER_NAMES = (
    "a", "tan_beta", "cos_beta", "R_min", "R_max", "L_belt",
    "J_mp", "J_ms", "J_sp", "J_ss", "m_p", "m_s", "i_w", "i_c", "i_e", "s",
    "k_w", "k_c", "k_belt", "k_tp", "k_ts",
    "alpha", "c_mp", "c_ms", "c_sp", "c_ss", "c_shafai",
    "coulomb_sp", "coulomb_ss", "coulomb_omega",
    "J_d", "J_p", "J_s", "J_l", "k_tc", "k_ds", "k_belt_driveline",
    "ln_r_low", "ln_r_med", "ln_r_od",
    "B_low", "B_med", "B_od", "C_low", "C_med", "C_od", "D_low", "D_med", "D_od",
    "E_low", "E_med", "E_od",
    "drive_kp", "drive_ki", "load_kp", "load_ki", "ratio_kp", "ratio_kd", "ratio_ki",
    "sheave_sense", "R_s0",
    "shift_law", "D_ref", "F_ref", "k_D", "a1", "a2", "gain", "omega_0", "xi_sat", "g_beta",
    "kappa_p0", "kappa_b0", "kappa_b1", "r_ref", "thrust_table", "creep_table",
    "traction_table")
assert len(PARAMETER_NAMES) == NP

#: the kernel's parameters read back by name (`constants`; written out in `._constants`)
assert KernelConstants._fields == PARAMETER_NAMES

#: the base states (actuation 12, driveline 6; see `empact.nonlinear.model`) and the optional
#: ones, each appended when its option is on (``ix`` holds their positions)
BASE_STATES = ("theta_mp", "theta_ms", "theta_sp", "theta_ss", "x_p", "x_s",
               "omega_mp", "omega_ms", "omega_sp", "omega_ss", "v_p", "v_s",
               "twist_tc", "twist_ds", "omega_d", "omega_p", "omega_s", "omega_l")
OPTIONAL_STATES = ("s_b", "z_d", "z_l", "z_r")

#: shift laws (``p[P_LAW]``): Shafai's c / |omega| on each sheave, or the belt's creep
#: resistance after Carbone et al. (log of the thrust ratio) or Ide et al. (thrust difference)
LAW_SHAFAI, LAW_CARBONE, LAW_IDE = 0.0, 1.0, 2.0

#: number of base states (actuation 12, driveline 6)
NX_BASE = len(BASE_STATES)

OUTPUTS = ("r_g", "nu", "nu_r", "theta_mp", "theta_ms", "F_p", "F_s", "F_p_act", "F_s_act",
           "omega_p", "omega_s", "omega_d", "omega_l", "omega_mp", "omega_ms", "T_b", "mu",
           "tau", "kappa", "kappa_eq", "r_g_dot", "F_creep", "R_p", "R_s", "phi", "x_p", "x_s",
           "belt_elongation", "T_mp_act", "T_d_act", "T_l_act", "E", "P_in", "P_diss",
           "P_creep", "T_ms_act", "T_ds", "mu_max")
NY = len(OUTPUTS)
(Y_RG, Y_NU, Y_NUR, Y_THMP, Y_THMS, Y_FP, Y_FS, Y_FPA, Y_FSA, Y_WP, Y_WS, Y_WD, Y_WL, Y_WMP,
 Y_WMS, Y_TB, Y_MU, Y_TAU, Y_KAP, Y_KEQ, Y_RDOT, Y_FCR, Y_RP, Y_RS, Y_PHI, Y_XP, Y_XS, Y_E,
 Y_TMP, Y_TD, Y_TL, Y_EN, Y_PIN, Y_PDISS, Y_PCREEP, Y_TMS, Y_TDS, Y_MUMAX) = range(NY)


def pack_parameters(values: Mapping[str, float], thrust_table: np.ndarray,
                    creep_table: np.ndarray, traction_table: np.ndarray) -> np.ndarray:
    """The parameter vector ``p`` from values by name (every name of `PARAMETER_NAMES` but the
    table offsets), followed by the encoded thrust-ratio, shift-speed and traction tables
    (each empty for its analytic law); ``thrust_table``, ``creep_table`` and
    ``traction_table`` hold their offsets."""
    offsets = ("thrust_table", "creep_table", "traction_table")
    names = [k for k in PARAMETER_NAMES if k not in offsets]
    missing = set(names) - set(values)
    if missing:
        raise KeyError(f"kernel parameters missing: {', '.join(sorted(missing))}")
    tables = (thrust_table, creep_table, traction_table)
    p = np.zeros(NP + sum(len(t) for t in tables))
    p[:NP] = [float(values.get(k, 0.0)) for k in PARAMETER_NAMES]
    at = NP
    for index, table in zip((P_TAB, P_CTAB, P_MTAB), tables):
        if len(table):
            p[index] = at
            p[at:at + len(table)] = table
            at += len(table)
    return p


def constants(p: np.ndarray) -> KernelConstants:
    """The kernel parameters of ``p`` by name."""
    return KernelConstants(*map(float, p[:NP]))


def state_layout(locked_belt: bool, drive_speed: bool, load_speed: bool,
                 ratio_control: bool) -> tuple[tuple[str, ...], np.ndarray]:
    """State names and the positions ``ix`` (int64, shape (4,), -1 when absent) of the
    optional states for the model's options."""
    states = list(BASE_STATES)
    ix = np.full(4, -1, dtype=np.int64)
    for k, on in enumerate((locked_belt, drive_speed, load_speed, ratio_control)):
        if on:
            ix[k] = len(states)
            states.append(OPTIONAL_STATES[k])
    return tuple(states), ix


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
    """Traction coefficient mu(nu, r_g) (scalar; real or complex): the magic formula, or the
    measured curves at ``p[P_MTAB]`` (`empact.variator._traction_table`)."""
    if p[P_MTAB] != 0.0:
        return table_mu(nu, r_g, p, int(p[P_MTAB]))
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
def _curve(tau, p, start):
    """Piecewise-linear ``ln kappa*`` of one tabulated curve at torque ratio `tau`, held
    constant outside its samples (real or complex `tau`)."""
    n = int(p[start])
    t0 = start + 1
    k0 = start + 1 + n
    if tau.real <= p[t0]:
        return p[k0] + 0.0 * tau
    for j in range(n - 1):
        if tau.real <= p[t0 + j + 1]:
            w = (tau - p[t0 + j]) / (p[t0 + j + 1] - p[t0 + j])
            return p[k0 + j] + w * (p[k0 + j + 1] - p[k0 + j])
    return p[k0 + n - 1] + 0.0 * tau


@njit(cache=True)
def _table(xv, lr, p, base):
    """A tabulated map at `xv` and log-ratio `lr` (the table encoded at ``p[base:]``): linear
    in x along each curve, linear in ln r_g between the curves, held constant outside."""
    n_r = int(p[base])
    if n_r == 1 or lr.real <= p[base + 1]:
        return _curve(xv, p, base + int(p[base + 1 + n_r]))
    for i in range(n_r - 1):
        if lr.real <= p[base + 2 + i]:
            w = (lr - p[base + 1 + i]) / (p[base + 2 + i] - p[base + 1 + i])
            c0 = _curve(xv, p, base + int(p[base + 1 + n_r + i]))
            c1 = _curve(xv, p, base + int(p[base + 2 + n_r + i]))
            return c0 + w * (c1 - c0)
    return _curve(xv, p, base + int(p[base + 2 * n_r]))


@njit(cache=True)
def log_kappa_eq(tau, lr, kgeo, p):
    """``ln kappa*(tau, r_g)``: the equilibrium thrust ratio F_p* / F_s at torque ratio `tau`
    and log-ratio `lr` (kappa_geo = `kgeo`), analytic or tabulated."""
    if p[P_TAB] == 0.0:
        return p[P_KP0] * np.log(kgeo) + (p[P_KB0] - p[P_KB1] * lr) * tau
    return _table(tau, lr, p, int(p[P_TAB]))


@njit(cache=True)
def creep_coefficient(r_g, R_p, F_s, p):
    """``K_c`` [-]: creep rate per radian of primary rotation per unit log thrust-ratio error
    (Carbone et al. 2007): ``gain D(F_s) G_beta r_g (R_p / a) (a1 + a2 ln^2 r_g)``, or
    ``gain`` times a measured shift-speed map ``K_c(F_s, r_g)``."""
    lr = np.log(r_g)
    if p[P_CTAB] != 0.0:
        return p[P_GAIN] * _table(F_s, lr, p, int(p[P_CTAB]))
    D = p[P_DREF] * (1.0 + p[P_KD] * (F_s - p[P_FREF]))
    return p[P_GAIN] * D * p[P_GBETA] * r_g * (R_p / p[P_A]) * (p[P_A1] + p[P_A2] * lr * lr)


@njit(cache=True)
def creep_force(r_g, R_p, R_s, phi, F_s, tau, rdot, w_p, p):
    """``(Lambda, kappa, kappa_eq)``: the belt's shift resistance as a generalised force on the
    ratio [N m] (on the sheaves as ``-Lambda dr_g/dq``), the thrust ratio F_p / F_s it
    implies, and the equilibrium thrust ratio kappa*(tau, r_g); `F_s` is the belt element's
    secondary force.

    The creep law solved for the thrust ratio: Carbone ``kappa = kappa* exp(xi)``, Ide
    ``kappa = kappa* (1 + xi)``, with ``xi = xi_sat tanh(r_g_dot / (omega_eff K_c) / xi_sat)``
    and ``omega_eff = sqrt(omega_p^2 + omega_0^2)``.  Lambda makes the clamping forces
    ``F_p = kappa_geo F_s + Lambda a``, ``F_s - Lambda b`` (``a = r_g / (tan(beta) R_p)``,
    ``b = r_g / (tan(beta) R_s)``) stand in the ratio kappa:
    ``Lambda = F_s (kappa - kappa_geo) / (a + kappa b)``.
    """
    tb = p[P_TB]
    kgeo = (np.pi + 2.0 * phi) / (np.pi - 2.0 * phi)
    lnk = log_kappa_eq(tau, np.log(r_g), kgeo, p)
    Kc = creep_coefficient(r_g, R_p, F_s, p)
    w_eff = np.sqrt(w_p * w_p + p[P_W0] * p[P_W0])
    xi = p[P_XSAT] * np.tanh(rdot / (w_eff * Kc) / p[P_XSAT])
    keq = np.exp(lnk)
    if p[P_LAW] == LAW_IDE:
        kap = keq * (1.0 + xi)
    else:
        kap = keq * np.exp(xi)
    a = r_g / (tb * R_p)
    b = r_g / (tb * R_s)
    return F_s * (kap - kgeo) / (a + kap * b), kap, keq


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
    F_p_el = N * g5                      # the belt element's axial forces (virtual work)
    F_s_el = N * (pi - 2.0 * phi) / tb

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

    # Shafai pulley damping with the current pulley speeds (shift law "shafai" only)
    c_p = zero
    c_s = zero
    if p[P_LAW] == LAW_SHAFAI and p[P_CSH] != 0.0:
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

    # ratio, slip (eq. 2)
    r_g = R_p / R_s
    nu = 1.0 - ws / (r_g * wp)
    mu = traction_mu(nu, r_g, p)
    lr = np.log(r_g)
    if p[P_MTAB] != 0.0:  # the measured curves' peak
        mu_max = table_mu_max(r_g, p, int(p[P_MTAB]))
    else:
        mu_max = _interp3(lr, p[P_LLOW], p[P_LMED], p[P_LOD], p[P_D0], p[P_D1], p[P_D2])
    if ix[0] >= 0:  # belt locked: elastic chain element R_p theta_p - R_s theta_s
        F_b = p[P_KBD] * x[ix[0]]
        T_b = R_s * F_b
        tau = T_b * p[P_COSB] / (2.0 * mu_max * F_s_el * R_s)
    else:
        tau = mu / mu_max

    # the belt's shift resistance (creep-mode shifting): a generalised force Lambda on the
    # ratio, on the sheaves through dr_g/dq5 = r_g / (tan(beta) R_p) and
    # dr_g/dq6 = sig r_g / (tan(beta) R_s) (virtual work)
    dr5 = r_g / (tb * R_p)
    dr6 = sig * r_g / (tb * R_s)
    rdot = dr5 * v5 + dr6 * v6
    if p[P_LAW] == LAW_SHAFAI:
        lam = zero
        kap = (pi + 2.0 * phi) / (pi - 2.0 * phi)
        keq = kap
    else:
        lam, kap, keq = creep_force(r_g, R_p, R_s, phi, F_s_el, tau, rdot, wp, p)
    # clamping forces at the contacts (opening the sheaves): the belt element's and the creep's
    F_p = F_p_el + lam * dr5
    F_s = F_s_el - lam * r_g / (tb * R_s)

    # traction (eq. 1) with the secondary clamping force
    if ix[0] >= 0:
        T_on_p = -R_p * F_b
        P_slip = zero
        dx[ix[0]] = R_p * wp - R_s * ws
    else:
        T_b = 2.0 * mu * F_s * R_s / p[P_COSB]
        T_on_p = -r_g * T_b
        P_slip = T_b * (r_g * wp - ws)

    # servo torques: direct, or the ratio controller (the integral carries the holding torque)
    if ix[3] >= 0:
        if p[P_LAW] == LAW_SHAFAI:  # PID on the shift coordinate of an inertia
            G = (-s * i_e / (i_w * tb)) * (R_s + R_p * (pi + 2.0 * phi) / (pi - 2.0 * phi)) \
                / (R_s * R_s)
        else:  # PI on the ratio rate per N m of primary servo torque the creep law gives
            w_eff = np.sqrt(wp * wp + p[P_W0] * p[P_W0])
            G = -w_eff * creep_coefficient(r_g, R_p, F_s_el, p) * i_w / (i_e * s * F_p_el)
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
    Q5 = -N * g5 - F_tp - c_p * v5 - lam * dr5
    Q6 = -N * g6 - F_ts - c_s * v6 - lam * dr6
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
              + Tf_sp * w3 + Tf_ss * w43 + P_slip + lam * rdot)
    y[Y_RG] = r_g
    y[Y_NU] = nu
    y[Y_NUR] = 1.0 - ws / (p[P_RREF] * wp)
    y[Y_THMP] = q1
    y[Y_THMS] = q2
    y[Y_FP] = F_p
    y[Y_FS] = F_s
    y[Y_FPA] = -F_tp
    y[Y_FSA] = sig * F_ts
    y[Y_TAU] = tau
    y[Y_KAP] = kap
    y[Y_KEQ] = keq
    y[Y_RDOT] = rdot
    y[Y_FCR] = lam * dr5
    y[Y_PCREEP] = lam * rdot
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
    y[Y_TMS] = T_ms
    y[Y_TDS] = T_ds
    y[Y_MUMAX] = mu_max


@njit(cache=True)
def _jacobian_cs(x, u, p, ix, A, B, C, D):
    """A = df/dx, B = df/du, C = dy/dx, D = dy/du by the complex step (h = 1e-30): the
    reference for `_jacobian` (tests, benchmarks), 4-7 real evaluations per column."""
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


# -- forward mode (tangents) in real arithmetic -----------------------------------------------
# Each function below returns a value of the kernel (the same operations as the routine it
# mirrors, so the same value) and its partial derivatives, each on the branch the complex step
# takes: every comparison is the one of the complex routine on the real part (a knot or a
# table sample counts to the segment on its left, |w| at w = 0 has slope +1).
@njit(cache=True)
def _interp3_d(lr, l0, l1, l2, c0, c1, c2):
    """`_interp3` at real `lr` and its slope d/d(lr)."""
    if lr <= l0:
        return c0, 0.0
    if lr <= l1:
        return c0 + (lr - l0) / (l1 - l0) * (c1 - c0), (c1 - c0) / (l1 - l0)
    if lr <= l2:
        return c1 + (lr - l1) / (l2 - l1) * (c2 - c1), (c2 - c1) / (l2 - l1)
    return c2, 0.0


@njit(cache=True)
def _traction_mu_d(nu, r_g, p):
    """``(mu, dmu/dnu, dmu/d ln r_g)``: `traction_mu` at real arguments and its partials."""
    if p[P_MTAB] != 0.0:
        return table_mu_d(nu, r_g, p, int(p[P_MTAB]))
    lr = np.log(r_g)
    l0, l1, l2 = p[P_LLOW], p[P_LMED], p[P_LOD]
    B, B_l = _interp3_d(lr, l0, l1, l2, p[P_B0], p[P_B1], p[P_B2])
    C, C_l = _interp3_d(lr, l0, l1, l2, p[P_C0], p[P_C1], p[P_C2])
    D, D_l = _interp3_d(lr, l0, l1, l2, p[P_D0], p[P_D1], p[P_D2])
    E, E_l = _interp3_d(lr, l0, l1, l2, p[P_E0], p[P_E1], p[P_E2])
    Bn = B * nu
    t = np.arctan(Bn)
    inner = Bn - E * (Bn - t)
    at = np.arctan(inner)
    sn = np.sin(C * at)
    mu_ca = D * np.cos(C * at)                      # d mu / d(C at)
    in_bn = 1.0 - E * (1.0 - 1.0 / (1.0 + Bn * Bn))  # d inner / d Bn
    at_in = 1.0 / (1.0 + inner * inner)             # d at / d inner
    mu_nu = mu_ca * C * at_in * in_bn * B
    mu_lr = D_l * sn + mu_ca * (C_l * at + C * at_in * (in_bn * B_l * nu - E_l * (Bn - t)))
    return D * sn, mu_nu, mu_lr


@njit(cache=True)
def _curve_d(tau, p, start):
    """`_curve` at real `tau` and its slope."""
    n = int(p[start])
    t0 = start + 1
    k0 = start + 1 + n
    if tau <= p[t0]:
        return p[k0], 0.0
    for j in range(n - 1):
        if tau <= p[t0 + j + 1]:
            w = (tau - p[t0 + j]) / (p[t0 + j + 1] - p[t0 + j])
            return (p[k0 + j] + w * (p[k0 + j + 1] - p[k0 + j]),
                    (p[k0 + j + 1] - p[k0 + j]) / (p[t0 + j + 1] - p[t0 + j]))
    return p[k0 + n - 1], 0.0


@njit(cache=True)
def _table_d(xv, lr, p, base):
    """`_table` at real arguments and its partials ``(value, d/d xv, d/d lr)``."""
    n_r = int(p[base])
    if n_r == 1 or lr <= p[base + 1]:
        v, s = _curve_d(xv, p, base + int(p[base + 1 + n_r]))
        return v, s, 0.0
    for i in range(n_r - 1):
        if lr <= p[base + 2 + i]:
            w = (lr - p[base + 1 + i]) / (p[base + 2 + i] - p[base + 1 + i])
            c0, s0 = _curve_d(xv, p, base + int(p[base + 1 + n_r + i]))
            c1, s1 = _curve_d(xv, p, base + int(p[base + 2 + n_r + i]))
            return (c0 + w * (c1 - c0), s0 + w * (s1 - s0),
                    (c1 - c0) / (p[base + 2 + i] - p[base + 1 + i]))
    v, s = _curve_d(xv, p, base + int(p[base + 2 * n_r]))
    return v, s, 0.0


@njit(cache=True)
def _eval_tangent(x, u, p, ix, Sx, Su, dx, y, Fd, Yd):
    """`_eval` (fills ``dx``, ``y``) and K directional derivatives by forward mode:
    ``Fd[:, k] = df/dx Sx[:, k] + df/du Su[:, k]`` and ``Yd[:, k] = dy/dx Sx[:, k] +
    dy/du Su[:, k]`` (``Sx`` (n, K), ``Su`` (4, K); ``Yd`` with no rows: outputs skipped).

    Hand-derived tangents of `_eval`, real arithmetic: one pass computes the values and the
    local partial derivatives (the operations of `_eval`, so the same ``dx`` and ``y``), then
    a loop over the directions propagates the tangents through the same formulas - about
    one real evaluation plus ~250 multiply-adds per direction.  Exact to rounding; every
    branch is the one the complex step (`_jacobian_cs`) takes.  `tests/test_jacobian.py`
    checks it against the complex step.
    """
    K = Sx.shape[1]
    want_y = Yd.shape[0] > 0
    a = p[P_A]
    tb = p[P_TB]
    pi = np.pi
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
    locked = ix[0] >= 0
    shafai = p[P_LAW] == LAW_SHAFAI
    ide = p[P_LAW] == LAW_IDE

    # -- values and local partials (the operations of _eval) --
    R_p = p[P_RMIN] + q5 / tb
    sig = p[P_SIG]
    R_s = p[P_RS0] - sig * q6 / tb
    z = (R_p - R_s) / a
    phi = np.arcsin(z)
    cphi = np.cos(phi)
    L = 2.0 * a * cphi + (pi + 2.0 * phi) * R_p + (pi - 2.0 * phi) * R_s
    L_phi = -2.0 * a * z + 2.0 * (R_p - R_s)   # dL/dphi (zero but for rounding)
    e = L - p[P_L0]
    g5 = (pi + 2.0 * phi) / tb
    g6 = -sig * (pi - 2.0 * phi) / tb
    edot = g5 * v5 + g6 * v6
    alpha = p[P_ALPHA]
    kbelt = p[P_KBELT]
    N = kbelt * (e + alpha * edot)
    F_p_el = N * g5
    F_s_el = N * (pi - 2.0 * phi) / tb

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
    kw = p[P_KW]
    kc = p[P_KC]
    ktp = p[P_KTP]
    kts = p[P_KTS]
    T_w = kw * (e_w + alpha * ed_w)
    T_c = kc * (e_c + alpha * ed_c)
    F_tp = ktp * (d_p + alpha * dd_p)
    F_ts = kts * (d_s + alpha * dd_s)

    c_p = 0.0
    c_s = 0.0
    cp_w = 0.0      # dc_p / d omega_p
    cs_w = 0.0
    if shafai and p[P_CSH] != 0.0:
        ap = _sabs(wp)
        aps = _sabs(ws)
        c_p = p[P_CSH] / ap
        c_s = p[P_CSH] / aps
        cp_w = -c_p / ap * (-1.0 if wp < 0 else 1.0)
        cs_w = -c_s / aps * (-1.0 if ws < 0 else 1.0)
    w43 = w4 - w3
    Tf_sp = 0.0
    Tf_ss = 0.0
    fsp_w = 0.0
    fss_w = 0.0
    if p[P_TCSP] != 0.0:
        th = np.tanh(w3 / p[P_WC])
        Tf_sp = p[P_TCSP] * th
        fsp_w = p[P_TCSP] * (1.0 - th * th) / p[P_WC]
    if p[P_TCSS] != 0.0:
        th = np.tanh(w43 / p[P_WC])
        Tf_ss = p[P_TCSS] * th
        fss_w = p[P_TCSS] * (1.0 - th * th) / p[P_WC]

    r_g = R_p / R_s
    rw = r_g * wp
    nu = 1.0 - ws / rw
    mu, mu_nu, mu_lr = _traction_mu_d(nu, r_g, p)
    lr = np.log(r_g)
    if p[P_MTAB] != 0.0:  # the measured curves' peak and its slope
        _, mu_max, mm_lr = table_peak(r_g, p, int(p[P_MTAB]))
    else:
        mu_max, mm_lr = _interp3_d(lr, p[P_LLOW], p[P_LMED], p[P_LOD], p[P_D0], p[P_D1],
                                   p[P_D2])
    cosb = p[P_COSB]
    xb = 0.0
    F_b = 0.0
    den_tau = 1.0
    T_b = 0.0
    if locked:
        xb = x[ix[0]]
        F_b = p[P_KBD] * xb
        T_b = R_s * F_b
        den_tau = 2.0 * mu_max * F_s_el * R_s
        tau = T_b * cosb / den_tau
    else:
        tau = mu / mu_max

    dr5 = r_g / (tb * R_p)
    dr6 = sig * r_g / (tb * R_s)
    b6 = r_g / (tb * R_s)
    rdot = dr5 * v5 + dr6 * v6
    kgeo = (pi + 2.0 * phi) / (pi - 2.0 * phi)
    kgeo_phi = 4.0 * pi / ((pi - 2.0 * phi) * (pi - 2.0 * phi))
    lam = 0.0
    kap = kgeo
    keq = kgeo
    lnk_kg = lnk_lr = lnk_tau = 0.0
    Kc = Kc_F = Kc_rg = Kc_Rp = Kc_lr = 0.0
    w_eff = weff_w = xi = xi_rd = xi_wk = den = 0.0
    if not shafai:  # creep_force(r_g, R_p, R_s, phi, F_s_el, tau, rdot, wp, p)
        if p[P_TAB] == 0.0:
            lnk = p[P_KP0] * np.log(kgeo) + (p[P_KB0] - p[P_KB1] * lr) * tau
            lnk_kg = p[P_KP0] / kgeo
            lnk_lr = -p[P_KB1] * tau
            lnk_tau = p[P_KB0] - p[P_KB1] * lr
        else:
            lnk, lnk_tau, lnk_lr = _table_d(tau, lr, p, int(p[P_TAB]))
        gain = p[P_GAIN]
        if p[P_CTAB] != 0.0:
            tv, t_f, t_lr = _table_d(F_s_el, lr, p, int(p[P_CTAB]))
            Kc = gain * tv
            Kc_F = gain * t_f
            Kc_lr = gain * t_lr
        else:
            Dc = p[P_DREF] * (1.0 + p[P_KD] * (F_s_el - p[P_FREF]))
            Q = p[P_A1] + p[P_A2] * lr * lr
            Kc = gain * Dc * p[P_GBETA] * r_g * (R_p / p[P_A]) * Q
            cg = gain * p[P_GBETA] / p[P_A]
            Kc_F = cg * p[P_DREF] * p[P_KD] * r_g * R_p * Q
            Kc_rg = cg * Dc * R_p * Q
            Kc_Rp = cg * Dc * r_g * Q
            Kc_lr = cg * Dc * r_g * R_p * 2.0 * p[P_A2] * lr
        w_eff = np.sqrt(wp * wp + p[P_W0] * p[P_W0])
        weff_w = wp / w_eff
        wk = w_eff * Kc
        th = np.tanh(rdot / (w_eff * Kc) / p[P_XSAT])
        xi = p[P_XSAT] * th
        xi_rd = (1.0 - th * th) / wk            # d xi / d rdot
        xi_wk = -xi_rd * rdot / wk               # d xi / d(w_eff Kc)
        keq = np.exp(lnk)
        if ide:
            kap = keq * (1.0 + xi)
        else:
            kap = keq * np.exp(xi)
        den = dr5 + kap * b6
        lam = F_s_el * (kap - kgeo) / den
    F_p = F_p_el + lam * dr5
    F_s = F_s_el - lam * r_g / (tb * R_s)

    slipv = 0.0
    if locked:
        T_on_p = -R_p * F_b
        P_slip = 0.0
        dx[ix[0]] = R_p * wp - R_s * ws
    else:
        T_b = 2.0 * mu * F_s * R_s / cosb
        T_on_p = -r_g * T_b
        slipv = r_g * wp - ws
        P_slip = T_b * slipv

    G = c0g = err = 0.0
    if ix[3] >= 0:
        if shafai:
            c0g = -s * i_e / (i_w * tb)
            G = c0g * (R_s + R_p * (pi + 2.0 * phi) / (pi - 2.0 * phi)) / (R_s * R_s)
        else:
            G = -w_eff * Kc * i_w / (i_e * s * F_p_el)
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

    cmp_ = p[P_CMP]
    cms = p[P_CMS]
    csp = p[P_CSP]
    css = p[P_CSS]
    Q1 = T_mp - T_w / i_w - cmp_ * w1
    Q2 = T_ms - T_c / i_c - cms * w2
    Q3 = T_w / i_e - s * F_tp + s * F_ts - csp * w3 - Tf_sp + css * w43 + Tf_ss
    Q4 = T_c / i_e - s * F_ts - css * w43 - Tf_ss
    Q5 = -N * g5 - F_tp - c_p * v5 - lam * dr5
    Q6 = -N * g6 - F_ts - c_s * v6 - lam * dr6
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
    T_tc = p[P_KTC] * tw_tc
    T_ds = p[P_KDS] * tw_ds
    dx[12] = wd - wp
    dx[13] = ws - wl
    dx[14] = (T_d - T_tc) / p[P_JD]
    dx[15] = (T_tc + T_on_p) / p[P_JP]
    dx[16] = (T_b - T_ds) / p[P_JS]
    dx[17] = (T_ds - T_l) / p[P_JL]

    E = 0.5 * (p[P_JMP] * w1 * w1 + p[P_JMS] * w2 * w2 + p[P_JSP] * w3 * w3
               + p[P_JSS] * w4 * w4 + p[P_MP] * v5 * v5 + p[P_MS] * v6 * v6
               + kw * e_w * e_w + kc * e_c * e_c + kbelt * e * e
               + ktp * d_p * d_p + kts * d_s * d_s
               + p[P_JD] * wd * wd + p[P_JP] * wp * wp + p[P_JS] * ws * ws + p[P_JL] * wl * wl
               + p[P_KTC] * tw_tc * tw_tc + p[P_KDS] * tw_ds * tw_ds)
    if locked:
        E += 0.5 * p[P_KBD] * x[ix[0]] * x[ix[0]]
    P_in = T_mp * w1 + T_ms * w2 + T_d * wd - T_l * wl
    P_diss = (cmp_ * w1 * w1 + cms * w2 * w2 + csp * w3 * w3
              + css * w43 * w43 + c_p * v5 * v5 + c_s * v6 * v6
              + alpha * (kw * ed_w * ed_w + kc * ed_c * ed_c
                         + kbelt * edot * edot + ktp * dd_p * dd_p
                         + kts * dd_s * dd_s)
              + Tf_sp * w3 + Tf_ss * w43 + P_slip + lam * rdot)
    y[Y_RG] = r_g
    y[Y_NU] = nu
    y[Y_NUR] = 1.0 - ws / (p[P_RREF] * wp)
    y[Y_THMP] = q1
    y[Y_THMS] = q2
    y[Y_FP] = F_p
    y[Y_FS] = F_s
    y[Y_FPA] = -F_tp
    y[Y_FSA] = sig * F_ts
    y[Y_TAU] = tau
    y[Y_KAP] = kap
    y[Y_KEQ] = keq
    y[Y_RDOT] = rdot
    y[Y_FCR] = lam * dr5
    y[Y_PCREEP] = lam * rdot
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
    y[Y_TMS] = T_ms
    y[Y_TDS] = T_ds
    y[Y_MUMAX] = mu_max

    # -- the tangents, direction by direction (suffix _t: the derivative along direction k);
    # divisions by the point's constants as multiplications by their reciprocals
    itb = 1.0 / tb
    ia_cphi = 1.0 / (a * cphi)
    iRs = 1.0 / R_s
    irg = 1.0 / r_g
    irw = 1.0 / rw
    ws_rw = ws * irw
    itbRp = 1.0 / (tb * R_p)
    itbRs = 1.0 / (tb * R_s)
    pm = pi - 2.0 * phi
    pp = pi + 2.0 * phi
    iw = 1.0 / i_w
    ic = 1.0 / i_c
    ie = 1.0 / i_e
    imm = 1.0 / mu_max
    iden_tau = 1.0 / den_tau
    iden = 1.0 / den if den != 0.0 else 0.0
    icosb2 = 2.0 / cosb
    iG = 1.0 / G if G != 0.0 else 0.0
    iRs2 = iRs * iRs
    ie_s_Fp = 1.0 / (i_e * s * F_p_el) if ix[3] >= 0 and not shafai else 0.0
    inur = 1.0 / (p[P_RREF] * wp)
    ws_wp = ws / wp
    iJmp = 1.0 / p[P_JMP]
    iJms = 1.0 / p[P_JMS]
    iJsp = 1.0 / p[P_JSP]
    iJss = 1.0 / p[P_JSS]
    iMp = 1.0 / p[P_MP]
    iMs = 1.0 / p[P_MS]
    iJd = 1.0 / p[P_JD]
    iJp = 1.0 / p[P_JP]
    iJs = 1.0 / p[P_JS]
    iJl = 1.0 / p[P_JL]
    for k in range(K):
        q1_t = Sx[0, k]
        q2_t = Sx[1, k]
        q3_t = Sx[2, k]
        q4_t = Sx[3, k]
        q5_t = Sx[4, k]
        q6_t = Sx[5, k]
        w1_t = Sx[6, k]
        w2_t = Sx[7, k]
        w3_t = Sx[8, k]
        w4_t = Sx[9, k]
        v5_t = Sx[10, k]
        v6_t = Sx[11, k]
        tw_tc_t = Sx[12, k]
        tw_ds_t = Sx[13, k]
        wd_t = Sx[14, k]
        wp_t = Sx[15, k]
        ws_t = Sx[16, k]
        wl_t = Sx[17, k]
        u0_t = Su[0, k]
        u1_t = Su[1, k]
        u2_t = Su[2, k]
        u3_t = Su[3, k]

        R_p_t = q5_t * itb
        R_s_t = -sig * q6_t * itb
        phi_t = (R_p_t - R_s_t) * ia_cphi
        e_t = L_phi * phi_t + pp * R_p_t + pm * R_s_t
        g5_t = 2.0 * phi_t * itb
        g6_t = sig * g5_t
        edot_t = g5_t * v5 + g5 * v5_t + g6_t * v6 + g6 * v6_t
        N_t = kbelt * (e_t + alpha * edot_t)
        F_p_el_t = N_t * g5 + N * g5_t
        F_s_el_t = (N_t * pm - 2.0 * N * phi_t) * itb

        e_w_t = q1_t * iw - q3_t * ie
        ed_w_t = w1_t * iw - w3_t * ie
        e_c_t = q2_t * ic - q4_t * ie
        ed_c_t = w2_t * ic - w4_t * ie
        d_p_t = s * q3_t + q5_t
        dd_p_t = s * w3_t + v5_t
        d_s_t = s * (q4_t - q3_t) + q6_t
        dd_s_t = s * (w4_t - w3_t) + v6_t
        T_w_t = kw * (e_w_t + alpha * ed_w_t)
        T_c_t = kc * (e_c_t + alpha * ed_c_t)
        F_tp_t = ktp * (d_p_t + alpha * dd_p_t)
        F_ts_t = kts * (d_s_t + alpha * dd_s_t)
        c_p_t = cp_w * wp_t
        c_s_t = cs_w * ws_t
        w43_t = w4_t - w3_t
        Tf_sp_t = fsp_w * w3_t
        Tf_ss_t = fss_w * w43_t

        r_g_t = (R_p_t - r_g * R_s_t) * iRs
        lr_t = r_g_t * irg
        nu_t = -(ws_t - ws_rw * (r_g_t * wp + r_g * wp_t)) * irw
        mu_t = mu_nu * nu_t + mu_lr * lr_t
        mu_max_t = mm_lr * lr_t
        xb_t = 0.0
        F_b_t = 0.0
        T_b_t = 0.0
        if locked:
            xb_t = Sx[ix[0], k]
            F_b_t = p[P_KBD] * xb_t
            T_b_t = R_s_t * F_b + R_s * F_b_t
            tau_t = (T_b_t * cosb - tau * 2.0 * (mu_max_t * F_s_el * R_s + mu_max * F_s_el_t
                                                 * R_s + mu_max * F_s_el * R_s_t)) * iden_tau
        else:
            tau_t = (mu_t - tau * mu_max_t) * imm
        dr5_t = (r_g_t - dr5 * tb * R_p_t) * itbRp
        b6_t = (r_g_t - b6 * tb * R_s_t) * itbRs
        dr6_t = sig * b6_t
        rdot_t = dr5_t * v5 + dr5 * v5_t + dr6_t * v6 + dr6 * v6_t
        kgeo_t = kgeo_phi * phi_t
        lam_t = 0.0
        kap_t = kgeo_t
        keq_t = kgeo_t
        Kc_t = 0.0
        weff_t = 0.0
        if not shafai:
            lnk_t = lnk_kg * kgeo_t + lnk_lr * lr_t + lnk_tau * tau_t
            Kc_t = Kc_F * F_s_el_t + Kc_rg * r_g_t + Kc_Rp * R_p_t + Kc_lr * lr_t
            weff_t = weff_w * wp_t
            xi_t = xi_rd * rdot_t + xi_wk * (weff_t * Kc + w_eff * Kc_t)
            keq_t = keq * lnk_t
            if ide:
                kap_t = keq_t * (1.0 + xi) + keq * xi_t
            else:
                kap_t = kap * (lnk_t + xi_t)
            den_t = dr5_t + kap_t * b6 + kap * b6_t
            lam_t = (F_s_el_t * (kap - kgeo) + F_s_el * (kap_t - kgeo_t) - lam * den_t) * iden
        F_p_t = F_p_el_t + lam_t * dr5 + lam * dr5_t
        F_s_t = F_s_el_t - lam_t * b6 - lam * b6_t

        P_slip_t = 0.0
        if locked:
            T_on_p_t = -(R_p_t * F_b + R_p * F_b_t)
            Fd[ix[0], k] = R_p_t * wp + R_p * wp_t - R_s_t * ws - R_s * ws_t
        else:
            T_b_t = (mu_t * F_s * R_s + mu * F_s_t * R_s + mu * F_s * R_s_t) * icosb2
            T_on_p_t = -(r_g_t * T_b + r_g * T_b_t)
            P_slip_t = T_b_t * slipv + T_b * (r_g_t * wp + r_g * wp_t - ws_t)

        if ix[3] >= 0:
            if shafai:
                G_t = (c0g * (R_s_t + R_p_t * kgeo + R_p * kgeo_t) * iRs2
                       - 2.0 * G * R_s_t * iRs)
            else:
                G_t = (-(weff_t * Kc + w_eff * Kc_t) * i_w - G * i_e * s * F_p_el_t) * ie_s_Fp
            err_t = (u0_t - r_g_t - err * G_t) * iG
            T_mp_t = Sx[ix[3], k] + p[P_RKP] * err_t - p[P_RKD] * w1_t
            Fd[ix[3], k] = p[P_RKI] * err_t
        else:
            T_mp_t = u0_t
        T_ms_t = u1_t
        if ix[1] >= 0:
            T_d_t = Sx[ix[1], k] + p[P_DKP] * (u2_t - wd_t)
            Fd[ix[1], k] = p[P_DKI] * (u2_t - wd_t)
        else:
            T_d_t = u2_t
        if ix[2] >= 0:
            T_l_t = Sx[ix[2], k] - p[P_LKP] * (u3_t - wl_t)
            Fd[ix[2], k] = -p[P_LKI] * (u3_t - wl_t)
        else:
            T_l_t = u3_t

        Fd[0, k] = w1_t
        Fd[1, k] = w2_t
        Fd[2, k] = w3_t
        Fd[3, k] = w4_t
        Fd[4, k] = v5_t
        Fd[5, k] = v6_t
        Fd[6, k] = (T_mp_t - T_w_t * iw - cmp_ * w1_t) * iJmp
        Fd[7, k] = (T_ms_t - T_c_t * ic - cms * w2_t) * iJms
        Fd[8, k] = (T_w_t * ie - s * F_tp_t + s * F_ts_t - csp * w3_t - Tf_sp_t + css * w43_t
                    + Tf_ss_t) * iJsp
        Fd[9, k] = (T_c_t * ie - s * F_ts_t - css * w43_t - Tf_ss_t) * iJss
        Fd[10, k] = (-(N_t * g5 + N * g5_t) - F_tp_t - (c_p_t * v5 + c_p * v5_t)
                     - (lam_t * dr5 + lam * dr5_t)) * iMp
        Fd[11, k] = (-(N_t * g6 + N * g6_t) - F_ts_t - (c_s_t * v6 + c_s * v6_t)
                     - (lam_t * dr6 + lam * dr6_t)) * iMs
        T_tc_t = p[P_KTC] * tw_tc_t
        T_ds_t = p[P_KDS] * tw_ds_t
        Fd[12, k] = wd_t - wp_t
        Fd[13, k] = ws_t - wl_t
        Fd[14, k] = (T_d_t - T_tc_t) * iJd
        Fd[15, k] = (T_tc_t + T_on_p_t) * iJp
        Fd[16, k] = (T_b_t - T_ds_t) * iJs
        Fd[17, k] = (T_ds_t - T_l_t) * iJl
        if not want_y:
            continue

        E_t = (p[P_JMP] * w1 * w1_t + p[P_JMS] * w2 * w2_t + p[P_JSP] * w3 * w3_t
               + p[P_JSS] * w4 * w4_t + p[P_MP] * v5 * v5_t + p[P_MS] * v6 * v6_t
               + kw * e_w * e_w_t + kc * e_c * e_c_t + kbelt * e * e_t
               + ktp * d_p * d_p_t + kts * d_s * d_s_t
               + p[P_JD] * wd * wd_t + p[P_JP] * wp * wp_t + p[P_JS] * ws * ws_t
               + p[P_JL] * wl * wl_t + p[P_KTC] * tw_tc * tw_tc_t + p[P_KDS] * tw_ds * tw_ds_t)
        if locked:
            E_t += p[P_KBD] * xb * xb_t
        P_in_t = (T_mp_t * w1 + T_mp * w1_t + T_ms_t * w2 + T_ms * w2_t + T_d_t * wd
                  + T_d * wd_t - T_l_t * wl - T_l * wl_t)
        P_diss_t = (2.0 * (cmp_ * w1 * w1_t + cms * w2 * w2_t + csp * w3 * w3_t
                           + css * w43 * w43_t + c_p * v5 * v5_t + c_s * v6 * v6_t
                           + alpha * (kw * ed_w * ed_w_t + kc * ed_c * ed_c_t
                                      + kbelt * edot * edot_t + ktp * dd_p * dd_p_t
                                      + kts * dd_s * dd_s_t))
                    + c_p_t * v5 * v5 + c_s_t * v6 * v6
                    + Tf_sp_t * w3 + Tf_sp * w3_t + Tf_ss_t * w43 + Tf_ss * w43_t + P_slip_t
                    + lam_t * rdot + lam * rdot_t)
        Yd[Y_RG, k] = r_g_t
        Yd[Y_NU, k] = nu_t
        Yd[Y_NUR, k] = -(ws_t - ws_wp * wp_t) * inur
        Yd[Y_THMP, k] = q1_t
        Yd[Y_THMS, k] = q2_t
        Yd[Y_FP, k] = F_p_t
        Yd[Y_FS, k] = F_s_t
        Yd[Y_FPA, k] = -F_tp_t
        Yd[Y_FSA, k] = sig * F_ts_t
        Yd[Y_TAU, k] = tau_t
        Yd[Y_KAP, k] = kap_t
        Yd[Y_KEQ, k] = keq_t
        Yd[Y_RDOT, k] = rdot_t
        Yd[Y_FCR, k] = lam_t * dr5 + lam * dr5_t
        Yd[Y_PCREEP, k] = lam_t * rdot + lam * rdot_t
        Yd[Y_WP, k] = wp_t
        Yd[Y_WS, k] = ws_t
        Yd[Y_WD, k] = wd_t
        Yd[Y_WL, k] = wl_t
        Yd[Y_WMP, k] = w1_t
        Yd[Y_WMS, k] = w2_t
        Yd[Y_TB, k] = T_b_t
        Yd[Y_MU, k] = mu_t
        Yd[Y_RP, k] = R_p_t
        Yd[Y_RS, k] = R_s_t
        Yd[Y_PHI, k] = phi_t
        Yd[Y_XP, k] = q5_t
        Yd[Y_XS, k] = q6_t
        Yd[Y_E, k] = e_t
        Yd[Y_TMP, k] = T_mp_t
        Yd[Y_TD, k] = T_d_t
        Yd[Y_TL, k] = T_l_t
        Yd[Y_EN, k] = E_t
        Yd[Y_PIN, k] = P_in_t
        Yd[Y_PDISS, k] = P_diss_t
        Yd[Y_TMS, k] = T_ms_t
        Yd[Y_TDS, k] = T_ds_t
        Yd[Y_MUMAX, k] = mu_max_t


@njit(cache=True)
def _full_seeds(n, m):
    """Seeds and tangent buffers for all n + m directions (the states', then the inputs')."""
    Sx = np.zeros((n, n + m))
    Su = np.zeros((m, n + m))
    for j in range(n):
        Sx[j, j] = 1.0
    for j in range(m):
        Su[j, n + j] = 1.0
    return Sx, Su, np.empty((n, n + m)), np.empty((NY, n + m))


@njit(cache=True)
def _split(Fd, Yd, n, A, B, C, D):
    """A, B, C, D from the tangents of all n + m directions."""
    for i in range(Fd.shape[0]):
        for j in range(n):
            A[i, j] = Fd[i, j]
        for j in range(B.shape[1]):
            B[i, j] = Fd[i, n + j]
    for i in range(Yd.shape[0]):
        for j in range(n):
            C[i, j] = Yd[i, j]
        for j in range(D.shape[1]):
            D[i, j] = Yd[i, n + j]


@njit(cache=True)
def _jacobian(x, u, p, ix, A, B, C, D):
    """Exact A = df/dx, B = df/du, C = dy/dx, D = dy/du by forward mode (`_eval_tangent`,
    all n + 4 directions in one pass; equal to `_jacobian_cs` to rounding)."""
    n = x.shape[0]
    Sx, Su, Fd, Yd = _full_seeds(n, u.shape[0])
    _eval_tangent(x, u, p, ix, Sx, Su, np.empty(n), np.empty(NY), Fd, Yd)
    _split(Fd, Yd, n, A, B, C, D)


@njit(cache=True)
def _state_jacobian(x, u, p, ix, A, cols):
    """Columns `cols` of A = df/dx, exact (forward mode, one pass), for the implicit
    integrators."""
    n = x.shape[0]
    K = cols.shape[0]
    Sx = np.zeros((n, K))
    for k in range(K):
        Sx[cols[k], k] = 1.0
    Fd = np.empty((n, K))
    _eval_tangent(x, u, p, ix, Sx, np.zeros((u.shape[0], K)), np.empty(n), np.empty(NY), Fd,
                  np.empty((0, K)))
    for k in range(K):
        j = cols[k]
        for i in range(n):
            A[i, j] = Fd[i, k]


@njit(cache=True)
def _input_direction(x, u, du, p, ix, out):
    """out = (df/du) du, exact (one forward-mode direction): the explicit time derivative for
    the Rosenbrock integrators."""
    n = x.shape[0]
    if not np.any(du != 0.0):  # inputs constant on this piece (the common case)
        out[:] = 0.0
        return
    Su = np.empty((u.shape[0], 1))
    for j in range(u.shape[0]):
        Su[j, 0] = du[j]
    Fd = np.empty((n, 1))
    _eval_tangent(x, u, p, ix, np.zeros((n, 1)), Su, np.empty(n), np.empty(NY), Fd,
                  np.empty((0, 1)))
    for i in range(n):
        out[i] = Fd[i, 0]


@njit(cache=True)
def stop_status(y, p, omega_min):
    """Why a simulation must stop at outputs `y` (0: it need not): 4 non-finite output,
    1 omega_p at or below `omega_min` (slip undefined), 2 clamping force at or below zero
    (slack belt), 3 a running radius outside [R_min, R_max]."""
    for i in range(y.shape[0]):
        if not np.isfinite(y[i]):
            return 4
    if y[Y_WP] <= omega_min:
        return 1
    if y[Y_FS] <= 0.0:
        return 2
    tol = 1e-9
    if y[Y_RP] < p[P_RMIN] - tol or y[Y_RP] > p[P_RMAX] + tol or y[Y_RS] < p[P_RMIN] - tol \
            or y[Y_RS] > p[P_RMAX] + tol:
        return 3
    return 0


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
def _state_jacobian_cs(x, u, p, ix, A, cols):
    """Columns `cols` of A = df/dx by the complex step (the reference for
    `_state_jacobian`)."""
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
def _input_direction_cs(x, u, du, p, ix, out):
    """out = (df/du) du by one complex step (the reference for `_input_direction`)."""
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


# -- batches over operating points (plant families) ------------------------------------------
@njit(cache=True)
def traction_many(nu, r_g, p, out):
    """``out[k] = traction_mu(nu[k], r_g[k])`` for 1-D arrays."""
    for k in range(nu.shape[0]):
        out[k] = traction_mu(nu[k], r_g[k], p)


@njit(cache=True)
def bisect_rising_many(r_g, goal, nu_pk, p, out):
    """The slip in ``[0, nu_pk[k]]`` where the traction curve at ``r_g[k]`` reaches
    ``goal[k]`` (64 bisection steps: to rounding), for 1-D arrays: ``out[k]``
    (`empact.nonlinear.equilibrium._bisect_rising`).  Step for step the vectorised NumPy
    bisection it replaced (the same midpoints and comparisons; a NaN goal moves the upper end;
    written out in the tests), so bitwise the same."""
    for k in range(r_g.shape[0]):
        a, b = 0.0, nu_pk[k]
        r, g = r_g[k], goal[k]
        for _ in range(64):
            mid = 0.5 * (a + b)
            if traction_mu(mid, r, p) < g:
                a = mid
            else:
                b = mid
        out[k] = 0.5 * (a + b)


@njit(cache=True)
def traction_peak_many(r_g, g, p, nu_out, mu_out):
    """Golden-section search of the traction curve's peak on slip [0, 0.99] at each ratio
    ``r_g[k]`` (90 steps, ratio `g`): ``nu_out[k], mu_out[k]``.  Step for step the search of
    `empact.nonlinear.equilibrium.traction_peak` (the same operations in the same order,
    each point's value reused where the search keeps it), so bitwise the same.  For measured
    curves (``p[P_MTAB]``) the exact peak of the interpolant (`_traction_table.table_peak`)."""
    for k in range(r_g.shape[0]):
        r = r_g[k]
        if p[P_MTAB] != 0.0:
            nu_out[k], mu_out[k], _ = table_peak(r, p, int(p[P_MTAB]))
            continue
        a, b = 0.0, 0.99
        c, d = b - g * (b - a), a + g * (b - a)
        fc, fd = traction_mu(c, r, p), traction_mu(d, r, p)
        for _ in range(90):
            if fc > fd:  # the peak lies in [a, d]
                b = d
                d, fd = c, fc
                c = b - g * (b - a)
                fc = traction_mu(c, r, p)
            else:
                a = c
                c, fc = d, fd
                d = a + g * (b - a)
                fd = traction_mu(d, r, p)
        nu = 0.5 * (a + b)
        nu_out[k] = nu
        mu_out[k] = traction_mu(nu, r, p)


@njit(cache=True)
def mu_max_many(r_g, p, out):
    """Peak traction coefficient mu_max(r_g) for a 1-D array of ratios: the magic formula's
    D(r_g), or the measured curves' peak (`_traction_table.table_peak`)."""
    for k in range(r_g.shape[0]):
        if p[P_MTAB] != 0.0:
            out[k] = table_peak(r_g[k], p, int(p[P_MTAB]))[1]
            continue
        out[k] = _interp3(np.log(r_g[k]), p[P_LLOW], p[P_LMED], p[P_LOD], p[P_D0], p[P_D1],
                          p[P_D2])


@njit(cache=True)
def creep_many(r_g, R_p, R_s, phi, F_s, tau, p, lam, keq):
    """The creep law at rest for 1-D arrays: ``lam[k], keq[k]`` (Lambda [N m], kappa*)."""
    for k in range(r_g.shape[0]):
        lk, _, kq = creep_force(r_g[k], R_p[k], R_s[k], phi[k], F_s[k], tau[k], 0.0, 1.0, p)
        lam[k] = lk
        keq[k] = kq


@njit(cache=True)
def linearize_batch(X, U, p, ix, DX, A, B, C, D):
    """For every point k: ``DX[k] = f(X[k], U[k])`` and the exact Jacobians ``A[k] = df/dx``,
    ``B[k]``, ``C[k]``, ``D[k]`` (forward mode, `_eval_tangent`), in one compiled loop."""
    n = X.shape[1]
    m = U.shape[1]
    Sx, Su, Fd, Yd = _full_seeds(n, m)
    y = np.empty(NY)
    for k in range(X.shape[0]):
        _eval_tangent(X[k], U[k], p, ix, Sx, Su, DX[k], y, Fd, Yd)
        _split(Fd, Yd, n, A[k], B[k], C[k], D[k])


@njit(cache=True)
def linearize_batch_cs(X, U, p, ix, DX, A, B, C, D):
    """`linearize_batch` by the complex step (`_jacobian_cs`): the reference."""
    y = np.empty(NY)
    for k in range(X.shape[0]):
        _eval(X[k], U[k], p, ix, DX[k], y)
        _jacobian_cs(X[k], U[k], p, ix, A[k], B[k], C[k], D[k])


@njit(cache=True)
def eval_batch(X, U, p, ix, DX, Y):
    """``DX[k], Y[k] = f(X[k], U[k]), y(X[k], U[k])`` for every point k."""
    for k in range(X.shape[0]):
        _eval(X[k], U[k], p, ix, DX[k], Y[k])
