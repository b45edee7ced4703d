"""Efficiency maps of the clamping strategies (`empact.efficiency.EfficiencyMap`)."""
from __future__ import annotations

from typing import Any

from ..efficiency import EfficiencyMap
from ._common import Plot, new_axes, styled

__all__ = ["plot_efficiency_map"]


@styled
def plot_efficiency_map(res: EfficiencyMap, quantity: str = "total_efficiency",
                        ax: Any = None) -> Plot:
    """Contours of an efficiency over input torque and ratio, one panel per strategy (at the
    first input speed); for a clamping sweep, the variator's and the total efficiency over the
    clamping force, one line per strategy.

    Parameters
    ----------
    res : EfficiencyMap
        The map (`empact.efficiency.efficiency_map`).
    quantity : {"total_efficiency", "efficiency"}
        What the contours show (a clamping sweep draws both).
    ax : Axes or array of Axes, optional
        One Axes per strategy (shape (1, n_strategies)) for a map, one Axes for a clamping
        sweep; default a new figure.

    Returns
    -------
    Plot
        The figure, its axes and the contour sets or lines drawn.
    """
    n = len(res.strategies)
    artists: list[Any] = []
    if "F_s" in res.axes:
        fig, axs = new_axes(ax, size=(7.0, 4.2))
        a = axs[0, 0]
        F = res.axes["F_s"] / 1e3
        for s in res.strategies:
            eff = res.grid("efficiency", s).ravel()
            tot = res.grid("total_efficiency", s).ravel()
            line, = a.plot(F, 100 * tot, label=f"{s}: total")
            artists.append(line)
            artists += a.plot(F, 100 * eff, "--", color=line.get_color(),
                              label=f"{s}: variator")
        a.set_xlabel("clamping force $F_s$ [kN]")
        a.set_ylabel("efficiency [%]")
        a.set_title(f"T_in = {res.axes['T_in'][0]:g} N m, omega_in = "
                    f"{res.axes['omega_in'][0]:g} rad/s, r_g = {res.axes['r_g'][0]:g}")
        a.legend(fontsize="small")
        return Plot(fig, axs, artists)
    fig, axs = new_axes(ax, 1, n, size=(3.6 * n + 1.0, 3.8), sharey=True)
    T, r = res.axes["T_in"], res.axes["r_g"]
    for k, s in enumerate(res.strategies):
        a = axs[0, k]
        Z = 100 * res.grid(quantity, s)[:, 0, :]  # (n_T, n_r) at the first speed
        if T.size >= 2 and r.size >= 2:
            cs = a.contourf(r, T, Z, levels=12, cmap="viridis")
            artists.append(cs)
            artists.append(a.contour(r, T, Z, levels=cs.levels, colors="k", linewidths=0.4))
            fig.colorbar(cs, ax=a, label=f"{quantity.replace('_', ' ')} [%]")
        else:  # one torque or one ratio: a line
            x, z = (r, Z[0]) if T.size == 1 else (T, Z[:, 0])
            artists += a.plot(x, z, "o-")
        a.set_title(s)
        a.set_xlabel("ratio $r_g$ [-]" if r.size >= 2 or T.size == 1 else "$T_{in}$ [N m]")
    axs[0, 0].set_ylabel("input torque $T_{in}$ [N m]" if T.size >= 2 and r.size >= 2
                         else "efficiency [%]")
    fig.suptitle(f"omega_in = {res.axes['omega_in'][0]:g} rad/s")
    return Plot(fig, axs, artists)
