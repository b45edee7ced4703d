"""Report section beyond the paper: the machine sheet (what the shipped variator is)."""
from __future__ import annotations

from ..plotting import plot_ratio_stability, plot_traction_reserve
from ..reproduction import machine as rep
from .context import Context

__all__ = ["machine"]


def machine(ctx: Context, res: rep.MachineSection) -> str:
    """Traction statistics, creep magnitudes, torque reserves, the ratio's static stability.

    Parameters
    ----------
    ctx : Context
        The report build: figures and CSV tables are written to ``ctx.out`` in its formats;
        its ``params.shift.gain`` is named in the note.
    res : MachineSection
        The result of `empact.reproduction.machine.machine`.

    Returns
    -------
    str
        HTML: a note, the traction-reserve figure, the tables of the curve statistics, the creep
        magnitudes and the torque reserves, the ratio-stability figure, the efficiency table
        and the clamping sweep, and the claims.
    """
    sh = ctx.params.shift
    names = {"P_loss_slip": "slip", "P_loss_clamp": "clamping", "P_loss_load": "load",
             "P_loss_drag": "drag", "P_loss_map": "loss map"}
    losses = [f"{names.get(k, k)} [W]" for k in res.loss_terms]
    return (
        "<p>The paper gives no variator laws; these are the shipped defaults, each with its "
        "source and plausible band in <code>empact params show --describe</code>. The "
        "traction curve is a magic formula shaped to the paper's Figs. 9-13 (not measured: "
        "replace it by measured tables where you have them); the creep law is Carbone et al. "
        f"(2007) with its magnitude calibrated to their anchors (shift.gain = {sh.gain:g}); "
        "the thrust-ratio map is an estimate chosen so that the ratio is statically stable "
        "with the servo torques held.</p>"
        + ctx.figure(plot_traction_reserve(res.curves), "machine_traction",
                     "The traction curves at LOW, r_g = 0.5, MED, r_g = 2 and OD: the slip at "
                     "90 % of the peak (an 11 % torque reserve) and the peak")
        + ctx.table("machine_traction_statistics",
                    ["r_g", "mu_max", "slip at 90 % [%]", "peak slip [%]", "mu'(0.1 %)",
                     "mu'(1 %)", "mu'(2 %)", "mu'(4 %)"], res.curve_rows,
                    "Traction curve statistics")
        + ctx.table("machine_creep", ["r_g", "F_s [kN]", "K_c [-]",
                                      "creep per rev at 20 % imbalance [mm of R_p]",
                                      "equivalent axial damping [N s/m]",
                                      "creep-to-slip transition [1/s]"], res.creep_rows,
                    "Creep shifting at 300 rad/s: rate per primary revolution, the axial "
                    "damping it amounts to on the primary sheave, the ratio rate at which the "
                    "belt passes from creep into slip mode (omega K_c xi_sat)")
        + ctx.table("machine_reserve", ["set-point", "r_g", "slip [%]", "torque ratio tau",
                                        "torque reserve [%]", "load [N m]",
                                        "capacity [N m]"], res.reserve_rows,
                    "Torque reserve at the shipped set-points (the trimmed machine, test "
                    "bench)")
        + ctx.figure(plot_ratio_stability(res.stability), "machine_ratio_stability",
                     "Static stability of the ratio with the servo torques held: d ln "
                     "kappa*/d r_g at fixed load torque (model notes Sec. 9); crosses: the "
                     "shipped set-points")
        + ctx.table("machine_efficiency",
                    ["tau", "input torque [N m]", "r_g", "F_s [kN]", "efficiency [%]",
                     *losses],
                    res.efficiency_rows,
                    "The variator's efficiency and its losses by term at 300 rad/s, at the "
                    "slip set-point (tau 0.9) and at a safety factor of 1.3 (tau 0.77) "
                    "(trimmed machine; [losses] of empact params show --describe)")
        + ctx.table("machine_efficiency_clamping",
                    ["tau", "F_s [kN]", "efficiency [%]", *losses], res.clamping_rows,
                    "Efficiency over clamping force at r_g 1, 60 N m, 300 rad/s: the slip "
                    "power falls and the clamping loss rises with the clamping force")
        + ctx.claims(res.claims))
