"""Report section beyond the paper: the machine in a car over WLTC 3b (issue 34)."""
from __future__ import annotations

from ..drive_cycle import MIN_CLAMPING, TERMS
from ..plotting import plot_drive_cycle
from ..reproduction import drive_cycle as rep
from .context import Context

__all__ = ["drive_cycle"]


def drive_cycle(ctx: Context, res: rep.DriveCycleSection) -> str:
    """The strategies' table, the phases' fuel, the pump anchors, the figure, the claims.

    Parameters
    ----------
    ctx : Context
        The report build (figures and CSV tables go to ``ctx.out``).
    res : DriveCycleSection
        The result of `empact.reproduction.drive_cycle.drive_cycle`.

    Returns
    -------
    str
        HTML.
    """
    veh, eng = ctx.params.vehicle, ctx.params.engine
    r = res.result
    return (
        f"<p>WLTC class 3b ({r.cycle.distance / 1e3:.3f} km, {r.cycle.duration:g} s; the JRC "
        "wltp package's table) on the shipped car: "
        f"{veh.mass:g} kg, road load {veh.f0:g} N + {veh.f1:g} N s/m v + {veh.f2:.4g} N "
        "s<sup>2</sup>/m<sup>2</sup> v<sup>2</sup> (the wltp package's example vehicle), "
        f"final drive {veh.i_fd:g}, a {eng.V_d * 1e3:g} l engine on a Willans line. "
        "Quasi-static (backward): at every sample the variator is trimmed on the engine's "
        "minimum-fuel operating line (ratio 0.43-2.25, at least "
        f"{eng.omega_drive * 30 / 3.141592653589793:.0f} rpm, a "
        f"{100 * (1 - eng.load_max):.0f} % torque reserve), clamped by the strategy and "
        f"never below {MIN_CLAMPING / 1e3:g} kN; no regeneration, the engine fuelled while "
        "coasting (no fuel cut), idle neutral at rest. hydraulic-slip is slip control on "
        "the hydraulic reference (the case of SAE 04CVT-39).</p>"
        + ctx.figure(plot_drive_cycle(r), "drive_cycle",
                     "WLTC 3b: speed, ratio, clamping force and cumulative losses by "
                     "strategy")
        + ctx.table("drive_cycle_strategies",
                    ["strategy", *(f"{k} [kJ]" for k in TERMS), "variator eff. [%]",
                     "transmission eff. [%]", "fuel [g]", "fuel [l/100 km]",
                     "saving [%]"], res.rows,
                    "Energy by term over WLTC 3b (the engine's output is the wheels' "
                    "traction plus these), efficiencies, fuel and the saving against "
                    "hydraulic-sf1.3")
        + ctx.table("drive_cycle_phases", ["strategy", *r.cycle.phases], res.phase_rows,
                    "Fuel by phase [l/100 km]")
        + ctx.table("drive_cycle_pump", ["line pressure [bar]", "SAE 04CVT-49 [kW]",
                                         "computed [kW]"], res.pump_rows,
                    "The hydraulic reference's pump at 2000 rpm against SAE 04CVT-49")
        + ctx.claims(res.claims))
