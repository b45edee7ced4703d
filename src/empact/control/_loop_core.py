"""The sampled closed loop compiled: the loop law's compiled sample and the integrator in one
numba loop (private; `empact.control.law.LoopLaw.run_compiled`, called by
`empact.nonlinear.simulation`'s sampled loop).

At each sample ``k`` the loop does what the simulator's Python loop does, in the same order
and with the same compiled routines: the free inputs of the sample, the model's outputs
(`empact.nonlinear._kernel._eval`), the measurements, the law's sample
(`_law_core.sample`), the held commands, and the integrator up to the next sample
(`empact.nonlinear._rodas._run` with the method's tableau).  So a run is bitwise the Python
loop's (`tests/test_loop.py`); what goes is the Python between the compiled calls (a third
of a load step's run, `bench/bench_compiled_loop.py`).

It is the one module outside `empact.nonlinear` that calls an integrator, and with the law's
sample (`_law_core`, which calls the kernel's traction peak and creep law) the only ones that
call the kernel (`tests/test_layout.py`): the loop needs both the law (here, above the model)
and the integrator (below it), and the model must not import the control layer.
"""
from __future__ import annotations

from numba import njit

from ..nonlinear._kernel import _eval
from ..nonlinear._rodas import _run
from ._driver_core import driver_sample
from ._law_core import sample

__all__ = ["run_samples", "run_samples_driven"]


@njit(cache=True)
def run_samples(k0, k1, law, z, z_next, k_law, s, t, h, filled, n_steps, n_rej):
    """Samples ``k0 .. k1 - 1`` of the sampled loop: the law (`law` its `_law_core.Law`;
    `z`, `z_next` its state and the spare, `k_law` its sample count) and the simulator's
    `SampledLoop` `s`, from time `t`, step `h`, with `filled` output samples and `n_steps`,
    `n_rej` steps so far.  Returns ``(status, t, h, filled, n_steps, n_rej, k, done,
    law_error)``: the integrator's status after sample `k` (the last one run), the samples
    the law took (its state is in `z` after an even number, in `z_next` after an odd one),
    and 1 when the law found no belt geometry at sample `k` (before taking it)."""
    tA, tC, tc, td, tH, gam, q = s.tableau
    x, u, y, meas = s.x, s.u, s.y, s.meas
    status = 0
    k = k0
    done = 0
    for k in range(k0, k1):
        for i in range(s.free_idx.shape[0]):
            u[s.free_idx[i]] = s.U_free[k, i]
        _eval(x, u, s.p, s.ix, s.dx, y)
        if k == 0:
            s.Y[0, :] = y
        for i in range(s.out_idx.shape[0]):
            meas[i] = y[s.out_idx[i]]
        if sample(law, z, z_next, meas, k_law + done, False):
            return status, t, h, filled, n_steps, n_rej, k, done, 1
        z, z_next = z_next, z
        done += 1
        for i in range(s.cmd_idx.shape[0]):
            cmd = law.wk.u[i]
            s.commands[k, i] = cmd
            u[s.cmd_idx[i]] = cmd
            s.sig_v[s.cmd_idx[i], 0] = cmd
        status, t, h, filled, ns, nr = _run(
            tA, tC, tc, td, tH, gam, q, x, t, s.t_grid[k + 1], h, s.samples, s.p, s.ix,
            s.sig_t, s.sig_v, s.sig_n, s.brk, s.rtol, s.atol, 1e-14, s.hmax, s.omega_min,
            s.max_steps - n_steps, s.X, s.Y, s.cols, s.J, k == 0, s.Q)
        n_steps += ns
        n_rej += nr
        if status != 0:
            break
    return status, t, h, filled, n_steps, n_rej, k, done, 0


@njit(cache=True)
def run_samples_driven(k0, k1, law, z, z_next, k_law, drv_c, drv_tab, drv_z, s, t, h,
                       filled, n_steps, n_rej):
    """`run_samples` with the car's driver (`_driver_core.driver_sample`, constants
    `drv_c`, table `drv_tab`, state `drv_z`) commanding the engine's torque and the brakes
    (``law.wk.u[2]``, ``law.wk.u[3]``: the law's commands are ``T_mp, T_ms, T_d, T_l``) at
    each sample after the law's own: the same order and routines otherwise."""
    tA, tC, tc, td, tH, gam, q = s.tableau
    x, u, y, meas = s.x, s.u, s.y, s.meas
    status = 0
    k = k0
    done = 0
    for k in range(k0, k1):
        for i in range(s.free_idx.shape[0]):
            u[s.free_idx[i]] = s.U_free[k, i]
        _eval(x, u, s.p, s.ix, s.dx, y)
        if k == 0:
            s.Y[0, :] = y
        for i in range(s.out_idx.shape[0]):
            meas[i] = y[s.out_idx[i]]
        if sample(law, z, z_next, meas, k_law + done, False):
            return status, t, h, filled, n_steps, n_rej, k, done, 1
        z, z_next = z_next, z
        done += 1
        driver_sample(drv_c, drv_tab, drv_z, y, k_law + done - 1, law.wk.u[2:])
        for i in range(s.cmd_idx.shape[0]):
            cmd = law.wk.u[i]
            s.commands[k, i] = cmd
            u[s.cmd_idx[i]] = cmd
            s.sig_v[s.cmd_idx[i], 0] = cmd
        status, t, h, filled, ns, nr = _run(
            tA, tC, tc, td, tH, gam, q, x, t, s.t_grid[k + 1], h, s.samples, s.p, s.ix,
            s.sig_t, s.sig_v, s.sig_n, s.brk, s.rtol, s.atol, 1e-14, s.hmax, s.omega_min,
            s.max_steps - n_steps, s.X, s.Y, s.cols, s.J, k == 0, s.Q)
        n_steps += ns
        n_rej += nr
        if status != 0:
            break
    return status, t, h, filled, n_steps, n_rej, k, done, 0
