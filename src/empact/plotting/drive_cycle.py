"""A quasi-static drive cycle (`empact.drive_cycle.CycleResult`): trace, ratio, clamping,
cumulative losses."""
from __future__ import annotations

from typing import Any

import numpy as np

from ..drive_cycle import TERMS, CycleResult
from ._common import Plot, new_axes, styled

__all__ = ["plot_drive_cycle"]


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
