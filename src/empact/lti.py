"""Linear time-invariant tools shared by every model: frequency response, zeros, damping,
named state-space objects, and root loci over any parameter.

* `FrequencyResponse` - a response ``H[i, j, k]`` from input j to output i at ``omega[k]``,
  with signal names; `frequency_response` computes ``C (j w I - A)^-1 B + D`` vectorised
  over frequency (the one implementation for state-space models; the lumped models of
  `empact.linear` evaluate their second-order form directly).
* `transmission_zeros` - finite invariant zeros of a square system (Rosenbrock pencil).
* `damping_ratio`, `oscillatory` - damping ratio ``-Re(p) / |p|`` and the oscillatory
  poles (or zeros) as natural frequency [Hz] and damping ratio.
* `statespace` - a named `control.StateSpace` (python-control is imported on first use).
* `cont2discrete` - a continuous state space at a sample time (Tustin, zero- or first-order
  hold): ``scipy.signal.cont2discrete``'s formulas, without importing ``scipy.signal``.
* `root_locus`, `track_branches`, `match_branches` - eigenvalues of ``A(p)`` along a scalar
  parameter with continuous branches.  python-control draws a root locus over a feedback gain
  only; here the parameter may enter ``A`` in any way:

  - steps are uniform in ``p`` (``spacing="linear"``) or in ``log(p)`` (``"log"``, for
    parameters spanning decades, such as a damping constant); the step is halved while any
    pole moves more than ``max_move`` times its own magnitude plus an absolute floor, and
    grown again when the poles move little, so that break-away points are resolved;
  - between steps the eigenvalues are matched to the previous ones by a minimum-cost
    assignment (`scipy.optimize.linear_sum_assignment` on ``|lambda_new - lambda_old|``), so
    column ``j`` of `RootLocus.poles` is one continuous branch.

  End points at ``p = 0`` or ``p -> inf`` usually need a separate, exact computation (see
  `empact.slip.belt_root_locus`).
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass
from typing import Callable, Literal, Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import linalg
from scipy.linalg import eigvals as generalized_eigvals

from ._lazy import lazy_module
from ._results import Result, TableResult

control = lazy_module("control")
#: one call (`match_branches`): imported on first use, not by every command that imports lti
optimize = lazy_module("scipy.optimize")

__all__ = ["FrequencyResponse", "frequency_response", "system_response", "transmission_zeros",
           "channel_zeros",
           "damping_ratio", "oscillatory", "statespace", "cont2discrete", "unwrapped_phase_deg",
           "RootLocus",
           "root_locus", "match_branches", "track_branches"]

Spacing = Literal["linear", "log"]


# --------------------------------------------------------------------------------------------
# Frequency response
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class FrequencyResponse(TableResult):
    """A frequency response ``H[i, j, k]`` from input j to output i at ``omega[k]``.

    Attributes
    ----------
    omega : frequencies [rad/s], shape (n_f,)
    H : complex response, shape (n_out, n_in, n_f), in output units per input unit
    inputs, outputs : signal names
    label : free text (e.g. the damping level)
    """

    omega: NDArray[np.float64]
    H: NDArray[np.complex128]
    inputs: tuple[str, ...]
    outputs: tuple[str, ...]
    label: str = ""

    def _columns(self) -> dict[str, NDArray]:
        """``omega`` [rad/s], then ``H[output/input]`` (complex) per channel."""
        return {"omega": self.omega, **{f"H[{o}/{i}]": self.H[a, b]
                                        for a, o in enumerate(self.outputs)
                                        for b, i in enumerate(self.inputs)}}

    @property
    def frequencies_hz(self) -> NDArray[np.float64]:
        """Frequencies [Hz]."""
        return self.omega / (2 * np.pi)

    def response(self, output: str, input: str) -> NDArray[np.complex128]:
        """The response of one named output to one named input, shape (n_f,).

        Parameters
        ----------
        output : str
            One of `outputs`.
        input : str
            One of `inputs`.
        """
        return self.H[index(self.outputs, output, "output"), index(self.inputs, input, "input")]

    def magnitude_db(self) -> NDArray[np.float64]:
        """``20 log10 |H|`` [dB]."""
        return 20 * np.log10(np.abs(self.H))

    def phase_deg(self) -> NDArray[np.float64]:
        """Phase [deg], unwrapped along frequency and shifted by a multiple of 360 deg so that
        it starts in (-180, 180] at the lowest frequency."""
        return unwrapped_phase_deg(self.H)


def unwrapped_phase_deg(H: ArrayLike) -> NDArray[np.float64]:
    """Phase of `H` [deg] unwrapped along the last axis, starting in (-180, 180].

    Parameters
    ----------
    H : array_like of complex, shape (..., n_f)
        A complex response, frequency along the last axis (e.g. `FrequencyResponse.H`).

    Returns
    -------
    ndarray, shape (..., n_f)
        The phase [deg], unwrapped along the last axis and shifted by a multiple of 360 deg
        so that its first entry lies in (-180, 180].
    """
    ph = np.degrees(np.unwrap(np.angle(np.asarray(H)), axis=-1))
    first = ph[..., :1]
    shift = 360.0 * np.ceil((first - 180.0) / 360.0)
    return ph - shift


def index(names: Sequence[str], name: str, what: str) -> int:
    """Position of `name` in `names`; a one-line `ValueError` naming the choices otherwise."""
    try:
        return list(names).index(name)
    except ValueError:
        raise ValueError(f"unknown {what} {name!r}: choose from {', '.join(names)}") from None


def frequency_response(A: ArrayLike, B: ArrayLike, C: ArrayLike, D: ArrayLike,
                       omega: ArrayLike, inputs: Sequence[str], outputs: Sequence[str],
                       label: str = "") -> FrequencyResponse:
    """``H(j w) = C (j w I - A)^-1 B + D`` at every `omega` [rad/s], one batched solve.

    Parameters
    ----------
    A, B, C, D : state-space matrices, shapes (n, n), (n, m), (p, n), (p, m)
    omega : frequencies [rad/s], shape (n_f,); none may be a pole on the imaginary axis
    inputs, outputs : signal names (m and p of them)
    label : free text for the result

    Returns
    -------
    FrequencyResponse
        ``H``, shape (p, m, n_f) (complex, the units of output / input), with `omega`,
        `inputs`, `outputs` and `label`.
    """
    A, B, C, D = (np.atleast_2d(np.asarray(x, float)) for x in (A, B, C, D))
    w = np.atleast_1d(np.asarray(omega, float))
    n = A.shape[0]
    Z = 1j * w[:, None, None] * np.eye(n)[None] - A[None]
    X = np.linalg.solve(Z, np.broadcast_to(B, (len(w),) + B.shape))
    H = np.einsum("on,fni->oif", C, X) + D[:, :, None]
    return FrequencyResponse(omega=w, H=H, inputs=tuple(inputs), outputs=tuple(outputs),
                             label=label)


def system_response(sys, omega: ArrayLike, label: str = "") -> FrequencyResponse:
    """`frequency_response` of a `control.StateSpace` (signal names from the system).

    Parameters
    ----------
    sys : control.StateSpace
        A continuous-time system with m inputs and p outputs; its ``input_labels`` and
        ``output_labels`` name the signals.
    omega : array_like, shape (n_f,)
        Frequencies [rad/s]; none may be a pole on the imaginary axis.
    label : str
        Free text for the result.

    Returns
    -------
    FrequencyResponse
        ``H``, shape (p, m, n_f) (complex, the units of output / input), with the system's
        signal names.
    """
    return frequency_response(sys.A, sys.B, sys.C, sys.D, omega, tuple(sys.input_labels),
                              tuple(sys.output_labels), label=label)


# --------------------------------------------------------------------------------------------
# Zeros, damping, named systems
# --------------------------------------------------------------------------------------------
def transmission_zeros(A: ArrayLike, B: ArrayLike, C: ArrayLike, D: ArrayLike, *,
                       scale: ArrayLike | None = None, max_abs: float = 1e12) \
        -> NDArray[np.complex128]:
    """Finite invariant zeros of a square system [rad/s], sorted by magnitude.

    The finite generalised eigenvalues of the Rosenbrock pencil ``[[A, B], [C, D]] - s [[I, 0],
    [0, 0]]``, after a diagonal state scaling ``x = S x~`` (`scale`, for states of very
    different units) and a normalisation of B and C; zeros above `max_abs` [rad/s] count as
    infinite.

    Parameters
    ----------
    A, B, C, D : array_like
        State-space matrices, shapes (n, n), (n, m), (m, n), (m, m) (square: as many outputs
        as inputs).
    scale : array_like, optional
        Diagonal state scaling ``S``, shape (n,) (default: none, ``S = 1``).
    max_abs : float
        Zeros larger than this [rad/s] count as infinite.

    Returns
    -------
    ndarray of complex
        The finite zeros [rad/s], shape (n_z,), sorted by magnitude.
    """
    a = np.atleast_2d(np.asarray(A, float))
    b = np.atleast_2d(np.asarray(B, float))
    c = np.atleast_2d(np.asarray(C, float))
    d = np.atleast_2d(np.asarray(D, float))
    n, m, p = a.shape[0], b.shape[1], c.shape[0]
    if m != p:
        raise ValueError(f"transmission_zeros: {p} outputs and {m} inputs; need a square system")
    S = np.ones(n) if scale is None else np.asarray(scale, float)
    a = a * S[None, :] / S[:, None]
    b = b / S[:, None]
    c = c * S[None, :]
    bs = max(float(np.max(np.abs(b))), 1e-300)
    cs = max(float(np.max(np.abs(c))), 1e-300)
    L = np.block([[a, b / bs], [c / cs, d / (bs * cs)]])
    M = np.zeros((n + m, n + m))
    M[:n, :n] = np.eye(n)
    w, beta = generalized_eigvals(L, M, homogeneous_eigvals=True)
    finite = np.abs(beta) > 1e-12 * np.abs(w)
    z = w[finite] / beta[finite]
    z = z[np.isfinite(z) & (np.abs(z) < max_abs)]
    return z[np.argsort(np.abs(z), kind="stable")]


def channel_zeros(sys, input: str, output: str, *, scale: ArrayLike | None = None,
                  max_abs: float = 1e12) -> NDArray[np.complex128]:
    """`transmission_zeros` of one named input -> output channel of a named system.

    Parameters
    ----------
    sys : control.StateSpace or empact.nonlinear.linearization.Plant
        The system, n states (``A, B, C, D``, ``input_labels``, ``output_labels``).
    input, output : str
        Names of the channel's input and output (from ``sys.input_labels`` and
        ``sys.output_labels``).
    scale : array_like, optional
        Diagonal state scaling ``S``, shape (n,) (default: none, ``S = 1``).
    max_abs : float
        Zeros larger than this [rad/s] count as infinite.

    Returns
    -------
    ndarray of complex
        The finite zeros of the single-input single-output channel [rad/s], shape (n_z,),
        sorted by magnitude.
    """
    i = index(sys.input_labels, input, "input")
    o = index(sys.output_labels, output, "output")
    return transmission_zeros(sys.A, sys.B[:, [i]], sys.C[[o]], sys.D[[o]][:, [i]],
                              scale=scale, max_abs=max_abs)


def damping_ratio(p: ArrayLike) -> NDArray[np.float64]:
    """Damping ratio ``-Re(p) / |p|`` [-] of poles (or zeros) `p`; 1 for ``p = 0``.

    Parameters
    ----------
    p : array_like of complex
        Poles or zeros [rad/s], any shape.

    Returns
    -------
    ndarray
        The damping ratios [-], the shape of `p`.
    """
    p = np.asarray(p, complex)
    mag = np.abs(p)
    return np.where(mag > 0, -p.real / np.where(mag > 0, mag, 1.0), 1.0)


def oscillatory(poles: ArrayLike, tol: float = 1e-3) \
        -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Natural frequencies ``|p| / (2 pi)`` [Hz] and damping ratios [-] of the poles (or
    zeros) with ``Im(p) > tol`` [rad/s], ascending in frequency.

    The default `tol` (1e-3 rad/s) is far above the rounding of structural zeros and far
    below any oscillatory mode of the CVT.

    Parameters
    ----------
    poles : array_like of complex
        Poles or zeros [rad/s], any shape (flattened); of each complex-conjugate pair only
        the one with positive imaginary part is kept.
    tol : float
        Smallest imaginary part [rad/s] that counts as oscillatory.

    Returns
    -------
    f_n : ndarray, shape (n_osc,)
        Natural frequencies ``|p| / (2 pi)`` [Hz], ascending.
    zeta : ndarray, shape (n_osc,)
        Their damping ratios ``-Re(p) / |p|`` [-].
    """
    p = np.asarray(poles, complex).ravel()
    p = p[p.imag > tol]
    p = p[np.argsort(np.abs(p), kind="stable")]
    return np.abs(p) / (2 * np.pi), damping_ratio(p)


def statespace(A: ArrayLike, B: ArrayLike, C: ArrayLike, D: ArrayLike, *,
               inputs: Sequence[str], outputs: Sequence[str], states: Sequence[str],
               name: str = "sys", dt: float | None = None):
    """A named `control.StateSpace` (the name made python-control safe); `dt` [s] makes it
    discrete-time.

    Parameters
    ----------
    A, B, C, D : array_like
        State-space matrices, shapes (n, n), (n, m), (p, n), (p, m).
    inputs, outputs, states : sequence of str
        Signal names (m, p and n of them).
    name : str
        System name; runs of characters other than letters, digits and ``_`` become ``_``.
    dt : float, optional
        Sample period [s] (default: continuous time).

    Returns
    -------
    control.StateSpace
        The named system, continuous-time or with sample period `dt`.
    """
    args = [np.asarray(A, float), np.asarray(B, float), np.asarray(C, float),
            np.asarray(D, float)] + ([] if dt is None else [dt])
    return control.ss(*args, inputs=list(inputs), outputs=list(outputs), states=list(states),
                      name=re.sub(r"[^A-Za-z0-9_]+", "_", name).strip("_"))


#: the methods of `cont2discrete`
DISCRETIZATIONS = ("tustin", "bilinear", "zoh", "foh")


def cont2discrete(A: ArrayLike, B: ArrayLike, C: ArrayLike, D: ArrayLike, dt: float,
                  method: str = "tustin") -> tuple[NDArray[np.float64], ...]:
    """The continuous state space ``(A, B, C, D)`` at sample time `dt` [s].

    The formulas and LAPACK calls of ``scipy.signal.cont2discrete`` (scipy 1.11-1.17), so the
    matrices are bitwise scipy's (`tests/test_lti.py` compares them): importing
    ``scipy.signal`` takes 0.9-1.5 s (it imports ``scipy.stats``), which every ``empact
    control`` command paid for one call (`bench/bench_discretize.py`).

    Parameters
    ----------
    A, B, C, D : array_like
        Shapes (n, n), (n, m), (p, n), (p, m).
    dt : float
        Sample time [s], positive.
    method : {"tustin", "bilinear", "zoh", "foh"}
        Tustin (= bilinear, the generalised bilinear transform with alpha = 1/2),
        zero-order hold or first-order (triangle) hold.

    Returns
    -------
    Ad, Bd, Cd, Dd : ndarray
        ``x[k+1] = Ad x[k] + Bd u[k]``, ``y[k] = Cd x[k] + Dd u[k]``; shapes as the input.
    """
    a, b, c, d = (np.asarray(M, dtype=float) for M in (A, B, C, D))
    if method not in DISCRETIZATIONS:
        raise ValueError(f"method {method!r}: one of {', '.join(DISCRETIZATIONS)}")
    n, m = b.shape
    if method in ("tustin", "bilinear"):
        alpha = 0.5
        ima = np.eye(n) - alpha * dt * a
        ad = linalg.solve(ima, np.eye(n) + (1.0 - alpha) * dt * a)
        bd = linalg.solve(ima, dt * b)
        cd = linalg.solve(ima.transpose(), c.transpose()).transpose()
        dd = d + alpha * np.dot(c, bd)
    elif method == "zoh":
        em = np.vstack((np.hstack((a, b)), np.zeros((m, n + m))))
        ms = linalg.expm(dt * em)[:n, :]
        ad, bd, cd, dd = ms[:, :n], ms[:, n:], c, d
    else:  # foh
        em_upper = linalg.block_diag(np.block([a, b]) * dt, np.eye(m))
        em = np.block([[em_upper], [np.zeros((m, n + 2 * m))]])
        ms = linalg.expm(em)
        ms11, ms12, ms13 = ms[:n, :n], ms[:n, n:n + m], ms[:n, n + m:]
        ad, bd, cd, dd = ms11, ms12 - ms13 + ms11 @ ms13, c, d + c @ ms13
    return ad, bd, cd, dd


# --------------------------------------------------------------------------------------------
# Root loci
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class RootLocus(Result):
    """Eigenvalues of ``A(p)`` along a parameter, one continuous branch per column.

    Attributes
    ----------
    parameter : parameter values, shape (n_steps,), monotone from ``p_start`` to ``p_stop``
    poles : eigenvalues [rad/s], shape (n_steps, n); column ``j`` is branch ``j``
    name : parameter name (with unit, for display)
    """

    parameter: NDArray[np.float64]
    poles: NDArray[np.complex128]
    name: str = "p"

    @property
    def start(self) -> NDArray[np.complex128]:
        """Poles at the first parameter value, shape (n,)."""
        return self.poles[0]

    @property
    def stop(self) -> NDArray[np.complex128]:
        """Poles at the last parameter value, shape (n,)."""
        return self.poles[-1]


def match_branches(previous: ArrayLike, current: ArrayLike) -> NDArray[np.complex128]:
    """Reorder `current` eigenvalues so that entry j continues ``previous[j]`` (shape (n,)).

    Minimum total distance ``sum |current[perm[j]] - previous[j]|`` (Hungarian algorithm).

    Parameters
    ----------
    previous : array_like of complex, shape (n,)
        Eigenvalues at the previous parameter value, in branch order.
    current : array_like of complex, shape (n,)
        Eigenvalues at the current parameter value, in any order.

    Returns
    -------
    ndarray of complex, shape (n,)
        `current` reordered so that entry j continues branch j of `previous`.
    """
    prev = np.asarray(previous, complex)
    cur = np.asarray(current, complex)
    if prev.shape != cur.shape or prev.ndim != 1:
        raise ValueError(f"eigenvalue vectors of shapes {prev.shape} and {cur.shape}: need two "
                         "equal 1-d shapes")
    cost = np.abs(prev[:, None] - cur[None, :])
    rows, cols = optimize.linear_sum_assignment(cost)
    out = np.empty_like(cur)
    out[rows] = cur[cols]
    return out


def track_branches(eigs: ArrayLike) -> NDArray[np.complex128]:
    """Match eigenvalues along the first axis (shape (n_steps, n)) into continuous branches.

    Parameters
    ----------
    eigs : array_like of complex, shape (n_steps, n)
        Eigenvalues at successive parameter values, each row in any order.

    Returns
    -------
    ndarray of complex, shape (n_steps, n)
        A copy with each row reordered (`match_branches` against the row before; the first
        row as given), so that column j is one continuous branch.
    """
    e = np.array(eigs, dtype=complex)
    if e.ndim != 2:
        raise ValueError(f"eigenvalues of shape {e.shape}: need (n_steps, n)")
    for k in range(1, len(e)):
        e[k] = match_branches(e[k - 1], e[k])
    return e


def root_locus(A_of_p: Callable[[float], ArrayLike], p_start: float, p_stop: float, *,
               spacing: Spacing = "linear", n_initial: int = 60, max_move: float = 0.05,
               abs_floor: float | None = None, min_step_fraction: float = 1e-6,
               max_points: int = 20000, name: str = "p") -> RootLocus:
    """Eigenvalues of ``A_of_p(p)`` from `p_start` to `p_stop`, tracked branch by branch.

    Parameters
    ----------
    A_of_p : callable
        ``p -> A``, a square real or complex matrix, shape (n, n), for a scalar parameter.
    p_start, p_stop : float
        Ends of the parameter range (either order).  With ``spacing="log"`` both must be
        positive (map an end point at 0 or infinity separately).
    spacing : {"linear", "log"}
        Steps uniform in ``p`` or in ``log(p)``.
    n_initial : int
        The largest step is ``1 / n_initial`` of the range (in the spacing's variable), so the
        locus has at least ``n_initial + 1`` points.
    max_move : float
        A step is accepted when every pole moves at most ``max_move * |lambda| + abs_floor``.
    abs_floor : float, optional
        Absolute part of the tolerance [units of the eigenvalues]; default 1 % of the median
        nonzero eigenvalue magnitude at `p_start` (so that poles near 0 do not force tiny steps).
    min_step_fraction : float
        Smallest step, as a fraction of the largest; a step this small is accepted anyway (at a
        break-away point the poles move like a square root of the parameter).
    max_points : int
        Hard limit on the number of points.
    name : str
        Parameter name for the result.

    Returns
    -------
    RootLocus
        ``parameter`` shape (n_steps,), ``poles`` shape (n_steps, n).

    Examples
    --------
    A mass on a spring with damping c: poles ``(-c +- sqrt(c^2 - 4)) / 2``.

    >>> loc = root_locus(lambda c: [[0, 1], [-1, -c]], 0.0, 4.0)
    >>> bool(np.allclose(sorted(loc.stop.real), [-2 - 3**0.5, -2 + 3**0.5]))
    True
    """
    if spacing not in ("linear", "log"):
        raise ValueError(f"spacing = {spacing!r}: choose 'linear' or 'log'")
    for label, v in (("p_start", p_start), ("p_stop", p_stop)):
        if not math.isfinite(v):
            raise ValueError(f"{label} = {v!r}: must be finite (map an infinite end point "
                             "separately)")
        if spacing == "log" and v <= 0:
            raise ValueError(f"{label} = {v!r}: must be > 0 with spacing='log'")
    if p_start == p_stop:
        raise ValueError(f"p_start = p_stop = {p_start!r}: the range is empty")
    if n_initial < 2:
        raise ValueError(f"n_initial = {n_initial}: must be >= 2")
    if not 0 < max_move < 1:
        raise ValueError(f"max_move = {max_move!r}: allowed range is (0, 1)")

    to_t = np.log if spacing == "log" else (lambda x: x)
    to_p = np.exp if spacing == "log" else (lambda x: x)
    t0, t1 = float(to_t(p_start)), float(to_t(p_stop))
    h_max = (t1 - t0) / n_initial  # signed
    h_min = abs(h_max) * min_step_fraction

    def eig(t: float) -> NDArray[np.complex128]:
        return np.linalg.eigvals(np.asarray(A_of_p(float(to_p(t)))))

    prev = eig(t0)
    if abs_floor is None:
        mags = np.abs(prev)
        nz = mags[mags > 1e-9 * max(mags.max(), 1e-300)]
        abs_floor = 0.01 * float(np.median(nz)) if nz.size else 1e-6
    params, poles = [float(to_p(t0))], [prev]
    t, h = t0, h_max
    while (t1 - t) * np.sign(h_max) > 0:
        if len(params) >= max_points:
            raise RuntimeError(f"root_locus: more than max_points = {max_points} points; "
                               "increase max_move or max_points")
        t_try = t + h
        if (t1 - t_try) * np.sign(h_max) < 0:
            t_try = t1
        cur = match_branches(prev, eig(t_try))
        ratio = float(np.max(np.abs(cur - prev) / (max_move * np.abs(prev) + abs_floor)))
        if ratio > 1 and abs(h) > h_min:
            h = np.sign(h_max) * max(abs(h) / 2, h_min)
            continue
        t, prev = t_try, cur
        params.append(float(to_p(t)))
        poles.append(cur)
        if ratio < 0.3:
            h = np.sign(h_max) * min(abs(h) * 1.5, abs(h_max))
    params[-1] = float(p_stop)
    return RootLocus(parameter=np.array(params), poles=np.array(poles), name=name)
