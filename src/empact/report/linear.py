"""Report sections for the linear models of Sec. 2.1 and 2.2 (Tables 1-2, Figs. 4-6, 8)."""
from __future__ import annotations

import html

from .. import paper
from ..plotting import plot_bode, plot_modal_energy, plot_mode_shapes
from ..reproduction import linear as rep
from .context import Context

__all__ = ["table1", "table2", "fig4_5", "fig6", "fig8"]


def table1(ctx: Context, res: rep.Table1) -> str:
    """Table 1 for both row sets, side by side, with its claims.

    Parameters
    ----------
    ctx : Context
        The report build: figures and CSV tables are written to ``ctx.out`` in its formats.
    res : Table1
        The result of `empact.reproduction.linear.table1`.

    Returns
    -------
    str
        HTML: the table ``table1`` (eigenfrequencies [Hz] of six modes at r_g = 0.5, 1, 2 for each
        row set), the claims and a note on the calibration.
    """
    kins = (rep.SEC21, rep.MACHINE)
    rows = [[j + 1] + [res.frequencies_hz[k][r][j] for k in kins for r in rep.RATIOS]
            for j in range(6)]
    head = ["mode"] + [f"{'Sec. 2.1' if k == rep.SEC21 else 'machine'} r_g = {r:g} [Hz]"
                       for k in kins for r in rep.RATIOS]
    return (ctx.table("table1", head, rows, "Table 1: undamped actuation eigenfrequencies [Hz], "
                      "the paper's Sec. 2.1 rows (left) and the machine (right)")
            + ctx.claims(res.claims)
            + f"<p>{html.escape(res.claims[0].explanation)} Both row sets are calibrated to the "
              "same three frequencies at r_g = 1 (paper_targets.toml): the Sec. 2.1 rows with "
              "their own stiffness overlay [paper_sec21], the machine with [actuation]. They "
              "differ at other ratios and in modes 5 and 6.</p>")


def table2(ctx: Context, res: rep.Table2) -> str:
    """Table 2, paper against computed, with the uncoupled sides.

    Parameters
    ----------
    ctx : Context
        The report build: figures and CSV tables are written to ``ctx.out`` in its formats.
    res : Table2
        The result of `empact.reproduction.linear.table2`.

    Returns
    -------
    str
        HTML: the table ``table2`` (paper against computed [Hz] and the relative error, then the
        uncoupled sides), the claims and the note on the side labels.
    """
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
    """Figs. 4 and 5, for the paper's Sec. 2.1 rows and for the machine, with the mode
    characters of both.

    Parameters
    ----------
    ctx : Context
        The report build: figures and CSV tables are written to ``ctx.out`` in its formats.
    res : ModeFigure
        The result of `empact.reproduction.linear.fig4_5` (with its
        ``machine`` modes and ``characters``).

    Returns
    -------
    str
        HTML: the mode-shape and modal-energy figures of both row sets, the table of the mode
        characters and the claims.
    """
    out = ""
    for modes, label, key in ((res.modes, "Sec. 2.1 rows as published", ""),
                              (res.machine, "machine (equal translation)", "_machine")):
        out += (ctx.figure(plot_mode_shapes(modes, split=4,
                                            title=f"Actuation modes, $r_g$ = 1, {label}"),
                           f"fig4_actuation_modes{key}",
                           f"Fig. 4 ({label}): normalised undamped eigenvectors (q~1..q~8), low "
                           "modes left, translational modes right")
                + ctx.figure(plot_modal_energy(modes, title=f"Actuation modal energy, "
                                                            f"$r_g$ = 1, {label}"),
                             f"fig5_actuation_energy{key}",
                             f"Fig. 5 ({label}): signed normalised potential energy of springs "
                             "1-5 (worm, chain, pushbelt, primary and secondary thrust "
                             "bearing). Each bar is k e² / Σ k e² for the spring's elongation e "
                             "in the mode, signed: positive where the spring is elongated, "
                             "negative where it is shortened; the magnitudes of a mode add up "
                             "to 1."))
    rows = [["Sec. 2.1" if k == rep.SEC21 else "machine", j, f, c]
            for k, j, f, c in res.characters]
    return (out + ctx.table("fig4_5_characters", ["rows", "mode", "frequency [Hz]",
                                                  "character (potential energy)"], rows,
                            "Mode characters at r_g = 1")
            + ctx.claims(res.claims)
            + "<p>Why they differ: in the Sec. 2.1 rows the belt row is (π + 2φ) q5 − (π − 2φ) q6, "
              "so a rotation of the primary servo against the held secondary squeezes both "
              "sheaves: the shift needs both servos (all q~ equal in the rigid-body mode) and "
              "the worm shares its modes with belt and bearings. On the machine the belt row "
              "is (π + 2φ) q5 + (π − 2φ) q6: the primary servo translates both sheaves equally "
              "and shifts alone (q~2 = q~4 = 0), the secondary servo clamps, and at r_g = 1 the "
              "worm decouples from belt and bearings (mode 3 is the worm mode, mode 2 the "
              "clamping mode of sheaves, bearings and belt).</p>")


def fig6(ctx: Context, res: rep.Fig6) -> str:
    """Fig. 6 (Sec. 2.1 rows) and the machine with the creep law's pulley damping.

    Parameters
    ----------
    ctx : Context
        The report build: figures and CSV tables are written to ``ctx.out`` in its formats.
    res : Fig6
        The result of `empact.reproduction.linear.fig6`.

    Returns
    -------
    str
        HTML: the Bode figures of the Sec. 2.1 rows and of the machine (servo torque -> servo angle
        [rad/(N m)]) and the claims.
    """
    pairs = [("theta_mp", "T_mp"), ("theta_ms", "T_ms")]
    return (ctx.figure(plot_bode(res.responses, pairs,
                                 title="Actuation, $r_g$ = 1, Sec. 2.1 rows", units="rad/(N m)"),
                       "fig6_actuation_frf",
                       "Fig. 6: servo torque to servo position, undamped, moderate and large "
                       "damping (the paper's Sec. 2.1 rows and illustrative damping levels)")
            + ctx.figure(plot_bode(res.machine, pairs, title="Actuation, $r_g$ = 1, machine",
                                   units="rad/(N m)"),
                         "fig6_actuation_frf_machine",
                         "Fig. 6 on the machine: undamped, moderate damping with Shafai's "
                         "pulley damping, and moderate damping with the creep law linearised "
                         "at the operating point as the pulley damping")
            + ctx.claims(res.claims))


def fig8(ctx: Context, res: rep.ModeFigure) -> str:
    """Fig. 8.

    Parameters
    ----------
    ctx : Context
        The report build: figures and CSV tables are written to ``ctx.out`` in its formats.
    res : ModeFigure
        The result of `empact.reproduction.linear.fig8`.

    Returns
    -------
    str
        HTML: the driveline mode-shape and modal-energy figures and the claims.
    """
    return (ctx.figure(plot_mode_shapes(res.modes, title="Driveline modes, $r_g$ = 1"),
                       "fig8_driveline_modes", "Fig. 8 (left): normalised undamped eigenvectors")
            + ctx.figure(plot_modal_energy(res.modes, title="Driveline modal energy, $r_g$ = 1"),
                         "fig8_driveline_energy",
                         "Fig. 8 (right): signed normalised potential energy of the torque "
                         "converter, pushbelt and driveshaft (as in Fig. 5)")
            + ctx.claims(res.claims))
