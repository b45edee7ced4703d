"""Report sections for the linear models of Sec. 2.1 and 2.2 (Tables 1-2, Figs. 4-6, 8)."""
from __future__ import annotations

import numpy as np

from . import paper
from .actuation import actuation_model
from .driveline import driveline_model, uncoupled_frequencies
from .params import DAMPING_LEVELS
from .plotting import plot_bode, plot_modal_energy, plot_mode_shapes
from .report import Context, register, verdict

RATIOS = (0.5, 1.0, 2.0)


@register("Table 1: undamped actuation eigenfrequencies")
def table1(ctx: Context) -> str:
    freqs = {r: actuation_model(ctx.params, r).modes().frequencies_hz for r in RATIOS}
    rows = [[j + 1] + [freqs[r][j] for r in RATIOS] for j in range(6)]
    ref = paper.ACTUATION_R1_HZ
    achieved = freqs[1.0][1:4]
    err = np.abs(achieved / np.array(ref) - 1)
    note = (f"<p>The paper's Table 1 is missing from its text; its prose gives 10.7, 17.3 and "
            f"47.9 Hz at r_g = 1. Computed: {', '.join(f'{x:.2f}' for x in achieved)} Hz "
            f"(largest relative error {100 * err.max():.2f} %), modes 5 and 6 at "
            f"{freqs[1.0][4]:.0f} and {freqs[1.0][5]:.0f} Hz ('very high frequency'). "
            f"{verdict(bool(err.max() < 0.01 and freqs[1.0][4] > 500))}</p>")
    return ctx.table("table1", ["mode"] + [f"r_g = {r:g} [Hz]" for r in RATIOS], rows,
                     "Table 1: undamped actuation eigenfrequencies [Hz]") + note


@register("Table 2: undamped driveline eigenfrequencies")
def table2(ctx: Context) -> str:
    rows, worst = [], 0.0
    for r in RATIOS:
        f = driveline_model(ctx.params, r).modes().frequencies_hz
        for j, ref in enumerate(paper.TABLE2_HZ[r]):
            rel = f[j] / ref - 1 if ref else 0.0
            worst = max(worst, abs(rel))
            rows.append([r, j + 1, ref, f[j], f"{100 * rel:+.2f} %" if ref else "-"])
    unc = uncoupled_frequencies(ctx.params)
    for side in ("primary", "secondary"):
        ref = paper.UNCOUPLED_HZ[side]
        rel = unc[side] / ref - 1
        worst = max(worst, abs(rel))
        rows.append(["uncoupled", side, ref, unc[side], f"{100 * rel:+.2f} %"])
    note = (f"<p>Largest relative error {100 * worst:.2f} % (target 1 %): {verdict(worst < 0.01)}."
            " The uncoupled rows use the swapped labels: the paper's text calls 15.5 Hz the "
            "primary side and 24.6 Hz the secondary side, but no parameter set of the Fig. 7 "
            "model reproduces Table 2 with those labels, while the swapped reading fits all of "
            "Table 2 and agrees with the paper's own root-locus story (the 24.6 Hz pair ends at "
            "the 22.5 Hz torque-converter mode).</p>")
    return ctx.table("table2", ["r_g", "mode", "paper [Hz]", "computed [Hz]", "error"], rows,
                     "Table 2: driveline eigenfrequencies, paper vs computed") + note


@register("Figures 4 and 5: actuation mode shapes and modal energy at r_g = 1")
def fig4_5(ctx: Context) -> str:
    modes = actuation_model(ctx.params, 1.0).modes()
    e = np.abs(modes.energy_fraction)
    V = modes.normalised_shapes
    checks = {
        "one rigid-body mode with q7 = q8 = 0": modes.n_rigid == 1
        and np.allclose(V[6:, 0], 0, atol=1e-9) and np.allclose(V[:6, 0], 1, atol=1e-9),
        "mode 2: q1 and q3 in the same direction": V[0, 1] * V[2, 1] > 0,
        "mode 3: q1 and q3 opposite": V[0, 2] * V[2, 2] < 0,
        "mode 4: chain holds most of the potential energy": e[3, 1] >= 0.5,
        "mode 5: in-phase pulley translation, belt not strained": e[4, 2] <= 0.05,
        "mode 6: out-of-phase pulley translation, belt strained": e[5, 2] >= 0.2,
    }
    items = "".join(f"<li>{k}: {verdict(bool(v))}</li>" for k, v in checks.items())
    return (ctx.figure(plot_mode_shapes(modes, split=4, title="Actuation modes, r_g = 1"),
                       "fig4_actuation_modes",
                       "Fig. 4: normalised undamped eigenvectors (q~1..q~8), low modes left, "
                       "translational modes right")
            + ctx.figure(plot_modal_energy(modes, title="Actuation modal energy, r_g = 1"),
                         "fig5_actuation_energy",
                         "Fig. 5: signed normalised potential energy of springs 1-5 (worm, "
                         "chain, pushbelt, primary and secondary thrust bearing)")
            + f"<ul>{items}</ul>")


@register("Figure 6: damped actuation transfer functions")
def fig6(ctx: Context) -> str:
    f = np.logspace(-1, 3.5, 800)
    resps = [actuation_model(ctx.params, 1.0, lvl).frequency_response(
        2 * np.pi * f, ["T_mp", "T_ms"], ["theta_mp", "theta_ms"], label=f"{lvl} damping")
        for lvl in DAMPING_LEVELS]
    large = resps[-1]
    f1 = actuation_model(ctx.params, 1.0).modes().frequencies_hz[1]
    slopes = []
    for out, inp in (("theta_mp", "T_mp"), ("theta_ms", "T_ms")):
        mag = np.log10(np.abs(large.response(out, inp)))
        s = np.gradient(mag, np.log10(f))
        slopes.append((s[np.argmin(abs(f - f1 / 20))], s[np.argmin(abs(f - 30 * f1))]))
    ok = all(abs(lo + 1) < 0.1 and abs(hi + 2) < 0.1 for lo, hi in slopes)
    txt = "; ".join(f"{p}: {lo:.2f} at {f1 / 20:.2f} Hz, {hi:.2f} at {30 * f1:.0f} Hz"
                    for p, (lo, hi) in zip(("T_mp -> theta_mp", "T_ms -> theta_ms"), slopes))
    return (ctx.figure(plot_bode(resps, [("theta_mp", "T_mp"), ("theta_ms", "T_ms")],
                                 title="Actuation, r_g = 1"), "fig6_actuation_frf",
                       "Fig. 6: servo torque to servo position, undamped, moderate and large "
                       "damping")
            + f"<p>Paper: with large damping, slope -1 at low and -2 at high frequency. "
              f"Computed slopes (decades/decade) with large damping: {txt}. {verdict(ok)}</p>")


@register("Figure 8: driveline mode shapes and modal energy at r_g = 1")
def fig8(ctx: Context) -> str:
    modes = driveline_model(ctx.params, 1.0).modes()
    e = np.abs(modes.energy_fraction)
    checks = {"mode 2 mainly driveshaft": e[1].argmax() == 2,
              "mode 3 mainly torque converter": e[2].argmax() == 0,
              "mode 4 mainly pushbelt": e[3].argmax() == 1}
    items = "".join(f"<li>{k}: {verdict(bool(v))}</li>" for k, v in checks.items())
    return (ctx.figure(plot_mode_shapes(modes, title="Driveline modes, r_g = 1"),
                       "fig8_driveline_modes", "Fig. 8 (left): normalised undamped eigenvectors")
            + ctx.figure(plot_modal_energy(modes, title="Driveline modal energy, r_g = 1"),
                         "fig8_driveline_energy",
                         "Fig. 8 (right): normalised potential energy of the torque converter, "
                         "pushbelt and driveshaft")
            + f"<ul>{items}</ul>")
