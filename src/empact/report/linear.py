"""Report sections for the linear models of Sec. 2.1 and 2.2 (Tables 1-2, Figs. 4-6, 8)."""
from __future__ import annotations

import html

from .. import paper
from ..plotting import plot_bode, plot_modal_energy, plot_mode_shapes
from ..reproduction import linear as rep
from .context import Context

__all__ = ["table1", "table2", "fig4_5", "fig6", "fig8"]


def table1(ctx: Context, res: rep.Table1) -> str:
    """Table 1 with its claim."""
    rows = [[j + 1] + [res.frequencies_hz[r][j] for r in rep.RATIOS] for j in range(6)]
    return (ctx.table("table1", ["mode"] + [f"r_g = {r:g} [Hz]" for r in rep.RATIOS], rows,
                      "Table 1: undamped actuation eigenfrequencies [Hz]")
            + ctx.claims(res.claims)
            + f"<p>{html.escape(res.claims[0].explanation)}</p>")


def table2(ctx: Context, res: rep.Table2) -> str:
    """Table 2, paper against computed, with the uncoupled sides."""
    rows = []
    for r in rep.RATIOS:
        f = res.frequencies_hz[r]
        for j, ref in enumerate(paper.TABLE2_HZ[r]):
            rel = f[j] / ref - 1 if ref else 0.0
            rows.append([r, j + 1, ref, f[j], f"{100 * rel:+.2f} %" if ref else "-"])
    for side in ("primary", "secondary"):
        ref = paper.UNCOUPLED_HZ[side]
        rows.append(["uncoupled", side, ref, res.uncoupled_hz[side],
                     f"{100 * (res.uncoupled_hz[side] / ref - 1):+.2f} %"])
    return (ctx.table("table2", ["r_g", "mode", "paper [Hz]", "computed [Hz]", "error"], rows,
                      "Table 2: driveline eigenfrequencies, paper vs computed")
            + ctx.claims(res.claims)
            + f"<p>{html.escape(res.claims[1].explanation)}</p>")


def fig4_5(ctx: Context, res: rep.ModeFigure) -> str:
    """Figs. 4 and 5."""
    return (ctx.figure(plot_mode_shapes(res.modes, split=4, title="Actuation modes, $r_g$ = 1"),
                       "fig4_actuation_modes",
                       "Fig. 4: normalised undamped eigenvectors (q~1..q~8), low modes left, "
                       "translational modes right")
            + ctx.figure(plot_modal_energy(res.modes, title="Actuation modal energy, $r_g$ = 1"),
                         "fig5_actuation_energy",
                         "Fig. 5: signed normalised potential energy of springs 1-5 (worm, "
                         "chain, pushbelt, primary and secondary thrust bearing). Each bar is "
                         "k e² / Σ k e² for the spring's elongation e in the mode, signed: "
                         "positive where the spring is elongated, negative where it is "
                         "shortened; the magnitudes of a mode add up to 1.")
            + ctx.claims(res.claims))


def fig6(ctx: Context, res: rep.Fig6) -> str:
    """Fig. 6."""
    return (ctx.figure(plot_bode(res.responses, [("theta_mp", "T_mp"), ("theta_ms", "T_ms")],
                                 title="Actuation, $r_g$ = 1", units="rad/(N m)"),
                       "fig6_actuation_frf",
                       "Fig. 6: servo torque to servo position, undamped, moderate and large "
                       "damping")
            + ctx.claims(res.claims))


def fig8(ctx: Context, res: rep.ModeFigure) -> str:
    """Fig. 8."""
    return (ctx.figure(plot_mode_shapes(res.modes, title="Driveline modes, $r_g$ = 1"),
                       "fig8_driveline_modes", "Fig. 8 (left): normalised undamped eigenvectors")
            + ctx.figure(plot_modal_energy(res.modes, title="Driveline modal energy, $r_g$ = 1"),
                         "fig8_driveline_energy",
                         "Fig. 8 (right): signed normalised potential energy of the torque "
                         "converter, pushbelt and driveshaft (as in Fig. 5)")
            + ctx.claims(res.claims))
