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
   traction_error * mu(nu*, r_g*)`` (times ``feedforward_gain``: below 1 it leaves the belt
   part of its damping of the driveshaft mode, which a full feedforward of the driveshaft
   torque cancels), through a first-order low-pass at
   ``feedforward_filter_hz`` (below the clamping mode near 9.5 Hz); or, with ``clamping =
   "safety-factor"``, the open-loop clamping of a production CVT (the slip loop off):
   ``F_s = SF T_l cos(beta) / (2 mu_design R_s)``, ``mu_design`` the smallest traction peak
   over the ratio range (``mu_design = "ratio-blind"``) or the peak at the measured ratio
   (``"ratio-aware"``);
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
   the controller's ``(A, C)``, so that ``A - L C`` is stable).

The servo torques are the trim's holding torques plus these terms: the controller starts in
its steady state at the trim (its integrators hold the holding torques less the
feedforward's share at the trim, computed with the feedforward's own traction estimate).

`LoopLaw.update` is a pure function of the law's state (a flat vector: sensor buffers,
feedforward filter, controller state), the raw measurements and the sample index; `step` is
the stateful `empact.nonlinear.simulation.SampledController` interface around it, and
`empact.control.loop` linearises the same function for the loop's linear model.  Its
arithmetic on floats (sensors, errors, the schedule's interpolation, the clamping
feedforward) is compiled (`empact.control._law_core`); numpy keeps what has its own
vectorised functions or BLAS (the schedule's ``exp``, the shift feedforward's ``tanh`` and
``expm1``, the controller's matrix products), so that every operation is the one the law's
array form had and a run gives the same numbers to the last bit.

`step` runs the whole sample compiled (`_law_core.step_core`, `LoopLaw.compiled`) when no
sample calls the model (no safety-factor clamping, no shift feedforward on a moving ratio
reference: the load steps, the Monte Carlo runs): the same operations, with the C library's
``exp`` and the controller's products summed in index order, so that its torques and states
agree with `update` to rounding (tested at every sample of the shipped load steps) and a run
with the frozen law to the runs' own one-ulp floor; about 3 us a sample instead of 11.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any, Mapping

import numpy as np
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
from ..nonlinear.scenario import REFERENCES, ControllerSpec, Scenario
from ..params import Params
from ..variator.geometry import ratio_range, secondary_radius, variator_state
from ..variator.shift_law import g_beta
from . import _law_core as core
from . import _loop_core
from .controller import Controller

linalg = lazy_module("scipy.linalg")

__all__ = ["LoopConfig", "LoopLaw", "RAW_SIGNALS", "SHIPPED_LOOP", "reference_table"]

_step_core: Any = core.step_core  # (numba's Dispatcher is typed without a call signature)
_run_samples: Any = _loop_core.run_samples


def _unique_rows(*columns: NDArray) -> tuple[NDArray[np.float64], NDArray[np.intp]]:
    """``np.unique(np.column_stack(columns), axis=0, return_inverse=True)`` (the distinct
    rows, sorted, and each row's index among them), computed on the first row of each run of
    equal rows: a reference table holds a few values for thousands of samples, and sorting
    every sample's row cost about 1 ms a column pair."""
    rows = np.column_stack(columns)
    start = np.ones(len(rows), dtype=bool)
    start[1:] = np.any(rows[1:] != rows[:-1], axis=1)
    distinct, inv = np.unique(rows[start], axis=0, return_inverse=True)
    return distinct, inv.ravel()[np.cumsum(start) - 1]


def _no_geometry(r_g: float) -> ParameterError:
    """A sample's refusal (`LoopLaw.update`, the compiled sample): the clamping feedforward
    finds no belt geometry at the measured ratio `r_g`."""
    return ParameterError(f"r_g = {r_g:g}: no belt geometry at this ratio")


#: the loop of the shipped scenarios and designs (`ControllerSpec` keys): the clamping
#: feedforward of the driveshaft torque at 0.9 of it, unfiltered but for noise, and the
#: primary servo following it through a 5 Hz low-pass (see the module notes)
SHIPPED_LOOP = {"feedforward": True, "feedforward_gain": 0.9, "feedforward_filter_hz": 100.0,
                "decoupling": True, "decoupling_filter_hz": 5.0}

#: what the law reads from the machine, in this order (model outputs)
RAW_SIGNALS = ("r_g", "omega_p", "omega_s", "T_ds", "omega_mp", "omega_ms", "T_l_act")
_SPEEDS = (1, 2)  # RAW_SIGNALS indices counted by encoders


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
        """The loop of a closed-loop scenario on the parameter set."""
        spec = scenario.controller
        if spec is None:
            raise ParameterError(f"scenario {scenario.name!r} has no [controller] table")
        return cls(spec, replace(params.servo, **scenario.limits) if spec.limits else None,
                   replace(params.sensors, **scenario.sensors) if spec.sensors else None)

    @classmethod
    def of(cls, params: Params, **spec: Any) -> "LoopConfig":
        """A loop on the parameter set's servos and sensors with the `ControllerSpec` keys
        `spec` (no file: for design and analysis)."""
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
    unit state and output noise (``A - L C`` stable whenever ``(A, C)`` is detectable)."""
    n, m = A.shape[0], C.shape[0]
    if n == 0:
        return np.zeros((0, m))
    P = linalg.solve_discrete_are(A.T, C.T, np.eye(n), np.eye(m))
    return A @ P @ C.T @ np.linalg.inv(C @ P @ C.T + np.eye(m))


@dataclass(frozen=True, eq=False)
class _Refs:
    """References on the sample grid: ratio, slip set-point, its traction coefficient, the
    ratio reference's rate."""

    r_g: NDArray[np.float64]
    slip: NDArray[np.float64]
    mu: NDArray[np.float64]
    rdot: NDArray[np.float64]
    decoupling: NDArray[np.float64]


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
    """

    commands = ("T_mp", "T_ms")

    def __init__(self, controller: Controller, model: EmpactModel, point: Mapping[str, float],
                 u0: NDArray, config: LoopConfig,
                 references: Mapping[str, NDArray] | None = None,
                 duration: float = 0.0) -> None:
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
        self.point = {k: float(point[k]) for k in ("r_g", "nu", "omega_p", "T_l", "F_s")}
        self.u0 = np.asarray(u0, float)[:2].copy()
        # references on the sample grid
        references = dict(references or {})
        for key in references:
            if key not in REFERENCES:
                raise ParameterError(f"reference {key!r}: choose from {', '.join(REFERENCES)}")
        if sum(k in references for k in ("nu", "nu_r", "tau")) > 1:
            raise ParameterError("give one slip set-point: references.nu, nu_r or tau")
        self.n_k = max(int(round(duration / dt)), 0) + 2
        self.t_k = np.arange(self.n_k) * dt
        self.references = references
        self.refs = self._references(references)
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
        self._noise = self._make_noise()
        # the law's state: buffers, feedforward filter, controller
        self._nb = len(RAW_SIGNALS) * self._n_buf
        self._mu_max_cache = (float("nan"), float("nan"))
        self._R_s_last = (float("nan"), float("nan"))
        self.n_state = self._nb + 2 + cd.n
        self._alpha_ff = float(np.exp(-2 * np.pi * spec.feedforward_filter_hz * dt))
        self._alpha_dec = float(np.exp(-2 * np.pi * spec.decoupling_filter_hz * dt))
        self._decoupling0 = float(self.refs.decoupling[0])
        self._L_aw = _antiwindup_gain(cd.A, cd.C) if spec.anti_windup else \
            np.zeros((cd.n, 2))
        self.raw0 = self.raw_at_rest(self.point)
        F0 = self._ff_force(self.raw0[3], self.raw0[0], self.refs.mu[0])  # T_ds = T_l
        self._F0 = F0 if spec.feedforward else 0.0
        self._bias = np.array([self.u0[0], self.u0[1] - self._tpf * self._F0])
        # the pre-processing's secondary servo torque at rest (the decoupler's zero)
        self._T_ms_start = self.u0[1]
        if spec.clamping == "safety-factor":
            self._T_ms_start = self._safety_torque(self.raw0[3], self.raw0[0])
        self.z0 = self.initial_state()
        self._pack()
        self.reset()

    def _pack(self) -> None:
        """The law's constants packed once for the compiled arithmetic
        (`empact.control._law_core`: ``P``, the per-sample table ``T``, the schedule ``S``)
        and as floats for the rest."""
        cfg, spec, refs = self.config, self.config.spec, self.refs
        p = self.model.params
        s = cfg.sensors
        sched = self.controller.schedule
        self._n_last = self.n_k - 1
        self._ref_rows = (refs.r_g.tolist(), refs.slip.tolist(), refs.mu.tolist(),
                          refs.rdot.tolist(), refs.decoupling.tolist())
        self._sched = sched is not None
        P = np.zeros(core.N_P)
        P[[core._P_NB, core._P_NBUF, core._P_DELAY, core._P_WINDOW]] = (
            self._nb, self._n_buf, self._delay, self._window)
        P[core._P_QUANTISE] = s is not None and cfg.quantise
        P[core._P_SPEED_Q] = self._speed_quantum
        P[core._P_RATIO_Q] = float(s.ratio_quantum) if s is not None else 0.0
        P[core._P_SLIP_NU] = self.slip_signal == "nu"
        P[core._P_R_REF0] = self._r_ref0
        P[core._P_LOG_R], P[core._P_LOG_S] = self._logs
        P[core._P_SCHED] = self._sched
        P[core._P_FEEDFORWARD] = spec.feedforward
        P[core._P_F_S0] = self.point["F_s"]
        P[core._P_BIAS0], P[core._P_BIAS1] = self._bias
        P[core._P_SAFETY] = spec.clamping == "safety-factor"
        P[core._P_FF_T_DS] = spec.feedforward_signal == "T_ds"
        P[core._P_SHIFT_FF] = spec.shift_feedforward
        P[core._P_J_S] = p.driveline.J_s
        P[core._P_ALPHA_FF] = self._alpha_ff
        P[core._P_TPF] = self._tpf
        P[core._P_FF_GAIN] = spec.feedforward_gain
        P[core._P_FF_DEN] = 2 * spec.traction_error
        P[core._P_COSB] = self._cosb
        P[core._P_L_BELT], P[core._P_A] = self._L, self._a
        P[core._P_N_LAST] = self._n_last
        self._P = P
        T = np.zeros((self.n_k, core.T_NOISE + len(RAW_SIGNALS)))
        T[:, core.T_R], T[:, core.T_SLIP], T[:, core.T_MU] = refs.r_g, refs.slip, refs.mu
        T[:, core.T_RDOT], T[:, core.T_DEC] = refs.rdot, refs.decoupling
        if sched is not None:
            T[:, core.T_MU_MAX] = self.model.mu_max(refs.r_g)
        T[:, core.T_NOISE:] = self._noise
        self._T = T
        self._S = sched._packed if sched is not None else np.zeros(2)
        self._R_s_cache = np.array([np.nan, np.nan])
        self._res = np.zeros(core.N_RES)
        self._no_ref = np.full(5, np.nan)
        self._F_s0 = self.point["F_s"]
        self._safety = spec.clamping == "safety-factor"
        self._mask = self.output_mask
        self._mask_ones = bool(np.all(self._mask == 1.0))  # (x * 1.0 is x)
        self._limited = cfg.limits is not None
        lim = cfg.limits
        if lim is not None:
            self._lim = ((float(lim.T_mp_max), float(lim.omega_mp_max)),
                         (float(lim.T_ms_max), float(lim.omega_ms_max)))
        # the shift feedforward's geometry at the reference ratio of every sample where the
        # reference moves (`_shift_torque`)
        a = p.actuation
        self._shift = p.shift
        self._g_beta = g_beta(p.variator.beta)
        self._shift_gain = -(a.i_e * a.s / a.i_w)
        self._creep_args = [np.empty(1) for _ in range(8)]
        self._shift_rows: dict[int, tuple[float, ...]] = {}
        if spec.shift_feedforward:
            ks = np.flatnonzero(refs.rdot != 0.0)
            if ks.size:
                self._shift_rows = dict(zip(ks.tolist(),
                                            self._shift_geometry(refs.r_g[ks])))
        # a whole sample compiled (`_law_core.step_core`) where no sample calls the model
        self._fast: tuple[Any, ...] | None = None
        self._u_out = np.zeros(2)
        if not self._safety and not (spec.shift_feedforward and np.any(refs.rdot != 0.0)):
            c = self.controller
            Q = np.zeros(core.N_Q)
            Q[core._Q_N_PRE] = self.n_pre
            Q[core._Q_SCHED] = self._sched
            if sched is not None:
                Q[core._Q_SIGN0], Q[core._Q_SIGN1] = sched._sign_list
            Q[core._Q_ALPHA_DEC] = self._alpha_dec
            Q[core._Q_T_MS_START] = self._T_ms_start
            Q[core._Q_SHIFT_FF] = spec.shift_feedforward
            Q[core._Q_LIMITED] = self._limited
            if lim is not None:
                (Q[core._Q_T_MAX], Q[core._Q_W_MAX]), (Q[core._Q_S_MAX], Q[core._Q_V_MAX]) = \
                    self._lim
            Q[core._Q_BAND] = SPEED_BAND
            Q[core._Q_ANTI_WINDUP] = spec.anti_windup
            mats = [np.ascontiguousarray(m, dtype=float)
                    for m in (c.A, c.B, c.C, c.D, self._L_aw)]
            self._fast = (self._no_ref, self._P, self._T, self._S, self._R_s_cache, self._res,
                          Q, *mats)

    # -- set-up ----------------------------------------------------------------------------
    def _references(self, references: Mapping[str, NDArray]) -> _Refs:
        t = self.t_k
        tab = reference_table(references, t)
        r = tab.get("r_g", np.full(t.shape, self.point["r_g"]))
        lo, hi = ratio_range(self.model.params.variator)
        if np.any((r < lo) | (r > hi)):
            bad = r[(r < lo) | (r > hi)][0]
            raise ParameterError(f"references.r_g = {bad:g}: outside the variator's ratio "
                                 f"range [{lo:.4g}, {hi:.4g}]")
        if "tau" in tab:
            pairs, inv = _unique_rows(tab["tau"], r)
            slip = slip_at_torque_ratio(self.model, pairs[:, 0], pairs[:, 1])[inv]
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
            ru, inv = np.unique(r, return_inverse=True)
            g = trim_grid(self.model, ru, self.point["omega_p"],
                          tau=np.full(ru.shape, self._tau_ref), F_s=self.point["F_s"])
            if not np.all(g.ok):
                bad = ru[~g.ok][0]
                raise ParameterError(f"decoupling: the machine does not trim at the reference "
                                     f"ratio {bad:g} ({g.reason[~g.ok][0]})")
            dec = (g.u[:, 0] / g.u[:, 1])[inv]
        return _Refs(r_g=r, slip=np.asarray(slip, float), mu=np.asarray(mu, float), rdot=rdot,
                     decoupling=dec)

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
        """The raw measurements at a steady operating point (`RAW_SIGNALS` order)."""
        w_p = point["omega_p"]
        return np.array([point["r_g"], w_p, point["r_g"] * w_p * (1 - point["nu"]),
                         point["T_l"], 0.0, 0.0, point["T_l"]])

    def initial_state(self) -> NDArray[np.float64]:
        """The law's state at rest at the starting point (buffers full of the point's
        measurements, the feedforward filter settled, the controller state zero)."""
        z = np.zeros(self.n_state)
        z[:self._nb] = np.repeat(self.raw0, self._n_buf)
        z[self._nb] = self._ff_force(self.raw0[3], self.raw0[0], self.refs.mu[0])
        return z

    def reset(self) -> None:
        """Back to the first sample at rest."""
        self._z = self.z0.copy()
        self._z_spare = np.empty_like(self._z)
        self._k = 0

    @property
    def measured(self) -> tuple[str, ...]:
        """What the simulator hands the law at each sample (`RAW_SIGNALS`)."""
        return RAW_SIGNALS

    # -- the law ---------------------------------------------------------------------------
    def _R_s(self, r_g: float) -> float:
        """Secondary running radius [m] at the measured ratio (unstretched belt; a function
        of the ratio alone, to the last bit: the last value is reused only for the same
        ratio)."""
        r = min(max(float(r_g), 1e-3), 1e3)
        if r != self._R_s_last[0]:
            self._R_s_last = (r, secondary_radius(r, self._L, self._a))
        return self._R_s_last[1]

    def _ff_force(self, T_ds: float, r_g: float, mu_ref: float) -> float:
        """Clamping force [N] that holds the traction coefficient ``traction_error * mu_ref``
        at driveshaft torque `T_ds` and ratio `r_g`."""
        spec = self.config.spec
        return spec.feedforward_gain * T_ds * self._cosb / (2 * spec.traction_error * mu_ref
                                                            * self._R_s(r_g))

    def sense(self, buf: NDArray, ideal: bool = False) -> NDArray[np.float64]:
        """The measurements the controller sees from the buffers (n_raw, n_buf): each signal
        `delay` samples late, the shaft speeds averaged over the counting window and
        quantised (not when `ideal`)."""
        buf = np.ascontiguousarray(buf, dtype=float)
        m = np.empty(buf.shape[0])
        core.sense(buf.ravel(), buf.shape[0], self._P, ideal, m)
        return m

    def preprocess(self, s: NDArray, raw: NDArray, k: int, ref: NDArray | None = None,
                   ideal: bool = False) -> tuple[NDArray, NDArray, NDArray, NDArray]:
        """Everything of one sample but the controller: from the sensor and feedforward
        state `s` (``n_pre``), the raw measurements `raw` (`RAW_SIGNALS`) and the sample
        index `k`, the next state, the controller's errors ``e``, the servo torques without
        the controller's share (holding torques and feedforwards) and the measurements the
        controller saw; `ref` (``r_g, slip, mu, dr_g/dt``) replaces the references of sample
        `k`; `ideal` drops noise and quantisation."""
        s = np.ascontiguousarray(s, dtype=float)
        s_next = np.empty(self.n_pre)
        e, u, m = self._pre(s, s_next, raw, k, ref, ideal)
        return s_next, np.array(e), np.array(u), np.array(m)

    def _pre(self, s: NDArray, out: NDArray, raw: NDArray, k: int, ref: NDArray | None,
             ideal: bool) -> tuple[list[float], list[float], list[float]]:
        """`preprocess` into ``out[:n_pre]`` (the next pre-processing state), returning the
        errors, the servo torques without the controller's share and the measurements as
        floats: the arithmetic compiled (`empact.control._law_core.pre_core`), then the
        schedule's gains, the safety-factor clamping, the shift feedforward and the
        primary servo's low-passed share."""
        spec = self.config.spec
        nb = self._nb
        kk = k if k < self._n_last else self._n_last
        if ref is None:
            refv = self._no_ref
            rows = self._ref_rows
            r_ref, rdot, dec = rows[0][kk], rows[3][kk], rows[4][kk]
        else:
            r = [float(x) for x in ref]
            r_ref, rdot, dec = r[0], r[3], self._decoupling0
            refv = np.array(r + [self._mu_max_ref(r_ref) if self._sched else np.nan])
        res = self._res
        core.pre_core(s, out, np.ascontiguousarray(raw, dtype=float), k, ideal, refv,
                      self._P, self._T, self._S, self._R_s_cache, res)
        v = res.tolist()
        e0, e1, u0, u1, f = v[core.R_E0], v[core.R_E1], v[core.R_U0], v[core.R_U1], \
            v[core.R_F]
        m = v[core.R_M:]
        if self._sched:
            g0, g1 = self.controller.schedule.exp_gains(v[core.R_L0:core.R_L1 + 1])
            e0 = e0 * g0
            e1 = e1 * g1
        if self._safety:
            e1 = 0.0  # the slip loop is replaced by the open-loop clamping strategy
            u1 = self._safety_torque(m[3], m[0])
        elif spec.feedforward and v[core.R_RS] != v[core.R_RS]:
            raise _no_geometry(m[0])
        # the primary servo's feedforward share, low-passed: the decoupler (it follows the
        # feedforward's clamping) and the shift feedforward
        t_mp = dec * (u1 - self._T_ms_start)
        if spec.shift_feedforward:
            t_mp += self._shift_torque(r_ref, rdot, m[1], f if spec.feedforward
                                       else self._F_s0, kk if ref is None else None)
        g = s.item(nb + 1)
        if dec or spec.shift_feedforward:
            a = self._alpha_dec
            g = a * g + (1 - a) * t_mp
            u0 += g
        else:
            g = 0.0
        out[nb + 1] = g
        return [e0, e1], [u0, u1], m

    def _safety_torque(self, T: float, r_m: float) -> float:
        """The safety-factor strategy's secondary servo torque for the torque `T` [N m] a
        production controller knows (the engine's torque estimate; here the driveshaft
        torque) at the measured ratio `r_m`: ``F_s = SF |T| cos(beta) / (2 mu_design R_s)``."""
        mu_d = self._mu_design if self._mu_design is not None else float(self.model.mu_max(r_m))
        return self._tpf * self.config.spec.safety_factor * abs(T) * self._cosb / (
            2 * mu_d * self._R_s(r_m))

    def _mu_max_ref(self, r_ref: float) -> float:
        """Peak traction coefficient at the reference ratio (cached per ratio)."""
        if r_ref != self._mu_max_cache[0]:
            self._mu_max_cache = (r_ref, float(self.model.mu_max(r_ref)))
        return self._mu_max_cache[1]

    @property
    def n_pre(self) -> int:
        """Size of the sensor, feedforward and decoupler state (`preprocess`)."""
        return self._nb + 2

    @property
    def output_mask(self) -> NDArray[np.float64]:
        """Which controller outputs reach the servos (the safety-factor strategy's clamping
        replaces the controller's secondary servo torque)."""
        return np.array([1.0, 0.0 if self.config.spec.clamping == "safety-factor" else 1.0])

    def update(self, z: NDArray, raw: NDArray, k: int, ref: NDArray | None = None,
               ideal: bool = False) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """One sample of the law: the next state and the servo torques ``[T_mp, T_ms]``
        [N m] held over the period, from the state `z` (`preprocess`'s, then the
        controller's), the raw measurements `raw` (`RAW_SIGNALS`) and the sample index `k`;
        `ref` replaces the references of sample `k`; `ideal` drops noise, quantisation and
        limits (the linear model's law)."""
        c, n = self.controller, self.n_pre
        z = np.ascontiguousarray(z, dtype=float)
        z_next = np.empty(self.n_state)
        e, (u0, u1), m = self._pre(z, z_next, raw, k, ref, ideal)
        xc = z[n:]
        ev = np.array(e)
        # (``M.dot(v)`` is ``M @ v``: the same BLAS call, cheaper to make)
        du = c.C.dot(xc) + c.D.dot(ev)
        du0, du1 = (du if self._mask_ones else du * self._mask).tolist()
        xc_next = c.A.dot(xc) + c.B.dot(ev)
        u0 = u0 + du0
        u1 = u1 + du1
        if not ideal and self._limited:
            s0, s1 = self._limit_f(u0, u1, m[4], m[5])
            # (without saturation the anti-windup term is zero)
            if self.config.spec.anti_windup and (s0 != u0 or s1 != u1):
                xc_next = xc_next + self._L_aw.dot((np.array([s0, s1]) - np.array([u0, u1]))
                                                   * self._mask)
            u0, u1 = s0, s1
        z_next[n:] = xc_next
        return z_next, np.array([u0, u1])

    def _shift_geometry(self, r: NDArray) -> list[tuple[float, ...]]:
        """What `_shift_torque` needs of the reference ratios `r` (1-D) alone, per ratio:
        ``(r, R_p, R_s, phi, R_p / a, a1 + a2 ln(r)^2, kappa*)`` (the creep coefficient's
        factors; ``kappa*`` the geometric thrust ratio, for Shafai's law)."""
        p = self.model.params
        sh = p.shift
        st = variator_state(r, p.variator)
        lr = np.log(r)
        rpa = st.R_p / p.variator.a
        poly = sh.a1 + sh.a2 * lr**2
        geo = (np.zeros(r.shape) if self.model.creep else
               (np.pi + 2 * st.phi) / (np.pi - 2 * st.phi))
        return list(zip(r.tolist(), st.R_p.tolist(), st.R_s.tolist(), st.phi.tolist(),
                        rpa.tolist(), poly.tolist(), geo.tolist()))

    def _shift_torque(self, r_ref: float, rdot: float, w_p: float, F_s: float,
                      k: int | None = None) -> float:
        """Primary servo torque [N m] over its holding value against the creep law's
        resistance at the ratio rate `rdot` [1/s] (at the reference ratio, speed `w_p`,
        clamping force `F_s`): the thrust ratio ``kappa* exp(xi)`` with ``xi = xi_sat
        tanh(rdot / (omega K_c) / xi_sat)`` (`empact.variator.shift_law`) needs the primary
        thrust ``kappa* (exp(xi) - 1) F_s`` more, ``T_mp = -(i_e s / i_w)`` times it (the
        kernel's ratio-controller gain has the same sign); the geometry at the reference
        ratio of sample `k` is prepared once."""
        if rdot == 0.0:
            return 0.0
        row = self._shift_rows.get(k) if k is not None else None
        if row is None or row[0] != r_ref:
            row = self._shift_geometry(np.array([float(r_ref)]))[0]
        _, R_p, R_s, phi, rpa, poly, keq = row
        sh = self._shift
        w_eff = float(np.hypot(w_p, sh.omega_0))
        # `creep_coefficient` and `EmpactModel.static_creep`, term by term
        D = sh.D_ref * (1 + sh.k_D * (F_s - sh.F_ref))
        K_c = float(sh.gain * D * self._g_beta * r_ref * rpa * poly)
        if self.model.creep:
            keq = self.model.static_creep_point(r_ref, R_p, R_s, phi, F_s, self._tau_ref,
                                                self._creep_args)[1]
        xi = sh.xi_sat * np.tanh(rdot / (w_eff * K_c) / sh.xi_sat)
        return float(self._shift_gain * keq * np.expm1(xi) * F_s)

    def _limit(self, u: NDArray, w: tuple[float, float]) -> NDArray[np.float64]:
        """The servo torques the drives deliver: within the torque limit, and the torque that
        would drive a servo faster falls to zero over the last `SPEED_BAND` of its speed."""
        return np.array(self._limit_f(float(u[0]), float(u[1]), float(w[0]), float(w[1])))

    def _limit_f(self, u0: float, u1: float, w0: float, w1: float) -> tuple[float, float]:
        """`_limit` on floats (`_law_core.servo_limited`, as the compiled sample)."""
        (T_max, w_max), (S_max, v_max) = self._lim
        return (core.servo_limited(u0, w0, T_max, w_max, SPEED_BAND),
                core.servo_limited(u1, w1, S_max, v_max, SPEED_BAND))

    @property
    def compiled(self) -> bool:
        """Whether `step` runs the whole sample compiled (`_law_core.step_core`: no
        safety-factor clamping, no moving shift feedforward) rather than `update`."""
        return self._fast is not None

    def run_compiled(self, k0: int, k1: int, sim: tuple[Any, ...], t: float, h: float,
                     filled: int, n_steps: int, n_rej: int) -> tuple[Any, ...]:
        """Samples `k0` to ``k1 - 1`` of the simulator's sampled loop with the law and the
        integrator in one compiled loop (`_loop_core.run_samples`; only when `compiled`):
        bitwise what `step` at each sample between the integrator's calls gives.

        Parameters
        ----------
        k0, k1 : int
            The simulator's first sample and the one after the last.
        sim : tuple
            The simulator's arrays and the integrator's arguments, in `run_samples`' order
            (from ``x`` to ``J``).
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
            When the clamping feedforward finds no belt geometry at the measured ratio (as
            `step` does).
        """
        if self._fast is None:
            raise RuntimeError("run_compiled needs a compiled law (LoopLaw.compiled)")
        status, t, h, filled, n_steps, n_rej, k, done, err = _run_samples(
            k0, k1, self._z, self._z_spare, self._k, *self._fast, self._u_out, *sim, t, h,
            filled, n_steps, n_rej)
        self._k += done
        if done % 2:
            self._z, self._z_spare = self._z_spare, self._z
        if err:
            raise _no_geometry(self._res[core.R_M])
        return status, t, h, filled, n_steps, n_rej, k

    def step(self, t: float, measured: NDArray[np.float64]) -> NDArray[np.float64]:
        """Servo torques ``[T_mp, T_ms]`` [N m] over ``[t, t + dt)``: `update` of the law's
        state, compiled when `compiled`."""
        if self._fast is not None:
            z_next = self._z_spare
            if _step_core(self._z, z_next, np.ascontiguousarray(measured, dtype=float),
                         self._k, *self._fast, self._u_out):
                raise _no_geometry(self._res[core.R_M])
            self._z_spare, self._z = self._z, z_next
            self._k += 1
            return self._u_out.copy()
        self._z, u = self.update(self._z, measured, self._k)
        self._k += 1
        return u

