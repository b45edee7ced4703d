"""The closed-loop runner of empact 0.1 (before issue 19), kept only as the baseline of
``bench_closed_loop.py``: a second simulator with its own Python-level input interpolation
(`_pl` at every controller step) and the integrator called with a fresh full Jacobian at
every sample.  Numerically it is the same loop as today's `empact.nonlinear.simulation` with
a sampled controller (the benchmark checks the outputs are bitwise equal from the same
initial point); only the bookkeeping differs.  Not part of the package."""
from __future__ import annotations

import numpy as np

from empact.control.closed_loop import LoopLaw, _pl
from empact.nonlinear import _kernel as K
from empact.nonlinear._rosenbrock import integrate
from empact.nonlinear.simulation import state_tolerances
from empact.variator.geometry import radii


def run_closed_loop_v01(scenario, model, op, controller):
    """The 0.1 loop (`empact.control.closed_loop.run_closed_loop` of commit 084ba6a), with
    the kernel's names where 0.1 spelled indices; returns ``(t, X, Y, U)``."""
    law = LoopLaw(controller, scenario, model, op)  # only for the discretised controller
    cd = law.controller
    spec = scenario.controller
    params = model.params
    dt = 1.0 / spec.rate
    measured_idx = [model.outputs.index(m[3:] if m.startswith("ln_") else m)
                    for m in cd.measured]
    logs = np.array([m.startswith("ln_") for m in cd.measured])
    refs = law.references
    n_steps = int(round(scenario.duration / dt))
    n_t = int(np.floor(scenario.duration * scenario.sample_rate + 1e-9)) + 1
    samples = np.arange(n_t) / scenario.sample_rate
    ny = len(model.outputs)
    X = np.full((n_t, model.n), np.nan)
    Y = np.full((n_t, ny), np.nan)
    U = np.full((n_t, 4), np.nan)
    x = op.x.copy()
    X[0] = x
    y = np.empty(ny)
    dxb = np.empty(model.n)
    K._eval(x, op.u, model.p, model.ix, dxb, y)
    Y[0] = y
    rel, atol = state_tolerances(model, scenario.rtol)
    cols = K.varying_columns(model.ix)
    J = np.empty((model.n, model.n))
    kmax = max([2] + [len(v) for v in scenario.inputs.values()])
    sig_t, sig_v = np.zeros((4, kmax)), np.zeros((4, kmax))
    sig_n = np.ones(4, dtype=np.int64)
    brk = [scenario.duration]
    for j, name in enumerate(model.inputs):
        if name in scenario.inputs:
            arr = scenario.inputs[name]
            sig_n[j] = len(arr)
            sig_t[j, :len(arr)], sig_v[j, :len(arr)] = arr[:, 0], arr[:, 1]
            brk.extend(arr[:, 0].tolist())
        else:
            sig_v[j, 0] = op.u[j]
    brk_arr = np.unique(np.array([b for b in brk if 0 < b <= scenario.duration]))

    def other(j, tq):
        return _pl(np.column_stack([sig_t[j, :sig_n[j]], sig_v[j, :sig_n[j]]]),
                   np.asarray(tq, float))

    a, v = params.actuation, params.variator
    torque_per_force = a.i_e * a.s * model.constants.sheave_sense / a.i_c
    cosb = np.cos(v.beta)
    slip_ref = next((refs[m][0, 1] for m in refs if m.startswith("nu")), op.nu)
    mu_ref = float(model.traction(slip_ref, op.r_g))
    mu_design = min(params.traction.D_low, params.traction.D_med, params.traction.D_od)
    j_load = model.inputs.index("T_l") if "T_l" in model.inputs else None
    i_rg, i_rs = model.output_index("r_g"), model.output_index("R_s")
    i_ds = model.state_index("twist_ds")
    xc = np.zeros(cd.n)
    t, h = 0.0, 1e-5
    filled = 1
    for k in range(n_steps):
        t_k = k * dt
        ym = y[measured_idx]
        rv = np.array([float(_pl(refs[m], np.array(t_k))) for m in refs])
        e = np.where(logs, np.log(np.maximum(rv, 1e-6)) - np.log(np.maximum(ym, 1e-6)),
                     rv - ym)
        if spec.clamping == "safety-factor":
            e[1:] = 0.0
        du = cd.C @ xc + cd.D @ e
        xc = cd.A @ xc + cd.B @ e
        T_mp = op.u[0] + du[0]
        T_l = float(other(j_load, t_k)) if j_load is not None else op.T_l
        if spec.clamping == "safety-factor":
            R_s = float(radii(max(y[i_rg], 1e-3), v.L_belt, v.a)[1])
            F_set = spec.safety_factor * abs(T_l) * cosb / (2 * mu_design * R_s)
            T_ms = torque_per_force * F_set
        else:
            T_ms = op.u[1] + du[1]
            if spec.feedforward:
                T_ds = params.driveline.k_ds * x[i_ds]
                T_ms += torque_per_force * (T_ds - op.T_l) * cosb / (2 * mu_ref * y[i_rs])
        sig_v[0, 0], sig_v[1, 0] = T_mp, T_ms
        sig_n[0] = sig_n[1] = 1
        t_end = min((k + 1) * dt, scenario.duration)
        status, t, h, filled_new, ns, _ = integrate(
            x, t, t_end, h, samples, model.p, model.ix, sig_t, sig_v, sig_n, brk_arr, rel,
            atol, 1e-14, scenario.max_step, 1.0, 10_000_000, X, Y, cols, J, True)
        U[filled:filled_new, :2] = T_mp, T_ms
        for j in (2, 3):
            U[filled:filled_new, j] = other(j, samples[filled:filled_new])
        filled = filled_new
        if status != 0:
            break
        K._eval(x, np.array([T_mp, T_ms, float(other(2, t)), float(other(3, t))]), model.p,
                model.ix, dxb, y)
    U[0] = op.u
    keep = slice(0, max(filled, 1))
    return samples[keep], X[keep], Y[keep], U[keep]
