"""State-space realisation from measured step responses (Kung's method / ERA).

The step responses are differenced into the Markov parameters of the zero-order-hold (ZOH)
discrete model, ``h_0 = D`` and ``h_k = C A_d^(k-1) B_d``; a block Hankel matrix of
``h_1, h_2, ...`` is factored by the SVD into an observability and a controllability matrix
(balanced split of the singular values), ``A_d`` follows from the shift structure of the
observability matrix (least squares), and the continuous model is the exact ZOH inverse:
``A_c = logm(A_d) / dt`` and ``B_c = (dt phi_1(A_c dt))^-1 B_d`` with
``phi_1(X) = sum_k X^k / (k+1)!`` (from the exponential of an augmented matrix).  Unlike
``A_c (A_d - I)^-1 B_d`` this stays defined for integrators (eigenvalues of ``A_d`` at 1),
which the servo-torque-to-ratio plant has.
"""
from __future__ import annotations

import numbers
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property

import numpy as np
import scipy.linalg as sla
from threadpoolctl import threadpool_limits

from .._results import Result
from ..lti import statespace

__all__ = ["RealizationResult", "realize_steps"]

#: highest order tried by the `min_fit` order selection
MAX_FIT_ORDER = 40


@dataclass(frozen=True)
class RealizationResult(Result):
    """Result of `realize_steps`.

    Attributes
    ----------
    A, B, C, D : numpy.ndarray
        Identified continuous-time model, shapes (n, n), (n, m), (p, n), (p, m).
    A_d, B_d : numpy.ndarray
        Identified ZOH discrete-time model (with the same ``C``, ``D``), sample time `dt`.
    dt : float
        Sample time [s].
    inputs, outputs : tuple of str
        Signal names.
    singular_values : numpy.ndarray
        Singular values of the block Hankel matrix, descending, shape (n_sv,).
    order : int
        Model order (number of states).
    fit : numpy.ndarray
        Normalised RMS fit per channel [%], shape (n_out, n_in):
        ``100 (1 - ||y - y_hat|| / ||y - mean(y)||)``; NaN where the measured step is constant.
    step_model : numpy.ndarray
        Step responses of the discrete model on the sample instants, shape (n_t, n_out, n_in).

    `sys` and `sys_discrete` are the models as named `control.StateSpace` objects (built on
    first use, so that a caller who needs only the matrices does not import python-control).
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    A_d: np.ndarray
    B_d: np.ndarray
    dt: float
    inputs: tuple[str, ...]
    outputs: tuple[str, ...]
    singular_values: np.ndarray
    order: int
    fit: np.ndarray
    step_model: np.ndarray

    @cached_property
    def sys(self):
        """The continuous-time model, a named `control.StateSpace` (states ``x0, x1, ...``)."""
        return statespace(self.A, self.B, self.C, self.D, inputs=self.inputs,
                          outputs=self.outputs, states=[f"x{i}" for i in range(self.order)],
                          name="identified")

    @cached_property
    def sys_discrete(self):
        """The ZOH discrete-time model, a named `control.StateSpace` with sample time `dt`."""
        return statespace(self.A_d, self.B_d, self.C, self.D, inputs=self.inputs,
                          outputs=self.outputs, states=[f"x{i}" for i in range(self.order)],
                          name="identified_d", dt=self.dt)


def _positive_int(name: str, value) -> int | None:
    if value is None:
        return None
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Integral) or value < 1:
        raise ValueError(f"{name} must be a positive integer or None, got {value!r}")
    return int(value)


def _names(name: str, names, count: int) -> list[str] | int:
    if names is None:
        return count
    if isinstance(names, str) or len(names) != count:
        raise ValueError(f"{name} must be a sequence of {count} names, got {names!r}")
    return [str(s) for s in names]


def _discrete_steps(A: np.ndarray, B: np.ndarray, C: np.ndarray, D: np.ndarray,
                    n_t: int) -> np.ndarray:
    """Step responses of ``(A, B, C, D)`` from rest, shape (n_t, n_out, n_in).

    ``A^k B`` for k = 0 .. n_t-2 is built by doubling (log2(n_t) matrix products).
    """
    M, Ap = B[None], A
    with np.errstate(over="ignore", invalid="ignore"):  # an unstable model may overflow
        while M.shape[0] < n_t - 1:
            M = np.concatenate([M, Ap @ M], axis=0)
            Ap = Ap @ Ap
        h = C @ M[: n_t - 1]
        cum = np.concatenate([np.zeros((1,) + D.shape), np.cumsum(h, axis=0)], axis=0)
    return D + cum


def _select_order(s: np.ndarray, n_max: int, sv_threshold: float) -> int:
    """Order at the largest ratio ``s[k-1] / s[k]`` among the candidate singular values.

    Candidates are those above ``sqrt(eps) s[0]`` if the Hankel matrix is numerically rank
    deficient (noise-free data: the rank break wins), else those above ``sv_threshold s[0]``.
    """
    n_rank = int(np.count_nonzero(s > np.sqrt(np.finfo(float).eps) * s[0]))
    n_sig = n_rank if n_rank < s.size else int(np.count_nonzero(s > sv_threshold * s[0]))
    n_sig = max(1, min(n_max, n_sig))
    nxt = np.append(s, 0.0)[1: n_sig + 1]
    ratio = s[:n_sig] / np.maximum(nxt, np.finfo(float).tiny)
    return int(np.argmax(ratio)) + 1


def _discrete(U, sv, Vt, n, h, p, m, n_t, steps):
    """Discrete model of order `n` from the Hankel SVD, its step responses and fit [%].

    Raises `ValueError` when ``A_d`` has eigenvalues on the closed negative real axis: such a
    model has no continuous-time ZOH equivalent.
    """
    root = np.sqrt(sv[:n])
    obs, ctr = U[:, :n] * root, root[:, None] * Vt[:n]
    Ad = np.linalg.lstsq(obs[:-p], obs[p:], rcond=None)[0]
    Bd, Cd, D = ctr[:, :m], obs[:p], h[0]
    lam = np.linalg.eigvals(Ad)
    bad = (np.abs(lam.imag) <= 1e-10 * np.abs(lam)) & (lam.real <= 0.0)
    if np.any(bad):
        raise ValueError(f"identified A_d has eigenvalue(s) {np.round(lam[bad].real, 6)} on the "
                         f"negative real axis or at zero: no continuous-time equivalent (try a "
                         f"lower order)")
    step_model = _discrete_steps(Ad, Bd, Cd, D, n_t)
    err = np.linalg.norm(steps - step_model, axis=0)
    ref = np.linalg.norm(steps - steps.mean(axis=0), axis=0)
    fit = np.full((p, m), np.nan)
    np.divide(err, ref, out=fit, where=ref > 0)
    fit = 100.0 * (1.0 - fit)
    return Ad, Bd, Cd, D, step_model, fit


def _continuous(Ad, Bd, dt):
    """Exact ZOH inverse: ``A_c = logm(A_d) / dt``, ``B_c = (dt phi_1(A_c dt))^-1 B_d``."""
    n = Ad.shape[0]
    Ac = np.real(sla.logm(Ad)) / dt
    aug = np.zeros((2 * n, 2 * n))
    aug[:n, :n], aug[:n, n:] = Ac * dt, np.eye(n)
    gamma = sla.expm(aug)[:n, n:] * dt  # int_0^dt expm(A_c tau) dtau = dt phi_1(A_c dt)
    return Ac, np.linalg.solve(gamma, Bd)


def realize_steps(t, steps, order: int | None = None, *, n_block_rows: int | None = None,
                  n_block_cols: int | None = None, sv_threshold: float = 1e-3,
                  min_fit: float | None = None, inputs: Sequence[str] | None = None,
                  outputs: Sequence[str] | None = None) -> RealizationResult:
    """Identify a continuous state-space model from sampled step responses.

    Parameters
    ----------
    t : array_like
        Uniformly spaced time vector [s], shape (n_t,); the steps are applied at ``t[0]``.
    steps : array_like
        Response of each output to a unit step on each input, from rest, shape
        (n_t, n_out, n_in) [output units per input unit]. ``steps[0]`` is the direct
        feedthrough ``D`` (usually zero).
    order : int, optional
        Model order. If None, it is chosen from the Hankel singular values ``s`` as the
        ``k`` with the largest ratio ``s_k / s_(k+1)`` among the significant ``s_k`` (the
        ratio to the first insignificant value included). Significant means
        ``s_k > sv_threshold * s_1``, or ``s_k > sqrt(eps) * s_1`` when the Hankel matrix is
        numerically rank deficient (noise-free data, where the order is its numerical rank).
        The threshold rejects the noise floor; the largest gap picks the clearest rank break
        above it.
    n_block_rows, n_block_cols : int, optional
        Block rows / columns of the Hankel matrix; ``n_block_rows + n_block_cols <= n_t``.
        Defaults: ``n_block_rows = min(n_t // 2, ceil(400 / n_out))`` and
        ``n_block_cols = n_t - n_block_rows`` (all Markov parameters used).
    sv_threshold : float, optional
        Relative singular-value threshold for the order selection, in (0, 1).
    min_fit : float, optional
        With ``order=None``: instead of the singular-value rule, the smallest order whose
        worst channel fits the steps to at least `min_fit` percent (the best-fitting order if
        none does).  For data whose singular values decay without a clear gap, such as the
        step responses of a nonlinear model.  One SVD serves all orders tried.
    inputs, outputs : sequence of str, optional
        Signal names for the returned models.

    Returns
    -------
    RealizationResult
        Continuous and discrete models, Hankel singular values, order, fit [%] and the
        model's step responses.

    Raises
    ------
    ValueError
        For malformed arguments, too few samples for the requested order or Hankel size, or
        an identified ``A_d`` with eigenvalues on the closed negative real axis (no
        continuous-time ZOH equivalent).
    """
    t = np.asarray(t, dtype=float)
    steps = np.asarray(steps, dtype=float)
    if t.ndim != 1:
        raise ValueError(f"t must be 1-D with shape (n_t,), got shape {t.shape}")
    if not np.all(np.isfinite(t)):
        raise ValueError("t must be finite, found NaN or inf")
    n_t = t.size
    if n_t < 4:
        raise ValueError(f"t needs at least 4 samples, got n_t={n_t}")
    dt = (t[-1] - t[0]) / (n_t - 1)
    dev = np.max(np.abs(np.diff(t) - dt)) / abs(dt) if dt != 0 else np.inf
    if not dt > 0 or dev > 1e-6:
        raise ValueError(f"t must be increasing and uniformly spaced (relative spacing "
                         f"deviation <= 1e-6), got deviation {dev:.3g}")
    if steps.ndim != 3 or steps.shape[0] != n_t:
        raise ValueError(f"steps must have shape (n_t={n_t}, n_out, n_in), got shape "
                         f"{steps.shape}")
    if not np.all(np.isfinite(steps)):
        raise ValueError("steps must be finite, found NaN or inf")
    order = _positive_int("order", order)
    r = _positive_int("n_block_rows", n_block_rows)
    s = _positive_int("n_block_cols", n_block_cols)
    if not 0.0 < sv_threshold < 1.0:
        raise ValueError(f"sv_threshold must be in (0, 1), got {sv_threshold!r}")
    _, p, m = steps.shape
    in_names, out_names = _names("inputs", inputs, m), _names("outputs", outputs, p)

    r = min(n_t // 2, -(-400 // p)) if r is None else r
    s = n_t - r if s is None else s
    if r < 2 or r + s > n_t:
        raise ValueError(f"too few samples: n_block_rows={r} (>= 2) and n_block_cols={s} need "
                         f"n_t >= {max(r, 2) + s}, got n_t={n_t}")
    n_max = min((r - 1) * p, s * m)
    if order is not None and order > n_max:
        raise ValueError(f"order={order} exceeds the maximum {n_max} identifiable with "
                         f"n_block_rows={r}, n_block_cols={s} (n_t={n_t}); supply more samples")

    h = np.diff(steps, axis=0, prepend=np.zeros((1, p, m)))       # h[0] = D, h[k] = C A^(k-1) B
    idx = np.arange(r)[:, None] + np.arange(1, s + 1)[None, :]     # H[i, j] = h[1 + i + j]
    hankel = h[idx].transpose(0, 2, 1, 3).reshape(r * p, s * m)
    if min_fit is not None and not 0 < min_fit < 100:
        raise ValueError(f"min_fit must be in (0, 100) percent, got {min_fit!r}")
    # small dense work: one BLAS thread (two fight over two cores, 4-7x slower measured)
    with threadpool_limits(limits=1, user_api="blas"):
        U, sv, Vt = np.linalg.svd(hankel, full_matrices=False)
        if sv[0] == 0.0:
            raise ValueError("steps are constant in time: nothing to identify")
        if order is not None or min_fit is None:
            n = _select_order(sv, n_max, sv_threshold) if order is None else order
            model = _discrete(U, sv, Vt, n, h, p, m, n_t, steps)
        else:  # smallest order reaching min_fit on every channel, else the best one tried
            model = None
            for k in range(1, min(n_max, MAX_FIT_ORDER) + 1):
                try:
                    cand = _discrete(U, sv, Vt, k, h, p, m, n_t, steps)
                except ValueError:  # no continuous-time equivalent at this order
                    continue
                if model is None or np.nanmin(cand[-1]) > np.nanmin(model[-1]):
                    model = cand
                if np.nanmin(cand[-1]) >= min_fit:
                    break
            if model is None:
                raise ValueError(f"no order up to {min(n_max, MAX_FIT_ORDER)} has a "
                                 "continuous-time equivalent")
        Ad, Bd, Cd, D, step_model, fit = model
        Ac, Bc = _continuous(Ad, Bd, dt)  # the chosen order only
    for a in (sv, fit, step_model):
        a.flags.writeable = False
    names = lambda given, count, prefix: (tuple(given) if not isinstance(given, int)  # noqa
                                          else tuple(f"{prefix}[{i}]" for i in range(count)))
    return RealizationResult(A=Ac, B=Bc, C=Cd, D=D, A_d=Ad, B_d=Bd, dt=float(dt),
                             inputs=names(in_names, m, "u"), outputs=names(out_names, p, "y"),
                             singular_values=sv, order=int(Ac.shape[0]), fit=fit,
                             step_model=step_model)
