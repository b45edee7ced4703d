"""Compiled higher-order stiff integrators for the nonlinear model (private; used by
`empact.nonlinear.simulation` as ``method="rodas5p"`` and ``method="rodas4"``).

Stiffly accurate, L-stable Rosenbrock-Wanner methods in the formulation of Hairer & Wanner
without matrix-vector products (Solving Ordinary Differential Equations II, 2nd ed.,
Springer 1996, sec. IV.7), with ``W = I - h gamma J`` factorised once per step::

    (I/(h gamma) - J) k_i = f(t + c_i h, x + sum_j A_ij k_j) + sum_j (C_ij / h) k_j
                            + h d_i df/dt,
    x_new = x + sum_j A_sj k_j + k_s         (stiffly accurate: the last stage's argument
    err   = k_s                               plus k_s; the embedded solution omits k_s)

in general ``x_new = x + sum_j b_j k_j`` and ``err = sum_j e_j k_j`` (rows 3 and 4 of H below:
for Rodas ``b`` the last row of A plus the last stage, ``e`` the last stage)

and the continuous extension (dense output) ::

    x(t + theta h) = (1 - theta) x + theta (x_new + (1 - theta) (K1 + theta (K2 + theta K3))),
    K_r = sum_j H_rj k_j.

Tableaus (A, C, c, d, H below; H's rows 0-2 the dense output, 3 the solution weights b, 4
the error weights e):

* ``rodas5p``: Rodas5P, order 5 with an embedded order-4 estimate, 8 stages, dense output of
  order 4 - G. Steinebach, "Construction of Rosenbrock-Wanner method Rodas5P and numerical
  benchmarks within the Julia Differential Equations package", BIT Numer. Math. 63, 27
  (2023); the coefficients as the author published them in OrdinaryDiffEq.jl
  (``OrdinaryDiffEqRosenbrock/src/rosenbrock_tableaus.jl``, ``Rodas5PTableau``).
* ``rodas4``: Rodas4, order 4(3), 6 stages, dense output of order 3 - Hairer & Wanner, op.
  cit., sec. VI.4, and their code RODAS (``rodas.f``, the coefficients of ``METH = 1`` with
  the dense-output coefficients ``H``), as tabulated in the same Julia file
  (``Rodas4Tableau``).
* ``ros2``: the modified Rosenbrock formula of Shampine & Reichelt (MATLAB's ``ode23s``),
  order 2 with an order-3 error estimate, L-stable, 3 stages, with its continuous extension -
  L. F. Shampine, M. W. Reichelt, "The MATLAB ODE Suite", SIAM J. Sci. Comput. 18, 1 (1997),
  written in the form above: with ``d = 1 / (2 + sqrt(2))`` and ``k_i`` its stages, this
  driver's ``k_1 = h d k_1``, ``k_2 = h d (k_2 - k_1)``, ``k_3 = h d (k_3 - e32 (k_2 - k_1) -
  2 k_1)`` (``e32 = 6 + sqrt(2)``, the formula's F0 and F1 eliminated through its stage
  equations), so ``gamma = d`` and the coefficients of `ROS2_A`, `ROS2_C`, `ROS2_d`, `ROS2_H`.

`tests/test_integrators.py` checks the orders (step ends and dense output) by fixed-step
convergence on a stiff linear problem with a known solution, running this module's own code
on that problem.

One driver (`_run`) for all three: piecewise-linear inputs found by running indices, no step
across a breakpoint, the explicit time derivative through the inputs (``df/dt = (df/du)
du/dt``, exact on a linear input piece), the Jacobian exact (forward mode,
`_tangent._state_jacobian`) at every step and in full only on the first call of a run, the stop
conditions checked at every accepted step, the status codes of `_rosenbrock.STATUS`. The state
at the end of a step is evaluated once (for the stop conditions) and reused as the first stage
of the next step while the inputs are continuous there (first same as last).

Step size: the elementary controller with the predictive (Gustafsson) correction of
``rodas.f``, exponent ``1/q`` (q = 5 for Rodas5P, 4 for Rodas4, 3 for ros2), factors in [0.2,
6], safety 0.9, no increase right after a rejection; a step shortened to land on a breakpoint
or the end of the call does not shrink the proposal for the next one.

Numba caches this module's compiled code with `_kernel._eval` inlined and re-checks only this
file's time stamp: `empact._compile.drop_stale_cache` drops the cache when a source of
`empact.nonlinear` changes.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from ._kernel import NY, _eval, energy_rates, stop_status
from ._rosenbrock import STATUS, _lu, _lu_solve, _segment_inputs, _u_at
from ._tangent import _input_direction, _state_jacobian

__all__ = ["integrate", "integrate_rodas4", "integrate_ros2", "METHODS", "STATUS"]

# -- Rodas5P (Steinebach 2023) ---------------------------------------------------------------
R5P_GAMMA = 0.21193756319429014
R5P_A = np.array([
    [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [3.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [2.849394379747939, 0.45842242204463923, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [-6.954028509809101, 2.489845061869568, -10.358996098473584, 0.0, 0.0, 0.0, 0.0, 0.0],
    [2.8029986275628964, 0.5072464736228206, -0.3988312541770524, -0.04721187230404641,
     0.0, 0.0, 0.0, 0.0],
    [-7.502846399306121, 2.561846144803919, -11.627539656261098, -0.18268767659942256,
     0.030198172008377946, 0.0, 0.0, 0.0],
    [-7.502846399306121, 2.561846144803919, -11.627539656261098, -0.18268767659942256,
     0.030198172008377946, 1.0, 0.0, 0.0],
    [-7.502846399306121, 2.561846144803919, -11.627539656261098, -0.18268767659942256,
     0.030198172008377946, 1.0, 1.0, 0.0]])
R5P_C = np.array([
    [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [-14.155112264123755, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [-17.97296035885952, -2.859693295451294, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [147.12150275711716, -1.41221402718213, 71.68940251302358, 0.0, 0.0, 0.0, 0.0, 0.0],
    [165.43517024871676, -0.4592823456491126, 42.90938336958603, -5.961986721573306,
     0.0, 0.0, 0.0, 0.0],
    [24.854864614690072, -3.0009227002832186, 47.4931110020768, 5.5814197821558125,
     -0.6610691825249471, 0.0, 0.0, 0.0],
    [30.91273214028599, -3.1208243349937974, 77.79954646070892, 34.28646028294783,
     -19.097331116725623, -28.087943162872662, 0.0, 0.0],
    [37.80277123390563, -3.2571969029072276, 112.26918849496327, 66.9347231244047,
     -40.06618937091002, -54.66780262877968, -9.48861652309627, 0.0]])
R5P_c = np.array([0.0, 0.6358126895828704, 0.4095798393397535, 0.9769306725060716,
                  0.4288403609558664, 1.0, 1.0, 1.0])
R5P_d = np.array([0.21193756319429014, -0.42387512638858027, -0.3384627126235924,
                  1.8046452872882734, 2.325825639765069, 0.0, 0.0, 0.0])
R5P_H = np.array([
    [25.948786856663858, -2.5579724845846235, 10.433815404888879, -2.3679251022685204,
     0.524948541321073, 1.1241088310450404, 0.4272876194431874, -0.17202221070155493],
    [-9.91568850695171, -0.9689944594115154, 3.0438037242978453, -24.495224566215796,
     20.176138334709044, 15.98066361424651, -6.789040303419874, -6.710236069923372],
    [11.419903575922262, 2.8879645146136994, 72.92137995996029, 80.12511834622643,
     -52.072871366152654, -59.78993625266729, -0.15582684282751913, 4.883087185713722],
    [*R5P_A[-1, :-1], 1.0],
    [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0]])

# -- Rodas4 (Hairer & Wanner 1996) -----------------------------------------------------------
R4_GAMMA = 0.25
R4_A = np.array([
    [0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [1.544, 0.0, 0.0, 0.0, 0.0, 0.0],
    [0.9466785280815826, 0.2557011698983284, 0.0, 0.0, 0.0, 0.0],
    [3.314825187068521, 2.896124015972201, 0.9986419139977817, 0.0, 0.0, 0.0],
    [1.221224509226641, 6.019134481288629, 12.53708332932087, -0.6878860361058950, 0.0, 0.0],
    [1.221224509226641, 6.019134481288629, 12.53708332932087, -0.6878860361058950, 1.0, 0.0]])
R4_C = np.array([
    [0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [-5.6688, 0.0, 0.0, 0.0, 0.0, 0.0],
    [-2.430093356833875, -0.2063599157091915, 0.0, 0.0, 0.0, 0.0],
    [-0.1073529058151375, -9.594562251023355, -20.47028614809616, 0.0, 0.0, 0.0],
    [7.496443313967647, -10.24680431464352, -33.99990352819905, 11.70890893206160, 0.0, 0.0],
    [8.083246795921522, -7.981132988064893, -31.52159432874371, 16.31930543123136,
     -6.058818238834054, 0.0]])
R4_c = np.array([0.0, 0.386, 0.21, 0.63, 1.0, 1.0])
R4_d = np.array([0.25, -0.1043, 0.1035, -0.0362, 0.0, 0.0])
R4_H = np.array([
    [10.12623508344586, -7.487995877610167, -34.80091861555747, -7.992771707568823,
     1.025137723295662, 0.0],
    [-0.6762803392801253, 6.087714651680015, 16.43084320892478, 24.76722511418386,
     -6.594389125716872, 0.0],
    [0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [*R4_A[-1, :-1], 1.0],
    [0.0, 0.0, 0.0, 0.0, 0.0, 1.0]])

# -- ros2 (Shampine & Reichelt 1997, ode23s) -------------------------------------------------
ROS2_GAMMA = 1.0 / (2.0 + np.sqrt(2.0))
_E32 = 6.0 + np.sqrt(2.0)
_G = ROS2_GAMMA
ROS2_A = np.array([[0.0, 0.0, 0.0], [0.5 / _G, 0.0, 0.0], [1.0 / _G, 1.0 / _G, 0.0]])
ROS2_C = np.array([[0.0, 0.0, 0.0], [-1.0 / _G, 0.0, 0.0], [-2.0 / _G, -_E32 / _G, 0.0]])
ROS2_c = np.array([0.0, 0.5, 1.0])
ROS2_d = np.array([_G, 0.0, -_G])
ROS2_H = np.array([[0.0, -1.0 / (_G * (1.0 - 2.0 * _G)), 0.0], [0.0, 0.0, 0.0],
                   [0.0, 0.0, 0.0], [1.0 / _G, 1.0 / _G, 0.0],
                   [1.0 / (6.0 * _G), (_E32 - 2.0) / (6.0 * _G), 1.0 / (6.0 * _G)]])


@njit(cache=True)
def _run(A, C, c, d, H, gam, q, x, t, t_end, h, samples, p, ix, sig_t, sig_v, sig_n, brk,
         rtol, atol, hmin, hmax, omega_min, max_steps, X, Y, cols, J, full, Q):
    """The stepper for one tableau (see the module docstring); arguments after `q` (the
    error's order) and the return value as `integrate`."""
    n = x.shape[0]
    m = sig_n.shape[0]
    s = A.shape[0]
    W = np.empty((n, n))
    piv = np.empty(n, dtype=np.int64)
    K = np.empty((s, n))
    D = np.zeros((3, n))
    E = np.empty(n)
    F0 = np.empty(n)
    Fs = np.empty(n)
    S = np.empty(n)
    Fn = np.empty(n)
    T = np.empty(n)
    xs = np.empty(n)
    xn = np.empty(n)
    y = np.empty(NY)
    yn = np.empty(NY)
    u = np.empty(m)
    u_end = np.empty(m)
    u0 = np.empty(m)
    slope = np.empty(m)
    tref = np.empty(m)
    hint = np.zeros(m, dtype=np.int64)
    all_cols = np.arange(n)
    nq = Q.shape[0]      # the energy rates' integrals (`integrate`), none when empty
    R0 = np.empty(nq)
    Rm = np.empty(nq)
    R1 = np.empty(nq)
    ym = np.empty(NY)
    ib = 0
    n_samp = samples.shape[0]
    js = 0
    while js < n_samp and samples[js] <= t:
        js += 1
    n_filled = js
    n_steps = 0
    n_rej = 0
    expo = 1.0 / q
    have_f0 = False      # F0 holds f(x, u_end) from the end of the last step
    rejected = False     # the last attempt was rejected: do not grow the step
    h_acc = 0.0          # Gustafsson's controller: last accepted step and its error
    err_acc = 1.0
    h_prop = h
    eps = 1e-12 * max(1.0, abs(t_end))
    while t_end - t > eps:
        if n_steps >= max_steps:
            return 6, t, h_prop, n_filled, n_steps, n_rej
        while ib < brk.shape[0] and brk[ib] - t <= eps:
            ib += 1
        t_stop = t_end
        if ib < brk.shape[0] and brk[ib] < t_stop:
            t_stop = brk[ib]
        h = min(h_prop, hmax)
        last = False
        if t + h >= t_stop - eps:
            h = t_stop - t
            last = True
        _segment_inputs(t + 0.5 * h, sig_t, sig_v, sig_n, u0, slope, tref, hint)
        _u_at(t, u0, slope, tref, u)
        if have_f0:
            for k in range(m):
                if abs(u[k] - u_end[k]) > 1e-13 * max(1.0, abs(u[k])):
                    have_f0 = False   # an input step at t: evaluate at the new value
        if not have_f0:
            _eval(x, u, p, ix, F0, y)
        if nq > 0:  # the rates at the step's start (on this input piece)
            energy_rates(yn if have_f0 else y, R0)
        _state_jacobian(x, u, p, ix, J, all_cols if full else cols)
        full = False
        _input_direction(x, u, slope, p, ix, T)
        accepted = False
        err = 0.0
        while not accepted:
            if h < hmin:
                return 5, t, h, n_filled, n_steps, n_rej
            hg = h * gam
            for i in range(n):
                for j in range(n):
                    W[i, j] = -hg * J[i, j]
                W[i, i] += 1.0
            if not _lu(W, piv):
                return 7, t, h, n_filled, n_steps, n_rej
            for st in range(s):
                # stage argument xs = x + sum_j A_ij k_j and the sum S = sum_j C_ij / h k_j
                for i in range(n):
                    xs[i] = x[i]
                    S[i] = 0.0
                for j in range(st):
                    a = A[st, j]
                    cj = C[st, j] / h
                    for i in range(n):
                        xs[i] += a * K[j, i]
                        S[i] += cj * K[j, i]
                if st == 0:
                    for i in range(n):
                        Fs[i] = F0[i]
                else:
                    _u_at(t + c[st] * h, u0, slope, tref, u)
                    _eval(xs, u, p, ix, Fs, y)
                # (I - h gamma J) k = h gamma (F + S + h d_i T)
                dh = h * d[st]
                for i in range(n):
                    K[st, i] = hg * (Fs[i] + S[i] + dh * T[i])
                _lu_solve(W, piv, K[st])
            # x_new = x + sum_j b_j k_j, the error sum_j e_j k_j (H's rows 3 and 4; zero
            # weights skipped, so a stiffly accurate method's x_s + k_s to the last bit)
            for i in range(n):
                xn[i] = x[i]
                E[i] = 0.0
            for j in range(s):
                bj = H[3, j]
                ej = H[4, j]
                if bj != 0.0:
                    for i in range(n):
                        xn[i] += bj * K[j, i]
                if ej != 0.0:
                    for i in range(n):
                        E[i] += ej * K[j, i]
            err = 0.0
            for i in range(n):
                sc = atol[i] + rtol[i] * max(abs(x[i]), abs(xn[i]))
                e = E[i] / sc
                err += e * e
            err = np.sqrt(err / n)
            if not np.isfinite(err):
                h *= 0.25
                last = False
                rejected = True
                n_rej += 1
                continue
            if err <= 1.0:
                accepted = True
            else:
                h *= max(0.2, 0.9 * err ** (-expo))
                last = False
                rejected = True
                n_rej += 1
        n_steps += 1
        t_new = t_stop if last else t + h
        # the end of the step: outputs for the stop conditions, first stage of the next step
        _u_at(t_new, u0, slope, tref, u_end)
        _eval(xn, u_end, p, ix, Fn, yn)
        # dense output at the samples inside (t, t_new] and at the step's midpoint
        if nq > 0 or (js < n_samp and samples[js] <= t_new * (1.0 + 1e-14)):
            for r in range(3):
                for i in range(n):
                    D[r, i] = 0.0
                for j in range(s):
                    hj = H[r, j]
                    if hj != 0.0:
                        for i in range(n):
                            D[r, i] += hj * K[j, i]
        if nq > 0:
            # the energy rates' integrals over the step: Simpson's rule on the step's ends
            # and its midpoint (the dense output), all on the step's input piece
            for i in range(n):
                xs[i] = 0.5 * x[i] + 0.5 * (xn[i] + 0.5 * (D[0, i] + 0.5 * (D[1, i]
                                                                            + 0.5 * D[2, i])))
            _u_at(t + 0.5 * h, u0, slope, tref, u)
            _eval(xs, u, p, ix, Fs, ym)
            energy_rates(ym, Rm)
            energy_rates(yn, R1)
            w6 = (t_new - t) / 6.0
            for i in range(nq):
                Q[i] += w6 * (R0[i] + 4.0 * Rm[i] + R1[i])
        while js < n_samp and samples[js] <= t_new * (1.0 + 1e-14):
            th = (samples[js] - t) / h
            th1 = 1.0 - th
            for i in range(n):
                xs[i] = th1 * x[i] + th * (xn[i] + th1 * (D[0, i] + th * (D[1, i]
                                                                           + th * D[2, i])))
                X[js, i] = xs[i]
            _u_at(samples[js], u0, slope, tref, u)
            _eval(xs, u, p, ix, Fs, Y[js])
            js += 1
            n_filled = js
        for i in range(n):
            x[i] = xn[i]
            F0[i] = Fn[i]
        have_f0 = True
        t = t_new
        status = stop_status(yn, p, omega_min)
        if status != 0:
            return status, t, h, n_filled, n_steps, n_rej
        # next step size: elementary controller with Gustafsson's predictive correction
        e = max(err, 1e-10)
        fac = 0.9 * e ** (-expo)
        if h_acc > 0.0:
            fac = min(fac, 0.9 * (h / h_acc) * (err_acc / (e * e)) ** expo)
        fac = min(6.0, max(0.2, fac))
        if rejected:
            fac = min(fac, 1.0)
        h_new = h * fac
        h_acc = h
        err_acc = max(1e-2, err)
        if last and h_new < h_prop:
            h_new = h_prop    # shortened to land on a breakpoint: keep the proposal
        h_prop = h_new
        rejected = False
    t = max(t, t_end)
    return 0, t, h_prop, n_filled, n_steps, n_rej


@njit(cache=True)
def integrate(x, t, t_end, h, samples, p, ix, sig_t, sig_v, sig_n, brk, rtol, atol,
              hmin, hmax, omega_min, max_steps, X, Y, cols, J, full, Q):
    """Rodas5P: integrate from `t` to `t_end` in place on `x`; fill `X`, `Y` at `samples` in
    (t, t_end].

    `cols` are the Jacobian columns that change (`_kernel.varying_columns`); `J` (n, n) holds
    the Jacobian between calls: with `full` every column is evaluated at the first step (the
    first call of a run), otherwise only `cols` (the others are constant over a run).

    `Q` (shape (len(`_kernel.ENERGY_RATES`),) or (0,)) accumulates, in place and across
    calls, the integrals of the energy rates (`_kernel.energy_rates`: the shaft powers and
    the dissipated powers by term) over the accepted steps: Simpson's rule on each step,
    its midpoint from the dense output, so to the integrator's own accuracy (no step spans an
    input breakpoint; each call starts on the inputs it is given, the right limit of a
    command held from there).  One evaluation more per step; none with an empty `Q`.

    Returns ``(status, t, h, n_filled, n_steps, n_rejected)`` (`_rosenbrock.STATUS`); on a
    stop, `x` holds the last accepted state at time `t`.
    """
    return _run(R5P_A, R5P_C, R5P_c, R5P_d, R5P_H, R5P_GAMMA, 5.0, x, t, t_end, h, samples,
                p, ix, sig_t, sig_v, sig_n, brk, rtol, atol, hmin, hmax, omega_min,
                max_steps, X, Y, cols, J, full, Q)


@njit(cache=True)
def integrate_rodas4(x, t, t_end, h, samples, p, ix, sig_t, sig_v, sig_n, brk, rtol, atol,
                     hmin, hmax, omega_min, max_steps, X, Y, cols, J, full, Q):
    """Rodas4: `integrate`'s signature, semantics and return value."""
    return _run(R4_A, R4_C, R4_c, R4_d, R4_H, R4_GAMMA, 4.0, x, t, t_end, h, samples,
                p, ix, sig_t, sig_v, sig_n, brk, rtol, atol, hmin, hmax, omega_min,
                max_steps, X, Y, cols, J, full, Q)


@njit(cache=True)
def integrate_ros2(x, t, t_end, h, samples, p, ix, sig_t, sig_v, sig_n, brk, rtol, atol,
                   hmin, hmax, omega_min, max_steps, X, Y, cols, J, full, Q):
    """ros2 (ode23s): `integrate`'s signature, semantics and return value."""
    return _run(ROS2_A, ROS2_C, ROS2_c, ROS2_d, ROS2_H, ROS2_GAMMA, 3.0, x, t, t_end, h,
                samples, p, ix, sig_t, sig_v, sig_n, brk, rtol, atol, hmin, hmax, omega_min,
                max_steps, X, Y, cols, J, full, Q)


#: the integrators of this module by `simulate`'s method name
METHODS = {"rodas5p": integrate, "rodas4": integrate_rodas4, "ros2": integrate_ros2}
#: each integrator's tableau as `_run` takes it (``A, C, c, d, H, gamma, q``): a compiled
#: loop around the integrator (`empact.control._loop_core`) calls `_run` with it
TABLEAUX = {integrate: (R5P_A, R5P_C, R5P_c, R5P_d, R5P_H, R5P_GAMMA, 5.0),
            integrate_rodas4: (R4_A, R4_C, R4_c, R4_d, R4_H, R4_GAMMA, 4.0),
            integrate_ros2: (ROS2_A, ROS2_C, ROS2_c, ROS2_d, ROS2_H, ROS2_GAMMA, 3.0)}
