"""Figures of the control results: the family's poles and zeros, loop shapes, robustness
maps and closed-loop runs (drawn from `empact.control` result objects)."""
from __future__ import annotations

from typing import Any, Mapping, Sequence

import matplotlib
import numpy as np

from ..control.closed_loop import ClosedLoopResult
from ..control.family import PlantFamily
from ..control.loop import LoopModel, LoopPrediction
from ..control.shifting import ShiftEnvelope
from ..lti import channel_zeros
from ._common import STYLES, Plot, new_axes, styled, symbol

__all__ = ["plot_family_poles", "plot_loop_shapes", "plot_robustness_maps",
           "plot_closed_loop", "plot_shift_envelope"]


@styled
def plot_family_poles(family: PlantFamily, f_max_hz: float = 60.0, title: str = "",
                      ax: Any = None) -> Plot:
    """Poles (left) and the zeros of T_mp -> r_g and T_ms -> nu (right) of every plant of a
    family below `f_max_hz` [Hz], coloured by ratio (complex plane in Hz).

    Parameters
    ----------
    family : PlantFamily
        The family (`empact.plant_family`, `empact.control.family.design_family`); points
        that did not trim are skipped.
    f_max_hz : float
        Poles and zeros of magnitude above this [Hz] are left out.
    title : str
        Figure title.
    ax : array of Axes, shape (1, 2), optional
        Poles (left) and zeros (right); default a new figure.

    Returns
    -------
    Plot
        The figure, the axes (shape (1, 2)) and the markers drawn.
    """
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
        sys = family.plant(k).system
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
def plot_loop_shapes(loops: Mapping[str, LoopModel], f_hz: np.ndarray | None = None,
                     title: str = "", ax: Any = None) -> Plot:
    """Diagonal loop gains ``|L_ii| = |(K G)_ii|`` of the sampled loops at the servo torques
    (`empact.control.loop.LoopModel`, one thin line per plant of the family) for each
    controller (one column per loop, one colour per controller).

    Parameters
    ----------
    loops : dict of str to LoopModel
        The loop models by controller name (`empact.control.loop.family_loops`), all
        sampled at the first one's rate.
    f_hz : array, shape (n_f,), optional
        Frequencies [Hz] (default: 150 from 0.01 Hz to 100 Hz or just below the Nyquist
        frequency, whichever is lower).
    title : str
        Figure title.
    ax : array of Axes, shape (1, 2), optional
        Ratio loop (left) and slip loop (right); default a new figure.

    Returns
    -------
    Plot
        The figure, the axes (shape (1, 2)) and the lines drawn.
    """
    first = next(iter(loops.values()))
    nyq = 0.49 / first.dt
    f = np.logspace(-2, np.log10(min(100.0, nyq)), 150) if f_hz is None else np.asarray(f_hz)
    w = 2 * np.pi * f
    fig, axs = new_axes(ax, 1, 2, size=(11, 4.0), sharex=True)
    artists = []
    for c, (name, lm) in enumerate(loops.items()):
        G = lm.plant_response(w).reshape((-1, len(w), 2, 2))
        K = lm.controller_response(w) * lm.mask[None, :, None]
        L = K @ G
        for j in range(2):
            for k in range(L.shape[0]):
                artists += axs[0, j].loglog(f, np.abs(L[k, :, j, j]), color=f"C{c}", lw=0.6,
                                            alpha=0.5, label=name if k == 0 else None)
    for j, loop in enumerate(("ratio loop (T_mp)", "slip loop (T_ms)")):
        ax = axs[0, j]
        ax.axhline(1, color="k", lw=0.6)
        ax.set_title(f"|L| of the {loop} at the servo torques, every plant", fontsize=8)
        ax.set_xlabel("frequency [Hz]")
        ax.grid(True, which="both")
        ax.legend(loc="best")
    axs[0, 0].set_ylabel("loop gain [-]")
    if title:
        fig.suptitle(title)
    return Plot(fig, axs, artists)


@styled
def plot_robustness_maps(family: PlantFamily, loops: Mapping[str, LoopModel],
                         title: str = "", ax: Any = None) -> Plot:
    """Multiloop disk margin of each loop model over the family: one row per controller,
    one panel per value of a third axis (the clamping force), ratio x torque ratio in each
    (0: unstable).

    Parameters
    ----------
    family : PlantFamily
        The family the loops were built on, with two or three axes (the first two the
        rows and columns of each panel, the third one panel per value).
    loops : dict of str to LoopModel
        The loop models by controller name (`empact.control.loop.family_loops`).
    title : str
        Figure title.
    ax : array of Axes, shape (len(loops), n3), optional
        ``n3`` the number of values of the third axis (1 with two axes); default a new
        figure.

    Returns
    -------
    Plot
        The figure, the axes (shape (len(loops), n3)) and the meshes drawn.

    Raises
    ------
    ValueError
        When the family has neither two nor three axes.
    """
    names = list(family.axes)
    if len(names) not in (2, 3):
        raise ValueError("robustness maps need a family with two or three axes")
    n3 = len(family.axes[names[2]]) if len(names) == 3 else 1
    fig, axs = new_axes(ax, len(loops), n3, size=(4.2 * n3, 3.6 * len(loops)))
    artists = []
    x, y = family.axes[names[0]], family.axes[names[1]]
    for row, (name, lm) in enumerate(loops.items()):
        dm = lm.disk_margins()["alpha"]
        dm = dm[..., None] if dm.ndim == 2 else dm
        for k in range(n3):
            ax = axs[row, k]
            m = dm[..., k]
            im = ax.pcolormesh(np.arange(len(y) + 1), np.arange(len(x) + 1), m, vmin=0,
                               vmax=max(1.0, float(dm.max())), cmap="viridis")
            artists.append(im)
            for i in range(len(x)):
                for j in range(len(y)):
                    ax.text(j + 0.5, i + 0.5, f"{m[i, j]:.2f}", ha="center", va="center",
                            fontsize=6, color="w")
            ax.set_xticks(np.arange(len(y)) + 0.5, [f"{v:.3g}" for v in y])
            ax.set_yticks(np.arange(len(x)) + 0.5, [f"{v:.3g}" for v in x])
            ax.set_xlabel(symbol(names[1]))
            ax.set_ylabel(symbol(names[0]))
            third = ""
            if len(names) == 3:
                v3 = family.axes[names[2]][k]
                shown = f"{v3 / 1e3:.3g} kN" if names[2] == "F_s" else f"{v3:.3g}"
                third = f", {symbol(names[2])} = {shown}"
            ax.set_title(f"{name}: disk margin{third}", fontsize=8)
        fig.colorbar(im, ax=list(axs[row]))
    if title:
        fig.suptitle(title)
    return Plot(fig, axs, artists)


@styled
def plot_closed_loop(runs: Sequence[ClosedLoopResult], title: str = "",
                     predictions: Mapping[str, LoopPrediction] | None = None,
                     ax: Any = None) -> Plot:
    """Slip, ratio, clamping force and servo torques over time for closed-loop runs (one
    colour per run, references dash-dot, the linear loop model's prediction dotted where
    given, by scenario name; the secondary servo's torque limit as thin grey lines).

    Parameters
    ----------
    runs : sequence of ClosedLoopResult
        The runs (`empact.run_closed_loop`), one colour each; slip drawn in %, clamping
        force in kN, servo torques in N m.
    title : str
        Figure title.
    predictions : dict of str to LoopPrediction, optional
        The linear loop model's predictions (`empact.control.loop.predict_scenario`) by
        scenario name, drawn over the run of that name.
    ax : array of Axes, shape (4, 1), optional
        Slip, ratio, clamping force, servo torques; default a new figure.

    Returns
    -------
    Plot
        The figure, the axes (shape (4, 1)) and the lines drawn.
    """
    fig, axs = new_axes(ax, 4, 1, size=(11, 9.5), sharex=True)
    artists = []
    predictions = predictions or {}
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
        artists += axs[3, 0].plot(res.t, res.output("T_ms_act"), color=f"C{c}")
        artists += axs[3, 0].plot(res.t, res.output("T_mp_act"), color=f"C{c}", lw=0.8,
                                  ls=STYLES[2])
        pred = predictions.get(run.scenario.name)
        if pred is not None:
            axs[0, 0].plot(pred.t, 100 * pred.output("nu"), color=f"C{c}", ls=":", lw=1.2)
            axs[1, 0].plot(pred.t, pred.output("r_g"), color=f"C{c}", ls=":", lw=1.2)
            axs[2, 0].plot(pred.t, pred.output("F_s") / 1e3, color=f"C{c}", ls=":", lw=1.2)
        lim = run.law.config.limits if run.law is not None else None
        if lim is not None and c == 0:
            for v in (lim.T_ms_max, -lim.T_ms_max):
                axs[3, 0].axhline(v, color="0.6", lw=0.6)
    axs[0, 0].set_ylabel("slip ν [%]")
    axs[1, 0].set_ylabel("ratio $r_g$ [-]")
    axs[2, 0].set_ylabel("$F_s$ [kN]")
    axs[3, 0].set_ylabel("servo torque [N m]\n(T_ms solid, T_mp dash-dot)")
    axs[3, 0].set_xlabel("time [s]")
    axs[0, 0].legend(fontsize=7, loc="best",
                     title="dash-dot: reference; dotted: linear prediction" if predictions
                     else None, title_fontsize=7)
    if title:
        fig.suptitle(title)
    return Plot(fig, axs, artists)


@styled
def plot_shift_envelope(envelope: ShiftEnvelope, runs: Sequence[ClosedLoopResult] = (),
                        title: str = "", ax: Any = None) -> Plot:
    """The shift-rate envelope over the ratio (`empact.control.shifting`), coloured by the
    limit that binds, with the ratio rate the runs reached (the magnitude of dr_g/dt against r_g).

    Parameters
    ----------
    envelope : ShiftEnvelope
        The envelope (`empact.control.shifting.shift_envelope`): largest ratio rate [1/s]
        over the ratio [-] and the limit that binds.
    runs : sequence of ClosedLoopResult
        Runs whose ratio rate [1/s] (the gradient of the ratio over time) is drawn against
        their ratio.
    title : str
        Figure title.
    ax : Axes, optional
        One Axes; default a new figure.

    Returns
    -------
    Plot
        The figure, the axes (shape (1, 1)) and the lines and markers drawn.
    """
    fig, axs = new_axes(ax, 1, 1, size=(8, 4.2))
    a = axs[0, 0]
    artists = []
    for c, kind in enumerate(sorted(set(envelope.binding))):
        sel = envelope.binding == kind
        artists += a.plot(envelope.r_g[sel], envelope.rate[sel], "o", color=f"C{c + 3}",
                          label=f"envelope: {kind} limit binds")
    artists += a.plot(envelope.r_g, envelope.rate, color="0.4", lw=0.8)
    for c, run in enumerate(runs):
        res = run.result
        r, t = res.output("r_g"), res.t
        rate = np.gradient(r, t)
        artists += a.plot(r, rate, color=f"C{c}", lw=1.0, label=f"{run.scenario.name}: reached")
    a.axhline(1.0, color="k", lw=0.6, ls=STYLES[1], label="goal 1 /s")
    a.set_xscale("log")
    a.set_xlabel("ratio $r_g$ [-]")
    a.set_ylabel("ratio rate [1/s]")
    a.set_title(f"upshift rate the servo limits allow at {envelope.omega_p:g} rad/s, "
                f"{envelope.T_l:g} N m, tau = {envelope.tau:g}", fontsize=8)
    a.grid(True, which="both")
    a.legend(fontsize=7, loc="best")
    if title:
        fig.suptitle(title)
    return Plot(fig, axs, artists)
