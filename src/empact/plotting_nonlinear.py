"""Figures of the nonlinear model's results (NMP analysis, simulations, exact plant Bode).

Drawn from result objects only (`empact.nmp.NmpResult`, `empact.simulate.SimulationResult`,
`empact.lumped.FrequencyResponse`); every function returns a matplotlib `Figure`.
"""
from __future__ import annotations

from typing import Sequence

import numpy as np
from matplotlib.figure import Figure

from .lumped import FrequencyResponse
from .nmp import NmpResult
from .plotting import STYLES, new_figure
from .simulate import SimulationResult

__all__ = ["plot_nmp", "plot_simulation", "plot_plant_magnitude"]


def plot_nmp(result: NmpResult, title: str = "") -> Figure:
    """Left: Delta_x and the belt-length change over the ratio; right: zeros of T_mp -> nu.

    The zeros are drawn in the complex plane [Hz], one colour per ratio; right-half-plane
    zeros filled.
    """
    fig, axes = new_figure(1, 2, size=(11, 4.2))
    g = result.geometry
    ax = axes[0, 0]
    ax.semilogx(g.r_g, 1e3 * g.delta_x, "-o", label="Delta_x = x_p - x_s (eq. 5) [mm]")
    ax.semilogx(g.r_g, 1e6 * g.dL_exact, "-s", label=f"dL exact, delta = {1e6 * g.delta:g} um [um]")
    ax.semilogx(g.r_g, 1e6 * g.dL_first_order, "--", label="dL = 4 phi delta / tan(beta) [um]")
    ax.axhline(0, color="k", lw=0.6)
    ax.axvline(1, color="k", lw=0.4, ls=":")
    ax.set_xlabel("geometric ratio r_g [-]")
    ax.legend(fontsize=7)
    ax.grid(True, which="both", lw=0.3)
    ax = axes[0, 1]
    colors = [f"C{k % 10}" for k in range(len(result.r_g))]
    for r, z, c in zip(result.r_g, result.zeros, colors):
        zh = z / (2 * np.pi)
        rhp = z.real > 1e-6 * np.abs(z)
        ax.plot(zh.real[~rhp], zh.imag[~rhp], "o", mfc="none", color=c, ms=5,
                label=f"r_g = {r:.3g}: {int(rhp.sum())} RHP")
        ax.plot(zh.real[rhp], zh.imag[rhp], "o", color=c, ms=6)
    ax.axvline(0, color="k", lw=0.6)
    ax.set_xscale("symlog", linthresh=1.0)
    ax.set_xlabel("Re(zero) [Hz] (symlog)")
    ax.set_ylabel("Im(zero) [Hz]")
    ax.set_ylim(-5, result.f_max)
    ax.set_title("zeros of T_mp -> nu (filled: right half-plane)", fontsize=9)
    ax.legend(fontsize=6, ncol=2)
    ax.grid(True, lw=0.3)
    if title:
        fig.suptitle(title)
    return fig


def plot_simulation(result: SimulationResult,
                    signals: Sequence[tuple[str, ...]] = (("r_g", "r_g_ref"), ("nu",),
                                                           ("F_s", "F_p"),
                                                           ("omega_p", "omega_s"),
                                                           ("T_b", "T_l_act", "T_d_act"),
                                                           ("T_mp_act",)),
                    title: str = "") -> Figure:
    """Time histories, one panel per group of signal names (missing names are skipped)."""
    known = set(result.outputs) | set(result.states) | set(result.inputs)
    groups = [[s for s in grp if s in known] for grp in signals]
    groups = [g for g in groups if g]
    ncol = 2
    nrow = (len(groups) + 1) // 2
    fig, axes = new_figure(nrow, ncol, size=(11, 2.3 * nrow + 0.8), sharex=True)
    for k, grp in enumerate(groups):
        ax = axes[k // ncol, k % ncol]
        for j, name in enumerate(grp):
            ax.plot(result.t, result.output(name), ls=STYLES[j % len(STYLES)], label=name)
        ax.legend(fontsize=7)
        ax.grid(True, lw=0.3)
    for ax in axes[-1]:
        ax.set_xlabel("time [s]")
    for k in range(len(groups), nrow * ncol):
        axes[k // ncol, k % ncol].set_visible(False)
    status = "" if result.complete else "  [INCOMPLETE]"
    fig.suptitle((title or f"simulation {result.scenario}") + status)
    return fig


def plot_plant_magnitude(responses: Sequence[FrequencyResponse], title: str = "") -> Figure:
    """2x2 magnitude plot of (T_mp, T_ms) -> (r_g, nu), one line style per response (Fig. 2)."""
    fig, axes = new_figure(2, 2, size=(10, 6), sharex=True)
    for k, resp in enumerate(responses):
        for i, out in enumerate(resp.outputs):
            for j, inp in enumerate(resp.inputs):
                ax = axes[i, j]
                ax.loglog(resp.frequencies_hz, np.abs(resp.H[i, j]), ls=STYLES[k % len(STYLES)],
                          label=resp.label)
                ax.set_title(f"{inp} -> {out}", fontsize=9)
                ax.grid(True, which="both", lw=0.3)
    for ax in axes[-1]:
        ax.set_xlabel("frequency [Hz]")
    axes[0, 0].set_ylabel("|r_g / T| [1/(N m)]")
    axes[1, 0].set_ylabel("|nu / T| [1/(N m)]")
    axes[0, 0].legend(fontsize=7)
    if title:
        fig.suptitle(title)
    return fig
