"""Multi-model, fixed-structure tuning of the gain-scheduled PI on the loop that runs (in the
spirit of MATLAB's ``systune``): the controller's structure is kept, a few named multipliers
of it are searched to maximise the worst multiloop disk margin over every plant of a family.

Structure tuned (`TUNABLE`, chosen by name): per loop (``ratio``: ``T_mp`` from the ratio
error, ``slip``: ``T_ms`` from the slip error)

* ``kp_<loop>``: the proportional gain, a multiplier on the loop's whole schedule (every grid
  point of ``Schedule.gains``), the integral gain ``k_p w_i`` held (``w_i`` divided by it);
* ``ki_<loop>``: the integral gain ``k_p w_i``, a multiplier on ``w_i``;
* ``rolloff_<loop>``: the corner of the second-order roll-off ``w_f``, a multiplier.

The schedule's interpolation, the feedforwards, the decoupler, the sensors, the delay and the
sample rate are the loop's (`empact.control.law.LoopConfig`) and are not tuned.

Every evaluation is the loop model `empact.control.loop.family_loops` builds (the machine
held and sampled, the law's pre-processing linearised), built once for the family and reused
with each candidate controller (`LoopModel.with_controller`: the augmented plant and its
frequency responses are shared), and the margins are the ones ``empact control check``
reports (`LoopModel.disk_margins`, `LoopModel.sensitivity_peaks`, `LoopModel.spectral_radius`).
A proportional multiplier is applied in the unit PI during the search and folded into the
schedule in the result: the two are the same loop (the schedule multiplies errors that are
zero at rest, so only its value at the point enters the linear loop); `tune_pi` rebuilds
the loop model with the tuned controller and reports that.

Objective (minimised, ``"disk-margin"``)::

    f = -min alpha + w_ms sum_j max(0, max Ms_j - max_ms)
        + w_bw sum_j max(0, 1 - min_points wc_j / floor_j)
    f = 10 + max rho - 1  where a plant is unstable (rho >= 1)

with ``alpha`` the multiloop disk margin at every plant, ``Ms_j`` loop j's loop-at-a-time
sensitivity peak, ``wc_j`` its sensitivity bandwidth (where ``|S_jj|`` first reaches
1/sqrt(2), at the servo torques) and ``floor_j`` its floor at each point (the starting
controller's bandwidth there, or one value in Hz for all).  The search is scipy's
Nelder-Mead over the logarithms of the multipliers (bounded), from an initial simplex drawn
with `seed` (deterministic).
"""
from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np
from numpy.typing import NDArray

from .._lazy import lazy_module
from .._results import Result
from .._validate import check_number
from ..errors import ParameterError
from ..params import Params
from .controller import Controller, Schedule
from .family import PlantFamily
from .law import LoopConfig
from .loop import LoopModel, default_omega, family_loops
from .pi import pi_controller
from .robustness import disk_gain_phase

optimize = lazy_module("scipy.optimize")

__all__ = ["TUNABLE", "DEFAULT_TUNABLE", "OBJECTIVES", "TuneOptions", "TuneResult", "check_pi",
           "loop_summary", "tune_pi"]

LOOPS = ("ratio", "slip")
#: the tunable multipliers by name: what each scales
TUNABLE = {f"{kind}_{loop}": text.format(loop=loop) for loop in LOOPS for kind, text in (
    ("kp", "the {loop} loop's proportional gain (its whole schedule), integral gain held"),
    ("ki", "the {loop} loop's integral gain k_p w_i (w_i)"),
    ("rolloff", "the corner of the {loop} loop's second-order roll-off w_f"))}
DEFAULT_TUNABLE = tuple(TUNABLE)
#: objectives of `tune_pi`
OBJECTIVES = ("disk-margin",)
#: weights of the objective's penalties: Ms excess, bandwidth shortfall
W_MS, W_BW = 1.0, 10.0
#: the bandwidth a result may fall short of its floor by (relative) and be `TuneResult.met`
BANDWIDTH_TOLERANCE = 0.01


@dataclass(frozen=True)
class TuneOptions:
    """Options of `tune_pi`.

    Attributes
    ----------
    objective : str
        ``"disk-margin"``: maximise the worst multiloop disk margin (`OBJECTIVES`).
    parameters : tuple of str
        The multipliers tuned (keys of `TUNABLE`).
    max_ms : float or None
        Sensitivity peak allowed per loop (loop at a time) [-]; None: no Ms penalty.
    bandwidth_floor_hz : tuple of float or None
        Lowest sensitivity bandwidth allowed per loop (ratio, slip) at every point [Hz]
        (``|S_jj|`` reaching 1/sqrt(2)); None: the starting controller's at each point.
    min_disk_margin : float
        The margin the result is judged against (`TuneResult.met`) [-]; not in the
        objective.
    bound : float
        Each multiplier stays within ``[1 / bound, bound]``.
    seed : int
        Seed of the initial simplex.
    max_evaluations : int
        Most objective evaluations.
    """

    objective: str = "disk-margin"
    parameters: tuple[str, ...] = DEFAULT_TUNABLE
    max_ms: float | None = 2.0
    bandwidth_floor_hz: tuple[float, float] | None = None
    min_disk_margin: float = 0.6
    bound: float = 4.0
    seed: int = 0
    max_evaluations: int = 300

    def __post_init__(self) -> None:
        if self.objective not in OBJECTIVES:
            raise ParameterError(f"objective = {self.objective!r}: choose one of "
                                 f"{', '.join(OBJECTIVES)}")
        params = tuple(self.parameters)
        bad = [p for p in params if p not in TUNABLE]
        if bad or not params or len(set(params)) != len(params):
            raise ParameterError(f"parameters = {','.join(params) or 'none'}: choose distinct "
                                 f"names from {', '.join(TUNABLE)}")
        object.__setattr__(self, "parameters", params)
        if self.max_ms is not None:
            check_number("max_ms", self.max_ms, 1.0, 100.0, lo_open=True)
        if self.bandwidth_floor_hz is not None:
            bw = tuple(float(check_number("bandwidth_floor", b, 0.0, 50.0, lo_open=True,
                                          unit="Hz")) for b in self.bandwidth_floor_hz)
            if len(bw) != 2:
                raise ParameterError(f"bandwidth_floor = {bw}: two values RATIO,SLIP [Hz]")
            object.__setattr__(self, "bandwidth_floor_hz", bw)
        check_number("min_disk_margin", self.min_disk_margin, 0.0, 1.99)
        check_number("bound", self.bound, 1.0, 100.0, lo_open=True)
        if not isinstance(self.seed, (int, np.integer)) or self.seed < 0:
            raise ParameterError(f"seed = {self.seed!r}: a non-negative integer")
        if not isinstance(self.max_evaluations, (int, np.integer)) or \
                not 1 <= self.max_evaluations <= 100_000:
            raise ParameterError(f"max_evaluations = {self.max_evaluations!r}: an integer "
                                 "1-100000")


def _bandwidths(lm: LoopModel, omega: NDArray) -> NDArray[np.float64]:
    """Sensitivity bandwidth of each loop at every point [rad/s], shape ``shape + (2,)``: the
    first frequency where the loop-at-a-time sensitivity ``|S_jj|`` at the servo torques
    (`LoopModel.sensitivity_peaks`' ``S``) reaches ``1/sqrt(2)`` from below
    (log-interpolated; the grid's last frequency where it never does)."""
    G = lm.plant_response(omega)
    K = lm.controller_response(omega) * lm.mask[None, :, None]
    S = np.abs(np.diagonal(np.linalg.inv(np.eye(2) + K @ G), axis1=-2, axis2=-1))
    ls = np.log(S) - np.log(np.sqrt(0.5))  # shape + (n_w, 2); crosses 0 upwards
    up = ls >= 0
    has = up.any(axis=-2)
    k = np.maximum(up.argmax(axis=-2), 1)  # first index at or above
    lw = np.log(omega)
    la = np.take_along_axis(ls, k[..., None, :] - 1, -2)[..., 0, :]
    lb = np.take_along_axis(ls, k[..., None, :], -2)[..., 0, :]
    t = np.clip(-la / np.where(lb - la == 0, 1.0, lb - la), 0.0, 1.0)
    wb = np.exp(lw[k - 1] + t * (lw[k] - lw[k - 1]))
    return np.asarray(np.where(has, wb, omega[-1]), dtype=np.float64)


def _bandwidth_ratio(lm: LoopModel, omega: NDArray, floor: NDArray) -> NDArray[np.float64]:
    """``min_points wc_j / floor_j`` of each loop (shape (2,)): the bandwidth against its
    floor [Hz] (shape ``shape + (2,)``) at the point where it is shortest."""
    wb = _bandwidths(lm, omega) / (2 * np.pi)
    return np.asarray((wb / floor).reshape(-1, 2).min(axis=0), dtype=np.float64)


def loop_summary(lm: LoopModel, axes: dict[str, NDArray] | None = None,
                 omega: NDArray | None = None) -> dict[str, Any]:
    """The worst case of a loop model over its grid, as ``control check`` measures it: the
    multiloop disk margin, each loop's sensitivity peak and lowest bandwidth, stability.

    Parameters
    ----------
    lm : LoopModel
        Stacked over a family's grid (`family_loops`).
    axes : dict, optional
        The family's axes (SI), to name the worst point.
    omega : ndarray, optional
        Frequencies [rad/s] (default `default_omega`, as ``control check``).

    Returns
    -------
    dict
        ``disk_margin`` [-], ``gain_margin_db`` [dB], ``phase_margin_deg`` [deg],
        ``ms`` [-] (per loop: ``{"ratio", "slip"}``), ``ms_above_2`` (points per loop),
        ``bandwidth_hz`` (the lowest sensitivity bandwidth per loop over the family,
        `_bandwidths`) [Hz], ``spectral_radius`` [-], ``all_stable``, ``worst_point`` (the
        axes' values where the disk margin is smallest, SI).
    """
    w = default_omega(lm.dt) if omega is None else np.asarray(omega, float)
    dm = lm.disk_margins(w)["alpha"]
    ms = lm.sensitivity_peaks(w)["ms"]
    rho = lm.spectral_radius()
    wc = _bandwidths(lm, w)
    i = np.unravel_index(int(np.argmin(dm)), dm.shape)
    a = float(dm[i])
    gm, pm = disk_gain_phase(a)
    flat_ms = ms.reshape(-1, 2)
    out: dict[str, Any] = {
        "disk_margin": a, "gain_margin_db": float(gm), "phase_margin_deg": float(pm),
        "ms": {loop: float(flat_ms[:, j].max()) for j, loop in enumerate(LOOPS)},
        "ms_above_2": {loop: int((flat_ms[:, j] > 2).sum()) for j, loop in enumerate(LOOPS)},
        "bandwidth_hz": {loop: float(wc.reshape(-1, 2)[:, j].min() / (2 * np.pi))
                         for j, loop in enumerate(LOOPS)},
        "spectral_radius": float(rho.max()), "all_stable": bool(np.all(rho < 1))}
    if axes is not None:
        out["worst_point"] = {k: float(v[i[n]]) for n, (k, v) in enumerate(axes.items())}
    return out


@dataclass(frozen=True, eq=False)
class TuneResult(Result):
    """What `tune_pi` did.

    Attributes
    ----------
    objective : str
        The objective (`OBJECTIVES`).
    parameters : tuple of str
        The multipliers tuned (`TUNABLE`).
    multipliers : dict str -> float
        Their tuned values [-] (1: unchanged).
    history : ndarray, shape (n_eval,)
        The objective at each evaluation, in order [-].
    before, after : dict
        `loop_summary` of the starting and the tuned controller on the family (``after``
        from a loop model rebuilt with the tuned controller).
    bandwidth_floor_hz : dict str -> float
        The lowest floor per loop over the family [Hz] (the floor is per point).
    max_ms, min_disk_margin : float or None
        The Ms bound of the objective and the margin judged.
    evaluations : int
        Objective evaluations.
    wall_time_s : float
        Wall time of the tuning (loop model, search, final check) [s].
    seed : int
    met : bool
        Every plant stable, the worst disk margin at least `min_disk_margin`, each loop's
        Ms at most `max_ms` (if given) and its bandwidth at every point at least its floor
        less `BANDWIDTH_TOLERANCE`.
    message : str
        The optimiser's message.
    """

    objective: str
    parameters: tuple[str, ...]
    multipliers: dict[str, float]
    history: NDArray[np.float64]
    before: dict[str, Any]
    after: dict[str, Any]
    bandwidth_floor_hz: dict[str, float]
    max_ms: float | None
    min_disk_margin: float
    evaluations: int
    wall_time_s: float
    seed: int
    met: bool
    message: str


def _unit_pi(ctrl: Controller) -> tuple[NDArray, NDArray, NDArray]:
    """``(k_p, w_i, w_f)`` of a (unit or not) `pi_controller`'s matrices, per loop."""
    A, B = ctrl.A, ctrl.B
    m = len(ctrl.measured)
    kp, wi, wf = np.empty(m), np.empty(m), np.empty(m)
    for j in range(m):
        i1, i2 = 3 * j, 3 * j + 1
        wf[j] = -A[i2, i2]
        kp[j] = B[i2, j] / wf[j]
        wi[j] = A[i2, i1] / (wf[j] * kp[j])
    return kp, wi, wf


def check_pi(ctrl: Controller) -> None:
    """Refuse a controller that is not a (scheduled) `pi_controller` on ratio and slip.

    Parameters
    ----------
    ctrl : Controller
        The controller to tune.

    Returns
    -------
    None
        Raises `ParameterError` naming the controller when it is not one.
    """
    if ctrl.method != "pi" or ctrl.dt or ctrl.n != 6 or len(ctrl.measured) != 2:
        raise ParameterError(f"tune: a continuous two-loop PI (method 'pi', 6 states) is "
                             f"tuned; got method {ctrl.method!r}, {ctrl.n} states, dt "
                             f"{ctrl.dt:g} s")
    kp, wi, wf = _unit_pi(ctrl)
    rebuilt = pi_controller(kp, wi, wf, ctrl.measured, ctrl.outputs)
    if not (np.allclose(rebuilt.A, ctrl.A, rtol=1e-12, atol=0)
            and np.allclose(rebuilt.B, ctrl.B, rtol=1e-12, atol=0)
            and np.allclose(rebuilt.C, ctrl.C) and not np.any(ctrl.D)):
        raise ParameterError("tune: the controller's matrices are not empact's PI structure "
                             "(empact.control.pi.pi_controller)")


def _candidate(ctrl: Controller, mult: dict[str, float], fold: bool) -> Controller:
    """The PI with the multipliers applied (``fold``: the proportional ones in the schedule,
    else in the unit PI's ``k_p``)."""
    kp, wi, wf = _unit_pi(ctrl)
    cp = np.array([mult.get(f"kp_{loop}", 1.0) for loop in LOOPS])
    ci = np.array([mult.get(f"ki_{loop}", 1.0) for loop in LOOPS])
    cf = np.array([mult.get(f"rolloff_{loop}", 1.0) for loop in LOOPS])
    wi2, wf2 = wi * ci / cp, wf * cf
    sched = ctrl.schedule
    if fold:
        if sched is not None:
            sched = Schedule(axes=dict(sched.axes), gains=sched.gains * cp)
            u = pi_controller(kp, wi2, wf2, ctrl.measured, ctrl.outputs)
        else:
            u = pi_controller(kp * cp, wi2, wf2, ctrl.measured, ctrl.outputs)
    else:
        u = pi_controller(kp * cp, wi2, wf2, ctrl.measured, ctrl.outputs)
    return Controller(u.A, u.B, u.C, u.D, ctrl.measured, ctrl.outputs, 0.0, "pi",
                      dict(ctrl.design), sched)


def tune_pi(controller: Controller, family: PlantFamily, loop: LoopConfig, params: Params,
            options: TuneOptions | None = None) -> tuple[Controller, TuneResult]:
    """Tune the multipliers of a (gain-scheduled) PI over every plant of `family` on the
    loop that runs (module notes: structure, objective, optimiser).

    Parameters
    ----------
    controller : Controller
        Continuous `pi_controller` structure (e.g. the shipped ``pi.json``), scheduled or
        not.
    family : PlantFamily
        Every point trimmed, with `empact.control.family.LOOP_FAMILY_OUTPUTS`.
    loop : LoopConfig
        The loop it runs in (`empact.control.law.SHIPPED_LOOP` for the shipped one).
    params : Params
        The parameter set.
    options : TuneOptions, optional
        Objective, tuned parameters, bounds, seed, evaluations (default `TuneOptions()`).

    Returns
    -------
    tuned : Controller
        The same structure with the tuned multipliers (proportional ones folded into the
        schedule); its ``design`` records ``tune`` (`TuneResult.to_dict` without the
        history, plus the structure's description) and the new ``wi_rad_s``,
        ``roll_off_hz``, ``kp_nominal`` and ``worst``.
    result : TuneResult

    Raises
    ------
    ParameterError
        For a controller that is not the PI structure or bad options.
    """
    opts = TuneOptions() if options is None else options
    check_pi(controller)
    t0 = time.perf_counter()
    lm0 = family_loops(family, controller, loop, params)
    w = default_omega(lm0.dt)
    before = loop_summary(lm0, dict(family.axes), w)
    floor = (_bandwidths(lm0, w) / (2 * np.pi) if opts.bandwidth_floor_hz is None
             else np.broadcast_to(np.array(opts.bandwidth_floor_hz), lm0.shape + (2,)))
    names = opts.parameters
    lo, hi = -np.log(opts.bound), np.log(opts.bound)
    history: list[float] = []

    def evaluate(x: NDArray) -> float:
        mult = dict(zip(names, np.exp(np.clip(x, lo, hi)).tolist()))
        lm = lm0.with_controller(_candidate(controller, mult, fold=False))
        rho = lm.spectral_radius()
        if np.any(rho >= 1):
            f = 10.0 + float(rho.max() - 1)
        else:
            f = -float(lm.disk_margins(w)["alpha"].min())
            if opts.max_ms is not None:
                ms = lm.sensitivity_peaks(w)["ms"].reshape(-1, 2).max(axis=0)
                f += W_MS * float(np.maximum(ms - opts.max_ms, 0.0).sum())
            f += W_BW * float(np.maximum(1.0 - _bandwidth_ratio(lm, w, floor), 0.0).sum())
        history.append(f)
        return f

    n = len(names)
    rng = np.random.default_rng(opts.seed)
    x0 = np.zeros(n)
    simplex = np.vstack([x0, x0 + np.log(1.3) * (np.eye(n) + 0.1 * rng.standard_normal((n, n)))])
    res = optimize.minimize(evaluate, x0, method="Nelder-Mead",
                            bounds=[(lo, hi)] * n,
                            options={"initial_simplex": simplex,
                                     "maxfev": int(opts.max_evaluations),
                                     "xatol": 1e-3, "fatol": 1e-5})
    hist = np.array(history)
    # the best evaluated point (Nelder-Mead's x is it; kept explicit)
    x_best = np.clip(res.x, lo, hi)
    mult = dict(zip(names, np.exp(x_best).tolist()))
    tuned = _candidate(controller, mult, fold=True)
    lm1 = family_loops(family, tuned, loop, params)
    after = loop_summary(lm1, dict(family.axes), w)
    wall = time.perf_counter() - t0
    met = bool(after["all_stable"] and after["disk_margin"] >= opts.min_disk_margin
               and (opts.max_ms is None or max(after["ms"].values()) <= opts.max_ms)
               and bool(np.all(_bandwidth_ratio(lm1, w, floor) >= 1 - BANDWIDTH_TOLERANCE)))
    after["bandwidth_ratio"] = dict(zip(LOOPS, _bandwidth_ratio(lm1, w, floor).tolist()))
    result = TuneResult(objective=opts.objective, parameters=names, multipliers=mult,
                        history=hist, before=before, after=after,
                        bandwidth_floor_hz={lp: float(floor[..., j].min())
                                            for j, lp in enumerate(LOOPS)},
                        max_ms=opts.max_ms, min_disk_margin=opts.min_disk_margin,
                        evaluations=int(len(hist)), wall_time_s=wall, seed=int(opts.seed),
                        met=met, message=str(res.message))
    kp, wi, wf = _unit_pi(tuned)
    design = dict(controller.design)
    record = {k: v for k, v in result.to_dict().items() if k != "history"}
    record.update(structure={p: TUNABLE[p] for p in names},
                  objective_formula=("-min alpha + w_ms sum_j max(0, Ms_j - max_ms) + w_bw "
                                     "sum_j max(0, 1 - wc_j / floor_j); unstable: 10 + "
                                     "rho - 1"),
                  weights={"ms": W_MS, "bandwidth": W_BW}, optimizer="scipy.optimize "
                  "Nelder-Mead on ln(multipliers), bounded, initial simplex from the seed",
                  objective_start=float(hist[0]), objective_end=float(res.fun),
                  bound=opts.bound)
    if "kp_nominal" in design and tuned.schedule is not None:
        cp = np.array([mult.get(f"kp_{loop_}", 1.0) for loop_ in LOOPS])
        design["kp_nominal"] = (np.asarray(design["kp_nominal"], float) * cp).tolist()
    design.update(wi_rad_s=wi.tolist(), roll_off_hz=(wf / 2 / np.pi).tolist(),
                  worst={k: after[k] for k in ("disk_margin", "gain_margin_db",
                                               "phase_margin_deg", "spectral_radius",
                                               "all_stable")},
                  tune=record)
    tuned = Controller(tuned.A, tuned.B, tuned.C, tuned.D, tuned.measured, tuned.outputs,
                       0.0, "pi", design, tuned.schedule)
    return tuned, result


def parse_parameters(text: str | Sequence[str]) -> tuple[str, ...]:
    """``"kp_ratio,ki_slip"`` (or a sequence) as a tuple of `TUNABLE` names (checked by
    `TuneOptions`, which refuses an empty item as any name not in `TUNABLE`)."""
    items = text.split(",") if isinstance(text, str) else list(text)
    return tuple(s.strip() for s in items)
