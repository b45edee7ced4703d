"""Compiled (numba) right-hand side of the nonlinear Empact model; see `empact.nonlinear.model`.

Private: the public interface, the state ordering and the sign conventions are documented in
`empact.nonlinear`.  Everything here works on flat arrays:

* ``x`` state, shape (n,); ``u`` inputs, shape (4,);
* ``p`` float parameters, shape (NP + n_tables,), laid out by the ``P_*`` indices below, then
  the traction laws' part generated from their registry (`P_TRACTION`: the analytic law's
  index, the knots' log-ratios, every law's coefficients; `empact.variator._laws`), and
  followed by the optional tabulated maps (a measured thrust-ratio map and a measured
  shift-speed map, `empact.variator._tables.encode_curves`; measured traction curves,
  `empact.variator._traction_table`; a measured loss map, `empact.variator._loss_table`),
  each found at the offset that ``p[P_TAB]`` / ``p[P_CTAB]`` / ``p[P_MTAB]`` / ``p[P_LTAB]``
  holds (0: the analytic law);
* ``ix`` int64, shape (4,): positions in ``x`` of the optional states (belt stretch, drive and
  load speed-loop integrators, ratio-controller integrator), -1 when absent.

The Jacobians are exact: `empact.nonlinear._tangent._eval_tangent` is `_eval` with
hand-derived forward-mode (tangent) derivatives in real arithmetic, any number of directions
in one pass.  `_eval` itself is written once for real and complex arguments, so that the
complex step differentiates it too (`_jacobian_cs`, `_state_jacobian_cs`,
`_input_direction_cs`; exact to rounding: no subtraction, step 1e-30), kept as the reference
the forward mode is tested and benchmarked against.  Comparisons use the real part; ``abs``
is written as a sign flip so that it stays analytic; the forward mode takes the same branch
at every comparison.  What both passes compute alike is written once, in the helpers above
`_eval` (`_belt`, `_springs`, `_dampers`, `_torque_ratio`, and `_finish` with the forces,
torques, equations of motion and outputs), and the variator's laws (belt geometry, traction,
tables, thrust ratio, creep) are `empact.variator._laws`, compiled
(`empact.variator._compiled`).  The modules around
this one: `_tangent` (forward mode), `_batch` (loops over operating points).

This module owns the layout of ``p``, ``x`` and ``y``: every index has a name here
(`PARAMETER_NAMES`, `BASE_STATES` and `OPTIONAL_STATES`, `OUTPUTS`), the model packs its
parameters by name (`pack_parameters`) and reads them back by name (`KernelConstants`), and
no other module spells an index.
"""
from __future__ import annotations

from typing import Mapping

import numpy as np
from numba import njit

from ..variator import _compiled as law
from ..variator._laws import TRACTION_KNOTS, traction_parameter_names
from ..variator._loss_table import table_loss
from ..variator._traction_table import table_mu, table_mu_d, table_mu_max, table_peak
from ._constants import KernelConstants

# -- parameter vector layout ---------------------------------------------------------------
(P_A, P_TB, P_COSB, P_RMIN, P_RMAX, P_L0,
 P_JMP, P_JMS, P_JSP, P_JSS, P_MP, P_MS, P_IW, P_IC, P_IE, P_S,
 P_KW, P_KC, P_KBELT, P_KTP, P_KTS,
 P_ALPHA, P_CMP, P_CMS, P_CSP, P_CSS, P_CSH,
 P_TCSP, P_TCSS, P_WC,
 P_JD, P_JP, P_JS, P_JL, P_KTC, P_KDS, P_KBD,
 P_DKP, P_DKI, P_LKP, P_LKI, P_RKP, P_RKD, P_RKI, P_SIG, P_RS0,
 P_LAW, P_DREF, P_FREF, P_KD, P_A1, P_A2, P_GAIN, P_W0, P_XSAT, P_GBETA,
 P_KP0, P_KB0, P_KB1, P_RREF, P_TAB, P_CTAB, P_MTAB,
 P_LF, P_LT, P_LV, P_LQ, P_LTS,
 P_LTAB) = range(69)

#: the vehicle driveline's parameters (`ModelOptions.driveline` ``"vehicle"``; all zero on
#: the bench): the flag, the wheel radius over the final drive ``r_w / i_fd`` [m/rad] (the
#: car's speed per rad/s of the load shaft, which turns at the secondary's speed), the road
#: load's ``f0`` [N], ``f1`` [N s/m], ``f2`` [N s^2/m^2] and grade force ``m g sin(grade)``
#: [N], and the final drive's efficiency [-] (`_vehicle_load`)
VEHICLE_PARAMETER_NAMES = ("vehicle", "vehicle_gear", "road_f0", "road_f1", "road_f2",
                           "road_grade_force", "eta_fd")

#: names of the parameter vector's entries, in the order of the ``P_*`` indices, then the
#: traction laws' part generated from their registry (`empact.variator._laws`): the law's
#: index ``traction_law`` (at `P_TRACTION`), the knots' log-ratios and every law's
#: coefficients at the knots
PARAMETER_NAMES = (
    "a", "tan_beta", "cos_beta", "R_min", "R_max", "L_belt",
    "J_mp", "J_ms", "J_sp", "J_ss", "m_p", "m_s", "i_w", "i_c", "i_e", "s",
    "k_w", "k_c", "k_belt", "k_tp", "k_ts",
    "alpha", "c_mp", "c_ms", "c_sp", "c_ss", "c_shafai",
    "coulomb_sp", "coulomb_ss", "coulomb_omega",
    "J_d", "J_p", "J_s", "J_l", "k_tc", "k_ds", "k_belt_driveline",
    "drive_kp", "drive_ki", "load_kp", "load_ki", "ratio_kp", "ratio_kd", "ratio_ki",
    "sheave_sense", "R_s0",
    "shift_law", "D_ref", "F_ref", "k_D", "a1", "a2", "gain", "omega_0", "xi_sat", "g_beta",
    "kappa_p0", "kappa_b0", "kappa_b1", "r_ref", "thrust_table", "creep_table",
    "traction_table",
    "loss_lambda_F", "loss_k_T", "loss_c_v", "loss_c_q", "loss_T_smooth",
    "loss_table",
    ) + VEHICLE_PARAMETER_NAMES + traction_parameter_names()
NP = len(PARAMETER_NAMES)
#: the traction law's index in ``p``; its parameters follow (`traction_parameter_names`)
P_TRACTION = PARAMETER_NAMES.index("traction_law")
P_LLOW, P_LMED, P_LOD = (PARAMETER_NAMES.index(f"ln_r_{k}") for k in TRACTION_KNOTS)
P_VEH, P_VGEAR, P_VF0, P_VF1, P_VF2, P_VFG, P_VETA = (PARAMETER_NAMES.index(k)
                                                    for k in VEHICLE_PARAMETER_NAMES)

#: the kernel's parameters read back by name (`constants`; typed in `_constants`)
assert KernelConstants._fields == PARAMETER_NAMES[:P_TRACTION] + ("traction",)

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
           "P_creep", "T_ms_act", "T_ds", "mu_max",
           "P_loss_slip", "P_loss_clamp", "P_loss_load", "P_loss_drag", "P_var_in", "P_var_out",
           "P_diss_servo", "P_diss_spindle", "P_diss_material", "P_diss_sheave",
           "P_loss_map")
NY = len(OUTPUTS)
(Y_RG, Y_NU, Y_NUR, Y_THMP, Y_THMS, Y_FP, Y_FS, Y_FPA, Y_FSA, Y_WP, Y_WS, Y_WD, Y_WL, Y_WMP,
 Y_WMS, Y_TB, Y_MU, Y_TAU, Y_KAP, Y_KEQ, Y_RDOT, Y_FCR, Y_RP, Y_RS, Y_PHI, Y_XP, Y_XS, Y_E,
 Y_TMP, Y_TD, Y_TL, Y_EN, Y_PIN, Y_PDISS, Y_PCREEP, Y_TMS, Y_TDS, Y_MUMAX,
 Y_LSLIP, Y_LCLAMP, Y_LLOAD, Y_LDRAG, Y_PVIN, Y_PVOUT,
 Y_DSERVO, Y_DSPINDLE, Y_DMAT, Y_DSHEAVE,
 Y_LMAP) = range(NY)
#: the vehicle driveline's outputs (zero on the bench), after the others: the car's speed
#: [m/s], the road load [N] and its power [W], the final drive's loss [W] (`_vehicle_load`),
#: the engine's torque referred to the secondary ``T_d omega_d / omega_s`` [N m] (as the
#: engine's controller reports it: the car's loop law's torque source)
VEHICLE_OUTPUTS = ("v", "F_road", "P_road", "P_loss_fd", "T_d_sec")
OUTPUTS = OUTPUTS + VEHICLE_OUTPUTS  # type: ignore[assignment]  # (a longer tuple)
NY = len(OUTPUTS)
Y_V, Y_FROAD, Y_PROAD, Y_LFD, Y_TDSEC = range(NY - len(VEHICLE_OUTPUTS), NY)

#: the variator's losses [W] (outputs): their sum is ``P_var_in - P_var_out`` (`_losses`);
#: ``P_loss_map`` is a measured loss map's (zero without one, and then the analytic clamping,
#: load and drag are)
VARIATOR_LOSSES = ("P_loss_slip", "P_loss_clamp", "P_loss_load", "P_loss_drag", "P_loss_map")
#: the named terms of ``P_diss`` [W] (outputs): the variator's losses, the creep resistance's
#: power, and the actuation's viscous, Coulomb and material (proportional) damping
DISSIPATION_TERMS = VARIATOR_LOSSES + ("P_creep", "P_diss_servo", "P_diss_spindle",
                                       "P_diss_material", "P_diss_sheave")
#: the rates [W] the integrators integrate over their own steps (`energy_rates`; the energy
#: balance of a run, `empact.nonlinear.simulation.energy_balance`): the shaft powers of the
#: drive, the load and the servos (torque times speed), the dissipated powers by term, and
#: the variator's shaft powers
ENERGY_RATES = (("drive", "load", "servo_mechanical_primary", "servo_mechanical_secondary")
                + DISSIPATION_TERMS + ("P_var_in", "P_var_out"))
#: the outputs behind `ENERGY_RATES` after the four shaft powers
_RATE_OUTPUTS = np.array([OUTPUTS.index(k) for k in ENERGY_RATES[4:]], dtype=np.int64)


def pack_parameters(values: Mapping[str, float], thrust_table: np.ndarray,
                    creep_table: np.ndarray, traction_table: np.ndarray,
                    loss_table: np.ndarray | None = None) -> np.ndarray:
    """The parameter vector ``p`` from values by name (every name of `PARAMETER_NAMES` but the
    table offsets), followed by the encoded thrust-ratio, shift-speed, traction and loss
    tables (each empty for its analytic law); ``thrust_table``, ``creep_table``,
    ``traction_table`` and ``loss_table`` hold their offsets."""
    offsets = ("thrust_table", "creep_table", "traction_table", "loss_table")
    names = [k for k in PARAMETER_NAMES if k not in offsets]
    missing = set(names) - set(values)
    if missing:
        raise KeyError(f"kernel parameters missing: {', '.join(sorted(missing))}")
    tables = (thrust_table, creep_table, traction_table,
              np.zeros(0) if loss_table is None else loss_table)
    p = np.zeros(NP + sum(len(t) for t in tables))
    p[:NP] = [float(values.get(k, 0.0)) for k in PARAMETER_NAMES]
    at = NP
    for index, table in zip((P_TAB, P_CTAB, P_MTAB, P_LTAB), tables):
        if len(table):
            p[index] = at
            p[at:at + len(table)] = table
            at += len(table)
    return p


def constants(p: np.ndarray) -> KernelConstants:
    """The kernel parameters of ``p`` by name (the traction laws' part as a dict)."""
    return KernelConstants._make([*map(float, p[:P_TRACTION]), dict(
        zip(PARAMETER_NAMES[P_TRACTION:], map(float, p[P_TRACTION:NP])))])


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


# -- the variator's laws on the parameter vector (the laws: `empact.variator._laws`) ----------
@njit(cache=True, inline="always")
def traction_mu(nu, r_g, p):
    """Traction coefficient mu(nu, r_g) (scalar; real or complex): the analytic law
    ``p[P_TRACTION]`` (`empact.variator._compiled.traction_law_mu`, generated from the
    registry), or the measured curves at ``p[P_MTAB]`` (`empact.variator._traction_table`)."""
    if p[P_MTAB] != 0.0:
        return table_mu(nu, r_g, p, int(p[P_MTAB]))
    return law.traction_law_mu(nu, np.log(r_g), p, P_TRACTION)


@njit(cache=True, inline="always")
def traction_mu_d(nu, r_g, p):
    """``(mu, dmu/dnu, dmu/d ln r_g)``: `traction_mu` and its partials."""
    if p[P_MTAB] != 0.0:
        return table_mu_d(nu, r_g, p, int(p[P_MTAB]))
    return law.traction_law_mu_d(nu, np.log(r_g), p, P_TRACTION)


@njit(cache=True, inline="always")
def mu_peak(r_g, lr, p):
    """The traction curve's peak value at ratio `r_g` (log-ratio `lr`): the analytic law's
    (the magic formula's D), or the measured curves' exact peak
    (`empact.variator._traction_table.table_mu_max`)."""
    if p[P_MTAB] != 0.0:
        return table_mu_max(r_g, p, int(p[P_MTAB]))
    return law.traction_law_peak(lr, p, P_TRACTION)


@njit(cache=True, inline="always")
def mu_max_d(r_g, lr, p):
    """``(mu_max, d mu_max / d lr)``: `mu_peak` and its slope."""
    if p[P_MTAB] != 0.0:
        _, mu_max, mm_lr = table_peak(r_g, p, int(p[P_MTAB]))
        return mu_max, mm_lr
    return law.traction_law_peak_d(lr, p, P_TRACTION)


@njit(cache=True, inline="always")
def log_kappa_eq_d(tau, lr, kgeo, p):
    """``(ln kappa*, d/d tau, d/d lr, d/d kappa_geo)``: the equilibrium thrust ratio F_p* /
    F_s at torque ratio `tau` and log-ratio `lr` (kappa_geo = `kgeo`), analytic or
    tabulated, and its partials."""
    if p[P_TAB] == 0.0:
        return (law.log_kappa_eq(tau, lr, kgeo, p[P_KP0], p[P_KB0], p[P_KB1]),
                p[P_KB0] - p[P_KB1] * lr, -p[P_KB1] * tau, p[P_KP0] / kgeo)
    v, d_tau, d_lr = law.table_at(tau, lr, p, int(p[P_TAB]))
    return v, d_tau, d_lr, 0.0 * kgeo


@njit(cache=True, inline="always")
def log_kappa_eq(tau, lr, kgeo, p):
    """``ln kappa*(tau, r_g)`` (`log_kappa_eq_d`'s value, without the partials)."""
    if p[P_TAB] == 0.0:
        return law.log_kappa_eq(tau, lr, kgeo, p[P_KP0], p[P_KB0], p[P_KB1])
    return law.table_at(tau, lr, p, int(p[P_TAB]))[0]


@njit(cache=True, inline="always")
def creep_coefficient_d(r_g, R_p, F_s, p):
    """``(K_c, dK_c/dF_s, dK_c/dr_g, dK_c/dR_p, dK_c/d ln r_g)`` [-]: creep rate per radian of
    primary rotation per unit log thrust-ratio error (Carbone et al. 2007), or ``gain``
    times a measured shift-speed map ``K_c(F_s, r_g)``, and its partials (real)."""
    lr = np.log(r_g)
    if p[P_CTAB] != 0.0:
        v, d_f, d_lr = law.table_at(F_s, lr, p, int(p[P_CTAB]))
        return p[P_GAIN] * v, p[P_GAIN] * d_f, 0.0, 0.0, p[P_GAIN] * d_lr
    return law.creep_coefficient_d(r_g, R_p, F_s, lr, p[P_A], p[P_GAIN], p[P_GBETA],
                                   p[P_DREF], p[P_KD], p[P_FREF], p[P_A1], p[P_A2])


@njit(cache=True, inline="always")
def creep_coefficient(r_g, R_p, F_s, p):
    """``K_c`` [-] (`creep_coefficient_d`'s value; real or complex)."""
    lr = np.log(r_g)
    if p[P_CTAB] != 0.0:
        return p[P_GAIN] * law.table_at(F_s, lr, p, int(p[P_CTAB]))[0]
    return law.creep_coefficient(r_g, R_p, F_s, lr, p[P_A], p[P_GAIN], p[P_GBETA], p[P_DREF],
                                 p[P_KD], p[P_FREF], p[P_A1], p[P_A2])


@njit(cache=True, inline="always")
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
    kgeo = law.kappa_geo(phi)
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


@njit(cache=True, inline="always")
def _sabs(w):
    """|w| for real w, analytic continuation (sign flip) for the complex step."""
    if w.real < 0:
        return -w
    return w


@njit(cache=True, inline="always")
def _tanh(w):
    """tanh(w) for real w, and for complex w of large real part, where numpy's complex tanh
    overflows (cosh) to NaN: the complex step through a smooth sign at speed."""
    if w.real < 0:
        t = np.exp(2.0 * w)
        return (t - 1.0) / (t + 1.0)
    t = np.exp(-2.0 * w)
    return (1.0 - t) / (1.0 + t)


# -- what the value pass (`_eval`) and the tangent pass (`_tangent._eval_tangent`) compute
# alike: each returns the values of its block (and, where the tangent pass needs them, the
# local slopes), real or complex
@njit(cache=True, inline="always")
def _belt(x, p):
    """The belt on the full geometry (eqs. 4 and 6): ``R_p, R_s, phi, e`` (stretch), ``g5,
    g6`` (dL/dq5, dL/dq6), ``edot``, the belt element's force ``N`` (elastic + proportional
    damping) and its axial forces ``F_p_el, F_s_el`` (virtual work)."""
    tb = p[P_TB]
    sig = p[P_SIG]
    R_p = p[P_RMIN] + x[4] / tb
    R_s = p[P_RS0] - sig * x[5] / tb
    phi, L = law.belt_geometry(R_p, R_s, p[P_A])
    e = L - p[P_L0]
    g5 = (np.pi + 2.0 * phi) / tb
    g6 = -sig * (np.pi - 2.0 * phi) / tb
    edot = g5 * x[10] + g6 * x[11]
    N = p[P_KBELT] * (e + p[P_ALPHA] * edot)
    return R_p, R_s, phi, e, g5, g6, edot, N, N * g5, N * (np.pi - 2.0 * phi) / tb


@njit(cache=True, inline="always")
def _springs(x, p):
    """The actuation springs (sign conventions of `empact.linear.actuation`): deflections and
    their rates ``e_w, ed_w, e_c, ed_c, d_p, dd_p, d_s, dd_s`` and forces ``T_w, T_c, F_tp,
    F_ts``."""
    i_w = p[P_IW]
    i_c = p[P_IC]
    i_e = p[P_IE]
    s = p[P_S]
    alpha = p[P_ALPHA]
    e_w = x[0] / i_w - x[2] / i_e
    ed_w = x[6] / i_w - x[8] / i_e
    e_c = x[1] / i_c - x[3] / i_e
    ed_c = x[7] / i_c - x[9] / i_e
    d_p = s * x[2] + x[4]
    dd_p = s * x[8] + x[10]
    d_s = s * (x[3] - x[2]) + x[5]
    dd_s = s * (x[9] - x[8]) + x[11]
    return (e_w, ed_w, e_c, ed_c, d_p, dd_p, d_s, dd_s, p[P_KW] * (e_w + alpha * ed_w),
            p[P_KC] * (e_c + alpha * ed_c), p[P_KTP] * (d_p + alpha * dd_p),
            p[P_KTS] * (d_s + alpha * dd_s))


@njit(cache=True, inline="always")
def _dampers(x, p):
    """Shafai pulley damping with the current pulley speeds (shift law "shafai" only) and
    smooth Coulomb friction in the spindles (screw rotations q3 and q4 - q3): ``c_p, c_s``
    with the speeds' magnitudes ``|omega_p|, |omega_s|`` they divide by, ``Tf_sp, Tf_ss``
    with their tanh (the tangent pass's slopes; 0 / 1 where off)."""
    zero = 0.0 * x[0]
    c_p = c_s = Tf_sp = Tf_ss = th_sp = th_ss = zero
    ap = aps = 1.0 + zero
    if p[P_LAW] == LAW_SHAFAI and p[P_CSH] != 0.0:
        ap = _sabs(x[15])
        aps = _sabs(x[16])
        c_p = p[P_CSH] / ap
        c_s = p[P_CSH] / aps
    if p[P_TCSP] != 0.0:
        th_sp = np.tanh(x[8] / p[P_WC])
        Tf_sp = p[P_TCSP] * th_sp
    if p[P_TCSS] != 0.0:
        th_ss = np.tanh((x[9] - x[8]) / p[P_WC])
        Tf_ss = p[P_TCSS] * th_ss
    return c_p, c_s, ap, aps, Tf_sp, Tf_ss, th_sp, th_ss


@njit(cache=True, inline="always")
def _torque_ratio(x, p, ix, mu, mu_max, F_s_el, R_s):
    """``(tau, F_b, T_b, den)``: the torque ratio, with the locked belt from its elastic chain
    element (force F_b, torque T_b, ``tau = T_b cos(beta) / den``), else ``mu / mu_max``."""
    zero = 0.0 * mu
    if ix[0] >= 0:
        F_b = p[P_KBD] * x[ix[0]]
        T_b = R_s * F_b
        den = 2.0 * mu_max * F_s_el * R_s
        return T_b * p[P_COSB] / den, F_b, T_b, den
    return mu / mu_max, zero, zero, 1.0 + zero


@njit(cache=True, inline="always")
def _belt_torque(x, p, ix, dx, mu, F_s, F_b, T_b, R_p, R_s, r_g):
    """``(T_b, T_on_p, P_slip)``: the belt torque on the secondary, its reaction on the
    primary and the slip power; traction (eq. 1) with the secondary clamping force, or the
    locked belt's chain element (its stretch rate into `dx`)."""
    if ix[0] >= 0:
        dx[ix[0]] = R_p * x[15] - R_s * x[16]
        return T_b, -R_p * F_b, 0.0 * T_b
    T_b = 2.0 * mu * F_s * R_s / p[P_COSB]
    return T_b, -r_g * T_b, T_b * (r_g * x[15] - x[16])


@njit(cache=True, inline="always")
def _losses(x, p, F_s, T_pb, R_p, r_g):
    """The variator's losses beside the slip (`_belt_torque`), as torques on the pulley shafts:
    ``(T_lp, T_ls, T_clamp, T_load, T_dp, T_dss, T_map)`` [N m], the whole loss torque on the
    primary and on the secondary, and its parts (`T_pb`: the belt's torque on the primary,
    ``r_g T_b``; `F_s`: the secondary clamping force).

    * **A measured map** (``p[P_LTAB]``, `empact.variator.losses.LossMap`) replaces the three
      terms below: ``T_map = sg(omega_p) T_loss(r_g, omega_p, T_in, F_s)`` on the primary at
      its input torque ``T_in = T_pb + T_map`` (`empact.variator._loss_table.table_loss`,
      exact on the interpolant), nothing on the secondary.

    * **Clamping** (band and segment friction, band-band sliding, sheave deflection and
      misalignment: Akehurst, Vaughan, Parker & Simner, Proc. IMechE D 218 (2004) Parts 1-2;
      Micklem et al., Proc. IMechE D 210 (1996), the belt's torque loss):
      ``T_clamp = lambda_F F_s R_p sg(omega_p)`` on the primary, i.e. a sliding power
      ``lambda_F F_s v_b`` at the belt speed ``v_b = R_p omega_p`` (``lambda_F``: an
      effective friction coefficient times the sliding fraction of the belt speed).  At a
      given input torque and torque ratio ``F_s R_p = T_in cos(beta) / (2 tau mu_max)``, so
      its share of the input torque grows as the clamping reserve grows and where mu_max is
      small (towards overdrive).
    * **Load** (the torque-dependent part of the belt's torque loss, segment compression
      and tilting; Akehurst Part 1): ``T_load = k_T |T_pb| sg(omega_p)`` on the primary,
      ``|T| ~ T tanh(T / T_smooth)``.
    * **Drag** (spin loss: bearings, seals, oil churning; the no-load torque ``T_0(omega)``
      of Micklem et al. and of Narita & Priest, Proc. IMechE J 221 (2007)): ``c_v omega +
      c_q omega^2 sg(omega)`` on each pulley shaft at its own speed, so that the faster
      secondary of overdrive drags more.

    ``sg(omega) = tanh(omega / coulomb_omega)``, the kernel's smooth sign of a speed (as its
    Coulomb terms): each loss opposes its shaft's rotation and the Jacobian exists.  The
    variator's shaft powers are then ``P_var_in = (T_pb + T_lp) omega_p`` and ``P_var_out =
    (T_b - T_ls) omega_s``, and their difference is the sum of `VARIATOR_LOSSES`
    (identically, beside the locked belt's elastic power)."""
    wp, ws = x[15], x[16]
    sg_p = _tanh(wp / p[P_WC])
    if p[P_LTAB] != 0.0:
        T_map = table_loss(T_pb, np.log(r_g), wp, F_s, sg_p, p, int(p[P_LTAB]))
        zero = 0.0 * T_map
        return T_map, zero, zero, zero, zero, zero, T_map
    sg_s = _tanh(ws / p[P_WC])
    T_clamp = p[P_LF] * F_s * R_p * sg_p
    T_load = p[P_LT] * T_pb * _tanh(T_pb / p[P_LTS]) * sg_p
    T_dp = p[P_LV] * wp + p[P_LQ] * wp * wp * sg_p
    T_dss = p[P_LV] * ws + p[P_LQ] * ws * ws * sg_s
    return T_clamp + T_load + T_dp, T_dss, T_clamp, T_load, T_dp, T_dss, 0.0 * T_dss


@njit(cache=True, inline="always")
def _ratio_servo(x, u, p, ix, dx, R_p, R_s, phi, r_g, F_s_el, F_p_el):
    """``(T_mp, G, err)``: the primary servo torque, direct or by the ratio controller (the
    integral carries the holding torque; its rate into `dx`), with the ratio's gain ``G``
    per N m and the scaled error (zeros without the controller).  Shafai: PID on the shift
    coordinate of an inertia; creep laws: PI on the ratio rate the creep law gives."""
    if ix[3] < 0:
        zero = 0.0 * r_g
        return u[0], zero, zero
    if p[P_LAW] == LAW_SHAFAI:
        G = (-p[P_S] * p[P_IE] / (p[P_IW] * p[P_TB])) \
            * (R_s + R_p * (np.pi + 2.0 * phi) / (np.pi - 2.0 * phi)) / (R_s * R_s)
    else:
        w_eff = np.sqrt(x[15] * x[15] + p[P_W0] * p[P_W0])
        G = -w_eff * creep_coefficient(r_g, R_p, F_s_el, p) * p[P_IW] \
            / (p[P_IE] * p[P_S] * F_p_el)
    err = (u[0] - r_g) / G
    dx[ix[3]] = p[P_RKI] * err
    return x[ix[3]] + p[P_RKP] * err - p[P_RKD] * x[6], G, err


@njit(cache=True, inline="always")
def _drive_load(x, u, p, ix, dx):
    """``(T_d, T_l)``: drive and load torques, direct or by their speed loops (the integrals'
    rates into `dx`)."""
    if ix[1] >= 0:
        T_d = x[ix[1]] + p[P_DKP] * (u[2] - x[14])
        dx[ix[1]] = p[P_DKI] * (u[2] - x[14])
    else:
        T_d = u[2]
    if ix[2] >= 0:
        T_l = x[ix[2]] - p[P_LKP] * (u[3] - x[17])
        dx[ix[2]] = -p[P_LKI] * (u[3] - x[17])
    else:
        T_l = u[3]
        if p[P_VEH] != 0.0:  # the car: the road load and the final drive's loss besides
            T_road, T_fd, _, _ = _vehicle_load(x, p)
            T_l = T_l + T_road + T_fd
    return T_d, T_l


@njit(cache=True, inline="always")
def _vehicle_load(x, p):
    """``(T_road, T_fd, F_road, v)``: the vehicle driveline's load on the load shaft (the
    car reflected to the secondary's speed, ``omega_l = v i_fd / r_w``): the road load
    ``F_road = f0 sg + f1 v + f2 v^2 sg + m g sin(grade)`` [N] at the car's speed ``v =
    (r_w / i_fd) omega_l`` as the torque ``T_road = (r_w / i_fd) F_road``, and the final
    drive's loss ``T_fd = (1 - eta_fd) |T_ds| sg`` on the driveshaft torque ``T_ds``
    (``sg = tanh(omega_l / coulomb_omega)``, the kernel's smooth sign; ``|T| ~ T tanh(T /
    T_smooth)`` as the variator's load loss): so the wheels get ``eta_fd T_ds`` while the
    engine drives them (``1 / (2 - eta_fd)`` of the power back while they drive the engine).
    The rolling and aerodynamic terms oppose the motion, smoothly through standstill."""
    wl = x[17]
    v = p[P_VGEAR] * wl
    sg = _tanh(wl / p[P_WC])
    F_road = p[P_VF0] * sg + p[P_VF1] * v + p[P_VF2] * v * v * sg + p[P_VFG]
    T_ds = p[P_KDS] * x[13]
    T_fd = (1.0 - p[P_VETA]) * T_ds * _tanh(T_ds / p[P_LTS]) * sg
    return p[P_VGEAR] * F_road, T_fd, F_road, v


@njit(cache=True, inline="always")
def _vehicle_outputs(x, p, y):
    """The vehicle driveline's outputs into `y` (`VEHICLE_OUTPUTS`; zeros on the bench)."""
    if p[P_VEH] != 0.0:
        T_road, T_fd, F_road, v = _vehicle_load(x, p)
        y[Y_V] = v
        y[Y_FROAD] = F_road
        y[Y_PROAD] = T_road * x[17]
        y[Y_LFD] = T_fd * x[17]
    else:
        y[Y_V] = 0.0
        y[Y_FROAD] = 0.0
        y[Y_PROAD] = 0.0
        y[Y_LFD] = 0.0


@njit(cache=True, inline="always")
def _motion(x, p, dx, sp, dm, T_mp, T_ms, T_d, T_l, N, g5, g6, lam, dr5, dr6, T_on_p, T_b):
    """The equations of motion into ``dx[:18]``: actuation, then the driveline (rotating
    frame: twists and speeds); `sp` and `dm` are `_springs`' and `_dampers`' values.
    Returns the drive shaft torque T_ds."""
    T_w, T_c, F_tp, F_ts = sp[8], sp[9], sp[10], sp[11]
    c_p, c_s, Tf_sp, Tf_ss = dm[0], dm[1], dm[4], dm[5]
    s = p[P_S]
    w43 = x[9] - x[8]
    Q1 = T_mp - T_w / p[P_IW] - p[P_CMP] * x[6]
    Q2 = T_ms - T_c / p[P_IC] - p[P_CMS] * x[7]
    Q3 = T_w / p[P_IE] - s * F_tp + s * F_ts - p[P_CSP] * x[8] - Tf_sp + p[P_CSS] * w43 + Tf_ss
    Q4 = T_c / p[P_IE] - s * F_ts - p[P_CSS] * w43 - Tf_ss
    Q5 = -N * g5 - F_tp - c_p * x[10] - lam * dr5
    Q6 = -N * g6 - F_ts - c_s * x[11] - lam * dr6
    for i in range(6):
        dx[i] = x[6 + i]
    dx[6] = Q1 / p[P_JMP]
    dx[7] = Q2 / p[P_JMS]
    dx[8] = Q3 / p[P_JSP]
    dx[9] = Q4 / p[P_JSS]
    dx[10] = Q5 / p[P_MP]
    dx[11] = Q6 / p[P_MS]
    T_tc = p[P_KTC] * x[12]
    T_ds = p[P_KDS] * x[13]
    dx[12] = x[14] - x[15]
    dx[13] = x[16] - x[17]
    dx[14] = (T_d - T_tc) / p[P_JD]
    dx[15] = (T_tc + T_on_p) / p[P_JP]
    dx[16] = (T_b - T_ds) / p[P_JS]
    dx[17] = (T_ds - T_l) / p[P_JL]
    return T_ds


@njit(cache=True, inline="always")
def _outputs(x, p, ix, y, sp, dm, e, edot, P_slip, lam, rdot, dr5, r_g, nu, F_p, F_s, tau, kap,
             keq, T_b, mu, mu_max, R_p, R_s, phi, T_mp, T_ms, T_d, T_l, T_ds):
    """The outputs into `y` (`OUTPUTS`), with the stored energy, the input power, and the
    dissipated power and its terms (`DISSIPATION_TERMS`) but the losses of `_losses`, which
    `_loss_outputs` adds (`sp`, `dm`: `_springs`' and `_dampers`' values)."""
    e_w, ed_w, e_c, ed_c, d_p, dd_p, d_s, dd_s, _, _, F_tp, F_ts = sp
    c_p, c_s, _, _, Tf_sp, Tf_ss, _, _ = dm
    w1, w2, w3, w4, v5, v6 = x[6], x[7], x[8], x[9], x[10], x[11]
    tw_tc, tw_ds, wd, wp, ws, wl = x[12], x[13], x[14], x[15], x[16], x[17]
    w43 = w4 - w3
    E = 0.5 * (p[P_JMP] * w1 * w1 + p[P_JMS] * w2 * w2 + p[P_JSP] * w3 * w3
               + p[P_JSS] * w4 * w4 + p[P_MP] * v5 * v5 + p[P_MS] * v6 * v6
               + p[P_KW] * e_w * e_w + p[P_KC] * e_c * e_c + p[P_KBELT] * e * e
               + p[P_KTP] * d_p * d_p + p[P_KTS] * d_s * d_s
               + p[P_JD] * wd * wd + p[P_JP] * wp * wp + p[P_JS] * ws * ws + p[P_JL] * wl * wl
               + p[P_KTC] * tw_tc * tw_tc + p[P_KDS] * tw_ds * tw_ds)
    if ix[0] >= 0:
        E += 0.5 * p[P_KBD] * x[ix[0]] * x[ix[0]]
    y[Y_PIN] = T_mp * w1 + T_ms * w2 + T_d * wd - T_l * wl
    y[Y_LSLIP] = P_slip
    y[Y_DSERVO] = p[P_CMP] * w1 * w1 + p[P_CMS] * w2 * w2
    y[Y_DSPINDLE] = p[P_CSP] * w3 * w3 + p[P_CSS] * w43 * w43 + Tf_sp * w3 + Tf_ss * w43
    y[Y_DMAT] = p[P_ALPHA] * (p[P_KW] * ed_w * ed_w + p[P_KC] * ed_c * ed_c
                              + p[P_KBELT] * edot * edot + p[P_KTP] * dd_p * dd_p
                              + p[P_KTS] * dd_s * dd_s)
    y[Y_DSHEAVE] = c_p * v5 * v5 + c_s * v6 * v6
    y[Y_PDISS] = (P_slip + lam * rdot + y[Y_DSERVO] + y[Y_DSPINDLE] + y[Y_DMAT]
                  + y[Y_DSHEAVE])
    y[Y_EN] = E
    y[Y_RG] = r_g
    y[Y_NU] = nu
    y[Y_NUR] = 1.0 - ws / (p[P_RREF] * wp)
    y[Y_THMP] = x[0]
    y[Y_THMS] = x[1]
    y[Y_FP] = F_p
    y[Y_FS] = F_s
    y[Y_FPA] = -F_tp
    y[Y_FSA] = p[P_SIG] * F_ts
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
    y[Y_XP] = x[4]
    y[Y_XS] = x[5]
    y[Y_E] = e
    y[Y_TMP] = T_mp
    y[Y_TD] = T_d
    y[Y_TL] = T_l
    y[Y_TMS] = T_ms
    y[Y_TDS] = T_ds
    y[Y_MUMAX] = mu_max


@njit(cache=True, inline="always")
def _loss_outputs(x, y, T_pb, T_b, T_lp, T_ls, T_clamp, T_load, T_dp, T_dss, T_map):
    """The variator's losses of `_losses` and its shaft powers into `y`, their sum into
    ``P_diss`` (`T_pb`: the belt's torque on the primary, `T_b` on the secondary)."""
    wp, ws = x[15], x[16]
    y[Y_LCLAMP] = T_clamp * wp
    y[Y_LLOAD] = T_load * wp
    y[Y_LDRAG] = T_dp * wp + T_dss * ws
    y[Y_LMAP] = T_map * wp
    y[Y_PVIN] = (T_pb + T_lp) * wp
    y[Y_PVOUT] = (T_b - T_ls) * ws
    y[Y_PDISS] += y[Y_LCLAMP] + y[Y_LLOAD] + y[Y_LDRAG] + y[Y_LMAP]


@njit(cache=True, inline="always")
def _finish(x, u, p, ix, dx, y, belt, sp, dm, r_g, nu, mu, mu_max, tau, F_b, T_b, lam, kap, keq,
            dr5, dr6, rdot):
    """A pass from the creep force `lam` on: the clamping forces at the contacts (opening the
    sheaves: the belt element's and the creep's), the belt torque, the servo, drive and load
    torques, the variator's losses (`_losses`: the primary's load torque is ``r_g T_b`` and
    the loss torque, the secondary's the belt torque less its drag), the equations of motion
    into `dx` and the outputs into `y` (`belt`, `sp`, `dm`: `_belt`'s, `_springs`' and
    `_dampers`' values).  Returns ``(F_s, T_b, T_mp, G, err, T_d,
    T_l)`` for the tangent pass."""
    R_p, R_s, phi, e, g5, g6, edot, N, F_p_el, F_s_el = belt
    F_p = F_p_el + lam * dr5
    F_s = F_s_el - lam * r_g / (p[P_TB] * R_s)
    T_b, T_on_p, P_slip = _belt_torque(x, p, ix, dx, mu, F_s, F_b, T_b, R_p, R_s, r_g)
    T_lp, T_ls, T_clamp, T_load, T_dp, T_dss, T_map = _losses(x, p, F_s, -T_on_p, R_p, r_g)
    T_mp, G, err = _ratio_servo(x, u, p, ix, dx, R_p, R_s, phi, r_g, F_s_el, F_p_el)
    T_d, T_l = _drive_load(x, u, p, ix, dx)
    T_ds = _motion(x, p, dx, sp, dm, T_mp, u[1], T_d, T_l, N, g5, g6, lam, dr5, dr6,
                   T_on_p - T_lp, T_b - T_ls)
    _outputs(x, p, ix, y, sp, dm, e, edot, P_slip, lam, rdot, dr5, r_g, nu, F_p, F_s, tau, kap,
             keq, T_b, mu, mu_max, R_p, R_s, phi, T_mp, u[1], T_d, T_l, T_ds)
    _loss_outputs(x, y, -T_on_p, T_b, T_lp, T_ls, T_clamp, T_load, T_dp, T_dss, T_map)
    _vehicle_outputs(x, p, y)
    y[Y_TDSEC] = T_d * x[14] / x[16] if p[P_VEH] != 0.0 else 0.0 * T_d
    return F_s, T_b, T_mp, G, err, T_d, T_l


# -- the value pass ---------------------------------------------------------------------------
@njit(cache=True, error_model="numpy")
def _eval(x, u, p, ix, dx, y):
    """Fill ``dx`` (shape (n,)) and ``y`` (shape (NY,)) at state x and inputs u.

    The helpers above are inlined (numba IR, ``inline="always"``); numpy's error model (a
    zero divisor gives inf or NaN, which `stop_status` reports as a non-finite output,
    instead of raising) lets numba drop the reference counting of their array arguments on
    the raise paths, which would cost the common path ~25 %."""
    tb = p[P_TB]
    v5, v6, wp, ws = x[10], x[11], x[15], x[16]
    belt = _belt(x, p)
    R_p, R_s, phi, _, _, _, _, _, _, F_s_el = belt
    sp = _springs(x, p)
    dm = _dampers(x, p)

    # ratio, slip (eq. 2), traction and the torque ratio
    r_g = R_p / R_s
    nu = 1.0 - ws / (r_g * wp)
    mu = traction_mu(nu, r_g, p)
    lr = np.log(r_g)
    mu_max = mu_peak(r_g, lr, p)
    tau, F_b, T_b, _ = _torque_ratio(x, p, ix, mu, mu_max, F_s_el, R_s)

    # the belt's shift resistance (creep-mode shifting): a generalised force Lambda on the
    # ratio, on the sheaves through dr_g/dq5 = r_g / (tan(beta) R_p) and
    # dr_g/dq6 = sig r_g / (tan(beta) R_s) (virtual work)
    dr5 = r_g / (tb * R_p)
    dr6 = p[P_SIG] * r_g / (tb * R_s)
    rdot = dr5 * v5 + dr6 * v6
    if p[P_LAW] == LAW_SHAFAI:
        lam = 0.0 * r_g
        kap = law.kappa_geo(phi)
        keq = kap
    else:
        lam, kap, keq = creep_force(r_g, R_p, R_s, phi, F_s_el, tau, rdot, wp, p)
    _finish(x, u, p, ix, dx, y, belt, sp, dm, r_g, nu, mu, mu_max, tau, F_b, T_b, lam, kap, keq,
            dr5, dr6, rdot)


# -- the complex-step references ----------------------------------------------------------------
@njit(cache=True)
def _jacobian_cs(x, u, p, ix, A, B, C, D):
    """A = df/dx, B = df/du, C = dy/dx, D = dy/du by the complex step (h = 1e-30): the
    reference for `_tangent._jacobian` (tests, benchmarks), 4-7 real evaluations per
    column."""
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


@njit(cache=True)
def _state_jacobian_cs(x, u, p, ix, A, cols):
    """Columns `cols` of A = df/dx by the complex step (the reference for
    `_tangent._state_jacobian`)."""
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
    """out = (df/du) du by one complex step (the reference for `_tangent._input_direction`)."""
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


@njit(cache=True, inline="always")
def energy_rates(y, out):
    """`ENERGY_RATES` [W] from the outputs `y` into `out`: the drive's, the load's and the
    servos' shaft powers (``T_d omega_d``, ``T_l omega_l``, ``T_mp omega_mp``, ``T_ms
    omega_ms``), then the outputs `_RATE_OUTPUTS` name."""
    out[0] = y[Y_TD] * y[Y_WD]
    out[1] = y[Y_TL] * y[Y_WL]
    out[2] = y[Y_TMP] * y[Y_WMP]
    out[3] = y[Y_TMS] * y[Y_WMS]
    for i in range(_RATE_OUTPUTS.shape[0]):
        out[4 + i] = y[_RATE_OUTPUTS[i]]


# -- the integrators' stop conditions and constant columns -------------------------------------
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


def varying_columns(ix: np.ndarray, p: np.ndarray | None = None) -> np.ndarray:
    """The columns of df/dx that change during a run of a model with optional states `ix`
    (and parameter vector `p`): `VARYING_BASE_COLUMNS`, with the vehicle driveline the
    driveshaft twist and the load speed (the final drive's loss and the road load are
    nonlinear in them), and, with the locked belt, its stretch (its force acts at the
    current radius).  `tests/test_nonlinear.py` checks every other column is constant."""
    cols = list(VARYING_BASE_COLUMNS)
    if p is not None and p[P_VEH] != 0.0:
        cols = sorted(cols + [13, 17])
    cols += [int(ix[0])] if ix[0] >= 0 else []
    return np.array(cols, dtype=np.int64)
