"""The linear model of the loop that runs: the machine linearised at an operating point,
held and sampled at the loop's rate, with the loop law's sensors, feedforwards and
controller (`empact.control.law`), limits inactive.

The law is split where the controller sits.  Its pre-processing (sensor delay and counting
window, slip from the speeds, errors, clamping and shift feedforwards, holding torques) is
linearised by central differences of `LoopLaw.preprocess` itself, the function every sample
of a run calls; the controller enters with its own discrete matrices.  With the machine
discretised exactly under the zero-order hold (``Phi = e^(A dt)``, ``Gamma = int e^(A s) ds
B``) the pre-processing and the machine form the *augmented plant* from the controller's
output ``du`` to its input ``e`` (the feedforward loops closed inside it), and the loop is
``du = K(z) e``.  Disk margins are taken at both places the controller meets the plant
(``L = K G`` at the servo torques, ``L = G K`` at the errors; `empact.control.robustness`),
closed-loop stability from the eigenvalues of the closed loop's state matrix (``|z| < 1``).

`loop_model` builds it for one closed-loop scenario (its trimmed start, model options, law)
and `LoopModel.predict` gives the linear prediction of the scenario's run; `family_loops`
builds it at every point of a plant family for a controller and a loop configuration.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Any, Mapping

import numpy as np
from numpy.typing import NDArray

from .._lazy import lazy_module
from .._results import Result, TableResult
from ..errors import ParameterError
from ..nonlinear.equilibrium import trim_grid
from ..nonlinear.linearization import linearized_plant
from ..nonlinear.model import EmpactModel, nonlinear_model
from ..nonlinear.scenario import Scenario
from ..nonlinear.simulation import scenario_model, scenario_signals
from ..params import Params
from .closed_loop import build_law
from .controller import Controller
from .family import LOOP_FAMILY_OUTPUTS, PlantFamily, plant_family
from .law import (
    CAR_SOURCE,
    OBSERVER_SIGNAL,
    RAW_SIGNALS,
    LoopConfig,
    LoopLaw,
    measured_signals,
    reference_table,
)
from .robustness import disk_margin

linalg = lazy_module("scipy.linalg")
#: the largest stack of matrices `LoopModel.plant_response` solves at once [bytes]
_CHUNK_BYTES = 32e6

__all__ = ["LoopModel", "loop_model", "predict_scenario", "family_loops", "LoopPrediction",
           "LoopShapes", "DiskMarginMap", "disk_margin_map", "PERFORMANCE",
           "LOOP_FAMILY_OUTPUTS", "linear_preprocess", "zoh", "default_omega",
           "loop_specification", "controller_at"]

#: the machine's signals a loop model predicts (with the servo torques ``T_mp``, ``T_ms``)
PERFORMANCE = ("r_g", "nu", "nu_r", "F_s", "T_ds", "tau")


#: central-difference steps of the pre-processing's linearisation, per raw signal (SI)
_H_RAW = np.array([1e-6, 1e-4, 1e-4, 1e-4, 1e-4, 1e-4, 1e-4])
#: the same by signal name (`LoopLaw.measured`: the car's torque source and the observer's
#: wheel speed besides `RAW_SIGNALS`)
_H_SIGNAL = {**dict(zip(RAW_SIGNALS, _H_RAW)), CAR_SOURCE: 1e-4, OBSERVER_SIGNAL: 1e-4}


def _state_steps(law: LoopLaw) -> NDArray[np.float64]:
    """The central-difference steps of the pre-processing's state (SI), in its layout
    (`empact.control._law_core.pre`): the raw signals' buffers (signal-major, ``n_buf``
    each), the clamping feedforward's filter [N] and the decoupler's [N m], the torque
    estimate's delay line [N m] (``n_est``), the observer's torque [N m], the slip-runaway
    guard's clamping [N]."""
    c = law._c
    n_sig = len(RAW_SIGNALS)
    n_tail = law.n_pre - 2 - n_sig * c.n_buf
    n_est, n_obs = int(c.n_est), int(bool(c.obs))
    n_guard = n_tail - n_est - n_obs
    assert n_guard in (0, 1), (n_tail, n_est, n_obs)
    return np.concatenate([np.repeat(_H_RAW, c.n_buf), [1e-3, 1e-6], np.full(n_est, 1e-4),
                           np.full(n_obs, 1e-4), np.full(n_guard, 1e-3)])
_H_REF = np.array([1e-6, 1e-8, 1e-7, 1e-6])


def zoh(A: NDArray, B: NDArray, dt: float) -> tuple[NDArray, NDArray]:
    """Exact zero-order-hold discretisation of stacked systems ``(..., n, n)``,
    ``(..., n, m)``: ``Phi = e^(A dt)``, ``Gamma = int_0^dt e^(A s) ds B`` (one matrix
    exponential of the block ``[[A, B], [0, 0]] dt``, `scipy.linalg.expm`).

    Parameters
    ----------
    A : array_like, shape (..., n, n)
        Continuous state matrices [1/s], any leading (grid) dimensions.
    B : array_like, shape (..., n, m)
        Continuous input matrices, the same leading dimensions.
    dt : float
        Sample period [s].

    Returns
    -------
    Phi : ndarray, shape (..., n, n)
        ``e^(A dt)`` [-].
    Gamma : ndarray, shape (..., n, m)
        ``int_0^dt e^(A s) ds B``, the input matrix under the zero-order hold.
    """
    A, B = np.asarray(A, float), np.asarray(B, float)
    n, m = A.shape[-1], B.shape[-1]
    M = np.zeros(A.shape[:-2] + (n + m, n + m))
    M[..., :n, :n] = A * dt
    M[..., :n, n:] = B * dt
    E = linalg.expm(M)
    return E[..., :n, :n], E[..., :n, n:]


def linear_preprocess(law: LoopLaw) -> dict[str, NDArray[np.float64]]:
    """The law's pre-processing (`LoopLaw.preprocess`, ideal sensors) linearised at its
    starting point by central differences: ``s' = Sz s + Sy y + Sr r``, ``e = Ez s + Ey y +
    Er r``, ``u_ff = Fz s + Fy y + Fr r`` in deviations of the state ``s``, the raw
    measurements ``y`` (`LoopLaw.measured`: `RAW_SIGNALS`, in the car with the engine's
    torque as the torque source's, then the observer's wheel speed) and the references
    ``r`` (``r_g, slip, mu, dr_g/dt``).  Every feedforward signal is covered: the measured
    driveshaft torque, the torque source's estimate through its delay line, the observer.

    Parameters
    ----------
    law : LoopLaw
        The law, linearised at its start (its first references, trim measurements and
        initial pre-processing state).

    Returns
    -------
    dict str -> ndarray
        ``Sz``, ``Sy``, ``Sr`` shapes (n_pre, n_pre), (n_pre, n_y), (n_pre, 4); ``Ez``,
        ``Ey``, ``Er`` and ``Fz``, ``Fy``, ``Fr`` shapes (2, n_pre), (2, n_y), (2, 4)
        (``n_y = len(law.measured)``): the
        next pre-processing state, the controller's two errors (ratio, slip) and the two
        feedforward servo torques ``(T_mp, T_ms)`` [N m] per unit deviation (SI units of
        each signal); ``n_pre`` is ``law.n_pre``.
    """
    s0 = law.z0[:law.n_pre]
    y0 = law.raw0
    r0 = np.array([law.refs.r_g[0], law.refs.slip[0], law.refs.mu[0], 0.0])
    h_s = _state_steps(law)
    h_y = np.array([_H_SIGNAL[n] for n in law.measured])

    def f(s, y, r):
        s1, e, u, _ = law.preprocess(s, y, 0, r, ideal=True)
        return s1, e, u

    out: dict[str, NDArray[np.float64]] = {}
    eps = np.finfo(float).eps
    for which, x0, h in (("z", s0, h_s), ("y", y0, h_y), ("r", r0, _H_REF)):
        vals: list[tuple[list, list]] = [([], []) for _ in range(3)]  # S, E, F: +h, -h
        for i in range(len(x0)):
            xp, xm = x0.copy(), x0.copy()
            xp[i] += h[i]
            xm[i] -= h[i]
            args_p = [s0, y0, r0]
            args_m = [s0, y0, r0]
            k = {"z": 0, "y": 1, "r": 2}[which]
            args_p[k], args_m[k] = xp, xm
            for v, a, b in zip(vals, f(*args_p), f(*args_m)):
                v[0].append(a)
                v[1].append(b)
        h2 = 2 * np.asarray(h, float)[:len(x0), None]
        for name, (plus, minus) in zip(("S", "E", "F"), vals):
            a, b = np.array(plus), np.array(minus)  # (columns, rows)
            d = (a - b) / h2
            # differences at the rounding level of the values are no derivative
            floor = 64 * eps * np.maximum(np.abs(a), np.abs(b)) / h2
            out[name + which] = np.where(np.abs(d) > floor, d, 0.0).T
    return {k: out[k] for k in ("Sz", "Ez", "Fz", "Sy", "Ey", "Fy", "Sr", "Er", "Fr")}


@dataclass(frozen=True, eq=False)
class LoopPrediction(TableResult):
    """A linear prediction of a closed-loop run: the signals at the loop's samples.

    Attributes
    ----------
    t : array (n,)
        Sample times [s].
    signals : dict name -> array (n,)
        `PERFORMANCE` and ``T_mp``, ``T_ms`` (absolute: trim plus deviation).
    """

    t: NDArray[np.float64]
    signals: dict[str, NDArray[np.float64]]

    def _columns(self) -> dict[str, NDArray[np.float64]]:
        return {"t": self.t, **self.signals}

    def output(self, name: str) -> NDArray[np.float64]:
        """One predicted signal by name.

        Parameters
        ----------
        name : str
            One of `outputs`.
        """
        if name not in self.signals:
            raise ParameterError(f"no predicted signal {name!r} (choose from "
                                 f"{', '.join(self.signals)})")
        return self.signals[name]


@dataclass(frozen=True, eq=False)
class LoopModel(Result):
    """The linear closed loop of a law around the machine (one point, or stacked over a
    family's grid: leading dimensions ``shape``), discrete at the law's sample time.

    Augmented plant (state ``xi = [x; s]``: the machine's, the pre-processing's)::

        xi' = Aa xi + Bu du + Bw w + Br r
        e   = Ce xi + Dew w + Der r           (the controller's input)
        y   = Cy xi + Dyu du + Dyw w + Dyr r  (`PERFORMANCE`, T_mp, T_ms)

    with ``du = mask * K(z) e`` (`controller`, discrete).  ``w`` are the machine's other
    inputs (`disturbances`), held over each sample, and ``r`` the references (``r_g``,
    slip, mu, dr_g/dt).

    Attributes
    ----------
    Aa, Bu, Bw, Br : ndarray
        State, servo-torque, disturbance and reference matrices of the augmented plant
        (discrete, per sample), shapes (n_xi, n_xi), (n_xi, 2), (n_xi, n_w), (n_xi, 4)
        after the leading dimensions `shape`.
    Ce, Dew, Der : ndarray
        The controller's errors (ratio, slip), shapes (2, n_xi), (2, n_w), (2, 4) after
        the leading dimensions.
    Cy, Dyu, Dyw, Dyr : ndarray
        The predicted `outputs`, shapes (n_y, n_xi), (n_y, 2), (n_y, n_w), (n_y, 4) after
        the leading dimensions.
    controller : Controller
        The controller, discrete at `dt`.
    mask : ndarray, shape (2,)
        Which controller outputs reach the servos (1 or 0; the safety-factor strategy
        drops the secondary's).
    dt : float
        Sample period [s].
    disturbances : tuple of str
        Names of the machine's other inputs ``w`` (n_w of them).
    outputs : tuple of str
        Names of the predicted signals: `PERFORMANCE`, then ``T_mp``, ``T_ms`` (n_y).
    y0 : ndarray, shape (n_y,)
        The outputs at the trim (SI; `loop_model`), added to the deviations by
        `predict_scenario`; empty for a family (`family_loops`).
    """

    Aa: NDArray[np.float64]
    Bu: NDArray[np.float64]
    Bw: NDArray[np.float64]
    Br: NDArray[np.float64]
    Ce: NDArray[np.float64]
    Dew: NDArray[np.float64]
    Der: NDArray[np.float64]
    Cy: NDArray[np.float64]
    Dyu: NDArray[np.float64]
    Dyw: NDArray[np.float64]
    Dyr: NDArray[np.float64]
    controller: Controller
    mask: NDArray[np.float64]
    dt: float
    disturbances: tuple[str, ...]
    outputs: tuple[str, ...]
    y0: NDArray[np.float64]
    _cache: dict = field(default_factory=dict, repr=False, compare=False)

    def with_controller(self, controller: Controller) -> "LoopModel":
        """The same loop with another controller (continuous: discretised by Tustin at the
        loop's rate); the augmented plant and its cached responses are shared.  Its
        schedule, if any, must be the one the model was built with (the schedule acts in
        the pre-processing).

        Parameters
        ----------
        controller : Controller
            The other controller (2 errors in, 2 servo torques out).
        """
        c = controller.discretize(self.dt) if not controller.dt else controller
        return LoopModel(**{f: getattr(self, f) for f in (
            "Aa", "Bu", "Bw", "Br", "Ce", "Dew", "Der", "Cy", "Dyu", "Dyw", "Dyr")},
            controller=c, mask=self.mask, dt=self.dt, disturbances=self.disturbances,
            outputs=self.outputs, y0=self.y0, _cache=self._cache)

    @property
    def shape(self) -> tuple[int, ...]:
        """Grid shape (``()`` for one point)."""
        return self.Aa.shape[:-2]

    def closed_loop(self) -> tuple[NDArray, NDArray, NDArray, NDArray]:
        """``(A, B, C, D)`` of the closed loop, state ``[xi; x_c]``, inputs ``[w; r]``,
        outputs `outputs`."""
        c = self.controller
        Bu = self.Bu * self.mask
        Dyu = self.Dyu * self.mask
        n, nc = self.Aa.shape[-1], c.n
        lead = self.shape
        A = np.zeros(lead + (n + nc, n + nc))
        A[..., :n, :n] = self.Aa + Bu @ c.D @ self.Ce
        A[..., :n, n:] = Bu @ c.C
        A[..., n:, :n] = c.B @ self.Ce
        A[..., n:, n:] = c.A
        Bwr = np.concatenate([self.Bw, self.Br], -1)
        Dewr = np.concatenate([self.Dew, self.Der], -1)
        B = np.concatenate([Bwr + Bu @ c.D @ Dewr,
                            np.broadcast_to(c.B @ Dewr, lead + (nc, Bwr.shape[-1]))], -2)
        C = np.concatenate([self.Cy + Dyu @ c.D @ self.Ce, Dyu @ c.C], -1)
        D = np.concatenate([self.Dyw, self.Dyr], -1) + Dyu @ c.D @ Dewr
        return A, B, C, D

    def poles(self) -> NDArray[np.complex128]:
        """Closed-loop eigenvalues (``z``-plane), shape ``shape + (n,)``."""
        key = ("poles", self._controller_key())
        if key not in self._cache:
            self._cache[key] = np.linalg.eigvals(self.closed_loop()[0])
        return self._cache[key].copy()

    def _controller_key(self) -> bytes:
        """What the closed loop's results depend on besides the shared augmented plant: the
        controller's matrices and the output mask (a key of `_cache`, which
        `with_controller` shares)."""
        c = self.controller
        return b"".join(np.ascontiguousarray(m, float).tobytes()
                        for m in (c.A, c.B, c.C, c.D, self.mask, [c.dt]))

    def spectral_radius(self) -> NDArray[np.float64]:
        """Largest ``|z|`` of the closed loop (< 1: stable), shape `shape`."""
        return np.abs(self.poles()).max(axis=-1)

    def plant_response(self, omega: NDArray) -> NDArray[np.complex128]:
        """The augmented plant ``G = -(e / du)`` at ``z = e^(j w dt)``: shape ``shape +
        (n_w, 2, 2)`` (the sign makes ``L = K G`` the loop gain of negative feedback).

        Parameters
        ----------
        omega : ndarray, shape (n_w,)
            Angular frequencies [rad/s].
        """
        key = ("G", np.asarray(omega, float).tobytes())
        if key in self._cache:
            return self._cache[key]
        z = np.exp(1j * np.asarray(omega, float) * self.dt)
        n = self.Aa.shape[-1]
        A = self.Aa.reshape(-1, n, n)
        Bu = np.broadcast_to(self.Bu * self.mask, self.Aa.shape[:-1] + (2,)).reshape(-1, n, 2)
        Ce = np.broadcast_to(self.Ce, self.Aa.shape[:-2] + self.Ce.shape[-2:])
        Ce = Ce.reshape(-1, *self.Ce.shape[-2:])
        G = np.empty((A.shape[0], z.size, Ce.shape[-2], 2), complex)
        zI = z[:, None, None] * np.eye(n)
        # a few points a solve: the stacked matrices of a whole family (63 points x 300
        # frequencies of 43 x 43, 560 MB) cost more in fresh memory than in the solve
        step = max(1, int(_CHUNK_BYTES // (16 * z.size * n * n)))
        for i in range(0, A.shape[0], step):
            M = zI - A[i:i + step, None]
            X = np.linalg.solve(M, np.broadcast_to(Bu[i:i + step, None], M.shape[:-1] + (2,)))
            G[i:i + step] = -(Ce[i:i + step, None] @ X)
        out = G.reshape(self.Aa.shape[:-2] + G.shape[1:])
        self._cache[key] = out
        return out

    def controller_response(self, omega: NDArray) -> NDArray[np.complex128]:
        """``K(e^(j w dt))``, shape ``(n_w, 2, 2)``.

        Parameters
        ----------
        omega : ndarray, shape (n_w,)
            Angular frequencies [rad/s].
        """
        c = self.controller
        z = np.exp(1j * np.asarray(omega, float) * self.dt)
        if c.n == 0:
            return np.broadcast_to(c.D, z.shape + c.D.shape).astype(np.complex128)
        M = z[:, None, None] * np.eye(c.n) - c.A
        K = c.C @ np.linalg.solve(M, np.broadcast_to(c.B, z.shape + c.B.shape)) + c.D
        return np.asarray(K, dtype=np.complex128)

    def disk_margins(self, omega: NDArray | None = None) -> dict[str, NDArray[np.float64]]:
        """Multiloop balanced disk margins at the servo torques (``input``: ``L = K G``) and
        at the errors (``output``: ``L = G K``), and their minimum (``alpha``, 0 where the
        loop is unstable), each of shape `shape`; over `omega` [rad/s] up to the Nyquist
        frequency (default 300 points from 0.01 Hz).

        Parameters
        ----------
        omega : ndarray, shape (n_w,), optional
            Angular frequencies [rad/s] (default 300 points from 0.01 Hz to the Nyquist
            frequency).
        """
        w = default_omega(self.dt) if omega is None else np.asarray(omega, float)
        key = ("disk margins", w.tobytes(), self._controller_key())
        if key not in self._cache:  # (the design table, the claims and the map read them)
            G = self.plant_response(w)
            K = self.controller_response(w) * self.mask[None, :, None]
            a_in = disk_margin(K @ G)
            a_out = disk_margin(G @ K)
            stable = self.spectral_radius() < 1
            self._cache[key] = {"input": a_in, "output": a_out,
                                "alpha": np.where(stable, np.minimum(a_in, a_out), 0.0)}
        return {k: v.copy() for k, v in self._cache[key].items()}

    def sensitivity_peaks(self, omega: NDArray | None = None) -> dict[str, NDArray[np.float64]]:
        """Loop-at-a-time sensitivity peaks ``Ms_j = max_w |S_jj|`` of each loop, the other
        loop closed: ``S = (I + L)^-1`` at the servo torques (``input``, ``L = K G``) and at
        the errors (``output``, ``L = G K``), and the larger of the two (``ms``); for two
        loops ``S_11 = 1 / (1 + L_11 - L_12 L_21 / (1 + L_22))``, the sensitivity of loop 1
        broken with loop 2 closed.  Inf where the loop is unstable.

        Parameters
        ----------
        omega : ndarray, shape (n_w,), optional
            Angular frequencies [rad/s] (default `default_omega`, as `disk_margins`).

        Returns
        -------
        dict str -> ndarray
            ``input``, ``output``, ``ms`` [-], each of shape ``shape + (2,)`` (ratio loop,
            slip loop).
        """
        w = default_omega(self.dt) if omega is None else np.asarray(omega, float)
        G = self.plant_response(w)
        K = self.controller_response(w) * self.mask[None, :, None]
        eye = np.eye(2)
        s_in = np.abs(np.diagonal(np.linalg.inv(eye + K @ G), axis1=-2, axis2=-1)).max(-2)
        s_out = np.abs(np.diagonal(np.linalg.inv(eye + G @ K), axis1=-2, axis2=-1)).max(-2)
        stable = (self.spectral_radius() < 1)[..., None]
        return {"input": s_in, "output": s_out,
                "ms": np.where(stable, np.maximum(s_in, s_out), np.inf)}

    def loop_shapes(self, f_hz: NDArray | None = None) -> "LoopShapes":
        """The diagonal loop gains ``L_ii = (K G)_ii`` at the servo torques over frequency,
        at every point.

        Parameters
        ----------
        f_hz : array, shape (n_f,), optional
            Frequencies [Hz] (default: 150 from 0.01 Hz to 100 Hz or just below the
            Nyquist frequency, whichever is lower).

        Returns
        -------
        LoopShapes
            The frequencies and the complex gains, shape (n_points, n_f, 2).
        """
        nyq = 0.49 / self.dt
        f = np.logspace(-2, np.log10(min(100.0, nyq)), 150) if f_hz is None \
            else np.asarray(f_hz, float)
        w = 2 * np.pi * f
        G = self.plant_response(w).reshape((-1, len(w), 2, 2))
        K = self.controller_response(w) * self.mask[None, :, None]
        L = K @ G
        return LoopShapes(f, np.stack([L[..., 0, 0], L[..., 1, 1]], axis=-1))

    def predict(self, w: NDArray, r: NDArray) -> NDArray[np.float64]:
        """Outputs (deviations, ``(n_k, n_y)``) for input deviations ``w`` ``(n_k, n_w)``
        and ``r`` ``(n_k, 4)`` at the samples (one point only).

        Parameters
        ----------
        w : ndarray, shape (n_k, n_w)
            Deviations of the machine's other inputs (`disturbances`) at the samples (SI).
        r : ndarray, shape (n_k, 4)
            Deviations of the references (``r_g``, slip, ``mu``, ``dr_g/dt``) at the samples.
        """
        if self.shape:
            raise ParameterError("predict: one operating point, not a grid")
        A, B, C, D = self.closed_loop()
        v = np.concatenate([w, r], axis=1)
        x = np.zeros(A.shape[0])
        y = np.empty((len(v), C.shape[0]))
        for k in range(len(v)):
            y[k] = C @ x + D @ v[k]
            x = A @ x + B @ v[k]
        return y


@dataclass(frozen=True, eq=False)
class LoopShapes(Result):
    """Diagonal loop gains of a loop model at the servo torques (`LoopModel.loop_shapes`).

    Attributes
    ----------
    f_hz : ndarray, shape (n_f,)
        Frequencies [Hz].
    gains : ndarray of complex, shape (n_points, n_f, 2)
        ``L_ii = (K G)_ii`` [-] of the ratio loop (``T_mp``, 0) and the slip loop (``T_ms``,
        1) at every point of the model (one point: ``n_points = 1``).
    """

    f_hz: NDArray[np.float64]
    gains: NDArray[np.complex128]


@dataclass(frozen=True, eq=False)
class DiskMarginMap(Result):
    """A loop model's multiloop disk margins over a family's grid (`disk_margin_map`).

    Attributes
    ----------
    axes : dict str -> ndarray
        The family's axes (SI), in order; the margins have shape ``tuple(len(v) for v in
        axes.values())``.
    alpha : ndarray
        The smaller of `input` and `output` [-], 0 where the loop is unstable.
    input, output : ndarray
        The disk margins at the servo torques and at the errors [-].
    """

    axes: dict[str, NDArray[np.float64]]
    alpha: NDArray[np.float64]
    input: NDArray[np.float64]
    output: NDArray[np.float64]


def disk_margin_map(family: PlantFamily, loop: LoopModel) -> DiskMarginMap:
    """The disk margins of a loop model built on a family (`family_loops`), with its axes.

    Parameters
    ----------
    family : PlantFamily
        The family `loop` was built on.
    loop : LoopModel
        Stacked over the family's grid (``loop.shape == family.shape``).

    Returns
    -------
    DiskMarginMap

    Raises
    ------
    ParameterError
        When the loop model's grid is not the family's.
    """
    if loop.shape != family.shape:
        raise ParameterError(f"the loop model's grid {loop.shape} is not the family's "
                             f"{family.shape}")
    dm = loop.disk_margins()
    return DiskMarginMap(dict(family.axes), dm["alpha"], dm["input"], dm["output"])


def default_omega(dt: float) -> NDArray[np.float64]:
    """300 frequencies [rad/s], log-spaced from 0.01 Hz to just below the Nyquist
    frequency.

    Parameters
    ----------
    dt : float
        Sample period [s].

    Returns
    -------
    ndarray, shape (300,)
        ``2 pi f`` [rad/s] for f log-spaced from 0.01 Hz to ``0.49 / dt`` [Hz].
    """
    return 2 * np.pi * np.logspace(-2, np.log10(0.49 / dt), 300)


def _assemble(Phi, Gam_u, Gam_w, C_raw, D_raw_w, C_perf, D_perf_u, D_perf_w, pre):
    """The augmented plant's matrices from the discretised machine and the linearised
    pre-processing (see `LoopModel`): the servo torques are ``u_ff + du``."""
    Sz, Sy, Sr = pre["Sz"], pre["Sy"], pre["Sr"]
    Ez, Ey, Er = pre["Ez"], pre["Ey"], pre["Er"]
    Fz, Fy, Fr = pre["Fz"], pre["Fy"], pre["Fr"]
    lead = Phi.shape[:-2]
    n, ns = Phi.shape[-1], Sz.shape[-1]
    Aa = np.zeros(lead + (n + ns, n + ns))
    Aa[..., :n, :n] = Phi + Gam_u @ Fy @ C_raw
    Aa[..., :n, n:] = Gam_u @ Fz
    Aa[..., n:, :n] = Sy @ C_raw
    Aa[..., n:, n:] = Sz
    Bu = np.concatenate([Gam_u, np.zeros(lead + (ns, 2))], -2)
    Bw = np.concatenate([Gam_w + Gam_u @ Fy @ D_raw_w, Sy @ D_raw_w], -2)
    Br = np.concatenate([Gam_u @ Fr, Sr], -2)
    Ce = np.concatenate([Ey @ C_raw, Ez], -1)
    Dew = Ey @ D_raw_w
    Der = Er
    # performance outputs and the servo torques u = u_ff + du
    n_p = C_perf.shape[-2]
    Cy = np.zeros(lead + (n_p + 2, n + ns))
    Cy[..., :n_p, :n] = C_perf + D_perf_u @ Fy @ C_raw
    Cy[..., :n_p, n:] = D_perf_u @ Fz
    Cy[..., n_p:, :n] = Fy @ C_raw
    Cy[..., n_p:, n:] = Fz
    eye2 = np.broadcast_to(np.eye(2), lead + (2, 2))
    Dyu = np.concatenate([D_perf_u, eye2], -2)
    Dyw = np.concatenate([D_perf_w + D_perf_u @ Fy @ D_raw_w, Fy @ D_raw_w], -2)
    Dyr = np.concatenate([D_perf_u @ Fr, np.broadcast_to(Fr, lead + Fr.shape[-2:])], -2)
    return _prune(dict(Aa=Aa, Bu=Bu, Bw=Bw, Br=Br, Ce=Ce, Dew=Dew, Der=Der, Cy=Cy, Dyu=Dyu,
                       Dyw=Dyw, Dyr=Dyr))


def _prune(mats: dict[str, NDArray]) -> dict[str, NDArray]:
    """Drop the augmented plant's states that no output sees (structurally: no path through
    ``Aa`` to ``Ce`` or ``Cy``, at any grid point), e.g. the sensor buffers' entries beyond a
    signal's delay; the loop's responses and the eigenvalues that matter are unchanged (the
    dropped states are unobservable; their eigenvalues are the buffers' zeros)."""
    Aa = mats["Aa"]
    n = Aa.shape[-1]
    flat = lambda M: np.abs(M).reshape(-1, *M.shape[-2:]).max(axis=0) > 0  # noqa: E731
    A_nz = flat(Aa)
    seen = flat(mats["Ce"]).any(axis=0) | flat(mats["Cy"]).any(axis=0)
    while True:
        more = seen | A_nz[seen].any(axis=0)
        if more.sum() == seen.sum():
            break
        seen = more
    keep = np.flatnonzero(seen)
    if keep.size == n:
        return mats
    out = dict(mats)
    out["Aa"] = Aa[..., keep[:, None], keep]
    for k in ("Bu", "Bw", "Br"):
        out[k] = mats[k][..., keep, :]
    for k in ("Ce", "Cy"):
        out[k] = mats[k][..., :, keep]
    return out


def _check_no_feedthrough(D_raw_u: NDArray) -> None:
    if np.abs(D_raw_u).max(initial=0.0) > 1e-9:
        raise ParameterError("the loop law's measurements depend directly on the servo "
                             "torques (feedthrough): the sampled loop would be algebraic")


def loop_model(scenario: Scenario, params: Params,
               controller: Controller | None = None) -> tuple[LoopModel, LoopLaw]:
    """The linear model of a closed-loop scenario's loop at its trimmed start, and the
    (ideal) law it linearises.

    Parameters
    ----------
    scenario : Scenario
        A scenario with a ``[controller]`` table.
    params : Params
        The parameter set the start is trimmed and linearised on.
    controller : Controller, optional
        Replaces the scenario's controller file.

    Returns
    -------
    loop : LoopModel
        One point (``shape == ()``), discrete at the law's sample time, with ``y0`` the
        trim's outputs.
    law : LoopLaw
        The law without servo limits, quantisation and noise (`LoopConfig.ideal`).

    Raises
    ------
    ParameterError
        When the law's measurements depend directly on the servo torques.
    """
    model, op = scenario_model(scenario, params)
    law = build_law(scenario, params, controller, model, op)
    ideal = LoopLaw(law.controller, model, law.point, law.u0, law.config.ideal(),
                    scenario.references, scenario.duration)
    dist = tuple(n for n in model.inputs if n not in LoopLaw.commands)
    outs = ideal.measured + PERFORMANCE
    pl = linearized_plant(op, LoopLaw.commands + dist, outs)  # (no python-control object)
    A, B, C, D = (np.asarray(M) for M in (pl.A, pl.B, pl.C, pl.D))
    Phi, Gam = zoh(A, B, ideal.dt)
    nr = len(ideal.measured)
    _check_no_feedthrough(D[:nr, :2])
    mats = _assemble(Phi, Gam[:, :2], Gam[:, 2:], C[:nr], D[:nr, 2:], C[nr:], D[nr:, :2],
                     D[nr:, 2:], linear_preprocess(ideal))
    y_trim = model.evaluate(op.x, op.u)[1]
    y0 = np.concatenate([[y_trim[model.output_index(n)] for n in PERFORMANCE], op.u[:2]])
    return LoopModel(**mats, controller=ideal.controller, mask=ideal.output_mask,
                     dt=ideal.dt, disturbances=dist, outputs=PERFORMANCE + LoopLaw.commands,
                     y0=y0), ideal


def predict_scenario(scenario: Scenario, params: Params,
                     controller: Controller | None = None) -> LoopPrediction:
    """The linear prediction of a closed-loop scenario's run (`loop_model` driven by the
    scenario's inputs and references, sampled at the loop's rate).

    Parameters
    ----------
    scenario : Scenario
        A scenario with a ``[controller]`` table.
    params : Params
        The parameter set.
    controller : Controller, optional
        Replaces the scenario's controller file.

    Returns
    -------
    LoopPrediction
        ``t`` shape (n_k,) [s], from 0 to the scenario's duration at the loop's sample
        period; ``signals``: `PERFORMANCE` and ``T_mp``, ``T_ms`` [N m], each shape (n_k,),
        absolute (trim plus the linear deviation).
    """
    lm, law = loop_model(scenario, params, controller)
    model, op = scenario_model(scenario, params)
    n_k = int(round(scenario.duration / lm.dt)) + 1
    t = np.arange(n_k) * lm.dt
    sig = scenario_signals(scenario, model, op)
    w = np.zeros((n_k, len(lm.disturbances)))
    for j, name in enumerate(lm.disturbances):
        if name in sig:
            arr = sig[name]
            # right-continuous piecewise-linear value at the samples, less the trim's
            w[:, j] = reference_table({name: arr}, t)[name] - op.u[model.input_index(name)]
    r = np.zeros((n_k, 4))
    refs = law.refs
    r[:, 0] = refs.r_g[:n_k] - refs.r_g[0]
    r[:, 1] = refs.slip[:n_k] - refs.slip[0]
    r[:, 2] = refs.mu[:n_k] - refs.mu[0]
    r[:, 3] = refs.rdot[:n_k]
    y = lm.predict(w, r) + lm.y0
    return LoopPrediction(t=np.asarray(t, dtype=np.float64),
                          signals={n: y[:, i] for i, n in enumerate(lm.outputs)})


def _engine_torques(family: PlantFamily, model: EmpactModel) -> NDArray[np.float64]:
    """The engine's torque [N m] at every point of a car's family (shape ``family.shape``):
    the family's own trim (`trim_grid` at its slips and clamping forces) again, whose input
    ``T_d`` the law's torque source reads at rest (a family records the operating variables,
    not the inputs)."""
    op = family.operating
    g = trim_grid(model, op["r_g"].ravel(), op["omega_p"].ravel(), nu=op["nu"].ravel(),
                  F_s=op["F_s"].ravel())
    T_d = np.where(g.ok, g.u[:, model.input_index("T_d")], np.nan)
    return T_d.reshape(family.shape)


def family_loops(family: PlantFamily, controller: Controller, config: LoopConfig,
                 params: Params, model: EmpactModel | None = None) -> LoopModel:
    """The loop model at every point of `family` (which must hold the `RAW_SIGNALS` and
    `PERFORMANCE` outputs: ``plant_family(..., outputs=LOOP_FAMILY_OUTPUTS)``) for
    `controller` under `config` (its ideal version), references held at each point.

    Parameters
    ----------
    family : PlantFamily
        Every point trimmed, with the outputs `LOOP_FAMILY_OUTPUTS`.
    controller : Controller
        The controller (continuous: discretised by the law at the loop's rate).
    config : LoopConfig
        The loop configuration; its ideal version (no limits, quantisation or noise) is
        linearised.
    params : Params
        The parameter set the law knows.
    model : EmpactModel, optional
        The machine's model (default: `nonlinear_model` with the family's options).

    Returns
    -------
    LoopModel
        Stacked over the grid (``shape == family.shape``), discrete at the loop's sample
        time; ``y0`` empty.

    Raises
    ------
    ParameterError
        When the family lacks outputs the loop needs, has points that did not trim, or the
        measurements depend directly on the servo torques.
    """
    if model is None:
        model = nonlinear_model(params, **family.options)
    signals = measured_signals(model.vehicle, config.spec)
    missing = [n for n in signals + PERFORMANCE if n not in family.outputs]
    if missing:
        raise ParameterError(f"the family lacks the outputs {', '.join(missing)} the loop "
                             "needs: build it with plant_family(..., outputs="
                             "LOOP_FAMILY_OUTPUTS)")
    if not np.all(family.ok):
        raise ParameterError("the family has points that did not trim")
    cfg = config.ideal()
    dt = cfg.dt
    ii = [family.inputs.index(n) for n in LoopLaw.commands]
    dist = tuple(n for n in family.inputs if n not in LoopLaw.commands)
    jj = [family.inputs.index(n) for n in dist]
    ro = [family.outputs.index(n) for n in signals]
    po = [family.outputs.index(n) for n in PERFORMANCE]
    Phi, Gam = zoh(family.A, family.B[..., ii + jj], dt)
    shape = family.shape
    C, D = family.C, family.D
    _check_no_feedthrough(D[..., ro, :][..., :, ii])
    pre: dict[str, NDArray] = {}
    ctrl = None
    mask = None
    T_d = _engine_torques(family, model) if model.vehicle else None
    for idx in np.ndindex(*shape):
        point = {k: float(family.operating[k][idx]) for k in ("r_g", "nu", "omega_p", "T_l",
                                                            "F_s")}
        if T_d is not None:
            point["T_d"] = float(T_d[idx])
        law = LoopLaw(controller, model, point, np.zeros(2), cfg)
        p = linear_preprocess(law)
        for k, v in p.items():
            pre.setdefault(k, np.empty(shape + v.shape))[idx] = v
        ctrl, mask = law.controller, law.output_mask
    assert ctrl is not None and mask is not None  # a family has one point at least
    mats = _assemble(Phi, Gam[..., :2], Gam[..., 2:], C[..., ro, :],
                     D[..., ro, :][..., :, jj], C[..., po, :], D[..., po, :][..., :, ii],
                     D[..., po, :][..., :, jj], pre)
    return LoopModel(**mats, controller=ctrl, mask=mask, dt=dt, disturbances=dist,
                     outputs=PERFORMANCE + LoopLaw.commands, y0=np.zeros(0))


#: the clamping feedforward and the decoupler as the law computes them (`empact.control.law`,
#: module notes), for the design record
_FEEDFORWARD_FORMULA = (
    "F_ff = feedforward_gain * T * cos(beta) / (2 * traction_error * mu(nu*, r_g*) * "
    "R_s(r_g)), T the feedforward_signal (plus J_s omega_p dr*/dt with shift_feedforward), "
    "R_s the secondary running radius at the measured ratio; through a first-order low-pass "
    "at feedforward_filter_hz; T_ms += tpf * (F_ff - F_ff at the start), tpf = i_e s "
    "sheave_sense / i_c")
_DECOUPLER_FORMULA = (
    "T_mp += LP(d * (T_ms,pre - T_ms at the start)), d = T_mp* / T_ms* (the holding torques "
    "at the reference ratio), LP a first-order low-pass at decoupling_filter_hz; T_ms,pre the "
    "secondary servo torque before the controller's share")
_SCHEDULE_POINT = (
    "r_g: the measured ratio; tau: mu(nu*, r_g*) / mu_max(r_g*); F_s: the clamping "
    "feedforward's filtered force F_ff (under the safety-factor clamping its force, at least "
    "min_clamping; the start's clamping force with neither)")


def loop_specification(config: LoopConfig) -> dict[str, Any]:
    """The whole specification of the loop a controller runs in, as plain data (a design
    record's ``loop``): every ``[controller]`` key of the loop (`ControllerSpec` but the
    file), the feedforward's and the decoupler's formulas, the sample delay and the counting
    window, the sensors and the servo limits.

    Parameters
    ----------
    config : LoopConfig
        The loop (a scenario's, or `LoopConfig.of` the shipped one).

    Returns
    -------
    dict
        ``rate_hz`` [Hz], ``feedforward`` (bool), ``feedforward_filter_hz`` [Hz],
        ``sensors`` (bool: the sensors are modelled), ``controller`` (the `ControllerSpec`
        fields but ``file``), ``feedforward_formula``, ``decoupler_formula``,
        ``schedule_point`` (str), ``discretization`` (``"tustin"``), ``delay_samples``,
        ``speed_window_samples`` (ints), ``sensor_params`` and ``servo_limits`` (their
        fields, SI, or None), ``holding_torques`` (how they are found).
    """
    spec = config.spec
    dt = config.dt
    s = config.sensors
    return {"rate_hz": spec.rate, "feedforward": spec.feedforward,
            "feedforward_filter_hz": spec.feedforward_filter_hz,
            "sensors": s is not None,
            "controller": {k: v for k, v in asdict(spec).items() if k != "file"},
            "feedforward_formula": _FEEDFORWARD_FORMULA,
            "decoupler_formula": _DECOUPLER_FORMULA,
            "schedule_point": _SCHEDULE_POINT,
            "discretization": "tustin",
            "delay_samples": int(s.delay) if s is not None else 0,
            "speed_window_samples": max(1, int(round(s.speed_window / dt)))
            if s is not None else 1,
            "sensor_params": None if s is None else asdict(s),
            "servo_limits": None if config.limits is None else asdict(config.limits),
            "holding_torques": "the trim's servo torques at the operating point (the "
                               "controller's integrators start at them, less the "
                               "feedforward's share)"}


#: the operating variables `controller_at` accepts
_POINT_KEYS = ("r_g", "nu", "tau", "F_s", "omega_p", "T_l")


def controller_at(controller: Controller, config: LoopConfig, params: Params,
                  point: Mapping[str, float], **options: Any) -> Controller:
    """The controller folded at an operating point, discrete at the loop's rate, with the
    loop that runs there: the schedule's gains at that point (where the law reads them,
    `LoopLaw.at_rest`) folded into B and D, discretised as the law does (Tustin), and in its
    ``design["loop_plant"]`` the augmented plant of the loop model at the point
    (`family_loops`: the machine held and sampled, with the sensors and feedforwards closed
    inside) from the servo-torque deviations ``du`` to the errors ``e``; closing ``du = K e``
    around it (positive feedback: ``e = P du``) gives the closed-loop poles `family_loops`
    computes there.

    Parameters
    ----------
    controller : Controller
        Continuous, scheduled or not.
    config : LoopConfig
        The loop it runs in.
    params : Params
        The parameter set.
    point : mapping of str to float
        Two of ``nu`` (or ``tau``), ``F_s``, ``T_l``, with ``r_g`` and optionally
        ``omega_p`` (SI); what is not given comes from ``params.operating``.
    **options
        `empact.nonlinear.model.ModelOptions` fields of the plant (default the design
        family's, `empact.control.family.BENCH_OPTIONS`).

    Returns
    -------
    Controller
        Discrete (``dt = 1 / rate``), without a schedule; its ``design`` adds ``point``
        (the operating point, SI), ``loop`` (`loop_specification` of `config`),
        ``at_rest`` (`LoopLaw.at_rest`), ``schedule_gains`` and ``loop_plant`` (``A``,
        ``B``, ``C`` of ``P`` and its names).

    Raises
    ------
    ParameterError
        For an unknown operating variable or a point that does not trim.
    """
    bad = [k for k in point if k not in _POINT_KEYS]
    if bad:
        raise ParameterError(f"operating point: {', '.join(bad)} unknown; give r_g and two "
                             f"of nu (or tau), F_s, T_l ({', '.join(_POINT_KEYS)})")
    values: dict[str, Any] = {k: float(v) for k, v in point.items()}
    fam = plant_family(params, outputs=LOOP_FAMILY_OUTPUTS, **options, **values)
    if not fam.ok.all():
        raise ParameterError(f"operating point {dict(point)}: does not trim "
                             f"({fam.reason.ravel()[0]})")
    model = nonlinear_model(params, **fam.options)
    op = {k: float(np.ravel(fam.operating[k])[0]) for k in ("r_g", "nu", "omega_p", "T_l",
                                                             "F_s")}
    rest = LoopLaw(controller, model, op, np.zeros(2), config.ideal()).at_rest()
    gains = (np.ones(len(controller.measured)) if controller.schedule is None
             else controller.schedule(rest["schedule_point"]))
    folded = Controller(controller.A, controller.B * gains, controller.C,
                        controller.D * gains, controller.measured, controller.outputs,
                        0.0, controller.method)
    lm = family_loops(fam, folded, config, params, model)
    Aa = lm.Aa.reshape(lm.Aa.shape[-2:])
    Bu = (lm.Bu * lm.mask).reshape(lm.Bu.shape[-2:])
    Ce = lm.Ce.reshape(lm.Ce.shape[-2:])
    k = lm.controller
    design = {**dict(controller.design),
              "point": {kk: float(np.ravel(v)[0]) for kk, v in fam.operating.items()},
              "loop": loop_specification(config), "discretized": "tustin", "at_rest": rest,
              "schedule_gains": [float(g) for g in gains],
              "loop_plant": {"A": Aa, "B": Bu, "C": Ce, "dt": lm.dt,
                             "inputs": list(k.outputs), "outputs": list(k.inputs),
                             "closing": "du = K e, e = P du (positive feedback of K and "
                                        "P = ss(A, B, C, 0, dt)); the poles are the loop "
                                        "model's (empact.control.loop.family_loops)"}}
    return Controller(k.A, k.B, k.C, k.D, k.measured, k.outputs, k.dt, k.method, design)
