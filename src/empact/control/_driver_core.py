"""The driver model's sample, compiled (private; `empact.control.driver`).

`driver_sample` is one sample of the driver of `empact.control.driver.Driver`: a PI on the
car's speed with the feedforward of the trace's acceleration and road load, the wheels' force
demand split into the engine's torque (limited by its full-load curve) and the friction
brakes.  It reads the car's speed, the engine's speed and the ratio from the model's outputs
(`empact.nonlinear._kernel`'s names) and runs inside the compiled closed loop
(`empact.control._loop_core.run_samples_driven`): no Python per sample.

Constants (`CONSTANTS`, a float64 array ``c``) and the table ``tab`` (``n_k`` rows of the
reference speed [m/s] and acceleration [m/s^2] at the loop's samples, the last held) are
built by `empact.control.driver.Driver.pack`; the state ``z`` is the speed error's integral
[m] and the engine's torque [N m] (its demand through a first-order lag).
"""
from __future__ import annotations

from numba import njit

from ..nonlinear._kernel import Y_RG, Y_V, Y_WD

#: the constants' names, in their order in ``c``
CONSTANTS = ("m_eff", "f0", "f1", "f2", "F_grade", "gear", "eta_fd", "kp", "ki", "dt",
             "T_peak", "omega_T", "c_full", "T_coast", "J_s", "J_p", "lag")
(C_M, C_F0, C_F1, C_F2, C_FG, C_GEAR, C_ETA, C_KP, C_KI, C_DT, C_TPK, C_WT, C_CF,
 C_TCOAST, C_JS, C_JP, C_LAG) = range(len(CONSTANTS))


@njit(cache=True)
def driver_sample(c, tab, z, y, k, out):
    """Sample `k` of the driver (constants `c`, table `tab`, state ``z``: the speed error's
    integral, the engine's torque) at the model's outputs `y`: the engine's torque into
    ``out[0]`` [N m] and the brakes' torque at the load shaft into ``out[1]`` [N m]; the
    state advanced by one period.

    The wheels' force demand ``F = m_eff a* + F_road(v*) + k_p (v* - v) + k_i int (v* - v)``
    [N], ``m_eff`` the car's (``m_eff`` of `c`: mass and rotating parts) with the secondary
    pulley and the engine's side reflected at the measured ratio, ``(J_s + J_p / r_g^2) /
    (r_w / i_fd)^2``; the engine delivers ``F (r_w / i_fd) r_g / eta_fd`` where ``F > 0``,
    at most its full-load torque at its speed (the integral then stops growing), else
    ``T_coast``; the brakes take ``-F (r_w / i_fd)`` where ``F < 0``.  The engine's torque
    follows its demand through a first-order lag (``lag`` the share of the difference closed
    per sample, ``1 - exp(-dt / tau_engine)``: the manifold's filling), itself at most the
    full-load torque at the current speed."""
    n_last = tab.shape[0] - 1
    kk = k if k < n_last else n_last
    v_ref = tab[kk, 0]
    a_ref = tab[kk, 1]
    v = y[Y_V]
    e = v_ref - v
    gear = c[C_GEAR]
    r = y[Y_RG]
    m_eff = c[C_M] + (c[C_JS] + c[C_JP] / (r * r)) / (gear * gear)
    road = c[C_F0] + c[C_F1] * v_ref + c[C_F2] * v_ref * v_ref + c[C_FG]
    F = m_eff * a_ref + road + c[C_KP] * e + c[C_KI] * z[0]
    integrate = True
    x = y[Y_WD] / c[C_WT] - 1.0
    T_full = c[C_TPK] * (1.0 - c[C_CF] * x * x)
    if F > 0.0:
        T_e = F * gear * r / c[C_ETA]
        if T_e > T_full:
            T_e = T_full
            if e > 0.0:
                integrate = False
        brake = 0.0
    else:
        T_e = c[C_TCOAST]
        brake = -F * gear
    if integrate:
        z[0] = z[0] + e * c[C_DT]
    z[1] = z[1] + c[C_LAG] * (T_e - z[1])
    if z[1] > T_full:  # the lagged torque too, where the speed moved the curve
        z[1] = T_full
    out[0] = z[1]
    out[1] = brake
