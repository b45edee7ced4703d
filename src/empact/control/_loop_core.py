"""The sampled closed loop compiled: the loop law's compiled sample and the integrator in one
numba loop (private; `empact.control.law.LoopLaw.run_compiled`, called by
`empact.nonlinear.simulation`'s sampled loop).

At each sample ``k`` the loop does what the simulator's Python loop does, in the same order
and with the same compiled routines: the free inputs of the sample, the model's outputs
(`empact.nonlinear._kernel._eval`), the measurements, the law's sample
(`_law_core.step_core`), the held commands, and the integrator up to the next sample
(`empact.nonlinear._rodas._run` with the method's tableau).  So a run is bitwise the Python
loop's (`tests/test_loop.py`); what goes is the Python between the compiled calls (a third
of a load step's run, `bench/bench_compiled_loop.py`).

It is the one module outside `empact.nonlinear` that calls the kernel and an integrator
(`tests/test_layout.py`): the loop needs both the law (here, above the model) and the
integrator (below it), and the model must not import the control layer.
"""
from __future__ import annotations

from numba import njit

from ..nonlinear._kernel import _eval
from ..nonlinear._rodas import _run
from ._law_core import step_core

__all__ = ["run_samples"]


@njit(cache=True)
def run_samples(k0, k1, z, z_next, k_law, no_ref, P, T, S, cache, res, Q, Ac, Bc, Cc, Dc, L,
                u_out, x, u, U_free, t_grid, out_idx, cmd_idx, free_idx, commands, dx, y, meas,
                tA, tC, tc, td, tH, gam, q, samples, p, ix, sig_t, sig_v, sig_n, brk, rtol,
                atol, hmax, omega_min, max_steps, X, Y, cols, J, t, h, filled, n_steps, n_rej):
    """Samples ``k0 .. k1 - 1`` of the sampled loop (`z`, `z_next` the law's state and its
    spare, `k_law` the law's sample count; ``no_ref .. L`` and `u_out` as `step_core`; the
    rest as the simulator's loop and the integrator).  Returns ``(status, t, h, filled,
    n_steps, n_rej, k, done, law_error)``: the integrator's status after sample `k` (the last
    one run), the samples the law took (its state is in `z` after an even number, in
    `z_next` after an odd one), and 1 when the law found no belt geometry at sample `k`
    (before taking it)."""
    status = 0
    k = k0
    done = 0
    for k in range(k0, k1):
        for i in range(free_idx.shape[0]):
            u[free_idx[i]] = U_free[k, i]
        _eval(x, u, p, ix, dx, y)
        if k == 0:
            Y[0, :] = y
        for i in range(out_idx.shape[0]):
            meas[i] = y[out_idx[i]]
        if step_core(z, z_next, meas, k_law + done, no_ref, P, T, S, cache, res, Q, Ac, Bc,
                     Cc, Dc, L, u_out):
            return status, t, h, filled, n_steps, n_rej, k, done, 1
        z, z_next = z_next, z
        done += 1
        for i in range(cmd_idx.shape[0]):
            c = u_out[i]
            commands[k, i] = c
            u[cmd_idx[i]] = c
            sig_v[cmd_idx[i], 0] = c
        status, t, h, filled, ns, nr = _run(
            tA, tC, tc, td, tH, gam, q, x, t, t_grid[k + 1], h, samples, p, ix, sig_t, sig_v,
            sig_n, brk, rtol, atol, 1e-14, hmax, omega_min, max_steps - n_steps, X, Y, cols,
            J, k == 0)
        n_steps += ns
        n_rej += nr
        if status != 0:
            break
    return status, t, h, filled, n_steps, n_rej, k, done, 0
