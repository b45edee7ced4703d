"""A drive cycle, quasi-static (`empact.drive_cycle.CycleResult`) or dynamic
(`empact.dynamic_cycle.DynamicCycleResult`): trace, ratio, clamping, slip, cumulative
losses."""
from __future__ import annotations

from typing import Any

import numpy as np

from ..drive_cycle import TERMS, CycleResult
from ._common import Plot, new_axes, styled

__all__ = ["plot_drive_cycle", "plot_dynamic_cycle"]


@styled
def plot_drive_cycle(res: CycleResult, ax: Any = None) -> Plot:
    """Four panels over time: the speed trace, the ratio and the clamping force by strategy,
    and each strategy's cumulative losses (every term of `empact.drive_cycle.TERMS`: the
    engine's output less the wheels' traction).

    Parameters
    ----------
    res : CycleResult
        The cycle (`empact.drive_cycle.quasi_static_cycle`).
    ax : array of Axes, shape (4, 1), optional
        Default a new figure.

    Returns
    -------
    Plot
        The figure, its axes and the lines drawn.
    """
    fig, axs = new_axes(ax, 4, 1, size=(8.0, 8.5), sharex=True)
    t = res.t
    artists: list[Any] = list(axs[0, 0].plot(t, 3.6 * res.v, color="k", lw=0.8))
    axs[0, 0].set_ylabel("speed [km/h]")
    axs[0, 0].set_title(f"{res.cycle.name}: quasi-static")
    for s in res.strategies:
        artists += axs[1, 0].plot(t, res.r_g[s], lw=0.8, label=s)
        artists += axs[2, 0].plot(t, res.F_s[s] / 1e3, lw=0.8, label=s)
        loss = sum(res.power[s][k] for k in TERMS)
        artists += axs[3, 0].plot(t, np.cumsum(res.weights * loss) / 1e6, label=s)
    axs[1, 0].set_ylabel("ratio $r_g$ [-]")
    axs[2, 0].set_ylabel("clamping $F_s$ [kN]")
    axs[3, 0].set_ylabel("cumulative losses [MJ]")
    axs[3, 0].set_xlabel("time [s]")
    axs[3, 0].legend(fontsize="small")
    return Plot(fig, axs, artists)


@styled
def plot_dynamic_cycle(res: Any, ax: Any = None) -> Plot:
    """Five panels over time for a dynamic cycle: the speed trace and the car's speed, the
    ratio and its reference, the slip, the clamping force by strategy, and each strategy's
    cumulative losses (every term of `empact.drive_cycle.TERMS`; the dynamic stretches'
    from the run, the rest the quasi-static cycle's).

    Parameters
    ----------
    res : DynamicCycleResult
        The cycle (`empact.dynamic_cycle.dynamic_cycle`).
    ax : array of Axes, shape (5, 1), optional
        Default a new figure.

    Returns
    -------
    Plot
        The figure, its axes and the lines drawn.
    """
    fig, axs = new_axes(ax, 5, 1, size=(8.0, 10.0), sharex=True)
    cyc = res.cycle
    artists: list[Any] = list(axs[0, 0].plot(cyc.t, 3.6 * cyc.v, color="k", lw=0.8,
                                             label="trace"))
    axs[0, 0].set_title(f"{cyc.name}: dynamic (law at {res.rate_hz:g} Hz)")
    qs = res.quasi_static
    for s, run in res.runs.items():
        t, sig = run.t, run.signals
        gap = np.flatnonzero(np.diff(t) > 0.5) + 1  # no line across the quasi-static rest
        tt = np.insert(t, gap, np.nan)

        def seg(x):
            return np.insert(np.asarray(x, float), gap, np.nan)

        artists += axs[0, 0].plot(tt, seg(3.6 * sig["v"]), lw=0.6, label=s)
        artists += axs[1, 0].plot(tt, seg(sig["r_g"]), lw=0.6, label=s)
        artists += axs[2, 0].plot(tt, seg(100 * sig["nu"]), lw=0.6, label=s)
        artists += axs[3, 0].plot(tt, seg(sig["F_s"] / 1e3), lw=0.6, label=s)
        # cumulative losses: the quasi-static rest at its samples and the run's
        P = qs.power[s]
        loss_qs = sum(P[k] for k in TERMS)
        dyn = sum(sig.get(f"P_loss_{k}", 0.0) for k in ("slip", "clamp", "load", "drag")) \
            + sig["P_loss_fd"] + sig["P_accessory"]
        grid = np.union1d(cyc.t, t)
        inside = np.zeros(grid.size, dtype=bool)
        for a, b in res.stretches:
            inside |= (grid >= a) & (grid <= b)
        p = np.where(inside, np.interp(grid, t, dyn), np.interp(grid, cyc.t, loss_qs))
        cum = np.concatenate([[0.0], np.cumsum(0.5 * (p[1:] + p[:-1]) * np.diff(grid))])
        artists += axs[4, 0].plot(grid, cum / 1e6, label=s)
    for a, b in res.stretches:
        axs[0, 0].axvspan(a, b, color="0.92", lw=0)
    axs[0, 0].set_ylabel("speed [km/h]")
    axs[1, 0].set_ylabel("ratio $r_g$ [-]")
    axs[2, 0].set_ylabel("slip $\\nu$ [%]")
    axs[3, 0].set_ylabel("clamping $F_s$ [kN]")
    axs[4, 0].set_ylabel("cumulative losses [MJ]")
    axs[4, 0].set_xlabel("time [s] (grey: dynamic stretches)")
    axs[4, 0].legend(fontsize="small")
    return Plot(fig, axs, artists)
