"""Report section beyond the paper: the machine in a car over WLTC 3b (issue 34)."""
from __future__ import annotations

from ..drive_cycle import MIN_CLAMPING, TERMS
from ..plotting import plot_drive_cycle, plot_dynamic_cycle
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
        + _dynamic(ctx, res)
        + ctx.claims(res.claims))


def _dynamic(ctx: Context, res: rep.DriveCycleSection) -> str:
    """The dynamic run's text, figure and table, and the car's shifts."""
    dyn = res.dynamic
    if dyn is None:
        return ""
    d = dyn.to_dict()
    return (
        "<p>Dynamic (forward, <code>empact cycle --dynamic</code>): the nonlinear vehicle "
        f"driveline with the loop law and a driver at {dyn.rate_hz:g} Hz, compiled into one "
        "sample loop; the driver a PI on the car's speed with the trace's acceleration and "
        "road load fed forward, the engine at most at full load through a 0.1 s lag, the "
        "brakes where the demand is negative; the references (the quasi-static operating "
        "line's ratio, the slip set-point) prepared from the trace in advance. Launch and "
        f"standstill: {d['launch_model']} ({d['dynamic_duration_s']:.0f} of "
        f"{d['duration_s']:g} s dynamic). The reference and the slip strategy run "
        f"({', '.join(dyn.strategies)}: the saving's two ends; each about a minute of CPU "
        "on a quiet machine, the section's cost).</p>"
        + ctx.figure(plot_dynamic_cycle(dyn), "drive_cycle_dynamic",
                     "WLTC 3b, dynamic: the trace and the car's speed, ratio, slip, clamping "
                     "force and cumulative losses (grey: the dynamic stretches)")
        + ctx.table("drive_cycle_dynamic",
                    ["strategy", *(f"{k} [kJ]" for k in TERMS + ("brakes",)), "fuel [g]",
                     "fuel [l/100 km]", "saving [%]", "saving, quasi-static [%]",
                     "speed error max [km/h]", "macro slip", "belt slack",
                     "variator losses, dynamic [kJ]", "quasi-static [kJ]",
                     "difference [%]"], res.dynamic_rows,
                    "WLTC 3b, dynamic: energy by term, fuel, savings, the run's checks, "
                    "and the variator's losses over the dynamic stretches beside the "
                    "quasi-static cycle's")
        + ctx.table("drive_cycle_shifts",
                    ["scenario", "ratio rate [1/s]", "ratio", "peak slip [%]",
                     "macro slip", "peak T_mp / T_ms [N m]"], res.shift_rows,
                    "The car's shifts (the shipped vehicle-* examples: steady cruise, then "
                    "the shift; the bench's shift-low-od is in the control section)"))
