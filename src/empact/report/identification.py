"""Report sections for identification: Fig. 2 by realisation, Fig. 14 on the virtual rig."""
from __future__ import annotations

from ..plotting import plot_frf_estimate, plot_identified_plant, symbol
from ..reproduction import identification as rep
from .context import Context

__all__ = ["fig2", "fig14"]


def fig2(ctx: Context, res: rep.Fig2) -> str:
    """Fig. 2 with the Sec. 3 remarks.

    Parameters
    ----------
    ctx : Context
        The report build: figures and CSV tables are written to ``ctx.out`` in its formats.
    res : Fig2
        The result of `empact.reproduction.identification.fig2`.

    Returns
    -------
    str
        HTML: the figure of the identified and exact plants, the claims and the tables of the Sec. 3
        damping, the creep-gain sensitivity and the identified models.
    """
    return (ctx.figure(plot_identified_plant(res.results, res.f_hz,
                                             title="Fig. 2: identified (solid) vs exact "
                                                   "linearisation (dashed)"),
                       "fig2_identified_plant",
                       "Fig. 2: |(T_mp, T_ms) -> (r_g, nu, nu_r)| at r_g = 0.5, 1, 2 (nu: eq. 2 "
                       "on the current radii; nu_r: at the operating ratio); order: the "
                       "smallest with every step fit ≥ 98 %")
            + ctx.claims(res.claims)
            + ctx.table("fig2_damping", ["r_g", "linear mode [Hz]", "linear zeta [-]",
                                         "nonlinear mode [Hz]", "nonlinear zeta [-]",
                                         "48 Hz zero of T_mp -> r_g / nu [Hz]"],
                        [row + [""] * (6 - len(row)) for row in res.damping_rows],
                        "Sec. 3 remarks: damping of the actuation modes (the machine's "
                        "linear model at moderate damping with Shafai's pulley damping vs the "
                        "exact linearisation, whose shift law is the creep law); the 48 Hz "
                        "zeros")
            + ctx.table("creep_gain", ["shift.gain [-]", "mode 2 [Hz]", "zeta 2 [-]",
                                       "mode 3 [Hz]", "zeta 3 [-]",
                                       "shift damping c_shift [N s/m]",
                                       "-1 slope of T_mp -> theta_mp up to [Hz]"],
                        res.gain_rows,
                        "Sensitivity to the creep law's magnitude (shift.gain; 1 is the "
                        "reconstruction's magnitude, the shipped 15 is calibrated against the "
                        "creep anchors, see the machine sheet): the machine's two lowest "
                        "actuation modes at r_g = 1 with the law's linearisation as pulley "
                        "damping. The damping peaks at an intermediate magnitude.")
            + ctx.table("fig2_identification", ["r_g", "order", "worst step fit [%]",
                                                "largest median FRF error [%]",
                                                "RHP zeros T_mp -> nu, identified [Hz]",
                                                "RHP zeros T_mp -> nu, exact [Hz]"], res.rows,
                        "Fig. 2: identified models"))


def fig14(ctx: Context, res: rep.Fig14) -> str:
    """Fig. 14 on the rig.

    Parameters
    ----------
    ctx : Context
        The report build: figures and CSV tables are written to ``ctx.out`` in its formats.
    res : Fig14
        The result of `empact.reproduction.identification.fig14`.

    Returns
    -------
    str
        HTML: one FRF-estimate figure per rig run, the claims and notes on the measured features and
        the paper's Sec. 4.
    """
    parts = []
    for run in res.runs:
        s = run.record.settings
        noise = ", ".join(f"{k} {v:g}" for k, v in s.noise.items())
        parts.append(ctx.figure(
            plot_frf_estimate(run.estimate, run.pairs, models=[run.model], fmin=0.5,
                              title=f"Virtual rig: {symbol(s.excite)} excited ({s.excitation}, "
                                    f"{s.rms:g} N m RMS)"),
            f"fig14_rig_{s.excite}",
            f"Fig. 14: H1 estimates with coherence, {s.duration:g} s at {s.sample_rate:g} Hz, "
            f"spindle Coulomb friction {s.coulomb[0]:g} / {s.coulomb[1]:g} N m, sensor noise "
            f"standard deviations {noise} (rad, rad, -), seed {s.seed}; dashed: the linearised "
            f"model without friction. {run.record.message}"))
    features = "; ".join(
        f"{k}: slope {v[0]:+.2f} between 1 and 2 Hz, median coherence in the excited band "
        f"{v[1]:.2f}, largest peak between 5 and 30 Hz at {v[2]:.1f} Hz"
        for k, v in res.slopes.items())
    return ("".join(parts) + ctx.claims(res.claims)
            + f"<p>Computed on the rig records: {features}.</p>"
            + "<p>Paper (Sec. 4): the measured FRFs of servo torque to servo angle show a -1 "
              "slope at low frequency, strongly damped modes, a resonance at 13 Hz from T_mp "
              "(and a first resonance near 20 Hz from T_ms); T_ms -> nu is dominated by "
              "disturbances. At nu0 = 0 the load torque is zero, so the slip responds only "
              "weakly to the servo torques (about -105 dB re 1/(N m) below 2 Hz); a realistic "
              "slip resolution of 1e-5 buries it in noise, as the paper found, so the rig here "
              "assumes 1e-7.</p>")
