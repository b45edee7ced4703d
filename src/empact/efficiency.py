"""Steady-state efficiency of the variator and its actuation, by clamping strategy.

At each point (input torque ``T_in`` [N m] at the primary, input speed ``omega_in`` [rad/s],
ratio ``r_g``) a strategy sets the clamping and the machine is trimmed there
(`empact.nonlinear.equilibrium.trim_grid`):

``sf1.3``
    A production CVT's open-loop clamping, ``F_s = SF |T_l| cos(beta) / (2 mu_design R_s)``
    with ``SF = 1.3`` and ``mu_design`` the smallest traction peak over the ratio range
    (ratio-blind), on the unstretched belt's secondary radius: the law of the loop's
    ``clamping = "safety-factor"`` (`empact.control.law`, `_law_core.safety_torque`) at
    steady state, where the driveshaft torque is the load torque.
``sf1.3-aware``
    The same with ``mu_design`` the traction peak at the ratio (``mu_design =
    "ratio-aware"``).
``slip``
    Slip control: the slip where the torque ratio ``tau = mu / mu_max`` is the set-point
    (default the parameter set's ``[operating] tau``, 0.9 as shipped), which the loop law's
    integrators hold at steady state.
``hydraulic``
    ``sf1.3``'s clamping with the hydraulic reference actuation
    (`empact.actuation_energy.hydraulic_power`) in place of the servos.

Each point gives the variator's input and output power at its shafts (``P_in`` at the
primary, ``P_out`` at the secondary), its losses by term (summing to ``P_in - P_out``), the
actuation's power by term (the servos' electrical power at their holding torques with their
transmissions, `empact.actuation_energy.servo_power`, or the pump's shaft power), the
variator's efficiency ``P_out / P_in`` and the total efficiency ``P_out / (P_in +
actuation)``.  With ``F_s`` given (a clamping sweep) the sweep's clamping replaces the
strategy's, and the strategy only chooses the actuation.
"""
from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ._results import Result, plain
from ._validate import check_choice, fmt
from .actuation_energy import (
    PUMP_TERMS,
    SERVO_TERMS,
    actuation_energy,
    hydraulic_power,
    servo_power,
)
from .errors import ParameterError
from .nonlinear import VARIATOR_LOSSES
from .nonlinear.equilibrium import trim_grid
from .nonlinear.model import EmpactModel, nonlinear_model
from .nonlinear.simulation import SimulationResult
from .params import Params
from .variator.geometry import check_ratio, ratio_range, secondary_radius

__all__ = ["STRATEGIES", "SAFETY_FACTOR", "INPUT_TORQUE_RTOL", "EfficiencyMap", "efficiency_map",
           "strategy_clamping", "run_energy", "energy_summary"]

#: the clamping strategies (module notes)
STRATEGIES = ("sf1.3", "sf1.3-aware", "slip", "hydraulic")
#: the safety factor of the ``sf1.3`` strategies [-]
SAFETY_FACTOR = 1.3
#: how closely a point meets its input torque [-] (relative): the trim's own rounding (the
#: slip's bisection, the creep law's fixed point) moves the input torque by up to about
#: 4e-12 of itself where the drag is large (``[losses] c_v``, ``c_q`` at their bands' ends)
INPUT_TORQUE_RTOL = 1e-10
#: the actuation's term names by strategy
_ACTUATION = {s: tuple(f"{t}_{side}" for side in ("mp", "ms") for t in SERVO_TERMS)
              for s in STRATEGIES if s != "hydraulic"}
_ACTUATION["hydraulic"] = PUMP_TERMS


def _variator_powers(y: Mapping[str, NDArray]) -> tuple[NDArray, NDArray, dict[str, NDArray]]:
    """The variator's input power at the primary, output power at the secondary and losses by
    name [W], from the model's outputs by name (each an array).

    The one place that reads them: the kernel's outputs ``P_var_in`` (the primary shaft's
    power into the variator), ``P_var_out`` (the secondary shaft's power out of it) and the
    loss terms `empact.nonlinear.VARIATOR_LOSSES` (slip, clamping, load, drag), which sum to
    ``P_var_in - P_var_out``.
    """
    return y["P_var_in"], y["P_var_out"], {k: y[k] for k in VARIATOR_LOSSES}


def strategy_clamping(model: EmpactModel, strategy: str, T_l: ArrayLike, r_g: ArrayLike,
                      safety_factor: float = SAFETY_FACTOR) -> NDArray[np.float64]:
    """The clamping force [N] of a safety-factor strategy at load torque `T_l` and ratio
    `r_g`: ``SF |T_l| cos(beta) / (2 mu_design R_s(r_g))`` (module notes).

    Parameters
    ----------
    model : EmpactModel
        The nonlinear model (its traction peaks and geometry).
    strategy : {"sf1.3", "sf1.3-aware", "hydraulic"}
        ``sf1.3`` and ``hydraulic``: the ratio-blind design traction; ``sf1.3-aware``: the
        peak at the ratio.
    T_l : array_like
        Load torques [N m].
    r_g : array_like
        Ratios [-] (broadcast against `T_l`).
    safety_factor : float, optional
        ``SF`` [-] (default `SAFETY_FACTOR`).

    Returns
    -------
    array
        Clamping forces [N], the broadcast shape.
    """
    v = model.params.variator
    T, r = np.broadcast_arrays(np.asarray(T_l, float), np.asarray(r_g, float))
    mu_d: Any
    if strategy == "sf1.3-aware":
        mu_d = model.mu_max(r)
    elif strategy in ("sf1.3", "hydraulic"):
        mu_d = float(np.min(model.mu_max(np.geomspace(*ratio_range(v), 41))))
    else:
        raise ParameterError(f"strategy = {strategy!r}: no safety-factor clamping (one of "
                             "sf1.3, sf1.3-aware, hydraulic)")
    R_s = np.vectorize(lambda x: secondary_radius(x, v.L_belt, v.a))(r)
    return np.asarray(safety_factor * np.abs(T) * np.cos(v.beta) / (2 * mu_d * R_s))


@dataclass(frozen=True, eq=False)
class EfficiencyMap(Result):
    """Steady-state efficiency points (`efficiency_map`), one per strategy and grid point.

    Attributes
    ----------
    strategy : tuple of str, length N
        Each point's strategy (`STRATEGIES`).
    T_in, omega_in, r_g : arrays, shape (N,)
        Input torque [N m] and speed [rad/s] at the primary, ratio [-].
    F_s, F_p : arrays, shape (N,)
        Secondary and primary clamping forces [N].
    tau, nu : arrays, shape (N,)
        Torque ratio and slip [-].
    T_mp, T_ms : arrays, shape (N,)
        The servos' holding torques [N m].
    P_in, P_out : arrays, shape (N,)
        The variator's input and output power at its shafts [W].
    losses : dict str -> array, shape (N,)
        The variator's losses by term [W]; they sum to ``P_in - P_out``.
    actuation : dict str -> array, shape (N,)
        The actuation's power by term [W] (NaN where a term is not the point's strategy's).
    efficiency, total_efficiency : arrays, shape (N,)
        ``P_out / P_in`` and ``P_out / (P_in + sum of actuation)`` [-].
    ok : bool array, shape (N,)
        Trimmed; ``reason`` says why not (values NaN).
    reason : tuple of str, length N
    axes : dict str -> array
        The swept values: ``T_in``, ``omega_in``, ``r_g`` and, for a clamping sweep, ``F_s``;
        the points run over the strategies, then these axes in this order (C order).
    strategies : tuple of str
        The strategies, in the order of the points.
    """

    strategy: tuple[str, ...]
    T_in: NDArray[np.float64]
    omega_in: NDArray[np.float64]
    r_g: NDArray[np.float64]
    F_s: NDArray[np.float64]
    F_p: NDArray[np.float64]
    tau: NDArray[np.float64]
    nu: NDArray[np.float64]
    T_mp: NDArray[np.float64]
    T_ms: NDArray[np.float64]
    P_in: NDArray[np.float64]
    P_out: NDArray[np.float64]
    losses: dict[str, NDArray[np.float64]]
    actuation: dict[str, NDArray[np.float64]]
    efficiency: NDArray[np.float64]
    total_efficiency: NDArray[np.float64]
    ok: NDArray[np.bool_]
    reason: tuple[str, ...]
    axes: dict[str, NDArray[np.float64]]
    strategies: tuple[str, ...]

    def points(self) -> list[dict[str, Any]]:
        """One record per point: ``strategy``, ``r_g``, ``T_in``, ``omega_in``, ``F_s``,
        ``F_p``, ``tau``, ``nu``, ``T_mp``, ``T_ms``, ``P_in``, ``P_out``, ``losses``,
        ``actuation`` (the strategy's terms), ``efficiency``, ``total_efficiency``, ``ok``,
        ``reason`` (SI, NaN as None).

        Returns
        -------
        list of dict
            JSON-safe records (`empact._results.plain`).
        """
        out = []
        for k, s in enumerate(self.strategy):
            rec: dict[str, Any] = {"strategy": s}
            for name in ("r_g", "T_in", "omega_in", "F_s", "F_p", "tau", "nu", "T_mp", "T_ms",
                         "P_in", "P_out"):
                rec[name] = float(getattr(self, name)[k])
            rec["losses"] = {n: float(v[k]) for n, v in self.losses.items()}
            rec["actuation"] = {n: float(self.actuation[n][k]) for n in _ACTUATION[s]}
            rec["efficiency"] = float(self.efficiency[k])
            rec["total_efficiency"] = float(self.total_efficiency[k])
            rec["ok"] = bool(self.ok[k])
            rec["reason"] = self.reason[k]
            out.append(rec)
        return plain(out)

    def to_dict(self) -> dict[str, Any]:
        """The map as plain JSON types: ``strategies``, ``axes`` (the swept values, SI) and
        ``points`` (`points`).

        Returns
        -------
        dict
            Ready for ``json.dumps(..., allow_nan=False)``.
        """
        return {"strategies": list(self.strategies), "axes": plain(self.axes),
                "points": self.points()}

    def grid(self, name: str, strategy: str) -> NDArray[np.float64]:
        """One quantity of one strategy on the swept axes.

        Parameters
        ----------
        name : str
            A field of shape (N,) (``"efficiency"``, ``"F_s"``, ...), or a loss or actuation
            term's name.
        strategy : str
            One of `strategies`.

        Returns
        -------
        array
            Shape ``(n_T_in, n_omega_in, n_r_g)`` (and ``n_F_s`` last for a clamping sweep).
        """
        check_choice("strategy", strategy, self.strategies)
        v = self.losses.get(name, self.actuation.get(name))
        if v is None:
            v = getattr(self, name)
        shape = tuple(len(a) for a in self.axes.values())
        i = self.strategies.index(strategy)
        n = int(np.prod(shape))
        return np.asarray(v, float)[i * n:(i + 1) * n].reshape(shape)


def efficiency_map(params: Params, T_in: ArrayLike, omega_in: ArrayLike, r_g: ArrayLike, *,
                   strategies: Sequence[str] = STRATEGIES, F_s: ArrayLike | None = None,
                   tau: float | None = None,
                   model: EmpactModel | None = None) -> EfficiencyMap:
    """Steady-state efficiency of the variator and its actuation over input torque, input
    speed and ratio (and clamping force), by strategy (module notes).

    Parameters
    ----------
    params : Params
        The parameter set (its ``[servo]`` and ``[hydraulic]`` bill the actuation).
    T_in : array_like, shape (n_T,)
        Input torques at the primary [N m], > 0.
    omega_in : array_like, shape (n_w,)
        Input (primary) speeds [rad/s], > 0.
    r_g : array_like, shape (n_r,)
        Ratios [-] in the variator's range.
    strategies : sequence of str, optional
        Any of `STRATEGIES` (default all).
    F_s : array_like, shape (n_F,), optional
        Clamping forces [N], > 0: a clamping sweep, the sweep's clamping in place of the
        strategies'.
    tau : float, optional
        The ``slip`` strategy's torque ratio set-point [-] in (0, 1) (default the parameter
        set's ``[operating] tau``, else 0.9).
    model : EmpactModel, optional
        The nonlinear model to trim (default ``nonlinear_model(params)``).

    Returns
    -------
    EfficiencyMap
        ``len(strategies) * n_T * n_w * n_r (* n_F)`` points.

    Raises
    ------
    ParameterError
        For a strategy not in `STRATEGIES`, a torque, speed or clamping force not positive, a
        ratio out of range or a set-point outside (0, 1) (before any trim).
    """
    strategies = tuple(dict.fromkeys(check_choice("strategy", s, STRATEGIES)
                                     for s in strategies))
    if not strategies:
        raise ParameterError("strategies: give at least one of " + ", ".join(STRATEGIES))
    axes = {"T_in": np.atleast_1d(np.asarray(T_in, float)),
            "omega_in": np.atleast_1d(np.asarray(omega_in, float)),
            "r_g": np.atleast_1d(np.asarray(r_g, float))}
    for name, unit in (("T_in", "N m"), ("omega_in", "rad/s")):
        bad = axes[name][~(axes[name] > 0)]
        if bad.size:
            raise ParameterError(f"{name} = {fmt(float(bad[0]))}: must be > 0 [{unit}]")
    check_ratio(axes["r_g"], params.variator, "r_g")
    if F_s is not None:
        axes["F_s"] = np.atleast_1d(np.asarray(F_s, float))
        bad = axes["F_s"][~(axes["F_s"] > 0)]
        if bad.size:
            raise ParameterError(f"F_s = {fmt(float(bad[0]))}: must be > 0 [N]")
    if tau is None:
        tau = params.operating.tau if params.operating.tau is not None else 0.9
    if not 0 < tau < 1:
        raise ParameterError(f"tau = {fmt(tau)}: the slip set-point must be in (0, 1)")
    model = nonlinear_model(params) if model is None else model
    mesh = [a.ravel() for a in np.meshgrid(*axes.values(), indexing="ij")]
    T, w, r = mesh[0], mesh[1], mesh[2]
    F_fix = mesh[3] if F_s is not None else None
    blocks = [_strategy_points(params, model, s, T, w, r, F_fix, tau)
              for s in strategies]
    cat = {k: np.concatenate([b[k] for b in blocks]) for k in blocks[0]
           if k not in ("losses", "actuation", "reason")}
    losses = {n: np.concatenate([b["losses"][n] for b in blocks]) for n in blocks[0]["losses"]}
    names = [n for s in strategies for n in _ACTUATION[s]]
    nan = np.full(T.size, np.nan)
    actuation = {n: np.concatenate([b["actuation"].get(n, nan) for b in blocks])
                 for n in dict.fromkeys(names)}
    reason = tuple(x for b in blocks for x in b["reason"])
    strategy = tuple(s for s in strategies for _ in range(T.size))
    return EfficiencyMap(strategy=strategy, losses=losses, actuation=actuation, reason=reason,
                         axes=axes, strategies=strategies, **cat)


def _strategy_points(params: Params, model: EmpactModel, strategy: str, T: NDArray,
                     w: NDArray, r: NDArray, F_fix: NDArray | None,
                     tau: float) -> dict[str, Any]:
    """One strategy's points: the load torque that gives the input torque `T` (the secant
    method on ``T_in(T_l) = T``, started with the slope ``r_g``, exact in one step while the
    variator has no torque loss; to `INPUT_TORQUE_RTOL`), its clamping, the trim and the
    powers."""
    T_l = T / r
    slope = r.copy()          # d T_in / d T_l, the secant's
    prev: tuple[NDArray, NDArray] | None = None
    for _ in range(50):
        if F_fix is not None:
            g = trim_grid(model, r, w, F_s=F_fix, T_l=T_l)
        elif strategy == "slip":
            g = trim_grid(model, r, w, tau=np.full(T.size, tau), T_l=T_l)
        else:
            g = trim_grid(model, r, w, F_s=strategy_clamping(model, strategy, T_l, r), T_l=T_l)
        assert g.y is not None  # (trim_grid always gives the outputs)
        y = {n: g.y[:, k] for k, n in enumerate(model.outputs)}
        P_in, P_out, losses = _variator_powers(y)
        T_got = P_in / w
        miss = np.where(g.ok, T - T_got, 0.0)
        if np.all(np.abs(miss) <= INPUT_TORQUE_RTOL * np.abs(T)):
            break
        if prev is not None:
            dT_l, dT_in = T_l - prev[0], T_got - prev[1]
            good = g.ok & (dT_l != 0) & (dT_in * dT_l > 0)  # a rising secant
            slope = np.where(good, dT_in / np.where(good, dT_l, 1.0), slope)
        prev = (T_l, T_got)
        T_l = T_l + miss / slope
    ok, reason = g.ok.copy(), list(g.reason)
    for k in np.flatnonzero(ok & (np.abs(miss) > INPUT_TORQUE_RTOL * np.abs(T))):
        ok[k] = False
        reason[k] = (f"the input torque {T[k]:g} N m not met within {INPUT_TORQUE_RTOL:g} "
                     f"(reached {T_got[k]:.12g} N m)")
    if strategy == "hydraulic":
        act = hydraulic_power(params.hydraulic, y["F_p"], y["F_s"], y["omega_p"])
    else:
        act = servo_power(params, y["T_mp_act"], y["T_ms_act"], y["omega_mp"], y["omega_ms"])
    P_act = sum(act.values())
    return {"T_in": T.copy(), "omega_in": w.copy(), "r_g": r.copy(), "F_s": y["F_s"],
            "F_p": y["F_p"], "tau": y["tau"], "nu": y["nu"], "T_mp": y["T_mp_act"],
            "T_ms": y["T_ms_act"], "P_in": P_in, "P_out": P_out, "losses": losses,
            "actuation": act, "efficiency": P_out / P_in,
            "total_efficiency": P_out / (P_in + P_act), "ok": ok, "reason": tuple(reason)}


class _Outputs(Mapping[str, NDArray]):
    """A run's signals by name (`SimulationResult.output`), read when asked for."""

    def __init__(self, result: SimulationResult) -> None:
        self._result = result

    def __getitem__(self, name: str) -> NDArray:
        return self._result.output(name)

    def __iter__(self) -> Any:
        return iter(self._result.outputs)

    def __len__(self) -> int:
        return len(self._result.outputs)


def run_energy(result: SimulationResult, params: Params,
               kinematics: str = "equal-translation") -> dict[str, Any]:
    """A simulation's energies by term [J]: the variator's input and output at its shafts, its
    losses by term (the integrator's integrals over its own steps,
    `SimulationResult.energy_integrals`; the trapezoidal rule on the output samples for a
    result without them), the servos' electrical energy
    (`empact.actuation_energy.actuation_energy`, billed quasi-statically on the samples) and
    the hydraulic reference's pump energy on the same motion.

    Parameters
    ----------
    result : SimulationResult
        A run of the nonlinear model.
    params : Params
        The parameter set whose ``[servo]`` and ``[hydraulic]`` bill the run.
    kinematics : str, optional
        The run's model option ``kinematics`` (default the model's default).

    Returns
    -------
    dict
        ``duration`` [s]; ``variator_in``, ``variator_out``, ``variator_losses`` [J] and
        ``losses`` (the variator's losses by term [J]); ``servo_electrical`` and ``pump``
        [J]; ``actuation`` (the `ActuationEnergy`).
    """
    q = result.energy_integrals
    if q:
        E_in, E_out = float(q["P_var_in"]), float(q["P_var_out"])
        terms = {k: float(q[k]) for k in VARIATOR_LOSSES}
    else:
        t = np.asarray(result.t, float)
        P_in, P_out, losses = _variator_powers(_Outputs(result))
        integral = lambda v: float(np.trapezoid(v, t)) if t.size > 1 else 0.0  # noqa: E731
        E_in, E_out = integral(P_in), integral(P_out)
        terms = {k: integral(v) for k, v in losses.items()}
    act = actuation_energy(result, params, kinematics)
    return {"duration": act.duration, "variator_in": E_in,
            "variator_out": E_out, "variator_losses": sum(terms.values()),
            "losses": terms, "servo_electrical": act.energy["servo_electrical"],
            "pump": act.hydraulic["pump"], "actuation": act}


def energy_summary(result: SimulationResult, params: Params,
                   kinematics: str = "equal-translation") -> dict[str, Any]:
    """A run's energy balance (`empact.nonlinear.simulation.energy_balance`) with the servos'
    electrical energy beside their mechanical energy.

    Parameters
    ----------
    result : SimulationResult
        A run of the nonlinear model.
    params : Params
        The parameter set whose ``[servo]`` bills the run (`actuation_energy`).
    kinematics : str, optional
        The run's model option ``kinematics`` (default the model's default).

    Returns
    -------
    dict
        ``energy`` [J] by term (those of `energy_balance` and ``servo_electrical``: the
        servos' electrical energy with their drives, copper and transmissions, billed
        quasi-statically) and ``energy_balance_residual`` [-] (the mechanical balance,
        relative to the input energy; the electrical side is not part of it).
    """
    summary = result.energy_balance()
    act = actuation_energy(result, params, kinematics)
    summary["energy"]["servo_electrical"] = act.energy["servo_electrical"]
    return summary
