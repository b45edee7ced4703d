"""Report section beyond the paper: plant family, controllers, robustness, closed loop."""
from __future__ import annotations

from ..plotting import (plot_closed_loop, plot_family_poles, plot_loop_shapes,
                        plot_robustness_maps)
from ..reproduction import control as rep
from .context import Context

__all__ = ["control"]


def control(ctx: Context, res: rep.ControlSection) -> str:
    """The family's pole/zero spread, loop shapes, robustness maps, closed-loop runs."""
    fam = res.family
    axes = ", ".join(f"{k}: {v.min():.3g}-{v.max():.3g} ({len(v)})" for k, v in fam.axes.items())
    rows = []
    for name, run in res.runs.items():
        m = run.metrics
        rows.append([name, "yes" if m["complete"] else "no (stopped)", m["slip_error_pp"],
                     m["peak_slip_pp"], 100 * m["ratio_error"], m.get("ratio_rate", ""),
                     m["mean_clamping_force"] / 1e3, m["mean_losses"]])
    design_rows = []
    for name, c in res.controllers.items():
        w = res.maps[name].worst()
        design_rows.append([name, c.n, "yes" if w["all_stable"] else "no", w["disk_margin"],
                            w["gain_margin_db"], w["phase_margin_deg"]])
    step_runs = [r for n, r in res.runs.items() if n.startswith("slip-load-step")]
    shift_runs = [r for n, r in res.runs.items() if n.startswith("shift")]
    return (
        f"<p>The machine (equal translation, creep law) trimmed and exactly linearised on a "
        f"grid of operating points ({axes}; clamping force and speed of [operating]; test "
        "bench: drive speed-, load torque-controlled): the plant family the controllers are "
        "designed for. Targets are issue 13's; verdicts below.</p>"
        + ctx.figure(plot_family_poles(fam, title="Plant family: poles and zeros below 60 Hz"),
                     "control_family", "Poles and zeros of every plant of the design family")
        + ctx.figure(plot_loop_shapes(fam, res.controllers,
                                      title="Loop shapes over the family"),
                     "control_loops", "Diagonal loop gains of the shipped PI and H-infinity "
                     "controllers against every plant of the family")
        + ctx.figure(plot_robustness_maps(fam, res.maps, title="Multiloop disk margin over "
                                          "the family"), "control_robustness",
                     "Robustness map: the multiloop disk margin (simultaneous gain and phase "
                     "in both loops) at every plant of the family; 0 where unstable")
        + ctx.table("control_designs", ["controller", "states", "all stable",
                                        "worst disk margin [-]", "gain margin [dB]",
                                        "phase margin [deg]"], design_rows,
                    "The shipped controllers over the design family")
        + ctx.figure(plot_closed_loop(step_runs, title="Slip control through load steps "
                                      "(50 % of the torque capacity at 0.5 s)"),
                     "control_load_steps", "Closed loop on the nonlinear machine: load steps "
                     "at r_g = 0.5, 1, 2 with the PI controller and the driveshaft-torque "
                     "feedforward")
        + ctx.figure(plot_closed_loop(shift_runs, title="LOW -> OD at 1 /s: slip control "
                                      "against the safety-factor 1.3 clamping"),
                     "control_shift", "Closed loop on the nonlinear machine: the shift with "
                     "slip control and with open-loop clamping (safety factor 1.3)")
        + ctx.table("control_metrics", ["scenario", "complete", "max |nu - nu*| [pp]",
                                        "peak slip [%]", "ratio error [%]",
                                        "ratio rate [1/s]", "mean F_s [kN]",
                                        "mean losses [W]"], rows,
                    "Closed-loop metrics (targets: |&nu; - &nu;*| &lt; 0.2 pp, peak slip &lt; "
                    "2 &times; set-point, ratio error &lt; 1 %, shift rate &ge; 1 /s with slip "
                    "within 0.5 pp, &ge; 25 % lower mean clamping than the safety-factor "
                    "strategy)")
        + ctx.claims(res.claims))
