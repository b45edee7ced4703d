"""The machine sheet (beyond the paper): what the shipped variator is, measured as a control
engineer would - the traction curves' micro-slip slope and torque reserve, the creep law's
magnitude against its anchors, the static stability of the ratio, the torque reserve at
every set-point the package ships, and the variator's efficiency (its losses by term) over
torque, ratio and clamping force.  Compute only: `empact.report` renders.

The bands the claims check are issue 20's (measured pushbelt behaviour and the anchors of the
creep magnitude; model notes Secs. 4, 7 and 9) and issue 32's (published pushbelt
efficiencies: Narita & Priest 2007, Micklem et al. 1996, van der Meulen et al.; model notes
Sec. 10).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from ..control.closed_loop import control_example_path, control_examples
from ..nonlinear.equilibrium import TrimGrid, trim, trim_grid
from ..nonlinear.linearization import BENCH_OPTIONS
from ..nonlinear.model import VARIATOR_LOSSES, EmpactModel, nonlinear_model
from ..nonlinear.scenario import load_scenario
from ..params import OperatingPoint, Params
from ..variator.geometry import primary_radius_per_ratio, variator_state
from ..variator.shift_law import creep_coefficient, creep_damping
from ..variator.thrust_ratio import (
    RatioStabilityMap,
    ratio_stability,
    ratio_stability_map,
    thrust_ratio_from_params,
    zero_torque_difference,
)
from ..variator.traction import TractionCurves, traction_curves, traction_from_params
from .claims import Claim
from .linear import MACHINE, READING

__all__ = ["MachineSection", "machine", "curve_statistics", "efficiency_at_torque", "loss_terms",
           "CURVE_RATIOS", "BANDS", "EFFICIENCY_TORQUES", "EFFICIENCY_RATIOS",
           "EFFICIENCY_TAUS", "CLAMPING_TAUS"]

#: ratios of the curve statistics: LOW, MED, OD (Fig. 10) and r_g = 0.5, 2
CURVE_RATIOS = (0.43, 0.5, 1.0, 2.0, 2.25)
#: slips of the slope table [-]
SLOPE_SLIPS = (0.001, 0.01, 0.02, 0.04)
#: issue 20's bands: slip at 90 % of the peak, peak slip [-], peak; creep per revolution at a
#: 20 % thrust imbalance [m of primary radius] ("a fraction of a millimetre"), equivalent
#: axial damping [N s/m] at 300 rad/s and 10-20 kN (order 1e6)
BANDS = {"nu90": (0.010, 0.020), "nu_peak": (0.020, 0.045), "mu_max": (0.09, 0.12),
         "creep_per_rev": (5e-5, 5e-4), "c_shift": (3e5, 3e6)}
#: operating points of the creep table: ratio, clamping force [N]; at 300 rad/s
CREEP_POINTS = ((0.5, 1e4), (1.0, 1e4), (2.0, 1e4), (1.0, 2e4))
#: thrust imbalance of the creep-rate anchor (Carbone et al. 2007: 10-20 %)
IMBALANCE = 0.2
#: issue 32's efficiency bands: the variator's efficiency [-] over input torque 25-150 N m at
#: 300 rad/s and every ratio 0.5-2 (its peak at most the upper end), and the torque ratio of
#: the maximum of the efficiency over clamping force at r_g 1, 60 N m
EFFICIENCY_BANDS = {"efficiency": (0.85, 0.97), "tau_best": (0.7, 0.95)}
#: input torques [N m] and ratios of the efficiency table, at `EFFICIENCY_SPEED`
EFFICIENCY_TORQUES = (25.0, 60.0, 150.0)
EFFICIENCY_RATIOS = (0.5, 1.0, 2.0)
EFFICIENCY_SPEED = 300.0
#: the clamping of the efficiency table: the slip set-point (the [operating] tau, 0.9) and a
#: safety factor of 1.3 on the traction peak (tau = 1 / 1.3)
EFFICIENCY_TAUS = (0.9, 1 / 1.3)
#: the clamping sweep at r_g 1, 60 N m: torque ratios (the clamping force follows)
CLAMPING_TAUS = tuple(np.round(np.arange(0.40, 0.991, 0.01), 2))


@dataclass(frozen=True)
class MachineSection:
    """The machine sheet.

    Attributes
    ----------
    curves : TractionCurves
        Traction curves over 0-10 % slip at `CURVE_RATIOS`.
    curve_rows : list of list of float
        Per ratio: r_g, mu_max, slip at 90 % of the peak [%], peak slip [%], mu' at
        `SLOPE_SLIPS`.
    creep_rows : list of list of float
        Per `CREEP_POINTS`: r_g, F_s [kN], K_c [-], creep per primary revolution at a
        20 % imbalance [mm of R_p], equivalent axial damping [N s/m], creep-to-slip transition
        rate omega_eff K_c xi_sat [1/s].
    reserve_rows : list of list
        Per shipped set-point (closed-loop scenarios' starts, the [operating] point
        at r_g = 0.5, 1, 2): name, r_g, slip [%], tau, torque reserve 1 - tau [%], load [N m],
        capacity at that clamping force [N m].
    stability : RatioStabilityMap
        The map of d ln kappa*/d r_g at fixed load torque over torque ratio and
        ratio, the shipped set-points marked.
    efficiency_rows : list of list of float
        Per `EFFICIENCY_TAUS` x `EFFICIENCY_TORQUES` x `EFFICIENCY_RATIOS` at 300 rad/s:
        tau, input torque [N m], r_g, F_s [kN], efficiency [%], the losses of
        `loss_terms` [W].
    clamping_rows : list of list of float
        The clamping sweep at r_g 1, 60 N m, 300 rad/s, per `CLAMPING_TAUS`: tau, F_s [kN],
        efficiency [%], the losses [W].
    claims : tuple of Claim
        The checks.
    loss_terms : tuple of str
        The variator's loss terms the rows hold (`loss_terms`).
    """

    curves: TractionCurves
    curve_rows: list[list[float]]
    creep_rows: list[list[float]]
    reserve_rows: list[list[object]]
    stability: RatioStabilityMap
    efficiency_rows: list[list[float]]
    clamping_rows: list[list[float]]
    claims: tuple[Claim, ...]
    loss_terms: tuple[str, ...] = ()


def curve_statistics(traction, r_g: float, nu: np.ndarray) -> list[float]:
    """``[r_g, mu_max, nu90 [%], nu_peak [%], mu'(SLOPE_SLIPS)...]`` of a curve on the slip
    grid `nu` (its resolution is the statistics').

    Parameters
    ----------
    traction : TractionModel
        The traction law (e.g. `empact.variator.traction.traction_from_params`).
    r_g : float
        Ratio [-].
    nu : array, shape (n,)
        Ascending slip grid [-].

    Returns
    -------
    list of float
        ``[r_g, mu_max, nu90 [%], nu_peak [%]]`` and the slope ``mu'`` [-] at each of `SLOPE_SLIPS`:
        ratio [-], peak traction coefficient [-], slip at 90 % of the peak and slip at the peak [%]
        (the first grid slip reaching them).
    """
    mu = traction.mu(nu, r_g)
    k = int(np.argmax(mu))
    nu90 = float(nu[np.argmax(mu >= 0.9 * mu[k])])
    return [r_g, float(mu[k]), 100 * nu90, 100 * float(nu[k])] + \
        [float(traction.dmu(s, r_g)) for s in SLOPE_SLIPS]


def efficiency_at_torque(model: EmpactModel, r_g: ArrayLike, T_in: ArrayLike,
                         tau: ArrayLike, omega_p: ArrayLike = EFFICIENCY_SPEED) -> TrimGrid:
    """The trimmed machine at input torques `T_in` (the drive torque, which carries the
    variator's input power ``P_var_in``), ratios `r_g`, torque ratios `tau` and primary
    speeds `omega_p` (broadcast): the clamping force is solved for, all points at once
    (secant: the drive torque is nearly affine in it; to 1e-6 N).

    Parameters
    ----------
    model : EmpactModel
        The machine (`empact.nonlinear.nonlinear_model`).
    r_g, T_in, tau, omega_p : array_like
        Ratios [-], input torques [N m], torque ratios [-], primary speeds [rad/s].

    Returns
    -------
    TrimGrid
        The trims (`empact.nonlinear.equilibrium.trim_grid`); ``y`` holds the outputs,
        ``P_var_in``, ``P_var_out`` and the losses of `VARIATOR_LOSSES` [W] among them.

    Raises
    ------
    RuntimeError
        When a point does not trim or the clamping force does not converge.
    """
    r, T, tau_, w = (np.asarray(a, float) for a in np.broadcast_arrays(r_g, T_in, tau,
                                                                        omega_p))
    i_d = model.output_index("T_d_act")

    def residual(F: np.ndarray) -> tuple[TrimGrid, np.ndarray]:
        g = trim_grid(model, r.ravel(), w.ravel(), tau=tau_.ravel(), F_s=F)
        if not g.ok.all():
            raise RuntimeError("efficiency_at_torque: " + "; ".join(set(g.reason) - {""}))
        assert g.y is not None
        return g, g.y[:, i_d] - T.ravel()

    F0, F1 = np.full(r.size, 1e4), np.full(r.size, 2e4)
    _, g0 = residual(F0)
    grid, g1 = residual(F1)
    for _ in range(50):
        step = np.where(g1 != g0, g1 * (F1 - F0) / np.where(g1 != g0, g1 - g0, 1.0), 0.0)
        F0, g0 = F1, g1
        F1 = F1 - step
        grid, g1 = residual(F1)
        if np.max(np.abs(step)) < 1e-6:
            return grid
    raise RuntimeError("efficiency_at_torque: the clamping force did not converge")


def loss_terms(model: EmpactModel) -> tuple[str, ...]:
    """The variator's loss terms a model's law produces (of `VARIATOR_LOSSES`): the slip and
    the measured map's, or the slip and the analytic clamping, load and drag terms.

    Parameters
    ----------
    model : EmpactModel
        The nonlinear model.

    Returns
    -------
    tuple of str
        Output names [W].
    """
    if model.options.loss_map is not None:
        return ("P_loss_slip", "P_loss_map")
    return tuple(k for k in VARIATOR_LOSSES if k != "P_loss_map")


def _efficiency(params: Params) -> tuple[list[list[float]], list[list[float]]]:
    """The efficiency table and the clamping sweep of `MachineSection`."""
    model = nonlinear_model(params)
    cols = [model.output_index(k) for k in loss_terms(model)]
    i_in, i_out = model.output_index("P_var_in"), model.output_index("P_var_out")

    def rows(heads: list[list[float]], g: TrimGrid) -> list[list[float]]:
        assert g.y is not None
        return [head + [float(g.F_s[k]) / 1e3, 100 * float(g.y[k, i_out] / g.y[k, i_in])]
                + [float(g.y[k, c]) for c in cols] for k, head in enumerate(heads)]

    heads = [[tau, T, r] for tau in EFFICIENCY_TAUS for T in EFFICIENCY_TORQUES
             for r in EFFICIENCY_RATIOS]
    h = np.array(heads)
    table = rows(heads, efficiency_at_torque(model, h[:, 2], h[:, 1], h[:, 0]))
    taus = np.array(CLAMPING_TAUS)
    sweep = rows([[float(t)] for t in taus], efficiency_at_torque(model, 1.0, 60.0, taus))
    return table, sweep


def _set_points(params: Params) -> list[tuple[str, OperatingPoint]]:
    """The operating points the package ships: each closed-loop scenario's start on the test
    bench (the car's, ``vehicle-*``, are the drive-cycle section's) and the [operating] point
    at r_g = 0.5, 1, 2."""
    scenarios = {name: load_scenario(control_example_path(name)) for name in control_examples()}
    points = [(name, sc.initial) for name, sc in scenarios.items()
              if sc.options.driveline == "bench"]
    points += [(f"[operating] at r_g = {r:g}", params.operating.replace(r_g=r))
               for r in (0.5, 1.0, 2.0)]
    return points


def machine(params: Params) -> MachineSection:
    """The machine sheet of `params`.

    Parameters
    ----------
    params : Params
        The parameter set (e.g. `empact.load_params`).

    Returns
    -------
    MachineSection
        The curves, the tables, the ratio-stability map and the claims.
    """
    tr = traction_from_params(params)
    nu = np.linspace(0.0, 0.1, 10001)
    curves = traction_curves(tr, CURVE_RATIOS, nu, label="(magic formula)")
    curve_rows = [curve_statistics(tr, r, nu) for r in CURVE_RATIOS]
    # creep: K_c, rate per revolution at a 20 % imbalance, damping, transition rate
    sh = params.shift
    creep_rows = []
    for r, F in CREEP_POINTS:
        R_p = float(variator_state(r, params.variator).R_p)
        K_c = float(creep_coefficient(params, r, F, R_p))
        dr_per_rad = K_c * np.log(1 + IMBALANCE)
        dRp_dr = float(primary_radius_per_ratio(r, params.variator))
        per_rev = 2 * np.pi * dr_per_rad * dRp_dr
        c = creep_damping(params, r, 300.0, F).c_shift
        w_eff = np.hypot(300.0, sh.omega_0)
        creep_rows.append([r, F / 1e3, K_c, 1e3 * per_rev, c, w_eff * K_c * sh.xi_sat])
    # torque reserve at the shipped set-points (the nonlinear model's trim: its tau)
    model = nonlinear_model(params, **BENCH_OPTIONS)
    reserve_rows, set_points = [], []
    for name, op in _set_points(params):
        t = trim(model, op)
        cap = t.T_b / t.tau if t.tau else float("nan")
        reserve_rows.append([name, t.r_g, 100 * t.nu, t.tau, 100 * (1 - t.tau), t.T_l, cap])
        set_points.append((t.tau, t.r_g))
    # static ratio stability over (tau, r_g)
    kmap = thrust_ratio_from_params(params)
    smap = ratio_stability_map(kmap, params.variator, tr.mu_max, np.linspace(0.0, 1.0, 51),
                               np.geomspace(0.45, 2.25, 61), tuple(set_points))
    S = smap.S
    S_pts = np.array([float(ratio_stability(kmap, params.variator, tr.mu_max, r, tau))
                      for tau, r in set_points])
    zt = zero_torque_difference(kmap, params.variator, np.array([0.5, 1.0, 2.0]))
    src = "issue 20 (the machine, beyond the paper)"
    cr = np.array(curve_rows)
    b = BANDS
    in_band = lambda col, band: bool(np.all((cr[:, col] >= band[0]) & (cr[:, col] <= band[1])))  # noqa: E731
    ok_90 = in_band(2, (100 * b["nu90"][0], 100 * b["nu90"][1]))
    ok_pk = in_band(3, (100 * b["nu_peak"][0], 100 * b["nu_peak"][1]))
    ok_mu = in_band(1, b["mu_max"])
    i4 = SLOPE_SLIPS.index(0.04)
    ok_neg = bool(cr[CURVE_RATIOS.index(1.0), 4 + i4] < 0)
    cw = np.array(creep_rows)
    ok_rev = bool(np.all((cw[:, 3] >= 1e3 * b["creep_per_rev"][0])
                         & (cw[:, 3] <= 1e3 * b["creep_per_rev"][1])))
    ok_c = bool(np.all((cw[:, 4] >= b["c_shift"][0]) & (cw[:, 4] <= b["c_shift"][1])))
    reserves = np.array([row[3] for row in reserve_rows])
    claims: tuple[Claim, ...] = (
        Claim(key="machine.traction", source=src,
              claim="the traction curve has a micro-slip slope: mu at 90 % of its peak at 1-2 "
                    "% slip, the peak at 2-4.5 % and 0.09-0.12, falling by 4 % at MED "
                    "(measured pushbelt behaviour)",
              computed="; ".join(f"r_g = {row[0]:g}: 90 % at {row[2]:.2f} %, peak "
                                 f"{row[1]:.3f} at {row[3]:.2f} %" for row in curve_rows)
                       + f"; mu'(4 %, MED) = {cr[CURVE_RATIOS.index(1.0), 4 + i4]:+.3f}",
              shown=ok_90 and ok_pk and ok_mu and ok_neg,
              explanation="A curve statistic lies outside its band.",
              reading=READING[MACHINE] + "; shaped to the paper's Figs. 9-13, not measured"),
        Claim(key="machine.creep", source=src,
              claim="creep shifting at its measured magnitude: a fraction of a millimetre of "
                    "radius per revolution at a 20 % thrust imbalance (Carbone et al. 2007), "
                    "an equivalent axial damping of order 1e6 N s/m at 300 rad/s (checked: "
                    "0.05-0.5 mm, 3e5-3e6 N s/m)",
              computed="; ".join(f"r_g = {row[0]:g}, {row[1]:g} kN: {row[3]:.3f} mm/rev, "
                                 f"{row[4]:.3g} N s/m, creep-to-slip at {row[5]:.2f} /s"
                                 for row in creep_rows),
              shown=ok_rev and ok_c, explanation="A creep magnitude lies outside its band.",
              reading=READING[MACHINE] + f"; shift.gain = {sh.gain:g} (calibrated)"),
        Claim(key="machine.ratio_stability", source=src,
              claim="with the servo torques held the ratio is statically stable at every "
                    "shipped set-point (d ln kappa*/d r_g > 0 at fixed load torque)",
              computed=f"smallest d ln kappa*/d r_g at the set-points {S_pts.min():+.3f}; over "
                       f"tau 0-1 x r_g 0.45-2.25 {S.min():+.3f} (unstable share "
                       f"{100 * np.mean(S < 0):.1f} %); kappa*(0) / kappa_geo - 1 = "
                       + ", ".join(f"{v:+.1e}" for v in zt) + " at r_g = 0.5, 1, 2",
              shown=bool(S_pts.min() > 0),
              explanation="The thrust-ratio map falls with the ratio at fixed load torque at a "
                          "shipped set-point: the ratio drifts away with the servo torques "
                          "held.",
              reading=READING[MACHINE] + "; the analytic thrust-ratio map (estimated, "
              "b1 = 0.30)"),
        Claim(key="machine.reserve", source=src,
              claim="every shipped set-point keeps a torque reserve (tau < 1)",
              computed=", ".join(f"{row[0]}: tau {row[3]:.3f}" for row in reserve_rows),
              shown=bool(np.all(reserves < 1)),
              explanation="A shipped set-point sits at the traction limit."),
    )
    # the variator's efficiency (issue 32)
    eff_rows, clamp_rows = _efficiency(params)
    ec = _efficiency_checks(params, eff_rows, clamp_rows)
    src32 = "issue 32 (the machine's efficiency, beyond the paper)"
    claims += (
        Claim(key="machine.efficiency", source=src32, claim=ec["eff_claim"],
              computed=ec["eff_computed"], shown=ec["eff_shown"],
              explanation="An efficiency lies outside the band, or a published trend is "
                          "missing.", reading=ec["reading"], values=ec["eff_values"]),
        Claim(key="machine.efficiency_clamping", source=src32, claim=ec["clamp_claim"],
              computed=ec["clamp_computed"], shown=ec["clamp_shown"],
              explanation="The maximum lies at an end of the sweep or outside the band of "
                          "torque ratios.", reading=ec["reading"], values=ec["clamp_values"]),
    )
    return MachineSection(curves, curve_rows, creep_rows, reserve_rows, smap, eff_rows,
                          clamp_rows, claims, loss_terms(nonlinear_model(params)))


def _efficiency_checks(params: Params, eff_rows: list[list[float]],
                       clamp_rows: list[list[float]]) -> dict:
    """What the efficiency claims of `machine` state: the verdicts, the computed texts, the
    numbers, the reading (issue 32)."""
    lo, hi = (100 * v for v in EFFICIENCY_BANDS["efficiency"])
    e = np.array(eff_rows)
    eta = e[:, 4].reshape(len(EFFICIENCY_TAUS), len(EFFICIENCY_TORQUES),
                          len(EFFICIENCY_RATIOS))
    in_band = bool(np.all((eta >= lo) & (eta <= hi)))
    low_load = bool(np.all(eta[:, 0, :] < eta[:, -1, :]))
    overdrive = bool(np.all(eta[:, :, -1] < eta[:, :, EFFICIENCY_RATIOS.index(1.0)]))
    c = np.array(clamp_rows)
    k = int(np.argmax(c[:, 2]))
    tau_best = float(c[k, 0])
    t_lo, t_hi = EFFICIENCY_BANDS["tau_best"]
    ls = params.losses
    by_tau = "; ".join(
        f"tau {tau:.3f}: " + ", ".join(
            f"{T:g} N m {eta[i, j].min():.1f}-{eta[i, j].max():.1f} %"
            for j, T in enumerate(EFFICIENCY_TORQUES))
        for i, tau in enumerate(EFFICIENCY_TAUS))
    return {
        "reading": READING[MACHINE] + f"; [losses] lambda_F = {ls.lambda_F:g}, k_T = "
                   f"{ls.k_T:g}, c_v = {ls.c_v:g} N m s/rad, c_q = {ls.c_q:g} N m s^2/rad^2 "
                   "(estimates, each in its plausible band)",
        "eff_claim": f"the variator's efficiency lies in the published {lo:.0f}-{hi:.0f} % "
                     "over input torque 25-150 N m at 300 rad/s and every ratio 0.5-2, "
                     "falling at low load and towards overdrive (Narita & Priest 2007; "
                     "Micklem et al. 1996)",
        "eff_computed": f"{by_tau} (over r_g = 0.5, 1, 2); peak {eta.max():.2f} %; lower at "
                        f"25 than at 150 N m at every ratio: {low_load}; lower at r_g 2 than "
                        f"at r_g 1 at every torque: {overdrive}",
        "eff_shown": in_band and low_load and overdrive,
        "eff_values": {"efficiency_min": float(eta.min()) / 100,
                       "efficiency_max": float(eta.max()) / 100},
        "clamp_claim": "the efficiency over clamping force has an interior maximum (van der "
                       "Meulen et al., extremum seeking of CVT efficiency), at a torque ratio "
                       f"between {t_lo:g} and {t_hi:g} at r_g 1, 60 N m",
        "clamp_computed": f"maximum {c[k, 2]:.3f} % at tau {tau_best:.2f} (F_s {c[k, 1]:.2f} "
                          f"kN) over tau {c[0, 0]:.2f}-{c[-1, 0]:.2f} (F_s {c[-1, 1]:.2f}-"
                          f"{c[0, 1]:.2f} kN): {c[0, 2]:.3f} % at the most clamping, "
                          f"{c[-1, 2]:.3f} % at the least",
        "clamp_shown": 0 < k < len(c) - 1 and t_lo <= tau_best <= t_hi,
        "clamp_values": {"tau_best": tau_best, "F_s_best": float(c[k, 1]) * 1e3,
                         "efficiency_best": float(c[k, 2]) / 100},
    }
