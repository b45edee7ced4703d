"""Figures of the nonlinear model's results (NMP analysis, simulations, exact plant
magnitudes).

Drawn from result objects only (`empact.nonlinear.nmp.NmpResult`,
`empact.nonlinear.simulation.SimulationResult`, `empact.lti.FrequencyResponse`); every function
draws on the given axes or a new figure and returns a `Plot`.
"""
from __future__ import annotations

from typing import Any, Sequence

import numpy as np

from ..lti import FrequencyResponse
from ..nonlinear.model import INPUT_UNITS, OUTPUT_UNITS, STATE_UNITS
from ..nonlinear.nmp import NmpResult
from ..nonlinear.simulation import SimulationResult
from ._common import STYLES, Plot, new_axes, styled, symbol

__all__ = ["plot_nmp", "plot_simulation", "plot_plant_magnitude"]


@styled
def plot_nmp(result: NmpResult, title: str = "", ax: Any = None) -> Plot:
    """Left: Delta_x and the belt-length change over the ratio; right: zeros of T_mp -> nu.

    The zeros are drawn in the complex plane [Hz], one colour per ratio; right-half-plane
    zeros filled.

    Parameters
    ----------
    result : NmpResult
        The analysis (`empact.nonlinear.nmp.nmp_analysis`): its geometry (Delta_x drawn in
        mm, the belt-length change in µm) and its zeros [rad/s] at each ratio.
    title : str
        Figure title.
    ax : array of Axes, shape (1, 2), optional
        Geometry (left) and zeros (right); default a new figure.

    Returns
    -------
    Plot
        The figure, the axes (shape (1, 2)) and the lines and markers drawn.
    """
    fig, axs = new_axes(ax, 1, 2, size=(11, 4.2))
    g = result.geometry
    ax = axs[0, 0]
    artists = []
    artists += ax.semilogx(g.r_g, 1e3 * g.delta_x, "-o",
                           label=r"$\Delta_x = x_p - x_s$ (eq. 5) [mm]")
    artists += ax.semilogx(g.r_g, 1e6 * g.dL_exact, "-s",
                           label=rf"$\Delta L$ exact, $\delta$ = {1e6 * g.delta:g} µm [µm]")
    artists += ax.semilogx(g.r_g, 1e6 * g.dL_first_order, "--",
                           label=r"$\Delta L = 4 \phi \delta / \tan\beta$ [µm]")
    ax.axhline(0, color="k", lw=0.6)
    ax.axvline(1, color="k", lw=0.4, ls=":")
    ticks = [t for t in (0.4, 0.5, 0.7, 1.0, 1.5, 2.0, 2.5) if g.r_g.min() <= t <= g.r_g.max()]
    ax.set_xticks(ticks, [f"{t:g}" for t in ticks])
    ax.minorticks_off()
    ax.set_xlabel(r"geometric ratio $r_g$ [-]")
    ax.set_ylabel("length [mm or µm, see legend]")
    ax.legend(loc="best")
    ax.grid(True, which="both")
    ax = axs[0, 1]
    colors = [f"C{k % 10}" for k in range(len(result.r_g))]
    top = 1.0
    for r, z, zr, c in zip(result.r_g, result.zeros, result.rhp_zeros, colors):
        zh = z / (2 * np.pi)
        rhp = np.isin(z, zr)  # the analysis' own right-half-plane set
        artists += ax.plot(zh.real[~rhp], zh.imag[~rhp], "o", mfc="none", color=c, ms=5,
                           label=f"$r_g$ = {r:.3g}: {int(rhp.sum())} RHP")
        artists += ax.plot(zh.real[rhp], zh.imag[rhp], "o", color=c, ms=6)
        top = max(top, float(np.abs(zh.imag).max(initial=0.0)))
    ax.axvline(0, color="k", lw=0.6)
    ax.set_xscale("symlog", linthresh=1.0)
    ax.set_xlabel("real part of zero / 2π [Hz] (symmetric log scale)")
    ax.set_ylabel("imaginary part of zero / 2π [Hz]")
    ax.set_ylim(-0.05 * top, 1.15 * top)
    ax.set_title(rf"zeros of $T_\mathrm{{mp}} \rightarrow$ {symbol(result.slip)} (filled: right "
                 "half-plane)")
    ax.legend(fontsize=6, ncol=2, loc="upper left")
    if title:
        fig.suptitle(title)
    return Plot(fig, axs, artists)


@styled
def plot_simulation(result: SimulationResult,
                    signals: Sequence[tuple[str, ...]] = (("r_g", "r_g_ref"), ("nu",),
                                                           ("F_s", "F_p"),
                                                           ("omega_p", "omega_s"),
                                                           ("T_b", "T_l_act", "T_d_act"),
                                                           ("T_mp_act",)),
                    title: str = "", ax: Any = None) -> Plot:
    """Time histories, one panel per group of signal names (missing names are skipped).

    Each panel's y label gives the unit of its signals (`empact.nonlinear.model` units; slip
    in %).

    Parameters
    ----------
    result : SimulationResult
        The simulation (`empact.simulate`, `empact.nonlinear.simulation.run_scenario`); an
        incomplete one is marked in the title.
    signals : sequence of tuple of str
        Groups of output, state or input names, one panel each (one line style per name);
        forces above 1 kN are drawn in kN.
    title : str
        Figure title (default: the scenario's name).
    ax : array of Axes, shape (ceil(groups / 2), 2), optional
        Two columns of panels, ``groups`` the groups with a known name; default a new
        figure.

    Returns
    -------
    Plot
        The figure, the axes (shape (ceil(groups / 2), 2); an unused last panel hidden) and the
        lines drawn.
    """
    known = set(result.outputs) | set(result.states) | set(result.inputs)
    groups = [[s for s in grp if s in known] for grp in signals]
    groups = [g for g in groups if g]
    ncol = 2
    nrow = (len(groups) + 1) // 2
    fig, axs = new_axes(ax, nrow, ncol, size=(11, 2.4 * nrow + 0.8), sharex=True)
    units = {**STATE_UNITS, **INPUT_UNITS, **OUTPUT_UNITS}
    artists = []
    for k, grp in enumerate(groups):
        ax = axs[k // ncol, k % ncol]
        for j, name in enumerate(grp):
            y = result.output(name)
            unit = units.get(name, "")
            if name == "nu":
                y, unit = 100 * y, "%"
            elif unit == "N" and np.nanmax(np.abs(y)) > 1e3:
                y, unit = y / 1e3, "kN"
            artists += ax.plot(result.t, y, ls=STYLES[j % len(STYLES)], label=symbol(name))
        ax.set_ylabel(f"[{unit}]" if unit else "[-]")
        ax.legend(loc="best")
    for ax in axs[-1]:
        ax.set_xlabel("time [s]")
    for k in range(len(groups), nrow * ncol):
        axs[k // ncol, k % ncol].set_visible(False)
    status = "" if result.complete else "  [INCOMPLETE]"
    fig.suptitle((title or f"simulation {result.scenario}") + status)
    return Plot(fig, axs, artists)


@styled
def plot_plant_magnitude(responses: Sequence[FrequencyResponse], title: str = "",
                         ax: Any = None) -> Plot:
    """Magnitudes of the plant (e.g. T_mp, T_ms, T_l -> r_g, nu, nu_r), one line style per
    response (Fig. 2).

    Parameters
    ----------
    responses : sequence of FrequencyResponse
        Plant responses with the outputs and inputs of the first (e.g.
        ``system_response(plant(...).system, w)``), inputs torques [N m]: the magnitudes are
        drawn in output units per N m.
    title : str
        Figure title.
    ax : array of Axes, shape (n_out, n_in), optional
        One panel per output and input of the responses; default a new figure.

    Returns
    -------
    Plot
        The figure, the axes (shape (n_out, n_in)) and the lines drawn.
    """
    n_out, n_in = len(responses[0].outputs), len(responses[0].inputs)
    fig, axs = new_axes(ax, n_out, n_in, size=(3.6 * n_in + 1.2, 2.3 * n_out + 1.0),
                        sharex=True)
    artists = []
    for k, resp in enumerate(responses):
        for i, out in enumerate(resp.outputs):
            for j, inp in enumerate(resp.inputs):
                ax = axs[i, j]
                artists += ax.loglog(resp.frequencies_hz, np.abs(resp.H[i, j]),
                                     ls=STYLES[k % len(STYLES)], label=resp.label)
                ax.set_title(f"{symbol(inp)} $\\rightarrow$ {symbol(out)}")
                ax.grid(True, which="both")
                if j == 0:
                    ax.set_ylabel(f"|{symbol(out)} / T| [{OUTPUT_UNITS.get(out, '-')}/(N m)]")
    for ax in axs[-1]:
        ax.set_xlabel("frequency [Hz]")
    axs[0, 0].legend(loc="best")
    if title:
        fig.suptitle(title)
    return Plot(fig, axs, artists)
