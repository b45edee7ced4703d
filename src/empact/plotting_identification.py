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
