"""The kernel's parameters by name, typed (private).

`KernelConstants` is `empact.nonlinear._kernel.constants`' answer: one float per entry of
`empact.nonlinear._kernel.PARAMETER_NAMES` up to the traction laws' part, in its order, and
that part (generated from the laws' registry) as one dict (the kernel asserts that the fields
equal the names, so a parameter added there must be added here).  Written out rather than
generated so that a type checker knows the fields.
"""
from __future__ import annotations

from typing import NamedTuple

__all__ = ["KernelConstants"]


class KernelConstants(NamedTuple):
    """The kernel's parameters read back by name (`constants`): the fields of
    `PARAMETER_NAMES`, in its order, each a float (SI; the table offsets as floats), and the
    traction laws' part as a dict."""

    a: float
    tan_beta: float
    cos_beta: float
    R_min: float
    R_max: float
    L_belt: float
    J_mp: float
    J_ms: float
    J_sp: float
    J_ss: float
    m_p: float
    m_s: float
    i_w: float
    i_c: float
    i_e: float
    s: float
    k_w: float
    k_c: float
    k_belt: float
    k_tp: float
    k_ts: float
    alpha: float
    c_mp: float
    c_ms: float
    c_sp: float
    c_ss: float
    c_shafai: float
    coulomb_sp: float
    coulomb_ss: float
    coulomb_omega: float
    J_d: float
    J_p: float
    J_s: float
    J_l: float
    k_tc: float
    k_ds: float
    k_belt_driveline: float
    drive_kp: float
    drive_ki: float
    load_kp: float
    load_ki: float
    ratio_kp: float
    ratio_kd: float
    ratio_ki: float
    sheave_sense: float
    R_s0: float
    shift_law: float
    D_ref: float
    F_ref: float
    k_D: float
    a1: float
    a2: float
    gain: float
    omega_0: float
    xi_sat: float
    g_beta: float
    kappa_p0: float
    kappa_b0: float
    kappa_b1: float
    r_ref: float
    thrust_table: float
    creep_table: float
    traction_table: float
    loss_lambda_F: float
    loss_k_T: float
    loss_c_v: float
    loss_c_q: float
    loss_T_smooth: float
    loss_table: float
    vehicle: float
    vehicle_gear: float
    road_f0: float
    road_f1: float
    road_f2: float
    road_grade_force: float
    eta_fd: float
    #: the traction laws' part by name (generated from their registry: the law's index
    #: ``traction_law``, the knots' ``ln_r_*``, the coefficients ``<c>_low`` ...)
    traction: dict[str, float]
