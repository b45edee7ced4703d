"""Figures of the control results: the family's poles and zeros, loop shapes, robustness
maps and closed-loop runs (drawn from `empact.control` result objects)."""
from __future__ import annotations

from typing import Any, Mapping, Sequence

import matplotlib
import numpy as np

from ..control.closed_loop import ClosedLoopResult
from ..control.controller import Controller
from ..control.family import PlantFamily
from ..control.robustness import RobustnessMap, frequency_responses, plant_responses
from ..lti import channel_zeros
from ._common import STYLES, Plot, new_axes, styled, symbol

__all__ = ["plot_family_poles", "plot_loop_shapes", "plot_robustness_maps",
           "plot_closed_loop"]


@styled
def plot_family_poles(family: PlantFamily, f_max_hz: float = 60.0, title: str = "",
                      ax: Any = None) -> Plot:
    """Poles (left) and the zeros of T_mp -> r_g and T_ms -> nu (right) of every plant of a
    family below `f_max_hz` [Hz], coloured by ratio (complex plane in Hz)."""
    fig, axs = new_axes(ax, 1, 2, size=(11, 4.2))
    r = family.operating["r_g"].ravel()
    norm = (np.log(r) - np.log(r).min()) / max(np.ptp(np.log(r)), 1e-12)
    cmap = matplotlib.colormaps["viridis"]
    artists = []
    for k in range(family.size):
        idx = np.unravel_index(k, family.shape)
        if not family.ok[idx]:
            continue
        c = cmap(norm[k])
        p = np.linalg.eigvals(family.A[idx])
        p = p[np.abs(p) < 2 * np.pi * f_max_hz] / (2 * np.pi)
        artists += axs[0, 0].plot(p.real, p.imag, "x", color=c, ms=4)
        sys = family.plant(idx).system
        for inp, out, mk in (("T_mp", "r_g", "o"), ("T_ms", "nu", "s")):
            z = channel_zeros(sys, inp, out, max_abs=2 * np.pi * f_max_hz)
            z = z / (2 * np.pi)
            artists += axs[0, 1].plot(z.real, z.imag, mk, mfc="none", color=c, ms=4)
    for ax, what in zip(axs[0], ("poles", "zeros (o: T_mp -> r_g, s: T_ms -> nu)")):
        ax.axvline(0, color="k", lw=0.6)
        ax.set_xscale("symlog", linthresh=1.0)
        ax.set_xlabel("real part / 2π [Hz] (symmetric log)")
        ax.set_ylabel("imaginary part / 2π [Hz]")
        ax.set_title(f"{what}, colour: r_g {r.min():.2g} (dark) .. {r.max():.2g} (light)",
                     fontsize=8)
    if title:
        fig.suptitle(title)
    return Plot(fig, axs, artists)


@styled
def plot_loop_shapes(family: PlantFamily, controllers: Mapping[str, Controller],
                     f_hz: np.ndarray | None = None, title: str = "",
                     ax: Any = None) -> Plot:
    """Diagonal loop gains |L_ii| = |(K G)_ii| over the family (thin lines, one per plant)
    for each controller (one column per loop, one colour per controller)."""
    f = np.logspace(-2, 2, 150) if f_hz is None else np.asarray(f_hz)
    w = 2 * np.pi * f
    fig, axs = new_axes(ax, 1, 2, size=(11, 4.0), sharex=True)
    artists = []
    for c, (name, ctrl) in enumerate(controllers.items()):
        G = plant_responses(family, ctrl.outputs, ctrl.measured, w).reshape(
            (-1, len(w), 2, 2))
        K = frequency_responses(ctrl.A, ctrl.B, ctrl.C, ctrl.D, w)
        L = K @ G
        for j in range(2):
            for k in range(L.shape[0]):
                artists += axs[0, j].loglog(f, np.abs(L[k, :, j, j]), color=f"C{c}", lw=0.6,
                                            alpha=0.5, label=name if k == 0 else None)
    for j, loop in enumerate(("ratio loop (T_mp)", "slip loop (T_ms)")):
        ax = axs[0, j]
        ax.axhline(1, color="k", lw=0.6)
        ax.set_title(f"|L| of the {loop} at the plant input, every plant", fontsize=8)
        ax.set_xlabel("frequency [Hz]")
        ax.grid(True, which="both")
        ax.legend(loc="best")
    axs[0, 0].set_ylabel("loop gain [-]")
    if title:
        fig.suptitle(title)
    return Plot(fig, axs, artists)


@styled
def plot_robustness_maps(family: PlantFamily, maps: Mapping[str, RobustnessMap],
                         title: str = "", ax: Any = None) -> Plot:
    """Multiloop disk margin over the family's two axes, one panel per controller."""
    names = list(family.axes)
    if len(names) != 2:
        raise ValueError("robustness maps need a family with two axes")
    fig, axs = new_axes(ax, 1, len(maps), size=(5.5 * len(maps), 4.0))
    artists = []
    x, y = family.axes[names[0]], family.axes[names[1]]
    for ax, (name, m) in zip(axs[0], maps.items()):
        im = ax.pcolormesh(np.arange(len(y) + 1), np.arange(len(x) + 1), m.disk_margin,
                           vmin=0, vmax=max(1.0, float(m.disk_margin.max())), cmap="viridis")
        artists.append(im)
        for i in range(len(x)):
            for j in range(len(y)):
                ax.text(j + 0.5, i + 0.5, f"{m.disk_margin[i, j]:.2f}", ha="center",
                        va="center", fontsize=6, color="w")
        ax.set_xticks(np.arange(len(y)) + 0.5, [f"{v:.3g}" for v in y])
        ax.set_yticks(np.arange(len(x)) + 0.5, [f"{v:.3g}" for v in x])
        ax.set_xlabel(symbol(names[1]))
        ax.set_ylabel(symbol(names[0]))
        ax.set_title(f"{name}: disk margin (unstable: 0)", fontsize=9)
        fig.colorbar(im, ax=ax)
    if title:
        fig.suptitle(title)
    return Plot(fig, axs, artists)


@styled
def plot_closed_loop(runs: Sequence[ClosedLoopResult], title: str = "",
                     ax: Any = None) -> Plot:
    """Slip, ratio and clamping force over time for closed-loop runs (one colour per run,
    references dashed)."""
    fig, axs = new_axes(ax, 3, 1, size=(11, 7.5), sharex=True)
    artists = []
    for c, run in enumerate(runs):
        res = run.result
        lbl = run.scenario.name + ("" if res.complete else " [stopped]")
        artists += axs[0, 0].plot(res.t, 100 * res.output("nu"), color=f"C{c}", label=lbl)
        if "nu" in run.references:
            axs[0, 0].plot(res.t, 100 * run.references["nu"], color=f"C{c}", ls=STYLES[1])
        artists += axs[1, 0].plot(res.t, res.output("r_g"), color=f"C{c}")
        if "r_g" in run.references:
            axs[1, 0].plot(res.t, run.references["r_g"], color=f"C{c}", ls=STYLES[1])
        artists += axs[2, 0].plot(res.t, res.output("F_s") / 1e3, color=f"C{c}")
    axs[0, 0].set_ylabel("slip ν [%]")
    axs[0, 0].set_yscale("symlog", linthresh=1.0)
    axs[1, 0].set_ylabel("ratio $r_g$ [-]")
    axs[2, 0].set_ylabel("$F_s$ [kN]")
    axs[2, 0].set_xlabel("time [s]")
    axs[0, 0].legend(fontsize=7, loc="best")
    if title:
        fig.suptitle(title)
    return Plot(fig, axs, artists)
