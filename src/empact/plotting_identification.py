"""Figures of identification results: FRF estimates with coherence, realised models."""
from __future__ import annotations

from typing import Sequence

import numpy as np
from matplotlib.figure import Figure

from .identification import FRFEstimate
from .lumped import FrequencyResponse
from .plotting import new_figure

__all__ = ["plot_frf_estimate"]


def plot_frf_estimate(est: FRFEstimate, pairs: Sequence[tuple[str, str]] | None = None,
                      models: Sequence[FrequencyResponse] = (), title: str = "",
                      fmin: float | None = None) -> Figure:
    """Magnitude [dB], phase [deg] and coherence of an FRF estimate, one column per pair.

    Parameters
    ----------
    est : the estimate
    pairs : ``(output, input)`` names (default: all)
    models : model responses to overlay (dashed), with the same signal names
    title : figure title
    fmin : lowest frequency shown [Hz] (default: the first non-zero bin)
    """
    pairs = list(pairs or [(o, i) for i in est.inputs for o in est.outputs])
    fig, axes = new_figure(3, len(pairs), size=(4.2 * len(pairs) + 0.8, 7.0), sharex="col")
    f = est.frequencies_hz
    keep = f >= (fmin if fmin is not None else f[1])
    for col, (out, inp) in enumerate(pairs):
        i, j = est.outputs.index(out), est.inputs.index(inp)
        h = est.H[i, j, keep]
        axes[0, col].semilogx(f[keep], 20 * np.log10(np.abs(h)), label=f"estimate ({est.method})")
        axes[1, col].semilogx(f[keep], np.degrees(np.unwrap(np.angle(h))))
        axes[2, col].semilogx(f[keep], est.coherence[i, j, keep])
        for m in models:
            if out in m.outputs and inp in m.inputs:
                hm = m.response(out, inp)
                axes[0, col].semilogx(m.frequencies_hz, 20 * np.log10(np.abs(hm)), "--",
                                      label=m.label or "model")
                axes[1, col].semilogx(m.frequencies_hz, np.degrees(np.unwrap(np.angle(hm))),
                                      "--")
        axes[0, col].set_title(f"{inp} -> {out}", fontsize=9)
        axes[0, col].set_ylabel("magnitude [dB]")
        axes[1, col].set_ylabel("phase [deg]")
        axes[2, col].set_ylabel("coherence [-]")
        axes[2, col].set_ylim(0, 1.05)
        axes[2, col].set_xlabel("frequency [Hz]")
        for ax in axes[:, col]:
            ax.grid(True, which="both", lw=0.3)
    axes[0, 0].legend(fontsize=7)
    if title:
        fig.suptitle(title)
    return fig


def plot_identified_plant(results, f_hz: np.ndarray, title: str = "") -> Figure:
    """Fig. 2: |(T_mp, T_ms) -> (r_g, nu)| of identified (solid) and exact (dashed) models.

    Parameters
    ----------
    results : sequence of `empact.identification.plant_id.PlantIdentification`
    f_hz : frequencies [Hz]
    """
    import control

    fig, axes = new_figure(2, 2, size=(10, 6.5), sharex=True)
    w = 2 * np.pi * np.asarray(f_hz)
    for k, res in enumerate(results):
        color = f"C{k}"
        for sys, ls, kind in ((res.realization.sys, "-", "identified"), (res.exact, "--", "exact")):
            H = control.frequency_response(sys, w).complex
            for i in range(2):
                for j in range(2):
                    axes[i, j].loglog(f_hz, np.abs(H[i, j]), ls=ls, color=color,
                                      label=f"r_g = {res.r_g:g}, {kind}"
                                      + (f" (order {res.realization.order})"
                                         if kind == "identified" else ""))
    names_in, names_out = ("T_mp", "T_ms"), ("r_g", "nu")
    for i in range(2):
        for j in range(2):
            axes[i, j].set_title(f"{names_in[j]} -> {names_out[i]}", fontsize=9)
            axes[i, j].grid(True, which="both", lw=0.3)
    axes[0, 0].set_ylabel("|r_g / T| [1/(N m)]")
    axes[1, 0].set_ylabel("|nu / T| [1/(N m)]")
    for ax in axes[-1]:
        ax.set_xlabel("frequency [Hz]")
    axes[0, 0].legend(fontsize=6)
    if title:
        fig.suptitle(title)
    return fig
