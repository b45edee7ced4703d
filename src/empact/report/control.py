"""Report section beyond the paper: slip and ratio control on the machine (issue 21)."""
from __future__ import annotations

import numpy as np

from ..control.closed_loop import shown_metric
from ..control.loop import disk_margin_map
from ..plotting import (
    plot_closed_loop,
    plot_family_poles,
    plot_loop_shapes,
    plot_robustness_maps,
    plot_shift_envelope,
)
from ..reproduction import control as rep
from .context import Context

__all__ = ["control", "studies", "estimate_table", "hinf_table"]


def _fmt(v) -> str:
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, (int, float, np.floating)):
        return f"{v:.4g}"
    return str(v)


def control(ctx: Context, res: rep.ControlSection) -> str:
    """The family, the loops' robustness, every closed-loop scenario against its targets and
    its linear prediction, the studies (traction estimate, Monte Carlo, saving, envelope).

    Parameters
    ----------
    ctx : Context
        The report build: figures and CSV tables are written to ``ctx.out`` in its formats.
    res : ControlSection
        The result of `empact.reproduction.control.control`.

    Returns
    -------
    str
        HTML: a note on the loop, the figures of the family's poles and zeros, the loop shapes, the
        robustness maps, the closed-loop runs and the shift envelope, the tables of the designs
        (with the H-infinity criterion), the targets with the PI and the H-infinity controller,
        the targets and the envelope, and the claims.
    """
    fam = res.family
    spec = res.loop.spec
    axes = ", ".join(f"{k}: {v.min():.3g}-{v.max():.3g} ({len(v)})" for k, v in fam.axes.items())
    design_rows = []
    for name, c in res.controllers.items():
        lm = res.loops[name]
        rho = lm.spectral_radius()
        dm = lm.disk_margins()
        ms = lm.sensitivity_peaks()["ms"].reshape(-1, 2).max(axis=0)
        norm = res.norms.get(name, {}).get("gamma", "")
        design_rows.append([name, c.n, "yes" if c.schedule is not None else "no",
                            f"{int((rho < 1).sum())} / {rho.size}", float(dm["alpha"].min()),
                            float(dm["input"].min()), float(dm["output"].min()),
                            float(ms[0]), float(ms[1]), norm])
        before = c.design.get("tune", {}).get("before")
        if before:  # the tuner's starting point (empact.control.tune), as recorded
            design_rows.append([f"{name} before tuning", c.n, design_rows[-1][2], "all" if
                                before["all_stable"] else "not all", before["disk_margin"],
                                "", "", before["ms"]["ratio"], before["ms"]["slip"], ""])
        if "gamma_start" in c.design:  # the H-infinity search's start, as recorded
            design_rows.append([f"{name} start (scheduled unit PI)", c.n, design_rows[-1][2],
                                "", "", "", "", "", "", c.design["gamma_start"]])
    target_rows = []
    for n, checks in res.targets.items():
        run = res.runs[n]
        m = run.metrics
        pred = res.predictions.get(n)
        for chk in checks:
            lin = ""
            if pred is not None and chk.name == "peak_slip_error":
                lin = f"{100 * pred.peak_slip_error:.3g} pp"
            value, unit = shown_metric(chk.name, chk.value)
            target_rows.append([n, chk.name, chk.describe().split("(")[1].split(")")[0],
                                lin, _fmt(value) + (f" {unit}" if unit else ""),
                                "met" if chk.met else "MISSED",
                                f"{m['peak_T_mp']:.2f} / {m['T_mp_max']:g}",
                                f"{m['peak_T_ms']:.2f} / {m['T_ms_max']:g}"])
    env = res.envelope
    env_rows = [[f"{r:.3g}", rate, b, F / 1e3, T]
                for r, rate, b, F, T in zip(env.r_g[::3], env.rate[::3], env.binding[::3],
                                            env.F_s[::3], env.T_mp[::3])]
    small = [r for n, r in res.runs.items() if n.startswith("slip-small-step")]
    steps = [r for n, r in res.runs.items() if n.startswith("slip-load-step")]
    shifts = [r for n, r in res.runs.items() if n.startswith("shift")]
    preds = {n: p.prediction for n, p in res.predictions.items() if n.startswith("slip-")}
    return (
        f"<p>The machine trimmed and exactly linearised on the design family ({axes}; speed "
        "of [operating]; test bench: drive speed-, load torque-controlled). The loop that "
        f"runs is sampled at {spec.rate:g} Hz with the parameter set's sensors (one sample of "
        "delay, shaft speeds counted over 10 ms) and servo limits, the clamping feedforward "
        f"of the driveshaft torque at {spec.feedforward_gain:g} of it"
        + (" above " + f"{spec.feedforward_gain_table[-1][0] / 1e3:g} kN of full feedforward "
           f"force ({spec.feedforward_gain_table[0][1]:g} at light load)"
           if spec.feedforward_gain_table is not None else "")
        + ", the primary servo "
        f"following the feedforward's clamping through a {spec.decoupling_filter_hz:g} Hz "
        "low-pass (the decoupler) and, on shifts, the feedforward of the reference's ratio "
        "rate; its linear model (empact.control.loop: the same law linearised, the machine "
        "held and sampled) gives every margin and pole below. Set-points are torque ratios "
        "on the traction curve (tau = 0.9: an 11 % torque reserve). Targets are issue 21's; "
        "verdicts below.</p>"
        + ctx.figure(plot_family_poles(fam.roots(60.0),
                                       title="Plant family: poles and zeros below 60 Hz"),
                     "control_family", "Poles and zeros of every plant of the design family")
        + ctx.figure(plot_loop_shapes({n: lm.loop_shapes() for n, lm in res.loops.items()},
                                      title="Loop shapes over the family"),
                     "control_loops", "Diagonal loop gains of the shipped controllers on "
                     "the sampled loop (sensors, feedforwards) against every plant")
        + ctx.figure(plot_robustness_maps({n: disk_margin_map(fam, lm)
                                           for n, lm in res.loops.items()},
                                          title="Multiloop disk margin over the family"),
                     "control_robustness",
                     "The multiloop disk margin (the smaller of servo torques and errors) "
                     "at every plant of the family; 0 where unstable")
        + ctx.figure(plot_robustness_maps(res.margin_maps, title="Stability and disk margin "
                                          "over clamping force x ratio"),
                     "control_margin_map",
                     "The same margins over clamping force x ratio, one panel per torque "
                     "ratio: where the shipped controllers are stable (0: unstable) and with "
                     "what margin, down to light-load overdrive cruising")
        + ctx.table("control_designs", ["controller", "states", "scheduled", "stable",
                                        "worst disk margin [-]", "at the servos [-]",
                                        "at the errors [-]", "max Ms ratio loop [-]",
                                        "max Ms slip loop [-]",
                                        "H-infinity criterion gamma [-]"], design_rows,
                    "The shipped controllers over the design family on the loop that runs "
                    "(Ms: loop-at-a-time sensitivity peak; gamma: the worst weighted "
                    "mixed-sensitivity norm of the H-infinity design, its weights and "
                    "bandwidths, over every plant, on the same loop and control check's "
                    "frequency grid, lower is better; a tuned controller's starting point as "
                    "its design record states it, `empact control tune`, and the H-infinity "
                    "search's start)")
        + hinf_table(ctx, res)
        + ctx.figure(plot_closed_loop(steps, title="Load steps of 50 % of the torque "
                                      "capacity at 0.5 s", predictions=preds),
                     "control_load_steps", "Closed loop on the nonlinear machine (solid), "
                     "its linear prediction (dotted): load steps at r_g = 0.5, 1, 2")
        + ctx.figure(plot_closed_loop(small, title="Load steps of 10 % of the torque "
                                      "capacity at 0.5 s", predictions=preds),
                     "control_small_steps", "Small load steps: nonlinear (solid) and linear "
                     "prediction (dotted)")
        + ctx.figure(plot_closed_loop(shifts, title="LOW -> OD: slip control (fast and "
                                      "slow) and the safety-factor 1.3 clamping"),
                     "control_shift", "Shifts on the nonlinear machine")
        + ctx.figure(plot_shift_envelope(env, [res.runs["shift-low-od"]],
                                         title="How fast the servos can shift"),
                     "control_envelope", "The shift-rate envelope and the rate reached")
        + ctx.table("control_targets", ["scenario", "metric", "target", "linear prediction",
                                        "nonlinear", "verdict", "peak |T_mp| / limit [N m]",
                                        "peak |T_ms| / limit [N m]"], target_rows,
                    "Every shipped closed-loop scenario against its targets ([targets] of "
                    "its file); the linear prediction is the loop model's at the scenario's "
                    "start (limits inactive, no noise): close for the load steps, far off for "
                    "the shifts, which leave the operating point the model is linearised at")
        + estimate_table(ctx, res)
        + ctx.table("control_envelope", ["r_g", "largest rate [1/s]", "limit that binds",
                                         "F_s at it [kN]", "|T_mp| at it [N m]"], env_rows,
                    "The shift-rate envelope (quasi-static; empact.control.shifting)")
        + ctx.claims(res.claims))


def hinf_table(ctx: Context, res: rep.ControlSection) -> str:
    """The shipped scenarios' targets with the PI (as shipped) and with the H-infinity
    controller in its place (`empact.reproduction.control.ControlSection.hinf_targets`,
    issue 33).

    Parameters
    ----------
    ctx : Context
        The report build (the table is also written as CSV).
    res : ControlSection
        Its ``targets`` and ``hinf_targets``.

    Returns
    -------
    str
        HTML: one row per scenario and target ("value: met" or "value: MISSED" for each
        controller); empty without H-infinity runs.
    """
    rows = []
    for n, checks in res.targets.items():
        for pi, hi in zip(checks, res.hinf_targets.get(n, [])):
            cells = [n, pi.name, pi.describe().split("(")[1].split(")")[0]]
            for chk in (pi, hi):
                value, unit = shown_metric(chk.name, chk.value)
                cells.append(_fmt(value) + (f" {unit}" if unit else "") +
                             (": met" if chk.met else ": MISSED"))
            rows.append(cells)
    if not rows:
        return ""
    return ctx.table("control_hinf_targets", ["scenario", "metric", "target", "PI (shipped)",
                                              "H-infinity (shipped:hinf)"], rows,
                     "Every shipped closed-loop scenario against its targets with the PI and "
                     "with the H-infinity controller in its place (the same loop: "
                     "feedforwards, decoupler, sensors, servo limits; "
                     "`empact control simulate --example NAME --controller shipped:hinf`)")


def estimate_table(ctx: Context, res: rep.ControlSection) -> str:
    """The table of the scenarios' targets with the clamping feedforward on the driveshaft
    torque and on the engine-torque estimate (`empact.reproduction.control.estimate_targets`,
    issue 33).

    Parameters
    ----------
    ctx : Context
        The report build (the table is also written as CSV).
    res : ControlSection
        Its ``estimate`` and ``loop`` (the parameter set's sensors: the estimate's delay).

    Returns
    -------
    str
        HTML: one row per scenario and target, a column per feedforward signal ("value:
        met" or "value: MISSED"); empty without estimate runs or sensors.
    """
    cols = next(iter(res.estimate.values()), {})
    rows = []
    for n, by_ff in res.estimate.items():
        for i, chk in enumerate(by_ff["T_ds"]):
            row = [n, chk.name, chk.describe().split("(")[1].split(")")[0]]
            for checks in by_ff.values():
                got = checks[i]
                value, unit = shown_metric(got.name, got.value)
                row.append(_fmt(value) + (f" {unit}" if unit else "") +
                           (": met" if got.met else ": MISSED"))
            rows.append(row)
    sensors = res.loop.sensors
    if not rows or sensors is None:
        return ""
    return ctx.table(
        "control_estimate", ["scenario", "metric", "target"] +
        [f"feedforward on {k}" for k in cols], rows,
        "The scenarios whose clamping feedforward runs, against their targets with the "
        "feedforward on the driveshaft torque (a bench's sensor, as shipped) and without a "
        "torque sensor: on an engine-torque estimate alone (T_e_est: the torque source's, "
        "here the load motor's, as its controller reports it, "
        f"{1e3 * sensors.engine_torque_delay:g} ms late and 15 % low, exact or 15 % high), "
        "and on the "
        "driveshaft torque observed from it and the driveline's twist rate, output less "
        "wheel speed (T_ds_est). A load step excites the driveline's shuffle mode (the "
        "driveshaft torque swings about 20 % past its new value), which the estimate alone "
        "cannot follow")


def studies(ctx: Context, res: rep.StudiesSection) -> str:
    """The traction-estimate runs, the Monte Carlo quantiles and the saving table.

    Parameters
    ----------
    ctx : Context
        The report build: figures and CSV tables are written to ``ctx.out`` in its formats.
    res : StudiesSection
        The result of `empact.reproduction.control.control_studies`.

    Returns
    -------
    str
        HTML: a note, the tables of the traction-estimate runs, the Monte Carlo quantiles and the
        clamping saving, and the claims.
    """
    te_rows = [[n, f"{f:.3g}", 100 * m["peak_slip"], 100 * m["peak_slip_error"],
                100 * m.get("slip_reserve", float("nan")), _fmt(m.get("macro_slip"))]
               for (n, f), m in res.traction_error.items()]
    mc = res.montecarlo
    mc_rows = []
    verdicts = mc.verdicts()
    for j, name in enumerate(mc.outputs):
        v = mc.values[mc.ok, j]
        if v.size and not name.startswith("met."):  # the verdicts are counted below
            q = np.quantile(v, [0.05, 0.5, 0.95])
            mc_rows.append([name, mc.units.get(name, "-"), q[0], q[1], q[2]])
    saving_rows = [[r["scenario"], r["strategy"], r["mean_clamping_force"] / 1e3,
                    r["mean_losses"], 100 * r["saving"] if r["saving"] else "",
                    "; ".join(f"{k} {v:.0f}" for k, v in r["variator_losses"].items()),
                    r["actuation"], r["total"],
                    100 * r["saving_energy"] if r["saving_energy"] else "",
                    _fmt(r["macro_slip"])] for r in res.saving]
    names = list(res.sensitivity[0]["saving"]) if res.sensitivity else []
    sens_rows = [[r["case"], r["parameter"] or "; ".join(f"{k} {v:g}" for k, v
                                                         in r["value"].items()),
                  r["value"] if r["parameter"] else "",
                  *(100 * r["saving"][n] for n in names),
                  100 * r["steady"]["least"], 100 * r["steady"]["largest"]]
                 for r in res.sensitivity]
    fair_rows = [[r["scenario"], f"{100 * r['traction_error']:+g}", r["strategy"],
                  _fmt(r["macro_slip"]) + ("" if r["start"] == "trimmed" else
                                           " (no steady start: " + r["start"] + ")"),
                  r["mean_clamping_force"] / 1e3, r["force_over_slip_control"],
                  "; ".join(f"{k} {v:.0f}" for k, v in r.get("variator_losses", {}).items()),
                  r.get("variator_losses_total", float("nan")),
                  r.get("actuation", float("nan")), r.get("total", float("nan"))]
                 for r in res.fair]
    def failed(r: dict) -> str:
        return ", ".join(k.replace("_", " ") for k in ("macro_slip", "belt_slack") if r[k]) \
            or "no"

    sat_rows = [[f"{r['r_g']:g}", r["F_s"] / 1e3, _fmt(r["within_capacity"]),
                 100 * r["plain"]["peak_slip_error"], failed(r["plain"]),
                 100 * r["protected"]["peak_slip_error"], failed(r["protected"]),
                 r["torque_reduction"], 100 * r["slip_setpoint_lowest"]]
                for r in res.saturation]
    return (
        "<p>The shipped controller and loop of the previous section on three questions: "
        "an error of the feedforward's traction estimate, the shipped parameter spread, and "
        "the clamping saving against a production CVT's safety factor of 1.3 (the same "
        "runs, started at the strategy's own steady clamping).</p>"
        + ctx.table("control_traction_error", ["scenario", "traction estimate factor",
                                               "peak slip [%]", "peak |nu - nu*| [pp]",
                                               "reserve to the peak [pp]", "macro slip"],
                    te_rows, "The 50 % load steps with the feedforward's traction "
                    "estimate 5 % high and 5 % low")
        + ctx.table("control_montecarlo", ["metric", "unit", "5 %", "median", "95 %"],
                    mc_rows, f"Monte Carlo: {int(mc.ok.sum())} of {mc.values.shape[0]} runs "
                    f"of {rep.MC_SCENARIO} on the shipped spread (data/montecarlo/"
                    "example-spread.toml) completed; quantiles of every metric (slips as "
                    "fractions); runs missing the scenario's targets (a failed run misses "
                    "every one): " + ", ".join(f"{t} {c['missed']}" for t, c
                                                 in verdicts["targets"].items()))
        + ctx.table("control_saving", ["scenario", "strategy", "mean F_s [kN]",
                                       "mean losses [W]", "saving in F_s [%]",
                                       "variator losses by term [W]", "actuation [W]",
                                       "total [W]", "saving in energy [%]",
                                       "macro slip"], saving_rows,
                    "The saving the paper is for: mean clamping force and variator losses "
                    "(slip power plus servo power) against a safety factor of 1.3, and in "
                    "energy: the variator's losses by term, the actuation's electrical power "
                    "(servos with copper, drive and transmission losses, "
                    "empact.actuation_energy) or, for the hydraulic reference on the "
                    "ratio-blind run's motion, the pump's shaft power, their total and the "
                    "saving of slip control's total against each row's (mean powers over "
                    "the run)")
        + (ctx.table("control_saving_sensitivity",
                     ["case", "parameter", "value (SI)",
                      *(f"saving {n} [%]" for n in names),
                      "steady state: least [%]", "steady state: largest [%]"], sens_rows,
                     "Is the energy saving's sign robust? Slip control's energy saving "
                     "against the ratio-blind safety factor 1.3 (the table above) with each "
                     "loss and servo parameter at each end of its plausible band "
                     "(data/parameter_sources.toml; the variator's losses act on the "
                     "machine: the runs are repeated; the servos' parameters bill the same "
                     "runs), then at the corners (every parameter at the end that lowers, "
                     "or raises, the mean saving), and the steady-state saving of the "
                     "efficiency map (slip against sf1.3, empact.efficiency) over 25, 60, "
                     "150 N m x r_g 0.5, 1, 2 at 300 rad/s")
           if res.sensitivity else "")
        + ctx.table("control_fair_saving", ["scenario", "traction error [%]", "strategy",
                                            "macro slip", "mean F_s [kN]",
                                            "F_s over slip control's [-]",
                                            "variator losses by term [W]",
                                            "variator losses [W]", "servo electrical [W]",
                                            "total [W]"], fair_rows,
                    "A fair account of the saving (issue 33 item 7): every strategy under "
                    "the same load (the 50 % load step as an absolute step of T_l), the same "
                    f"torque signal ({rep.FAIR_SIGNAL}: the driveshaft torque observed "
                    "without a torque sensor) and the same traction knowledge (the nominal "
                    "curve), on a machine whose traction peak is that estimate's times 1 + "
                    "the error; slip control (its slip loop) against the safety factor 1.3 "
                    "(ratio-blind and ratio-aware) and the open-loop clamping at slip "
                    "control's own reserve (tau = 0.9 of the estimate's peak, no feedback). "
                    "Each starts in its own steady state; an open-loop clamping below what "
                    "the machine needs has none (macro slip from the start). Mean powers "
                    "over the run (empact.efficiency.run_energy)")
        + ctx.table("control_saturation", ["r_g", "F_s [kN]", "within the servo's capacity",
                                           "peak |nu - nu*| as shipped [pp]",
                                           "macro slip or belt slack as shipped",
                                           "peak |nu - nu*| protected [pp]",
                                           "macro slip or belt slack protected",
                                           "load cut [N m]", "lowest slip set-point [%]"],
                    sat_rows,
                    "Saturation (issue 33 item 3): 50 % load steps from tau = 0.9 over "
                    "ratio x starting clamping force, as shipped (the slip guard on, "
                    "controller.slip_guard) and with the reserve ahead "
                    "and the honoured torque request (controller.reserve_ahead, "
                    "torque_request = 'honoured'; off in the shipped scenarios, where the reserve "
                    "ahead would move the nominal load steps' set-point: CHANGELOG); within "
                    "the capacity: the "
                    "step's steady clamping below what the secondary servo's torque limit "
                    "holds; the protected slip error is against the set-point the law ran")
        + ctx.claims(res.claims))
