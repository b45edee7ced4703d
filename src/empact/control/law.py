"""The sampled loop law that runs on the machine: sensors, references, controller, clamping
feedforward, servo limits and anti-windup, as one state-space update.

At each sample ``k`` (period ``dt = 1 / rate``) the law

1. **senses** (`empact.control.hardware.SensorParams`): the ratio ``r_g``, the shaft speeds
   ``omega_p``, ``omega_s``, the driveshaft torque ``T_ds`` and the servo speeds, each
   ``delay`` samples late; the shaft speeds as counting encoders give them (the mean over
   ``speed_window``, quantised), with the configured noise (seeded);
2. computes the **slip** from the speeds, ``nu = 1 - omega_s / (r_g omega_p)`` (``nu_r`` on
   the reference ratio), and the tracking errors ``e = reference - measured`` (of their
   logarithms for ``ln_`` signals);
3. runs the **controller** (`empact.control.controller.Controller`, discretised by Tustin at
   the rate when continuous): ``x_c' = A x_c + B e``, ``du = C x_c + D e``;
4. adds the **clamping feedforward** (``feedforward``): the secondary servo torque that holds
   the set-point's traction coefficient at the measured driveshaft torque and ratio,
   ``T_ms,ff = (i_e s / i_c) T_ds cos(beta) / (2 mu_hat R_s(r_g))`` with ``mu_hat =
   traction_error * mu(nu*, r_g*)`` (``feedforward_signal``: the driveshaft torque a bench
   measures, the load motor's torque, or, with no torque sensor, an engine-torque estimate:
   the torque of the machine's torque source as its controller reports it,
   ``sensors.engine_torque_delay`` late and ``1 + sensors.engine_torque_error`` times the
   truth; on the test bench the source is the load motor, which sets the torque the belt
   carries as a car's engine does) (times ``feedforward_gain``: below 1 it leaves the belt
   part of its damping of the driveshaft mode, which a full feedforward of the driveshaft
   torque cancels; with ``feedforward_gain_table``, the integral of the table's gain over
   the full force ``F_full = T_ds cos(beta) / (2 mu_hat R_s)``, so that a change of load
   sees the table's gain at that load: lower at light load, where the full gain destabilises
   the loop in overdrive), through a first-order low-pass at
   ``feedforward_filter_hz`` (below the clamping mode near 9.5 Hz); or, with ``clamping =
   "safety-factor"``, the open-loop clamping of a production CVT (the slip loop off):
   ``F_s = SF T_l cos(beta) / (2 mu_design R_s)``, ``mu_design`` the smallest traction peak
   over the ratio range (``mu_design = "ratio-blind"``) or the peak at the measured ratio
   (``"ratio-aware"``), ``T_l`` the driveshaft torque on the bench and in the car the
   engine's torque at the secondary as its controller reports it (`CAR_SOURCE`), in the car
   plus the engine's inertia torque of an upshift at the reference's rate; that torque
   held: up at once, down as a first-order lag of ``clamping_release`` (a tip-out's torque
   still passes the belt while the driveline unwinds); the gain schedule's ``F_s`` is then
   this clamping (at least ``min_clamping``);
5. with ``decoupling``, makes the primary servo torque follow the feedforward's clamping:
   ``T_mp += d LP(T_ms,ff - T_ms,ff*)`` with ``d = T_mp* / T_ms*`` the ratio of the holding
   torques at the reference ratio (`empact.nonlinear.equilibrium.trim_grid`) and ``LP`` a
   first-order low-pass at ``decoupling_filter_hz`` (below the 17 Hz actuation mode, which
   a fast primary servo torque excites).  With equal translation the
   primary servo holds the thrust difference ``F_p - F_s`` (``T_mp = (i_e s / i_w) (F_p -
   F_s)`` at rest): a clamping change at a held primary torque changes the thrust ratio and
   the belt creeps to another ratio (and, on a bench, the ratio change accelerates the
   dynamometers); scaling both servo torques together keeps the thrust ratio;
6. with ``shift_feedforward``, adds the primary servo torque that makes the creep law shift
   at the reference's ratio rate (``dr*/dt`` over ``omega K_c``, the inverse of the
   unsaturated creep law at the reference ratio; `empact.variator.shift_law`) and the
   clamping for the secondary side's acceleration (``J_s omega_p dr*/dt`` of belt torque);
7. **limits** each servo torque (`empact.control.hardware.ServoLimits`: the torque limit, and
   the speed limiter) and feeds the difference back to the controller state (observer-form
   anti-windup, Astrom & Wittenmark, *Computer-Controlled Systems*, 3rd ed., Sec. 9.4:
   ``x_c' = A x_c + B e + L (u_applied - u_controller)``, ``L`` the steady Kalman gain of
   the controller's ``(A, C)``, so that ``A - L C`` is stable);
8. with ``torque_request``, protects a saturating secondary servo: it requests at most the
   torque the servo can clamp for, ``T_request = F_cap 2 mu_hat R_s(r_g) / cos(beta)``
   (secondary shaft; ``r_g T_request`` at the engine), ``F_cap`` the clamping the servo's
   torque limit holds with ``torque_request_margin`` of it kept for the slip loop; honoured
   (``"honoured"``) the bench's load torque follows it, ``|T_l| <= T_request``, as an engine
   honours a transmission's torque request.  The controller knows its servo's limit, the
   measured ratio and its own traction estimate: no other sensor.

The servo torques are the trim's holding torques plus these terms: the controller starts in
its steady state at the trim (its integrators hold the holding torques less the
feedforward's share at the trim, computed with the feedforward's own traction estimate).

`LoopLaw.update` is a pure function of the law's state (a flat vector: sensor buffers,
feedforward filter, decoupler filter, controller state), the raw measurements and the sample
index; `step` is the stateful `empact.nonlinear.simulation.SampledController` interface around
it, and `empact.control.loop` linearises its pre-processing (`preprocess`) for the loop's
linear model.  All three run the one compiled sample (`empact.control._law_core.sample` and
`pre`; the constants, per-sample tables and work arrays handed over as the named
`LawConstants`, `LawTables` and `LawWork`), the safety-factor clamping and the moving shift
feedforward included (their model calls are the kernel's compiled traction peak and creep
law); `run_compiled` runs it with the integrator in one compiled loop
(`empact.control._loop_core`).
"""
from __future__ import annotations

import functools
import hashlib
from collections import OrderedDict
from dataclasses import dataclass, fields, replace
from typing import Any, Mapping

import numpy as np
from numba import typeof
from numpy.typing import NDArray

from .._lazy import lazy_module
from ..errors import ParameterError
from ..hardware import SPEED_BAND, SensorParams, ServoLimits
from ..nonlinear.equilibrium import (
    slip_at_torque_ratio,
    smallest_slip_reserve,
    traction_peak,
    trim_grid,
)
from ..nonlinear.model import EmpactModel
from ..nonlinear.scenario import ControllerSpec, Scenario, check_reference_names
from ..nonlinear.simulation import SampledLoop
from ..params import Params
from ..variator.geometry import ratio_range, secondary_radius, variator_state
from . import _law_core as core
from . import _loop_core
from .controller import Controller

linalg = lazy_module("scipy.linalg")

__all__ = ["LoopConfig", "LoopLaw", "RAW_SIGNALS", "SHIPPED_LOOP", "measured_signals",
           "reference_table"]

_pre: Any = core.pre  # (numba's Dispatcher is typed without a call signature)
_run_samples: Any = _loop_core.run_samples


def _entry(dispatcher: Any, *args: Any) -> Any:
    """The compiled overload of `dispatcher` for the types of `args` (compiled or loaded from
    numba's cache once), to be called without numba's per-call type dispatch (typing a
    `_law_core.Law` costs about 2 us a call, two thirds of a sample).  It does not check its
    arguments: the caller passes arrays of exactly these types and shapes (`LoopLaw._raw`)."""
    return dispatcher.compile(tuple(typeof(a) for a in args))


def _unique_rows(*columns: NDArray) -> tuple[NDArray[np.float64], NDArray[np.intp]]:
    """``np.unique(np.column_stack(columns), axis=0, return_inverse=True)`` (the distinct
    rows, sorted, and each row's index among them), computed on the first row of each run of
    equal rows: a reference table holds a few values for thousands of samples, and sorting
    every sample's row cost about 1 ms a column pair; sorted by `numpy.lexsort` (the rows'
    own structured sort, which ``np.unique(axis=0)`` runs, took 14 ms for a shift's 10 000
    distinct rows, the lexical sort 2 ms)."""
    rows = np.column_stack(columns)
    start = np.ones(len(rows), dtype=bool)
    start[1:] = np.any(rows[1:] != rows[:-1], axis=1)
    first = rows[start]
    order = np.lexsort(first.T[::-1])  # by the first column, then the next, ...
    ranked = first[order]
    new = np.ones(len(ranked), dtype=bool)
    new[1:] = np.any(ranked[1:] != ranked[:-1], axis=1)
    inv = np.empty(len(ranked), dtype=np.intp)
    inv[order] = np.cumsum(new) - 1
    return ranked[new], inv[np.cumsum(start) - 1]


def _no_geometry(r_g: float) -> ParameterError:
    """A sample's refusal (`LoopLaw.update`, the compiled sample): the clamping feedforward
    finds no belt geometry at the measured ratio `r_g`."""
    return ParameterError(f"r_g = {r_g:g}: no belt geometry at this ratio")


#: the loop of the shipped scenarios and designs (`ControllerSpec` keys): the clamping
#: feedforward of the driveshaft torque at 0.9 of it above 8 kN of full feedforward force,
#: 0.5 below 4 kN (linear between; at light load in overdrive the feedforward at 0.9
#: destabilises the loop, issue 33), unfiltered but for noise, and the primary servo
#: following it through a 5 Hz low-pass (see the module notes)
SHIPPED_LOOP = {"feedforward": True, "feedforward_gain": 0.9,
                "feedforward_gain_table": ((0.0, 0.5), (4000.0, 0.5), (8000.0, 0.9)),
                "feedforward_filter_hz": 100.0, "decoupling": True, "decoupling_filter_hz": 5.0}

#: what the law reads from the machine, in this order (model outputs)
RAW_SIGNALS = ("r_g", "omega_p", "omega_s", "T_ds", "omega_mp", "omega_ms", "T_l_act")
#: the torque source's signal (`RAW_SIGNALS`' last) in the car: the engine's torque referred
#: to the secondary as its controller reports it (the bench's is the load motor's, T_l_act)
CAR_SOURCE = "T_d_sec"
#: what the driveshaft-torque observer (``feedforward_signal = "T_ds_est"``) reads after
#: `RAW_SIGNALS`: the wheel (load) speed, which a car's wheel-speed sensors give
OBSERVER_SIGNAL = "omega_l"
_SPEEDS = (1, 2)  # RAW_SIGNALS indices counted by encoders


def _reads_observer(spec: ControllerSpec) -> bool:
    """Whether a law of `spec` runs the driveshaft-torque observer (its feedforward's signal)."""
    return spec.feedforward and spec.feedforward_signal == "T_ds_est"


def measured_signals(vehicle: bool, spec: ControllerSpec) -> tuple[str, ...]:
    """The signals a law of `spec` reads at each sample (`LoopLaw.measured`): `RAW_SIGNALS`,
    in the car (`vehicle`) with the engine's torque `CAR_SOURCE` as the torque source's,
    then `OBSERVER_SIGNAL` where the law runs the driveshaft-torque observer.

    Parameters
    ----------
    vehicle : bool
        The machine is in the car (``driveline = "vehicle"``).
    spec : ControllerSpec
        The loop's ``[controller]`` keys.

    Returns
    -------
    tuple of str
        The model outputs, in the order the law reads them.
    """
    raw = RAW_SIGNALS if not vehicle else RAW_SIGNALS[:-1] + (CAR_SOURCE,)
    return raw + ((OBSERVER_SIGNAL,) if _reads_observer(spec) else ())


@dataclass(frozen=True)
class LoopConfig:
    """How the law runs: a scenario's ``[controller]`` table (`ControllerSpec`) with the
    servo limits and sensors resolved (the parameter set's ``[servo]`` and ``[sensors]``
    under the scenario's ``[limits]`` and ``[sensors]``).

    Attributes
    ----------
    spec : ControllerSpec
    limits : ServoLimits or None
        None: no servo limits.
    sensors : SensorParams or None
        None: ideal sensors (no delay, counting window, quantisation or noise).
    quantise : bool
        Quantise the measurements (False: the delay and counting window only).
    """

    spec: ControllerSpec
    limits: ServoLimits | None = None
    sensors: SensorParams | None = None
    quantise: bool = True

    @property
    def dt(self) -> float:
        """Sample period [s]."""
        return 1.0 / self.spec.rate

    @classmethod
    def for_scenario(cls, scenario: Scenario, params: Params) -> "LoopConfig":
        """The loop of a closed-loop scenario on the parameter set.

        Parameters
        ----------
        scenario : Scenario
            A closed-loop scenario (with a ``[controller]`` table; its ``[limits]`` and
            ``[sensors]`` override the parameter set's key by key).
        params : Params
            The parameter set (its ``[servo]`` and ``[sensors]`` sections).
        """
        spec = scenario.controller
        if spec is None:
            raise ParameterError(f"scenario {scenario.name!r} has no [controller] table")
        return cls(spec, replace(params.servo, **scenario.limits) if spec.limits else None,
                   replace(params.sensors, **scenario.sensors) if spec.sensors else None)

    @classmethod
    def of(cls, params: Params, **spec: Any) -> "LoopConfig":
        """A loop on the parameter set's servos and sensors with the `ControllerSpec` keys
        `spec` (no file: for design and analysis).

        Parameters
        ----------
        params : Params
            The parameter set (its ``[servo]`` and ``[sensors]`` sections).
        **spec : Any
            `ControllerSpec` fields (a scenario's ``[controller]`` keys but ``file``).
        """
        sp = ControllerSpec(file="", **spec)
        return cls(sp, params.servo if sp.limits else None,
                   params.sensors if sp.sensors else None)

    def ideal(self) -> "LoopConfig":
        """The same loop without limits, quantisation and noise (the delay and the counting
        window, which are linear, stay): what `empact.control.loop` linearises."""
        if self.sensors is None:
            return replace(self, limits=None, quantise=False)
        s = replace(self.sensors, speed_noise=0.0, ratio_quantum=0.0, torque_noise=0.0)
        return replace(self, limits=None, sensors=s, quantise=False)


def reference_table(references: Mapping[str, NDArray], t: NDArray) -> dict[str, NDArray]:
    """Piecewise-linear references ``{name: [[t, v], ...]}`` at times `t` (right-continuous:
    a repeated time is a step; held before the first and after the last point).

    Parameters
    ----------
    references : dict str -> ndarray, shape (k, 2)
        Each reference as rows ``[t, value]`` (times [s] non-decreasing; values in the
        reference's units, e.g. ``r_g`` [-], ``nu`` [-]).
    t : ndarray, shape (n_t,)
        Times to evaluate at [s].

    Returns
    -------
    dict str -> ndarray, shape (n_t,)
        Each reference's value at `t`, by name.
    """
    out = {}
    tt = np.asarray(t, float)
    for name, arr in references.items():
        ts, vs = arr[:, 0], arr[:, 1]
        n = len(ts)
        i = np.clip(np.searchsorted(ts, tt, side="right") - 1, 0, max(n - 2, 0))
        j = np.minimum(i + 1, n - 1)
        span = ts[j] - ts[i]
        frac = np.divide(tt - ts[i], span, out=np.ones_like(tt), where=span > 0)
        out[name] = np.where(tt < ts[0], vs[0], np.where(tt >= ts[-1], vs[-1],
                                                          vs[i] + (vs[j] - vs[i]) * frac))
    return out


def _antiwindup_gain(A: NDArray, C: NDArray) -> NDArray:
    """Observer gain ``L`` of the discrete controller ``(A, C)``: the steady Kalman gain for
    unit state and output noise (``A - L C`` stable whenever ``(A, C)`` is detectable);
    solved once per controller (a Monte Carlo builds a law per run of one controller)."""
    A, C = np.ascontiguousarray(A, float), np.ascontiguousarray(C, float)
    return _antiwindup_solved(A.shape, C.shape, A.tobytes(), C.tobytes()).copy()


@functools.lru_cache(maxsize=32)
def _antiwindup_solved(a_shape: tuple[int, ...], c_shape: tuple[int, ...], a: bytes,
                       c: bytes) -> NDArray:
    """`_antiwindup_gain` of the matrices given by their shapes and bytes (cached)."""
    A, C = np.frombuffer(a).reshape(a_shape), np.frombuffer(c).reshape(c_shape)
    n, m = A.shape[0], C.shape[0]
    if n == 0:
        return np.zeros((0, m))
    P = linalg.solve_discrete_are(A.T, C.T, np.eye(n), np.eye(m))
    return A @ P @ C.T @ np.linalg.inv(C @ P @ C.T + np.eye(m))


#: a reference that moves through at least this many distinct ratios prepares its slips and
#: holding torques on a grid of ratios (`_rising_slips`, `_on_ratio_grid`): fewer, at each
#: ratio (a load step's few ratios; a shift's thousands cost about 20 ms of CPU a thousand)
_GRID_MIN = 256
#: the grid's spacing in ``ln r_g`` for the slips' first guesses (`_rising_slips`) and for
#: the interpolated holding torques (`_on_ratio_grid`), and the nodes of each interpolating
#: polynomial (`_interpolate`: quintic)
_GUESS_STEP, _GRID_STEP, _POINTS = 1.0 / 64, 1.0 / 256, 6
#: the interpolated holding torques' ratio: its estimated error's bound, relative to its
#: largest magnitude (it scales a filtered change of the feedforward's torque: an error of
#: 1e-11 moves the primary servo torque by less than 1e-11 of its range, against the 1e-10
#: of a run's golden comparison and the 1e-6 a change of the law makes)
_GRID_RTOL = 1e-11
#: the polished slips' certified bound relative to the slip (`_polish_rising`)
_SLIP_RTOL = 1e-13
#: secant steps of `_polish_rising` at most (from the shipped shifts' guesses, within 2e-6
#: of the slip, the last ratio settles after 8: 12 evaluations of the curve in all)
_POLISH_STEPS = 10


def _ratio_nodes(r: NDArray, step: float) -> NDArray[np.float64]:
    """An odd number (at least 11: every other one at least `_POINTS`) of ratios uniform in
    ``ln r_g`` from ``min(r)`` to ``max(r)`` (both exactly), at most `step` apart in
    ``ln r_g``."""
    lo, hi = float(np.min(r)), float(np.max(r))
    n = 2 * max(int(np.ceil((np.log(hi) - np.log(lo)) / (2 * step))), _POINTS - 1) + 1
    q = np.exp(np.linspace(np.log(lo), np.log(hi), n))
    q[0], q[-1] = lo, hi
    return q


def _interpolate(q: NDArray, v: NDArray, r: NDArray) -> NDArray[np.float64]:
    """The values `v` at the ratios `q` (uniform in ``ln r_g``, at least `_POINTS`)
    interpolated at the ratios `r` (inside them): the polynomial through the `_POINTS` nodes
    around each ratio (Lagrange's form), in ``ln r_g`` (error ``O(h^6)`` on a smooth curve,
    ``h`` the nodes' spacing)."""
    lq, x = np.log(q), np.log(r)
    h = (lq[-1] - lq[0]) / (len(q) - 1)
    first = _POINTS // 2 - 1  # the nodes i - first ... i - first + _POINTS - 1
    i = np.clip(np.floor((x - lq[0]) / h).astype(np.intp), first, len(q) - _POINTS + first)
    s = (x - lq[i]) / h
    offsets = range(-first, _POINTS - first)
    out = np.zeros(np.shape(r))
    for j in offsets:
        w = np.ones(np.shape(r))
        for k in offsets:
            if k != j:
                w *= (s - k) / (j - k)
        out += w * v[i + j]
    return out


def _polish_rising(model: EmpactModel, r: NDArray, goal: NDArray,
                   guess: NDArray) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    """The slip where the traction curve at `r` reaches `goal` on its rising branch, by
    secant steps from `guess` (close to it), and whether it is certified: the curve lies below
    `goal` at ``(1 - _SLIP_RTOL)`` of the slip and reaches it at ``(1 + _SLIP_RTOL)`` (so
    the slip is within `_SLIP_RTOL` of the rising branch's crossing, which
    `empact.nonlinear.equilibrium.slip_at_torque_ratio` bisects to rounding; the curve is
    unimodal, rising before its peak).  Arrays of one shape; slips [-]."""
    x0, x1 = guess, guess * (1 + 1e-6)
    f0, f1 = model.traction(x0, r) - goal, model.traction(x1, r) - goal
    live = np.ones(r.shape, dtype=bool)
    for _ in range(_POLISH_STEPS):
        live &= (f1 != f0) & (f1 != 0)
        if not live.any():
            break
        x2 = np.where(live, x1 - f1 * (x1 - x0) / np.where(live, f1 - f0, 1.0), x1)
        live &= x2 != x1
        x0, f0, x1 = x1, f1, x2
        f1 = model.traction(x1, r) - goal
    ok = (np.isfinite(x1) & (x1 > 0)
          & (model.traction(x1 * (1 - _SLIP_RTOL), r) < goal)
          & (model.traction(x1 * (1 + _SLIP_RTOL), r) >= goal))
    return x1, ok


def _rising_slips(model: EmpactModel, tau: float, r: NDArray) -> NDArray[np.float64]:
    """`empact.nonlinear.equilibrium.slip_at_torque_ratio` at one torque ratio `tau` [-]
    and the ratios `r` (1-D) [-]: at fewer than `_GRID_MIN` ratios that function itself (a
    traction-peak search and a bisection at each ratio); at more, its slips at ratios
    `_GUESS_STEP` apart in ``ln r_g`` interpolated (`_interpolate`) and polished at each ratio
    (`_polish_rising`: within `_SLIP_RTOL` of the bisection's, certified; where not, the
    bisection's).  About 12 traction evaluations a ratio against the search's 157."""
    if r.size < _GRID_MIN:
        return slip_at_torque_ratio(model, tau, r)
    q = _ratio_nodes(r, _GUESS_STEP)
    guess = _interpolate(q, slip_at_torque_ratio(model, tau, q), r)
    nu, ok = _polish_rising(model, r, tau * model.mu_max(r), guess)
    if not ok.all():
        nu[~ok] = slip_at_torque_ratio(model, tau, r[~ok])
    return nu


def _on_ratio_grid(values_at: Any, r: NDArray) -> NDArray[np.float64] | None:
    """``values_at(r)`` (a smooth function of the ratio, 1-D arrays) interpolated
    (`_interpolate`) from its values at ratios `_GRID_STEP` apart in ``ln r_g`` spanning `r`
    (1-D), or None: when the grid is not smaller than half of `r`, when ``values_at``
    returns None at the grid, or when the error is not estimated below `_GRID_RTOL` of the
    largest value.  The estimate: four times the largest miss of the polynomials through
    every other node at the nodes between (those through all nodes, the ones used, miss by
    ``2^-6`` of that on a smooth curve, by up to 1.7 times it at a kink, a jump of the
    slope, over the kink's place between the nodes: `tests/test_loop.py`).  An estimate,
    not a bound: a feature narrower than the nodes' spacing can hide between them."""
    q = _ratio_nodes(r, _GRID_STEP)
    if 2 * q.size > r.size:
        return None
    v = values_at(q)
    if v is None:
        return None
    miss = np.max(np.abs(_interpolate(q[::2], v[::2], q[1::2]) - v[1::2]))
    if not 4 * miss <= _GRID_RTOL * np.max(np.abs(v)):
        return None
    return _interpolate(q, v, r)


#: the references of the last laws built (`LoopLaw._cached_references`), by a digest of
#: what they are computed from
_REFERENCES: "OrderedDict[bytes, tuple[_Refs, float]]" = OrderedDict()


@dataclass(frozen=True, eq=False)
class _Refs:
    """References on the sample grid: ratio, slip set-point, its traction coefficient, the
    ratio reference's rate."""

    r_g: NDArray[np.float64]
    slip: NDArray[np.float64]
    mu: NDArray[np.float64]
    rdot: NDArray[np.float64]
    decoupling: NDArray[np.float64]
    slip_lo: NDArray[np.float64]
    mu_lo: NDArray[np.float64]


class LoopLaw:
    """The loop law of the module notes, with the step interface of
    `empact.nonlinear.simulation.SampledController`.

    Parameters
    ----------
    controller : Controller
        From the errors of ``r_g`` and a slip signal (``nu``, ``nu_r``, or ``ln_`` of them)
        to ``T_mp``, ``T_ms``; continuous (discretised by Tustin at the rate) or discrete at
        the rate.
    model : EmpactModel
    point : mapping
        The operating point the loop starts at: ``r_g``, ``nu``, ``omega_p``, ``T_l``
        (``T_ds`` at rest), ``F_s``.
    u0 : array, shape (2,)
        The servo torques that hold it [N m].
    config : LoopConfig
    references : dict name -> array (k, 2), optional
        ``r_g`` and one of ``nu``, ``nu_r``, ``tau``; a signal not given holds the point's
        value.
    duration : float
        Length of the run [s] (the references and noise are prepared for it).
    load : array (k, 2), optional
        The bench's load-torque demand ``[[t, T_l], ...]`` [s, N m] that an honoured torque
        request (``torque_request = "honoured"``) limits (default: the point's ``T_l``
        held); the law then commands ``T_l`` too.
    """

    commands: tuple[str, ...] = ("T_mp", "T_ms")
    _c: core.LawConstants
    _tb: core.LawTables
    _wk: core.LawWork
    _tau_ref: float

    def __init__(self, controller: Controller, model: EmpactModel, point: Mapping[str, float],
                 u0: NDArray, config: LoopConfig,
                 references: Mapping[str, NDArray] | None = None,
                 duration: float = 0.0, load: NDArray | None = None) -> None:
        self.config = cfg = config
        self.dt = dt = cfg.dt
        spec = cfg.spec
        if controller.outputs != ("T_mp", "T_ms"):
            raise ParameterError(f"controller outputs {controller.outputs}: must drive T_mp, "
                                 "T_ms")
        cd = controller.discretize(dt) if not controller.dt else controller
        if abs(cd.dt - dt) > 1e-12:
            raise ParameterError(f"controller sample time {cd.dt:g} s differs from the "
                                 f"loop's rate {spec.rate:g} Hz")
        self.controller = cd
        signals = [m[3:] if m.startswith("ln_") else m for m in cd.measured]
        if len(signals) != 2 or signals[0] != "r_g" or signals[1] not in ("nu", "nu_r"):
            raise ParameterError(f"the controller measures {cd.measured}: the loop tracks "
                                 "(r_g, nu or nu_r), or their logarithms (ln_)")
        self.slip_signal = signals[1]
        self.logs = np.array([m.startswith("ln_") for m in cd.measured])
        self._logs = tuple(bool(x) for x in self.logs)
        self.model = model
        v, a = model.params.variator, model.params.actuation
        self._L, self._a = v.L_belt, v.a
        self._cosb = float(np.cos(v.beta))
        self._tpf = a.i_e * a.s * model.constants.sheave_sense / a.i_c  # T_ms per N of F_s
        self._r_ref0 = float(model.options.reference_ratio or point["r_g"])
        self.point = {k: float(point[k]) for k in ("r_g", "nu", "omega_p", "T_l", "F_s",
                                                   "T_d") if k in point}
        if model.vehicle and "T_d" not in self.point and spec.feedforward \
                and spec.feedforward_signal != "T_ds":
            raise ParameterError(f"feedforward_signal = {spec.feedforward_signal!r} in the car "
                                 "reads the engine's torque: the starting point needs T_d")
        self.u0 = np.asarray(u0, float)[:2].copy()
        # references on the sample grid
        references = dict(references or {})
        check_reference_names(references)
        self.n_k = max(int(round(duration / dt)), 0) + 2
        self.t_k = np.arange(self.n_k) * dt
        self.references = references
        self.refs = self._cached_references(references)
        # the safety-factor strategy's traction coefficient
        self._mu_design = None
        if spec.mu_design == "ratio-blind":
            rr = np.geomspace(*ratio_range(v), 41)
            self._mu_design = float(np.min(model.mu_max(rr)))
        # sensors: buffers of delay + window samples per raw signal
        s = cfg.sensors
        self._delay = int(s.delay) if s is not None else 0
        self._window = max(1, int(round(s.speed_window / dt))) if s is not None else 1
        self._n_buf = self._delay + self._window
        self._speed_quantum = (2 * np.pi / (s.speed_counts * self._window * dt)
                               if s is not None else 0.0)
        self._observer = _reads_observer(spec)
        self._estimate = self._observer or (spec.feedforward
                                            and spec.feedforward_signal == "T_e_est")
        self._n_est = 0
        if self._estimate:
            est_delay = s.engine_torque_delay if s is not None else 0.0
            self._n_est = int(round(est_delay / dt)) + 1
        self._ahead = spec.reserve_ahead and spec.clamping == "feedback"
        self._guard = spec.slip_guard and spec.feedforward and spec.clamping == "feedback"
        self._request = spec.torque_request != "off"
        self._honour = spec.torque_request == "honoured"
        if self._honour:
            self.commands = ("T_mp", "T_ms", "T_l")
        self._load = (reference_table({"T_l": np.asarray(load, float)}, self.t_k)["T_l"]
                      if self._honour and load is not None else
                      np.full(self.n_k, self.point["T_l"]) if self._honour else np.zeros(1))
        self._noise = self._make_noise()
        # the law's state: buffers, feedforward filter, controller
        self._nb = len(RAW_SIGNALS) * self._n_buf
        self._R_s_last = (float("nan"), float("nan"))
        self.n_state = self._nb + 2 + self._n_est + self._observer + self._guard + cd.n
        self._alpha_ff = float(np.exp(-2 * np.pi * spec.feedforward_filter_hz * dt))
        self._alpha_dec = float(np.exp(-2 * np.pi * spec.decoupling_filter_hz * dt))
        self._decoupling0 = float(self.refs.decoupling[0])
        self._ff_table = core.ff_table(spec.feedforward_gain_table)
        self._L_aw = _antiwindup_gain(cd.A, cd.C) if spec.anti_windup else \
            np.zeros((cd.n, 2))
        self.raw0 = self.raw_at_rest(self.point)
        # the clamping the secondary servo's torque limit holds (the reserve ahead's and
        # the guard's bound): its rating even where the loop runs without limits (the
        # linear model's law is the law that runs); the holding torque is tpf F_s (no
        # constant share on this machine's actuation: T_0 = 0 to rounding at every trim)
        servo = cfg.limits if cfg.limits is not None else model.params.servo
        self._F_max = float(servo.T_ms_max / abs(self._tpf))
        F0 = self._ff_force(self._ff_torque0(), self.raw0[0], self._mu_at_rest())
        self._F0 = F0 if spec.feedforward else 0.0
        self._bias = np.array([self.u0[0], self.u0[1] - self._tpf * self._F0])
        self._T_ms_start = float(self.u0[1])
        self._F_cap = self._servo_capacity(spec.torque_request_margin)
        self._pack()
        if spec.clamping == "safety-factor":
            # the pre-processing's secondary servo torque at rest (the decoupler's zero)
            self._T_ms_start = float(core.safety_torque(
                self.raw0[6] if self.model.vehicle else self._ff_torque0(), self.raw0[0],
                self._c, self._tb, self._wk))
            self._c = self._c._replace(T_ms_start=self._T_ms_start)
        self._law = core.law(self._c, self._tb, self._wk)
        self._at: tuple[tuple[float, ...], Any] | None = None  # `_law_at`'s last row
        self.z0 = self.initial_state()
        self.reset()

    def _pack(self) -> None:
        """The law's constants, per-sample tables and work arrays as the compiled sample
        takes them (`empact.control._law_core`: `LawConstants`, `LawTables`, `LawWork`)."""
        cfg, spec, refs = self.config, self.config.spec, self.refs
        p, s, lim = self.model.params, cfg.sensors, cfg.limits
        sched = self.controller.schedule
        a = p.actuation
        sign = sched._sign_list if sched is not None else [1.0, 1.0]
        self._c = core.constants(
            n_pre=self.n_pre, n_buf=self._n_buf, delay=self._delay, window=self._window,
            quantise=s is not None and cfg.quantise, speed_quantum=self._speed_quantum,
            ratio_quantum=s.ratio_quantum if s is not None else 0.0,
            slip_nu=self.slip_signal == "nu", r_ref0=self._r_ref0, log_r=self._logs[0],
            log_s=self._logs[1], scheduled=sched is not None, sign0=sign[0], sign1=sign[1],
            feedforward=spec.feedforward, ff_t_ds=spec.feedforward_signal == "T_ds",
            F_s0=self.point["F_s"], bias0=self._bias[0], bias1=self._bias[1],
            safety=spec.clamping == "safety-factor", safety_factor=spec.safety_factor,
            mu_design=np.nan if self._mu_design is None else self._mu_design,
            shift_ff=spec.shift_feedforward,
            J_s=0.0 if self.model.vehicle else p.driveline.J_s, J_e=self._J_e(),
            sf_engine=self.model.vehicle,
            alpha_ff=self._alpha_ff,
            tpf=self._tpf, ff_gain=spec.feedforward_gain, ff_den=2 * spec.traction_error,
            cosb=self._cosb, L_belt=self._L, a=self._a, alpha_dec=self._alpha_dec,
            T_ms_start=self._T_ms_start, shift_gain=-(a.i_e * a.s / a.i_w),
            omega_0=p.shift.omega_0, xi_sat=p.shift.xi_sat, creep=self.model.creep,
            tau_ref=self._tau_ref, mask1=self.output_mask[1], limited=lim is not None,
            T_max=lim.T_mp_max if lim else 0.0, w_max=lim.omega_mp_max if lim else 0.0,
            S_max=lim.T_ms_max if lim else 0.0, v_max=lim.omega_ms_max if lim else 0.0,
            band=SPEED_BAND, anti_windup=spec.anti_windup,
            ff_est=self._estimate, n_est=self._n_est,
            est_gain=self._c_est_gain() if self._estimate else 1.0,
            obs=self._observer, obs_k=p.driveline.k_ds * self.dt,
            obs_a=-float(np.expm1(-2 * np.pi * spec.observer_hz * self.dt)),
            request=self._request, honour=self._honour, F_cap=self._F_cap,
            ahead=self._ahead, F_max=self._F_max,
            ahead_h0=spec.reserve_ahead_headroom, guard=self._guard,
            guard_margin=spec.slip_guard_margin, guard_gain=spec.slip_guard_gain,
            guard_decay=float(np.exp(-self.dt / spec.slip_guard_release)),
            alpha_rel=float(np.exp(-self.dt / spec.clamping_release))
            if spec.clamping_release > 0.0 else 0.0,
            floor=spec.min_clamping > 0.0, T_floor=self._clamping_torque(spec.min_clamping))
        # the shift feedforward's geometry at the reference ratio where it moves
        geo = [np.full(self.n_k, np.nan) for _ in range(4)]
        ks = np.flatnonzero(refs.rdot != 0.0) if spec.shift_feedforward else np.zeros(0, int)
        if ks.size:
            for col, v in zip(geo, self._shift_geometry(refs.r_g[ks])):
                col[ks] = v
        c = self.controller
        self._tb = core.tables(
            r_g=refs.r_g, slip=refs.slip, mu=refs.mu, slip_lo=refs.slip_lo,
            mu_lo=refs.mu_lo, rdot=refs.rdot, decoupling=refs.decoupling,
            mu_max=self.model.mu_max(refs.r_g) if sched is not None else np.zeros(self.n_k),
            R_p=geo[0], R_s=geo[1], phi=geo[2], kappa_geo=geo[3], noise=self._noise,
            schedule=sched._packed if sched is not None else np.zeros(2), A=c.A, B=c.B,
            C=c.C, D=c.D, L=self._L_aw, ff_table=self._ff_table, p=self.model.p,
            load=self._load)
        self._wk = core.work(len(self.measured), len(self.commands),
                             self.n_k if self._request else 1,
                             self.n_k if self._ahead or self._guard else 1)

    def _law_at(self, ref: NDArray, k: int) -> Any:
        """The law on one row of tables: sample `k`'s noise, the references `ref` (``r_g,
        slip, mu, dr_g/dt``) and what the law computes of them (`preprocess` and `update`
        with a `ref`, the linear model's)."""
        r_ref, slip, mu, rdot = (float(x) for x in ref)
        kk = min(int(k), self.n_k - 1)
        key = (r_ref, slip, mu, rdot, kk)
        if self._at is not None and self._at[0] == key:  # the linearisation's central
            return self._at[1]  # differences ask for one reference row ~170 times a law
        rr = np.array([r_ref])
        one = [np.full(1, np.nan) for _ in range(4)]
        if self.config.spec.shift_feedforward and rdot != 0.0:
            one = list(self._shift_geometry(rr))
        law = core.law(self._c, core.tables(
            r_g=rr, slip=[slip], mu=[mu], slip_lo=self._tb.slip_lo[kk:kk + 1],
            mu_lo=self._tb.mu_lo[kk:kk + 1], rdot=[rdot], decoupling=[self._decoupling0],
            mu_max=(self.model.mu_max(rr) if self.controller.schedule is not None
                    else np.zeros(1)),
            R_p=one[0], R_s=one[1], phi=one[2], kappa_geo=one[3],
            noise=self._tb.noise[kk:kk + 1], schedule=self._tb.schedule, A=self._tb.A,
            B=self._tb.B, C=self._tb.C, D=self._tb.D, L=self._tb.L,
            ff_table=self._tb.ff_table, p=self._tb.p,
            load=self._tb.load[min(kk, self._tb.load.shape[0] - 1):][:1]), self._wk)
        self._at = (key, law)
        return law

    # -- set-up ----------------------------------------------------------------------------
    def _cached_references(self, references: Mapping[str, NDArray]) -> _Refs:
        """`_references`, computed once for the same model, start, references and loop (a
        shift's cost 30-35 ms of CPU even on the grid of ratios, and the report builds one
        scenario's law for its run, the ideal run, the linear model and the feedforward's
        estimates: the same references each time)."""
        h = hashlib.sha256()
        for part in (type(self).__qualname__.encode(), self.model.p.tobytes(),
                     repr(self.model.options).encode(),
                     repr(self.model.params).encode(), repr(sorted(self.point.items())).encode(),
                     repr((self.n_k, self.dt, self.slip_signal, self.config.spec.decoupling,
                           self.config.spec.reserve_ahead,
                           self.config.spec.reserve_ahead_tau)).encode()):
            h.update(part + b"\0")
        for name in sorted(references):
            h.update(name.encode() + np.ascontiguousarray(references[name], float).tobytes())
        key = h.digest()
        if key not in _REFERENCES:
            refs = self._references(references)
            _REFERENCES[key] = (refs, self._tau_ref)
            while len(_REFERENCES) > 16:
                _REFERENCES.popitem(last=False)
        _REFERENCES.move_to_end(key)
        refs, tau_ref = _REFERENCES[key]
        self._tau_ref = float(tau_ref)
        return _Refs(**{f.name: getattr(refs, f.name).copy() for f in fields(_Refs)})

    def _references(self, references: Mapping[str, NDArray]) -> _Refs:
        t = self.t_k
        tab = reference_table(references, t)
        r = tab.get("r_g", np.full(t.shape, self.point["r_g"]))
        lo, hi = ratio_range(self.model.params.variator)
        if np.any((r < lo) | (r > hi)):
            bad = r[(r < lo) | (r > hi)][0]
            raise ParameterError(f"references.r_g = {bad:g}: outside the variator's ratio "
                                 f"range [{lo:.4g}, {hi:.4g}]")
        # the traction peak at each distinct reference ratio, searched once: the slip
        # set-points and the decoupler's trims below share it (a shift's ratio moves at every
        # sample: a search per sample).  A reference through `_GRID_MIN` ratios or more (a
        # shift) searches none: its slips are polished from a grid's (`_rising_slips`) and
        # its holding torques interpolated from a grid's trims (`_on_ratio_grid`)
        ru, at_ru = np.unique(r, return_inverse=True)
        grid = ru.size >= _GRID_MIN
        peak = traction_peak(self.model, ru) if not grid and (
            "tau" in tab or self.config.spec.decoupling) else None
        by_tau = None  # the distinct (tau, r_g) of a torque-ratio reference and their slips
        if "tau" in tab:
            pairs, inv = _unique_rows(tab["tau"], r)
            if peak is not None:
                at_pk = np.searchsorted(ru, pairs[:, 1])
                at = slip_at_torque_ratio(self.model, pairs[:, 0], pairs[:, 1],
                                          peak=(peak[0][at_pk], peak[1][at_pk]))
            else:  # by torque ratio (the pairs are sorted by it, then by the ratio)
                at = np.empty(len(pairs))
                for tau_k in np.unique(pairs[:, 0]):
                    sel = np.flatnonzero(pairs[:, 0] == tau_k)
                    at[sel] = _rising_slips(self.model, float(tau_k), pairs[sel, 1])
            by_tau, slip = (pairs, at), at[inv]
        else:
            slip = tab.get(self.slip_signal if self.slip_signal in tab else
                           ("nu" if "nu" in tab else "nu_r"),
                           np.full(t.shape, self.point["nu"]))
        # below the traction peak at every sample: its closest approach to the peak
        # (`smallest_slip_reserve`, not a search per sample of a shift's moving ratio)
        slip = np.asarray(slip, float)
        pairs, inv = _unique_rows(slip, r)
        reserve, j = smallest_slip_reserve(self.model, pairs[:, 1], pairs[:, 0])
        bad = np.flatnonzero(~(slip > 0))
        if bad.size or not reserve > 0:
            k = int(bad[0]) if bad.size else int(np.flatnonzero(inv == j)[0])
            nu_pk = float(traction_peak(self.model, r[k])[0])
            raise ParameterError(f"slip set-point {slip[k]:g} at r_g = {r[k]:g}: must lie on "
                                 f"the rising traction curve (0, {nu_pk:.4g})")
        mu = self.model.traction(pairs[:, 0], pairs[:, 1])[inv]
        self._tau_ref = float(mu[0] / self.model.mu_max(r[0]))
        self._tau_ref = min(max(self._tau_ref, 1e-3), 0.999)
        # the rate of the reference over each sample period (no smearing across a corner)
        rdot = np.append(np.diff(r) / np.diff(t), 0.0) if len(t) > 1 else np.zeros_like(t)
        dec = np.zeros_like(t)
        if self.config.spec.decoupling:
            # the holding torques' ratio T_mp* / T_ms* at the reference ratios (at the
            # set-point's torque ratio and the starting clamping force)
            ratio = None
            if grid:
                ratio = _on_ratio_grid(lambda q: self._holding_ratio(
                    q, nu=_rising_slips(self.model, self._tau_ref, q), strict=False), ru)
            tau = np.full(ru.shape, self._tau_ref)
            if ratio is None and by_tau is not None and np.array_equal(by_tau[0][:, 1], ru) \
                    and np.all(by_tau[0][:, 0] == tau) \
                    and (peak is None or np.all(tau * self.model.mu_max(ru) <= peak[1])):
                # the set-points are at this torque ratio at every distinct ratio: their
                # slips are the trims' (the same bisection, or its polish, certified on the
                # rising branch), trimmed at them
                ratio = self._holding_ratio(ru, nu=by_tau[1])
            if ratio is None:
                if peak is None:
                    peak = traction_peak(self.model, ru)
                ratio = self._holding_ratio(ru, tau=tau, peak=peak)
            assert ratio is not None  # (strict: a ParameterError where it does not trim)
            dec = ratio[at_ru]
        slip_lo, mu_lo = np.asarray(slip, float), np.asarray(mu, float)
        if self.config.spec.reserve_ahead:
            # the reserve ahead's lowest set-point: its torque ratio at each reference ratio
            # (never above the reference's own)
            nu_lo = _rising_slips(self.model, self.config.spec.reserve_ahead_tau, ru)[at_ru]
            slip_lo = np.minimum(nu_lo, slip_lo)
            mu_lo = np.asarray(self.model.traction(slip_lo, r), float)
        return _Refs(r_g=r, slip=np.asarray(slip, float), mu=np.asarray(mu, float), rdot=rdot,
                     decoupling=dec, slip_lo=slip_lo, mu_lo=mu_lo)

    def _holding_ratio(self, r: NDArray, strict: bool = True,
                       **slip: Any) -> NDArray[np.float64] | None:
        """The holding torques' ratio ``T_mp* / T_ms*`` [-] at the ratios `r` (1-D) [-]: the
        trims (`trim_grid`) at the starting primary speed and clamping force and the slip
        `slip` (``nu=`` the slips, or ``tau=`` the torque ratios with ``peak=``).  Where a
        ratio does not trim: a ParameterError (`strict`), else None."""
        g = trim_grid(self.model, r, self.point["omega_p"], F_s=self.point["F_s"], **slip)
        if not np.all(g.ok):
            if not strict:
                return None
            bad = r[~g.ok][0]
            raise ParameterError(f"decoupling: the machine does not trim at the reference "
                                 f"ratio {bad:g} ({g.reason[~g.ok][0]})")
        return g.u[:, 0] / g.u[:, 1]

    def _make_noise(self) -> NDArray[np.float64]:
        s = self.config.sensors
        noise = np.zeros((self.n_k, len(RAW_SIGNALS)))
        if s is None:
            return noise
        rng = np.random.default_rng(self.config.spec.seed)
        if s.speed_noise:
            noise[:, list(_SPEEDS)] = s.speed_noise * rng.standard_normal((self.n_k, 2))
        if s.torque_noise:
            noise[:, 3] = s.torque_noise * rng.standard_normal(self.n_k)
        return noise

    def raw_at_rest(self, point: Mapping[str, float]) -> NDArray[np.float64]:
        """The raw measurements at a steady operating point (`RAW_SIGNALS` order).

        Parameters
        ----------
        point : mapping of str to float
            The steady operating point (``r_g``, ``omega_p``, ... in SI units).
        """
        w_p = point["omega_p"]
        w_s = point["r_g"] * w_p * (1 - point["nu"])
        source = point["T_d"] * w_p / w_s if self.model.vehicle and "T_d" in point \
            else point["T_l"]
        raw = [point["r_g"], w_p, w_s, point["T_l"], 0.0, 0.0, source]
        if self._observer:
            raw.append(w_s)  # the wheel speed at rest: the output speed (no final drive)
        return np.array(raw)

    def initial_state(self) -> NDArray[np.float64]:
        """The law's state at rest at the starting point (buffers full of the point's
        measurements, the feedforward filter settled, the controller state zero)."""
        z = np.zeros(self.n_state)
        z[:self._nb] = np.repeat(self.raw0[:len(RAW_SIGNALS)], self._n_buf)
        z[self._nb] = self._ff_force(self._ff_torque0(), self.raw0[0], self._mu_at_rest())
        if self.config.spec.clamping == "safety-factor":  # the held torque at rest
            z[self._nb] = abs(self.raw0[6] if self.model.vehicle else self._ff_torque0())
        if self._n_est:  # the estimate at rest: its value of the start, settled
            z[self._nb + 2:self._nb + 2 + self._n_est] = self.raw0[6]
        if self._observer:  # the observer at rest: the estimate's torque
            z[self._nb + 2 + self._n_est] = self._ff_torque0()
        return z

    def reset(self) -> None:
        """Back to the first sample at rest."""
        self._z: NDArray[np.float64] = self.z0.copy()
        self._z_spare: NDArray[np.float64] = np.empty_like(self._z)
        self._k = 0

    @property
    def measured(self) -> tuple[str, ...]:
        """What the simulator hands the law at each sample (`RAW_SIGNALS`, in the car with
        the engine's torque `CAR_SOURCE` as the torque source's, then `OBSERVER_SIGNAL` for
        the driveshaft-torque observer)."""
        return measured_signals(self.model.vehicle, self.config.spec)

    # -- the law ---------------------------------------------------------------------------
    def _R_s(self, r_g: float) -> float:
        """Secondary running radius [m] at the measured ratio (unstretched belt; the set-up's:
        a sample's is the compiled `_law_core.secondary_radius`)."""
        r = min(max(float(r_g), 1e-3), 1e3)
        if r != self._R_s_last[0]:
            self._R_s_last = (r, secondary_radius(r, self._L, self._a))
        return self._R_s_last[1]

    def _ff_torque0(self) -> float:
        """The clamping feedforward's torque at rest [N m]: ``T_ds = T_l``, or the torque
        estimate's ``(1 + engine_torque_error) T_l``."""
        if not self._estimate:
            return float(self.raw0[3])
        return float(self._c_est_gain() * self.raw0[6])

    def _c_est_gain(self) -> float:
        """The engine-torque estimate over the truth, ``1 + engine_torque_error`` [-]."""
        s = self.config.sensors
        return 1.0 + (s.engine_torque_error if s is not None else 0.0)

    def _servo_capacity(self, margin: float) -> float:
        """The clamping force [N] the secondary servo holds with `margin` of its torque
        limit held back: ``(+-(1 - margin) T_ms_max - T_0) / tpf`` (the sign of ``tpf``, the
        servo torque per N of clamping, which the sheaves' sense sets), ``T_0`` the holding
        torque's share that does not scale with the clamping (at the start); NaN without
        limits."""
        lim = self.config.limits
        if lim is None:
            return float("nan")
        T_0 = self.u0[1] - self._tpf * self.point["F_s"]
        return float((np.copysign((1 - margin) * lim.T_ms_max, self._tpf) - T_0) / self._tpf)

    def setpoint(self, T: float, r_g: float, k: int = 0) -> tuple[float, float]:
        """The set-point the law runs at sample `k` with the torque `T` [N m] (the
        feedforward's signal) at the measured ratio `r_g`: the reference's slip and traction
        coefficient, moved by the reserve ahead (``controller.reserve_ahead``) towards the
        lowest set-point's as the secondary servo's headroom shrinks (the compiled sample's
        law, `empact.control._law_core.pre`).

        Parameters
        ----------
        T : float
            The torque the clamping is computed for [N m].
        r_g : float
            The measured ratio [-].
        k : int, optional
            The sample (its references; default the first).

        Returns
        -------
        slip, mu : float
            The set-point's slip [-] and traction coefficient [-].
        """
        kk = min(int(k), self.n_k - 1)
        slip, mu = float(self.refs.slip[kk]), float(self.refs.mu[kk])
        if not self._ahead:
            return slip, mu
        F_full = abs(T) * self._cosb / (2 * self.config.spec.traction_error * mu
                                        * self._R_s(r_g))
        h = max(1.0 - F_full / self._F_max, 0.0)
        mu_lo, slip_lo = float(self.refs.mu_lo[kk]), float(self.refs.slip_lo[kk])
        w = (self.config.spec.reserve_ahead_headroom - h) / \
            self.config.spec.reserve_ahead_headroom
        cap = mu * h / (mu - mu_lo) if mu > mu_lo else 0.0
        w = min(max(min(w, cap), 0.0), 1.0)
        return slip + w * (slip_lo - slip), mu + w * (mu_lo - mu)

    def _mu_at_rest(self) -> float:
        """The set-point's traction coefficient at the start (`setpoint` of the start's
        torque and ratio)."""
        return self.setpoint(self._ff_torque0(), float(self.raw0[0]))[1]

    @property
    def setpoint_trace(self) -> NDArray[np.float64]:
        """Per sample (`t_k`) the slip set-point the law ran [-] (the reserve ahead's) and
        the slip-runaway guard's clamping share [-] (NaN where neither runs, or not
        reached), shape (n_k, 2); shape (1, 2) of NaN without either."""
        return self._wk.setpoint.copy()

    def _J_e(self) -> float:
        """The inertia on the primary's side in the car [kg m^2]: the engine's and the
        primary pulley's, whose deceleration in an upshift the belt carries (``(J_e + J_p)
        omega_p dr/dt / r_g^2`` at the secondary: the ratio sets the engine's speed, the
        wheels the secondary's), which the clamping feedforward and the safety-factor
        clamping add at the reference's rate; 0 on the bench (the drive holds the primary's
        speed)."""
        if not self.model.vehicle:
            return 0.0
        c = self.model.constants
        return float(c.J_d + c.J_p)

    def _clamping_torque(self, F: float) -> float:
        """The secondary servo torque [N m] that clamps `F` [N]: the holding torque's share
        that does not scale with the clamping (at the start) plus ``tpf F`` (the clamping
        floor's, `ControllerSpec.min_clamping`)."""
        return float(self.u0[1] - self._tpf * self.point["F_s"] + self._tpf * F)

    @property
    def servo_capacity(self) -> float:
        """The clamping force [N] the torque request is computed for (`_servo_capacity`:
        the secondary servo's torque limit less its margin); NaN without limits."""
        return self._F_cap

    @property
    def request_trace(self) -> NDArray[np.float64]:
        """Per sample (`t_k`) the torque request [N m] (secondary shaft) and the load torque
        the bench applied [N m] (NaN where not honoured, or not reached), shape (n_k, 2);
        shape (1, 2) of NaN without a torque request."""
        return self._wk.trace.copy()

    def _ff_force(self, T_ds: float, r_g: float, mu_ref: float) -> float:
        """Clamping force [N] that holds the traction coefficient ``traction_error * mu_ref``
        at driveshaft torque `T_ds` and ratio `r_g`."""
        spec = self.config.spec
        if spec.feedforward_gain_table is not None:
            return float(core.scheduled_ff(self._ff_table, T_ds * self._cosb / (
                2 * spec.traction_error * mu_ref * self._R_s(r_g))))
        return spec.feedforward_gain * T_ds * self._cosb / (2 * spec.traction_error * mu_ref
                                                            * self._R_s(r_g))

    def sense(self, buf: NDArray, ideal: bool = False) -> NDArray[np.float64]:
        """The measurements the controller sees from the buffers (n_raw, n_buf): each signal
        `delay` samples late, the shaft speeds averaged over the counting window and
        quantised (not when `ideal`).

        Parameters
        ----------
        buf : ndarray, shape (n_raw, n_buf)
            The measurement buffers, one row per raw signal (`RAW_SIGNALS`), newest last.
        ideal : bool, optional
            No quantisation (default False).
        """
        buf = np.ascontiguousarray(buf, dtype=float)
        m = np.empty(buf.shape[0])
        core.sense(buf.ravel(), buf.shape[0], self._c, bool(ideal), m)
        return m

    def preprocess(self, s: NDArray, raw: NDArray, k: int, ref: NDArray | None = None,
                   ideal: bool = False) -> tuple[NDArray, NDArray, NDArray, NDArray]:
        """Everything of one sample but the controller: from the sensor and feedforward
        state `s` (``n_pre``), the raw measurements `raw` (`RAW_SIGNALS`) and the sample
        index `k`, the next state, the controller's errors ``e``, the servo torques without
        the controller's share (holding torques and feedforwards) and the measurements the
        controller saw; `ref` (``r_g, slip, mu, dr_g/dt``) replaces the references of sample
        `k`; `ideal` drops noise and quantisation.

        Parameters
        ----------
        s : ndarray, shape (n_pre,)
            The sensor and feedforward state.
        raw : ndarray, shape (len(RAW_SIGNALS),)
            The raw measurements of this sample, in `RAW_SIGNALS` order (SI).
        k : int
            The sample index.
        ref : ndarray, shape (4,), optional
            ``r_g`` [-], slip [-], ``mu`` [-] and ``dr_g/dt`` [1/s] replacing the references of
            sample `k` (default: the law's own).
        ideal : bool, optional
            Drop noise and quantisation (default False).
        """
        s = np.ascontiguousarray(s, dtype=float)
        s_next = np.empty(self.n_pre)
        law, kk = (self._law, int(k)) if ref is None else (self._law_at(ref, k), 0)
        status, e0, e1, u0, u1 = _pre(law, s, s_next,
                                      np.ascontiguousarray(raw, dtype=float), kk, bool(ideal))
        if status:
            raise _no_geometry(self._wk.meas[0])
        return s_next, np.array([e0, e1]), np.array([u0, u1]), self._wk.meas.copy()

    @property
    def n_pre(self) -> int:
        """Size of the sensor, feedforward and decoupler state (`preprocess`; with the
        engine-torque estimate's buffer)."""
        return self._nb + 2 + self._n_est + self._observer + self._guard

    @property
    def output_mask(self) -> NDArray[np.float64]:
        """Which controller outputs reach the servos (the safety-factor strategy's clamping
        replaces the controller's secondary servo torque)."""
        return np.array([1.0, 0.0 if self.config.spec.clamping == "safety-factor" else 1.0])

    def at_rest(self) -> dict[str, Any]:
        """What the law holds at its trimmed start: the point its schedule is read at
        (``r_g`` the measured ratio [-], ``tau`` the set-point's ``mu / mu_max`` at the
        reference ratio [-], ``F_s`` the clamping feedforward's force, or the start's
        clamping force without feedforward [N]), the holding torques ``u0`` [N m], the
        feedforward's clamping force ``F_ff`` [N] and servo torque per newton ``tpf`` [N m/N],
        and the decoupler's gain ``decoupling`` [-] (``T_mp* / T_ms*``).

        Returns
        -------
        dict
            ``schedule_point`` (dict name -> float), ``u0`` (list of 2 floats), ``F_ff``,
            ``tpf``, ``decoupling`` (floats).
        """
        tau = float(self.refs.mu[0] / self.model.mu_max(self.refs.r_g[:1])[0])
        F = self._F0 if self.config.spec.feedforward else self.point["F_s"]
        return {"schedule_point": {"r_g": float(self.raw0[0]), "tau": tau, "F_s": float(F)},
                "u0": [float(x) for x in self.u0], "F_ff": float(self._F0),
                "tpf": float(self._tpf), "decoupling": float(self._decoupling0)}

    def update(self, z: NDArray, raw: NDArray, k: int, ref: NDArray | None = None,
               ideal: bool = False) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """One sample of the law: the next state and the servo torques ``[T_mp, T_ms]``
        [N m] held over the period, from the state `z` (`preprocess`'s, then the
        controller's), the raw measurements `raw` (`RAW_SIGNALS`) and the sample index `k`;
        `ref` replaces the references of sample `k`; `ideal` drops noise, quantisation and
        limits (the linear model's law).

        Parameters
        ----------
        z : ndarray
            The law's state: `preprocess`'s (``n_pre``), then the controller's.
        raw : ndarray, shape (len(RAW_SIGNALS),)
            The raw measurements of this sample, in `RAW_SIGNALS` order (SI).
        k : int
            The sample index.
        ref : ndarray, shape (4,), optional
            As `preprocess`'s.
        ideal : bool, optional
            Drop noise, quantisation and limits (default False).
        """
        z = np.ascontiguousarray(z, dtype=float)
        if z.shape != (self.n_state,):
            raise ValueError(f"z has shape {z.shape}: expected ({self.n_state},)")
        z_next = np.empty(self.n_state)
        law, kk = (self._law, int(k)) if ref is None else (self._law_at(ref, k), 0)
        if self._sample(law, z, z_next, self._raw(raw), kk, bool(ideal)):
            raise _no_geometry(self._wk.meas[0])
        return z_next, self._wk.u.copy()

    def _sample(self, law: Any, z: NDArray, z_next: NDArray, raw: NDArray, k: int,
                ideal: bool) -> Any:
        """One compiled sample (`_law_core.sample`): its overload is resolved on the first
        call, not when the law is built (a run by `run_compiled` never calls it, and loading
        it from numba's cache cost 30-50 ms of CPU in a process's first law), and then set on
        the instance in this method's place (later calls go to it directly)."""
        entry = _entry(core.sample, self._law, self._z, self._z_spare, self.raw0, 0, False)
        self._sample = entry  # type: ignore[method-assign]
        return entry(law, z, z_next, raw, k, ideal)

    def _raw(self, raw: NDArray) -> NDArray[np.float64]:
        """The raw measurements as the compiled sample takes them (float64, shape (7,))."""
        raw = np.ascontiguousarray(raw, dtype=float)
        if raw.shape != (len(self.measured),):
            raise ValueError(f"raw measurements of shape {raw.shape}: expected "
                             f"({len(self.measured)},), {', '.join(self.measured)}")
        return raw

    def _shift_geometry(self, r: NDArray) -> tuple[NDArray, NDArray, NDArray, NDArray]:
        """The shift feedforward's geometry at the reference ratios `r` (1-D): ``R_p``,
        ``R_s`` [m], ``phi`` [rad] and the geometric thrust ratio (Shafai's law's)."""
        st = variator_state(r, self.model.params.variator)
        return st.R_p, st.R_s, st.phi, (np.pi + 2 * st.phi) / (np.pi - 2 * st.phi)

    @property
    def compiled(self) -> bool:
        """Whether `run_compiled` can run the law (always: every sample is compiled)."""
        return True

    def run_compiled(self, k0: int, k1: int, loop: SampledLoop, t: float, h: float,
                     filled: int, n_steps: int, n_rej: int) -> tuple[int, float, float, int,
                                                                     int, int, int]:
        """Samples `k0` to ``k1 - 1`` of the simulator's sampled loop with the law and the
        integrator in one compiled loop (`_loop_core.run_samples`): bitwise what `step` at
        each sample between the integrator's calls gives
        (`empact.nonlinear.simulation.CompiledSampledController`).

        Parameters
        ----------
        k0, k1 : int
            The simulator's first sample and the one after the last.
        loop : SampledLoop
            The simulator's arrays and the integrator's arguments.
        t, h : float
            Time [s] and step size [s] the integrator continues from.
        filled, n_steps, n_rej : int
            Output samples filled, integration steps taken and rejected so far.

        Returns
        -------
        tuple
            ``(status, t, h, filled, n_steps, n_rej, k)``: the integrator's status after
            sample `k`, the last one run.

        Raises
        ------
        ParameterError
            When the clamping finds no belt geometry at the measured ratio (as `step`
            does).
        """
        status, t, h, filled, n_steps, n_rej, k, done, err = _run_samples(
            k0, k1, self._law, self._z, self._z_spare, self._k, loop, t, h, filled, n_steps,
            n_rej)
        self._k += done
        if done % 2:
            self._z, self._z_spare = self._z_spare, self._z
        if err:
            raise _no_geometry(self._wk.meas[0])
        return status, t, h, filled, n_steps, n_rej, k

    def step(self, t: float, measured: NDArray[np.float64]) -> NDArray[np.float64]:
        """Servo torques ``[T_mp, T_ms]`` [N m] over ``[t, t + dt)``: the compiled sample
        (`update`) of the law's state.

        Parameters
        ----------
        t : float
            The sample time [s].
        measured : ndarray, shape (len(RAW_SIGNALS),)
            The measured signals at `t` in `RAW_SIGNALS` order (SI).
        """
        z_next = self._z_spare
        if self._sample(self._law, self._z, z_next, self._raw(measured), self._k, False):
            raise _no_geometry(self._wk.meas[0])
        self._z_spare, self._z = self._z, z_next
        self._k += 1
        return self._wk.u.copy()
