"""Compiled loops over operating points (private; see `empact.nonlinear._kernel`): the
traction curve's values, peaks and rising-branch inverse, the creep law at rest, and the
right-hand side with its exact Jacobians (plant families, trims)."""
from __future__ import annotations

import numpy as np
from numba import njit

from ..variator._traction_table import table_peak
from ._kernel import (
    BASE_STATES,
    NX_BASE,
    NY,
    P_MTAB,
    _eval,
    _jacobian_cs,
    _losses,
    creep_force,
    mu_peak,
    traction_mu,
)
from ._tangent import _eval_tangent, _full_seeds, _split

__all__ = ["traction_many", "bisect_rising_many", "traction_peak_many", "mu_max_many",
           "creep_many", "linearize_batch", "linearize_batch_cs", "eval_batch", "losses_many"]

#: the pulley speeds' places in the state (the variator's losses read them)
_WP, _WS = BASE_STATES.index("omega_p"), BASE_STATES.index("omega_s")


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
    D(r_g), or the measured curves' peak (`_kernel.mu_peak`)."""
    for k in range(r_g.shape[0]):
        out[k] = mu_peak(r_g[k], np.log(r_g[k]), p)


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


@njit(cache=True)
def losses_many(T_pb, r_g, R_p, omega_p, omega_s, F_s, p, T_lp, T_ls):
    """The variator's loss torques beside the slip (`_kernel._losses`, the law the kernel
    applies: the analytic terms or the measured map) on the primary, ``T_lp[k]``, and on the
    secondary, ``T_ls[k]`` [N m], at the belt's torque `T_pb` on the primary [N m], ratio
    `r_g`, primary radius `R_p` [m], shaft speeds `omega_p`, `omega_s` [rad/s] and clamping
    force `F_s` [N] (1-D arrays)."""
    x = np.zeros(NX_BASE)
    for k in range(T_pb.shape[0]):
        x[_WP] = omega_p[k]
        x[_WS] = omega_s[k]
        lp, ls, _, _, _, _, _ = _losses(x, p, F_s[k], T_pb[k], R_p[k], r_g[k])
        T_lp[k] = lp
        T_ls[k] = ls
