"""Figures of the variator as a machine (the report's machine sheet), from result objects:
the traction curves with their 90 % and peak slips, and the static stability of the ratio
over torque ratio and ratio."""
from __future__ import annotations

from typing import Any

import matplotlib as mpl
import numpy as np

from ..variator.thrust_ratio import RatioStabilityMap
from ..variator.traction import TractionCurves
from ._common import Plot, new_axes, styled

__all__ = ["plot_traction_reserve", "plot_ratio_stability"]


@styled
def plot_traction_reserve(curves: TractionCurves, title: str = "", ax: Any = None) -> Plot:
    """Traction coefficient over slip, one line per ratio, with the slip at 90 % of each
    curve's peak (circle: the set-point of an 11 % torque reserve) and the peak (dot).

    Parameters
    ----------
    curves : TractionCurves
        The curves (`empact.variator.traction.traction_curves`): traction coefficient [-]
        over slip (drawn in %), one row per ratio; the slip grid's resolution is the
        markers'.
    title : str
        Axes title (default: "Traction curves: micro-slip slope and torque reserve").
    ax : Axes, optional
        One Axes; default a new figure.

    Returns
    -------
    Plot
        The figure, the axes (shape (1, 1)) and the lines and markers drawn.
    """
    fig, axs = new_axes(ax, size=(7.2, 4.4))
    ax = axs[0, 0]
    artists = []
    x = 100 * curves.nu
    for k, r in enumerate(curves.r_g):
        mu = curves.mu[k]
        j = int(np.argmax(mu))
        j90 = int(np.argmax(mu >= 0.9 * mu[j]))
        line, = ax.plot(x, mu, label=f"$r_g$ = {r:g}")
        artists.append(line)
        artists += ax.plot(x[j90], mu[j90], "o", mfc="none", color=line.get_color())
        artists += ax.plot(x[j], mu[j], ".", color=line.get_color(), ms=8)
    ax.plot([], [], "ko", mfc="none", label=r"90 % of the peak ($\tau$ = 0.9)")
    ax.plot([], [], "k.", ms=8, label="peak")
    ax.set_xlabel(r"slip $\nu$ [%]")
    ax.set_ylabel(r"traction coefficient $\mu$ [-]")
    ax.legend(loc="lower right")
    ax.set_title(title or "Traction curves: micro-slip slope and torque reserve")
    return Plot(fig, axs, artists)


@styled
def plot_ratio_stability(smap: RatioStabilityMap, title: str = "",
                         ax: Any = None) -> Plot:
    """``d ln kappa*/d r_g`` at fixed load torque over torque ratio and ratio (the ratio is
    statically unstable where it is negative: hatched), the marked points as crosses.

    Parameters
    ----------
    smap : RatioStabilityMap
        The map (`empact.variator.thrust_ratio.ratio_stability_map`): ``S`` [-] over torque
        ratio [-] and ratio [-], with its marked ``points`` ``(tau, r_g)``.
    title : str
        Axes title (default: one saying the hatched region is unstable).
    ax : Axes, optional
        One Axes; default a new figure.

    Returns
    -------
    Plot
        The figure, the axes (shape (1, 1)) and the mesh, hatching and markers drawn.
    """
    fig, axs = new_axes(ax, size=(7.2, 4.6))
    ax = axs[0, 0]
    lim = float(np.abs(smap.S).max()) or 1.0
    mesh = ax.pcolormesh(smap.tau, smap.r_g, smap.S, cmap=mpl.colormaps["RdBu"],
                         vmin=-lim, vmax=lim, shading="auto", rasterized=True)
    fig.colorbar(mesh, ax=ax, label=r"$d \ln \kappa^* / d r_g$ at fixed load torque [-]")
    artists: list[Any] = [mesh]
    if (smap.S < 0).any():
        h = ax.contourf(smap.tau, smap.r_g, (smap.S < 0).astype(float), levels=[0.5, 1.5],
                        colors="none", hatches=["//"])
        h.set_rasterized(True)
        artists.append(h)
    if smap.points:
        t, r = np.array(smap.points).T
        artists += ax.plot(t, r, "kx", ms=7, label="shipped set-points")
        ax.legend(loc="upper left")
    ax.grid(False)
    ax.set_xlabel(r"torque ratio $\tau = \mu / \mu_{max}$ [-]")
    ax.set_ylabel(r"ratio $r_g$ [-]")
    ax.set_title(title or "Static stability of the ratio with the servo torques held "
                 "(hatched: unstable)")
    return Plot(fig, axs, artists)
