"""A stiff linear problem with a known solution on the Rosenbrock driver's own code (private).

``x' = A x + B u(t)``, ``u = u0 + u1 t``: a damped oscillator (eigenvalues -1 +- 9.95i)
drives a stiff follower (-1e4) that drives a very stiff one (-1e7, also fed by u); the
solution is the matrix exponential of the augmented matrix.  `stepper` compiles
`empact.nonlinear._rodas`'s ``_run`` once more with this problem's right-hand side,
Jacobian, input direction and stop test in place of the kernel's: the integrators' order
and dense-output tests (``tests/test_integrators.py``) run on it.  It lives in the package so
that `empact._compile.compile_all` compiles it with the rest (a first test run is then as
fast as the second).
"""
from __future__ import annotations

import hashlib
import types
from typing import Callable

import numpy as np
import scipy.linalg as sl
from numba import njit

from .nonlinear import _rodas

__all__ = ["A_LIN", "B_LIN", "U0", "U1", "T_END", "TABLEAU", "stepper"]


@njit(cache=True)
def _lin_eval(x, u, p, ix, dx, y):
    n = x.shape[0]
    for i in range(n):
        acc = 0.0
        for j in range(n):
            acc += p[i * n + j] * x[j]
        for k in range(u.shape[0]):
            acc += p[n * n + i * u.shape[0] + k] * u[k]
        dx[i] = acc
    for i in range(y.shape[0]):
        y[i] = x[i]


@njit(cache=True)
def _lin_jacobian(x, u, p, ix, J, cols):
    n = x.shape[0]
    for j in cols:
        for i in range(n):
            J[i, j] = p[i * n + j]


@njit(cache=True)
def _lin_direction(x, u, du, p, ix, out):
    n = x.shape[0]
    for i in range(n):
        acc = 0.0
        for k in range(u.shape[0]):
            acc += p[n * n + i * u.shape[0] + k] * du[k]
        out[i] = acc


@njit(cache=True)
def _lin_stop(y, p, omega_min):
    for i in range(y.shape[0]):
        if not np.isfinite(y[i]):
            return 4
    return 0


W_N, ZETA, LAM1, LAM2 = 10.0, 0.1, -1e4, -1e7
#: the problem's matrices (4 states, 1 input)
A_LIN = np.array([[0.0, 1.0, 0.0, 0.0], [-W_N ** 2, -2 * ZETA * W_N, 0.0, 0.0],
                  [-LAM1, 0.0, LAM1, 0.0], [0.0, 0.0, -LAM2, LAM2]])
B_LIN = np.array([[0.0], [1.0], [0.0], [-LAM2]])
#: the input ``u = U0 + U1 t`` and the end of the runs [s]
U0, U1, T_END = 1.0, 20.0, 1.0
#: the tableaus of `_rodas` by method name: (A, C, c, d, H, gamma, order + 1)
TABLEAU = {"rodas5p": (_rodas.R5P_A, _rodas.R5P_C, _rodas.R5P_c, _rodas.R5P_d, _rodas.R5P_H,
                       _rodas.R5P_GAMMA, 5.0),
           "rodas4": (_rodas.R4_A, _rodas.R4_C, _rodas.R4_c, _rodas.R4_d, _rodas.R4_H,
                      _rodas.R4_GAMMA, 4.0),
           "ros2": (_rodas.ROS2_A, _rodas.ROS2_C, _rodas.ROS2_c, _rodas.ROS2_d, _rodas.ROS2_H,
                    _rodas.ROS2_GAMMA, 3.0)}


def stepper() -> tuple[Callable, Callable[[float], np.ndarray]]:
    """The driver compiled on this problem, and the exact solution.

    Returns
    -------
    solve : callable
        ``solve(method, h, samples, t_end=T_END) -> (status tuple, x, X)``: fixed steps `h`
        [s] (tolerances 1e6, largest step `h`) of `method` (a key of `TABLEAU`) from the
        start to `t_end` [s]; ``x`` (4,) the end state, ``X`` (len(samples), 4) the dense
        output at `samples` [s].
    exact : callable
        ``exact(t) -> x(t)``, shape (4,), the known solution.
    """
    f = _rodas._run.py_func
    g = dict(f.__globals__, _eval=_lin_eval, _state_jacobian=_lin_jacobian,
             _input_direction=_lin_direction, stop_status=_lin_stop, NY=4)
    # cached beside `_rodas`'s own (about 10 s to compile): under a name of its own that
    # carries a hash of this problem's functions, so that an edited problem compiles anew;
    # numba's index checks `_run`'s bytecode and `_rodas.py`'s stamp, and `drop_stale_cache`
    # drops it with the rest when a source of `empact.nonlinear` changes
    # (and of their module: the cached code names it)
    problem = hashlib.sha256(b"".join(
        fn.py_func.__module__.encode() + fn.py_func.__code__.co_code
        + repr(fn.py_func.__code__.co_consts).encode()
        for fn in (_lin_eval, _lin_jacobian, _lin_direction, _lin_stop))).hexdigest()[:16]
    name = f"_run_linear_test_{problem}"
    code = f.__code__.replace(co_name=name, co_qualname=name)
    run = njit(cache=True)(types.FunctionType(code, g, name, f.__defaults__, f.__closure__))
    # start on the slow manifold (the polynomial particular solution plus the oscillator's
    # modes), so that the solution is smooth: no fast transient of the stiff components
    b = -np.linalg.solve(A_LIN, B_LIN[:, 0] * U1)
    a = np.linalg.solve(A_LIN, b - B_LIN[:, 0] * U0)
    ev, V = np.linalg.eig(A_LIN)
    slow = np.argsort(np.abs(ev))[:2]
    x0 = a + np.real(V[:, slow] @ np.ones(2))
    M = np.zeros((6, 6))
    M[:4, :4], M[:4, 4:5], M[4, 5] = A_LIN, B_LIN, 1.0

    def exact(t):
        return (sl.expm(M * t) @ np.concatenate([x0, [U0, U1]]))[:4]

    def solve(method, h, samples, t_end=T_END):
        """Fixed steps h (tolerances 1e6, largest step h); returns (status tuple, x, X)."""
        x = x0.copy()
        X = np.full((len(samples), 4), np.nan)
        Y = np.full((len(samples), 4), np.nan)
        huge = np.full(4, 1e6)
        out = run(*TABLEAU[method], x, 0.0, t_end, h, np.asarray(samples, float),
                  np.concatenate([A_LIN.ravel(), B_LIN.ravel()]), np.full(4, -1, np.int64),
                  np.array([[0.0, T_END]]), np.array([[U0, U0 + U1 * T_END]]),
                  np.array([2], np.int64), np.array([T_END]), huge, huge, 1e-14, h, 0.0,
                  10 ** 7, X, Y, np.arange(4, dtype=np.int64), np.zeros((4, 4)), True,
                  np.empty(0))
        return out, x, X


    return solve, exact
