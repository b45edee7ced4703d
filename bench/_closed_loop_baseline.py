"""The closed-loop runner of empact 0.1 (before issue 19), kept only as the baseline of
``bench_closed_loop.py``: a second simulator with its own Python-level input interpolation
(`_pl` at every controller step) and the integrator called with a fresh full Jacobian at
every sample.  Numerically it is the same loop as today's `empact.nonlinear.simulation` with
a sampled controller (the benchmark checks the outputs are bitwise equal from the same
initial point); only the bookkeeping differs.  Not part of the package.

Self-contained since the loop law was rewritten (issue 21: sensors, feedforwards, limits,
`empact.control.law`): the 0.1 law this runner needs (`LoopLaw`, `_pl`) is frozen here as
``empact/control/closed_loop.py`` had it at commit 84d399c; the benchmark hands the same
frozen law to today's simulator, so both routes run one law and differ only in the loop."""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from empact.errors import ParameterError
from empact.nonlinear import _kernel as K
from empact.nonlinear._rodas import integrate_ros2 as integrate
from empact.nonlinear.simulation import scenario_signals, state_tolerances
from empact.variator.geometry import radii

if TYPE_CHECKING:
    from empact.control.controller import Controller
    from empact.nonlinear.equilibrium import TrimResult
    from empact.nonlinear.model import EmpactModel
    from empact.nonlinear.scenario import Scenario


# -- frozen from empact/control/closed_loop.py at 84d399c (the 0.1 law) -----------------------
def _pl(arr: NDArray, t: NDArray) -> NDArray:
    """A piecewise-linear signal ``[[t, v], ...]`` at times `t` (vectorised): right-continuous
    (a repeated time is a step), held before its first and after its last point."""
    ts, vs = arr[:, 0], arr[:, 1]
    n = len(ts)
    tt = np.asarray(t, float)
    i = np.clip(np.searchsorted(ts, tt, side="right") - 1, 0, max(n - 2, 0))
    j = np.minimum(i + 1, n - 1)
    span = ts[j] - ts[i]
    frac = np.divide(tt - ts[i], span, out=np.ones_like(tt), where=span > 0)
    return np.where(tt < ts[0], vs[0], np.where(tt >= ts[-1], vs[-1],
                                                 vs[i] + (vs[j] - vs[i]) * frac))


class LoopLaw:
    """The closed-loop law of a scenario, with the step interface of
    `empact.nonlinear.simulation.SampledController`: at each sample the discrete controller
    acts on the tracking errors, the servo torques are the trimmed holding torques plus its
    output, with the clamping feedforward or the safety-factor strategy (module notes).

    Parameters
    ----------
    controller : Controller
        Continuous (discretised here by Tustin at ``scenario.controller.rate``) or discrete at
        that rate.
    scenario : Scenario
        With a ``[controller]`` table.
    model : EmpactModel
    op : TrimResult
        The trimmed initial point (the holding torques, the default references).
    """

    commands = ("T_mp", "T_ms")

    def __init__(self, controller: Controller, scenario: Scenario, model: EmpactModel,
                 op: TrimResult) -> None:
        spec = scenario.controller
        if spec is None:
            raise ParameterError(f"scenario {scenario.name!r} has no [controller] table")
        if controller.outputs != ("T_mp", "T_ms"):
            raise ParameterError(f"controller outputs {controller.outputs}: must drive T_mp, "
                                 "T_ms")
        self.dt = 1.0 / spec.rate
        cd = controller.discretize(self.dt) if not controller.dt else controller
        if abs(cd.dt - self.dt) > 1e-12:
            raise ParameterError(f"controller sample time {cd.dt:g} s differs from the "
                                 f"scenario's controller rate {spec.rate:g} Hz")
        self.controller = cd
        self.spec = spec
        base = [m[3:] if m.startswith("ln_") else m for m in cd.measured]
        for m in base:
            if m not in ("r_g", "nu", "nu_r"):
                raise ParameterError(f"the controller measures {m!r}: the loop tracks r_g, "
                                     "nu or nu_r")
        self.logs = np.array([m.startswith("ln_") for m in cd.measured])
        default = {"r_g": op.r_g, "nu": op.nu, "nu_r": op.nu}
        self.references = {m: scenario.references.get(m, np.array([[0.0, default[m]]]))
                           for m in base}
        n_k = int(round(scenario.duration / self.dt))
        t_k = np.minimum(np.arange(n_k + 1) * self.dt, scenario.duration)
        self._refs = np.column_stack([_pl(self.references[m], t_k) for m in base])
        self._n_e = len(base)
        extra = ["T_ds", "R_s"]
        if "T_l" in model.inputs:
            extra.append("T_l")
        self.measured = tuple(base) + tuple(extra)
        a, v = model.params.actuation, model.params.variator
        self._tpf = a.i_e * a.s * model.constants.sheave_sense / a.i_c  # T_ms per F_s
        self._cosb = float(np.cos(v.beta))
        self._L, self._a = v.L_belt, v.a
        slip_ref = next((self.references[m][0, 1] for m in self.references
                         if m.startswith("nu")), op.nu)
        self._mu_ref = float(model.traction(slip_ref, op.r_g))
        t = model.params.traction
        self._mu_design = min(t.D_low, t.D_med, t.D_od)
        self._u0 = op.u[:2].copy()
        self._T_l0 = op.T_l
        self._has_load = "T_l" in model.inputs
        self._safety = spec.clamping == "safety-factor"
        self.reset()

    def reset(self) -> None:
        """Back to the first sample (controller state zero)."""
        self._xc = np.zeros(self.controller.n)
        self._k = 0

    def step(self, t: float, measured: NDArray[np.float64]) -> NDArray[np.float64]:
        """Servo torques ``[T_mp, T_ms]`` [N m] over ``[t, t + dt)``."""
        c = self.controller
        ne = self._n_e
        ym = measured[:ne]
        rv = self._refs[min(self._k, len(self._refs) - 1)]
        self._k += 1
        e = np.where(self.logs, np.log(np.maximum(rv, 1e-6)) - np.log(np.maximum(ym, 1e-6)),
                     rv - ym)
        if self._safety:
            e[1:] = 0.0  # the slip loop is replaced by the open-loop clamping strategy
        du = c.C @ self._xc + c.D @ e
        self._xc = c.A @ self._xc + c.B @ e
        T_mp = self._u0[0] + du[0]
        T_ds, R_s = measured[ne], measured[ne + 1]
        T_l = measured[ne + 2] if self._has_load else self._T_l0
        if self._safety:
            R_s0 = float(radii(max(ym[0], 1e-3), self._L, self._a)[1])
            F_set = self.spec.safety_factor * abs(T_l) * self._cosb / (2 * self._mu_design
                                                                         * R_s0)
            T_ms = self._tpf * F_set
        else:
            T_ms = self._u0[1] + du[1]
            if self.spec.feedforward:  # from the measured driveshaft torque
                T_ms += self._tpf * (T_ds - self._T_l0) * self._cosb / (2 * self._mu_ref
                                                                          * R_s)
        return np.array([T_mp, T_ms])



# -- the 0.1 runner ---------------------------------------------------------------------------


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
    kmax = max([2] + [len(v) for v in scenario_signals(scenario, model, op).values()])
    sig_t, sig_v = np.zeros((4, kmax)), np.zeros((4, kmax))
    sig_n = np.ones(4, dtype=np.int64)
    brk = [scenario.duration]
    # today's scenario files give a load step as `load_step` (0.1: a T_l signal): the inputs
    # as the simulator reads them
    signals = scenario_signals(scenario, model, op)
    for j, name in enumerate(model.inputs):
        if name in signals:
            arr = np.asarray(signals[name], float)
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
