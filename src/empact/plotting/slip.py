"""Figures of the slip dynamics (paper Figs. 9-13 and the stability map), from result objects.

Every function takes the result object computed by `empact.slip` or `empact.traction`, draws
on the given axes or a new figure (no pyplot state) and returns a `Plot`.  Pole and zero
locations are drawn in rad/s (as computed); slip in percent, clamping force in kN and frequency
in Hz for display only.
"""
from __future__ import annotations

from typing import Any, Sequence

import matplotlib as mpl
import numpy as np
from numpy.typing import NDArray

from ..lti import FrequencyResponse
from ..slip import BeltRootLocus, PoleSweep, StabilityMap, ZeroLocus
from ..variator.traction import TractionCurves
from ._common import Plot, new_axes, styled
from .linear import plot_bode

__all__ = ["plot_belt_root_locus", "plot_traction", "plot_pole_sweep", "plot_slip_bode",
           "plot_zero_locus", "plot_stability_map", "DISPLAY"]

#: Display scale and label of each operating-point variable (SI value * scale).
DISPLAY = {"nu": (100.0, r"slip $\nu$ [%]"),
           "F_s": (1e-3, r"clamping force $F_\mathrm{s}$ [kN]"),
           "omega_p": (1.0, r"primary speed $\omega_\mathrm{p}$ [rad/s]"),
           "r_g": (1.0, r"ratio $r_\mathrm{g}$ [-]")}


def _value(name: str, value: float) -> str:
    """``symbol = value unit`` of an operating-point variable in display units."""
    scale, label = DISPLAY[name]
    sym = label[label.index("$"):label.rindex("$") + 1]
    unit = label[label.rindex("[") + 1:-1]
    return f"{sym} = {scale * value:g}" + ("" if unit == "-" else f" {unit}")


def _hz_circles(ax, freqs_hz: Sequence[float] | NDArray[np.float64], style: str,
                label: str) -> None:
    """Quarter circles |s| = 2 pi f in the second quadrant, to read natural frequencies."""
    th = np.linspace(np.pi / 2, np.pi, 60)
    for k, f in enumerate(freqs_hz):
        w = 2 * np.pi * f
        ax.plot(w * np.cos(th), w * np.sin(th), style, lw=0.7, color="0.5",
                label=label if k == 0 else None)


@styled
def plot_belt_root_locus(rl: BeltRootLocus, title: str = "", ax: Any = None) -> Plot:
    """Root locus over ``c_b`` from 0 (x) to infinity (o), upper half plane (Fig. 9).

    The branch that leaves for ``-inf`` is cut at the left edge of the axes.

    Parameters
    ----------
    rl : BeltRootLocus
        The root locus (`empact.slip.belt_root_locus`); its poles [rad/s] are drawn, the
        natural frequencies of its end points [Hz] as quarter circles.
    title : str
        Axes title (default: one naming the ratio).
    ax : Axes, optional
        One Axes; default a new figure.

    Returns
    -------
    Plot
        The figure, the axes (shape (1, 1)) and the lines drawn.
    """
    fig, axs = new_axes(ax, size=(7.0, 4.8))
    ax = axs[0, 0]
    P = rl.locus.poles
    artists = []
    w_max = max(np.abs(rl.start).max(), np.abs(rl.stop).max())
    for j in range(P.shape[1]):
        br = P[:, j]
        if np.all(br.imag < -1e-9):
            continue
        artists += ax.plot(br.real, np.abs(br.imag), lw=1.3)
    artists += ax.plot(rl.start.real, np.abs(rl.start.imag), "kx", ms=8,
                       label=r"$c_b = 0$ (uncoupled)")
    artists += ax.plot(rl.stop.real, np.abs(rl.stop.imag), "ko", mfc="none", ms=8,
                       label=r"$c_b \rightarrow \infty$ (coupled)")
    _hz_circles(ax, rl.uncoupled_hz, ":", "uncoupled |s| = " + ", ".join(
        f"{f:.1f}" for f in rl.uncoupled_hz) + " Hz")
    _hz_circles(ax, rl.coupled_hz, "--", "coupled |s| = " + ", ".join(
        f"{f:.2f}" for f in rl.coupled_hz) + " Hz")
    ax.set_xlim(-1.3 * w_max, 0.1 * w_max)
    ax.set_ylim(-0.05 * w_max, 1.15 * w_max)
    ax.set_aspect("equal")
    ax.axvline(0, color="k", lw=0.6)
    ax.axhline(0, color="k", lw=0.6)
    ax.set_xlabel("real part [rad/s]")
    ax.set_ylabel("imaginary part [rad/s]")
    ax.legend(loc="upper left")
    ax.set_title(title or f"Root locus over $c_b$, $r_g$ = {rl.r_g:g} (one real pole "
                          r"$\rightarrow -\infty$)")
    return Plot(fig, axs, artists)


@styled
def plot_traction(curves: TractionCurves, names: Sequence[str] | None = None,
                  title: str = "", ax: Any = None) -> Plot:
    """Traction coefficient and its slope over slip, one line per ratio (Fig. 10).

    Parameters
    ----------
    curves : TractionCurves
        The curves (`empact.variator.traction.traction_curves`): traction coefficient [-]
        and its slope [-] over slip (drawn in %), one row per ratio.
    names : sequence of str, optional
        A name per ratio for the legend (e.g. ``("LOW", "MED", "OD")``), before its value.
    title : str
        Figure title (default: one naming the curves' ``label``).
    ax : array of Axes, shape (1, 2), optional
        Coefficient (left) and slope (right); default a new figure.

    Returns
    -------
    Plot
        The figure, the axes (shape (1, 2)) and the lines drawn.
    """
    fig, axs = new_axes(ax, 1, 2, size=(10.0, 3.8))
    x = 100 * curves.nu
    artists = []
    for k, r in enumerate(curves.r_g):
        label = f"{names[k]} " if names is not None else ""
        label += f"$r_g$ = {r:g}"
        artists += axs[0, 0].plot(x, curves.mu[k], label=label)
        artists += axs[0, 1].plot(x, curves.dmu[k], label=label)
    nu_pk, mu_pk = curves.peak()
    axs[0, 0].plot(100 * nu_pk, mu_pk, "k.", label="maximum")
    axs[0, 0].set_ylabel(r"traction coefficient $\mu$ [-]")
    axs[0, 1].set_yscale("symlog", linthresh=0.01)
    axs[0, 1].axhline(0, color="k", lw=0.6)
    axs[0, 1].set_ylabel(r"slope $\mu' = d\mu / d\nu$ [-]")
    for ax in axs[0]:
        ax.set_xlabel(r"slip $\nu$ [%]")
    axs[0, 0].legend(loc="lower right")
    fig.suptitle(title or f"Traction curves {curves.label}".strip())
    return Plot(fig, axs, artists)


@styled
def plot_pole_sweep(sweep: PoleSweep, title: str = "", uncoupled_hz: Sequence[float] = (),
                    coupled_hz: Sequence[float] = (), ax: Any = None) -> Plot:
    """Poles over the swept variable (Fig. 11): markers coloured by value, arrows along it.

    Only the upper half plane near the oscillatory poles is shown; optional quarter circles
    mark the uncoupled and coupled natural frequencies [Hz].

    Parameters
    ----------
    sweep : PoleSweep
        The sweep (`empact.slip.pole_sweep`); poles [rad/s], coloured by the swept value in
        display units (`DISPLAY`: slip in %, clamping force in kN).
    title : str
        Axes title (default: one naming the swept variable and the fixed ones).
    uncoupled_hz : sequence of float
        Uncoupled natural frequencies [Hz] to mark (e.g. ``BeltRootLocus.uncoupled_hz``).
    coupled_hz : sequence of float
        Coupled natural frequencies [Hz] to mark (e.g. ``BeltRootLocus.coupled_hz``).
    ax : Axes, optional
        One Axes; default a new figure.

    Returns
    -------
    Plot
        The figure, the axes (shape (1, 1)) and the lines and markers drawn.
    """
    fig, axs = new_axes(ax, size=(7.0, 4.8))
    ax = axs[0, 0]
    scale, label = DISPLAY[sweep.name]
    P = sweep.poles
    artists = []
    osc = P[P.imag > 1e-6]
    w_max = float(np.abs(osc).max()) if osc.size else float(np.abs(P).max())
    for j in range(P.shape[1]):
        br = P[:, j]
        if np.all(br.imag < -1e-6):
            continue
        artists += ax.plot(br.real, np.abs(br.imag), "-", color="0.7", lw=0.8, zorder=1)
        for k in range(len(br) - 1):
            a, b = br[k], br[k + 1]
            if abs(b - a) > 1e-3 * w_max:
                ax.annotate("", xy=(b.real, abs(b.imag)), xytext=(a.real, abs(a.imag)),
                            arrowprops=dict(arrowstyle="->", color="0.4", lw=0.8))
    sc = None
    for j in range(P.shape[1]):
        br = P[:, j]
        if np.all(br.imag < -1e-6):
            continue
        sc = ax.scatter(br.real, np.abs(br.imag), c=scale * sweep.values, cmap="viridis",
                        s=28, zorder=3)
        artists.append(sc)
    if sc is not None:
        fig.colorbar(sc, ax=ax, label=label)
    if len(uncoupled_hz):
        _hz_circles(ax, uncoupled_hz, ":", "uncoupled " + ", ".join(
            f"{f:.1f}" for f in uncoupled_hz) + " Hz")
    if len(coupled_hz):
        _hz_circles(ax, coupled_hz, "--", "coupled " + ", ".join(
            f"{f:.2f}" for f in coupled_hz) + " Hz")
    re_osc = osc.real if osc.size else P.real
    left = min(float(re_osc.min()), -0.05 * w_max)
    right = max(float(re_osc.max()), 0.0)
    pad = 0.1 * (right - left)
    ax.set_xlim(left - pad, right + pad)
    ax.set_ylim(0, 1.15 * w_max)
    ax.axvline(0, color="k", lw=0.8)
    ax.axvspan(0, right + pad, color="r", alpha=0.06, lw=0)
    ax.set_xlabel("real part [rad/s]")
    ax.set_ylabel("imaginary part [rad/s]")
    if len(uncoupled_hz) or len(coupled_hz):
        ax.legend(loc="upper left")
    b = sweep.base
    ax.set_title(title or f"Poles over {DISPLAY[sweep.name][1].split(' [')[0]} at "
                          + ", ".join(_value(k, v) for k, v in b.to_dict().items()
                                      if k != sweep.name))
    return Plot(fig, axs, artists)


def plot_slip_bode(responses: Sequence[FrequencyResponse], title: str = "",
                   ax: Any = None) -> Plot:
    """Bode plot of ``F_s -> nu`` responses (Fig. 12), one line per operating point.

    Parameters
    ----------
    responses : sequence of FrequencyResponse
        ``F_s -> nu`` responses (`empact.slip.slip_frequency_responses`) [1/N], one line each;
        the pair drawn is the first response's first output and input.
    title : str
        Figure title.
    ax : array of Axes, shape (2, 1), optional
        Magnitude and phase; default a new figure.

    Returns
    -------
    Plot
        The figure, the axes (shape (2, 1)) and the lines drawn (`plot_bode`).
    """
    return plot_bode(responses, [(responses[0].outputs[0], responses[0].inputs[0])], title=title,
                     units="1/N", ax=ax)


@styled
def plot_zero_locus(zl: ZeroLocus, title: str = "",
                    reference_hz: dict[float, Sequence[float]] | None = None,
                    ax: Any = None) -> Plot:
    """Zeros of ``F_s -> nu`` over the ratio (Fig. 13).

    Left: the zeros in the complex plane (upper half), coloured by ``r_g``, arrows for
    increasing ``r_g``.  Right: their magnitudes [Hz] over ``r_g`` with the coupled-limit poles
    (dashed) and optional reference points ``{r_g: [Hz, ...]}`` (e.g. Table 2).

    Parameters
    ----------
    zl : ZeroLocus
        The zero locus (`empact.slip.zero_locus`): zeros [rad/s] and the coupled-limit poles
        over the ratio.
    title : str
        Figure title (default: "Zeros of the slip model over the ratio").
    reference_hz : dict of float to sequence of float, optional
        Reference frequencies [Hz] by ratio [-], drawn as open squares on the right.
    ax : array of Axes, shape (1, 2), optional
        Complex plane (left) and magnitudes (right); default a new figure.

    Returns
    -------
    Plot
        The figure, the axes (shape (1, 2)) and the lines and markers drawn.
    """
    fig, axs = new_axes(ax, 1, 2, size=(10.5, 4.2))
    ax, ax2 = axs[0]
    Z = zl.zeros
    artists = []
    sc = None
    for j in range(Z.shape[1]):
        br = Z[:, j]
        if np.all(~np.isfinite(br)) or np.nanmax(br.imag) <= 0:
            continue
        artists += ax.plot(br.real, br.imag, "-", color="0.7", lw=0.8)
        sc = ax.scatter(br.real, br.imag, c=zl.r_g, cmap="plasma", s=18, zorder=3)
        artists.append(sc)
        k = len(br) // 2
        if k + 1 < len(br):
            ax.annotate("", xy=(br[k + 1].real, br[k + 1].imag), xytext=(br[k].real, br[k].imag),
                        arrowprops=dict(arrowstyle="->", lw=1.2))
    if sc is not None:
        fig.colorbar(sc, ax=ax, label=r"ratio $r_g$ [-]")
    lim = 1.1 * np.nanmax(np.abs(Z)) if np.isfinite(Z).any() else 1.0
    ax.set_xlim(-0.25 * lim, 0.25 * lim)
    ax.set_ylim(0, lim)
    ax.axvline(0, color="k", lw=0.6)
    ax.set_xlabel("real part [rad/s]")
    ax.set_ylabel("imaginary part [rad/s]")
    ax.set_title(r"zeros of $F_s \rightarrow \nu$ (upper half plane)")
    artists += ax2.plot(zl.r_g, zl.zero_hz, "o-", ms=3, label=r"zeros $|z| / 2\pi$")
    coupled = np.sort(np.abs(zl.coupled), axis=1)[:, ::2] / (2 * np.pi)
    artists += ax2.plot(zl.r_g, coupled, "k--", lw=0.9,
                        label=r"coupled limit $c_b \rightarrow \infty$")
    if reference_hz:
        for k, (r, fs) in enumerate(sorted(reference_hz.items())):
            ax2.plot([r] * len(fs), fs, "rs", mfc="none", label="paper Table 2" if k == 0 else None)
    ax2.set_xlabel(r"ratio $r_g$ [-]")
    ax2.set_ylabel("frequency [Hz]")
    ax2.set_yscale("log")
    ax2.grid(True, which="both")
    handles, labels = ax2.get_legend_handles_labels()
    seen: dict[str, Any] = {}
    for h, lab in zip(handles, labels):
        seen.setdefault(lab, h)
    ax2.legend(seen.values(), seen.keys(), loc="best")
    fig.suptitle(title or "Zeros of the slip model over the ratio")
    return Plot(fig, axs, artists)


@styled
def plot_stability_map(sm: StabilityMap, title: str = "", ax: Any = None) -> Plot:
    """Smallest damping ratio over the stable part of the grid; unstable region red, hatched.

    The outline is the contour ``max_real = tol`` (the stability boundary).

    Parameters
    ----------
    sm : StabilityMap
        The map (`empact.slip.stability_map`); its axes drawn in display units
        (`DISPLAY`: slip in %, clamping force in kN).
    title : str
        Axes title (default: one naming the fixed variables).
    ax : Axes, optional
        One Axes; default a new figure.

    Returns
    -------
    Plot
        The figure, the axes (shape (1, 1)) and the mesh, hatching and contour drawn.
    """
    fig, axs = new_axes(ax, size=(7.2, 4.8))
    ax = axs[0, 0]
    sx, lx = DISPLAY[sm.x_name]
    sy, ly = DISPLAY[sm.y_name]
    X, Y = sx * sm.x, sy * sm.y
    stable_zeta = np.ma.masked_where(sm.unstable, sm.min_damping)
    cmap = mpl.colormaps["viridis"].with_extremes(bad=(0.95, 0.75, 0.75))
    top = float(stable_zeta.max()) if stable_zeta.count() else 1.0
    mesh = ax.pcolormesh(X, Y, stable_zeta, cmap=cmap, vmin=0.0, vmax=max(top, 1e-6),
                         shading="auto", rasterized=True)
    artists = [mesh]
    fig.colorbar(mesh, ax=ax, label="smallest damping ratio of the stable points [-]")
    unstable = sm.unstable.astype(float)
    if unstable.any():
        hatch = ax.contourf(X, Y, unstable, levels=[0.5, 1.5], colors="none", hatches=["//"])
        hatch.set_rasterized(True)
        artists.append(hatch)
    if 0 < unstable.mean() < 1:
        artists.append(ax.contour(X, Y, sm.max_real, levels=[sm.tol], colors="k",
                                  linewidths=1.2))
    ax.grid(False)
    ax.set_xlabel(lx)
    ax.set_ylabel(ly)
    fixed = ", ".join(_value(k, v) for k, v in sm.base.to_dict().items()
                      if k not in (sm.x_name, sm.y_name))
    ax.set_title(title or f"Stability map (red, hatched: unstable) at {fixed}")
    return Plot(fig, axs, artists)
