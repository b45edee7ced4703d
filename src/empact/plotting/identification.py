"""Figures of identification results: FRF estimates with coherence, realised models (Figs. 2
and 14)."""
from __future__ import annotations

from typing import Any, Sequence

import numpy as np

from ..identification import FRFEstimate
from ..lti import FrequencyResponse, system_response, unwrapped_phase_deg
from ._common import Plot, new_axes, styled, symbol

__all__ = ["plot_frf_estimate", "plot_identified_plant"]


@styled
def plot_frf_estimate(est: FRFEstimate, pairs: Sequence[tuple[str, str]] | None = None,
                      models: Sequence[FrequencyResponse] = (), title: str = "",
                      fmin: float | None = None, min_coherence: float = 0.5,
                      ax: Any = None) -> Plot:
    """Magnitude [dB], phase [deg] and coherence of an FRF estimate, one column per pair.

    Parameters
    ----------
    est : FRFEstimate
        The estimate (`empact.identification.estimate_frf`, e.g. ``rig_frf(record)``).
    pairs : sequence of (output, input), optional
        ``(output, input)`` names (default: all)
    models : sequence of FrequencyResponse
        Model responses to overlay (dashed), with the same signal names; a model without a
        pair's signals is skipped in that column.
    title : str
        Figure title.
    fmin : float, optional
        Lowest frequency shown [Hz] (default: the first non-zero bin).
    min_coherence : float
        The estimate's phase is drawn only where the coherence [-] reaches this
        (elsewhere noise, unwrapped, runs off by many turns); the magnitude is drawn everywhere.
    ax : array of Axes, shape (3, len(pairs)), optional
        Rows magnitude, phase, coherence; default a new figure.

    Returns
    -------
    Plot
        The figure, the axes (shape (3, len(pairs))) and the lines drawn.
    """
    pairs = list(pairs or [(o, i) for i in est.inputs for o in est.outputs])
    fig, ax = new_axes(ax, 3, len(pairs), size=(4.4 * len(pairs) + 0.8, 7.2), sharex="col")
    f = est.frequencies_hz
    keep = (f >= (fmin if fmin is not None else f[1])) & np.all(np.isfinite(est.H), axis=(0, 1))
    artists = []
    for col, (out, inp) in enumerate(pairs):
        i, j = est.outputs.index(out), est.inputs.index(inp)
        h = est.H[i, j, keep]
        artists += ax[0, col].semilogx(f[keep], 20 * np.log10(np.abs(h)),
                                       label=f"estimate ({est.method})")
        good = est.coherence[i, j, keep] >= min_coherence
        if good.any():
            phase = np.full(h.shape, np.nan)
            phase[good] = unwrapped_phase_deg(h[good])
            artists += ax[1, col].semilogx(f[keep], phase)
        artists += ax[2, col].semilogx(f[keep], est.coherence[i, j, keep])
        for m in models:
            if out in m.outputs and inp in m.inputs:
                hm = m.response(out, inp)
                artists += ax[0, col].semilogx(m.frequencies_hz, 20 * np.log10(np.abs(hm)), "--",
                                               label=m.label or "model")
                artists += ax[1, col].semilogx(m.frequencies_hz, unwrapped_phase_deg(hm), "--")
        ax[0, col].set_title(f"{symbol(inp)} $\\rightarrow$ {symbol(out)}")
        ax[0, col].set_ylabel("magnitude [dB]")
        ax[1, col].set_ylabel(f"phase [deg] (estimate: coherence ≥ {min_coherence:g})"
                              if col == 0 else "phase [deg]")
        ax[2, col].set_ylabel("coherence [-]")
        ax[2, col].set_ylim(0, 1.05)
        ax[2, col].set_xlabel("frequency [Hz]")
    ax[0, 0].legend(loc="best")
    if title:
        fig.suptitle(title)
    return Plot(fig, ax, artists)


@styled
def plot_identified_plant(results, f_hz: np.ndarray, title: str = "", ax: Any = None) -> Plot:
    """Fig. 2: the magnitude of (T_mp, T_ms) -> (r_g, nu, nu_r) of identified (solid) and exact
    (dashed) models, one row per output.

    Parameters
    ----------
    results : sequence of PlantIdentification
        One `empact.experiments.plant_id.PlantIdentification` per ratio (one colour each);
        all with the inputs and outputs of the first.
    f_hz : array, shape (n_f,)
        Frequencies [Hz].
    title : str
        Figure title.
    ax : array of Axes, shape (n_outputs, 2), optional
        One row per output, one column per input; default a new figure.

    Returns
    -------
    Plot
        The figure, the axes (shape (n_outputs, 2)) and the lines drawn.
    """
    names_in = tuple(results[0].realization.inputs)
    names_out = tuple(results[0].realization.outputs)
    n_out = len(names_out)
    fig, ax = new_axes(ax, n_out, 2, size=(10, 2.6 * n_out + 1.3), sharex=True)
    w = 2 * np.pi * np.asarray(f_hz)
    artists = []
    for k, res in enumerate(results):
        color = f"C{k}"
        for sys, ls, kind in ((res.realization.sys, "-", "identified"), (res.exact, "--", "exact")):
            H = system_response(sys, w).H
            for i in range(n_out):
                for j in range(2):
                    artists += ax[i, j].loglog(
                        f_hz, np.abs(H[i, j]), ls=ls, color=color,
                        label=f"$r_g$ = {res.r_g:g}, {kind}"
                        + (f" (order {res.realization.order})" if kind == "identified" else ""))
    for i in range(n_out):
        for j in range(2):
            ax[i, j].set_title(f"{symbol(names_in[j])} $\\rightarrow$ {symbol(names_out[i])}")
            ax[i, j].grid(True, which="both")
        ax[i, 0].set_ylabel(f"$|${symbol(names_out[i])}$ / T|$ [1/(N m)]")
    for a in ax[-1]:
        a.set_xlabel("frequency [Hz]")
    ax[0, 0].legend(fontsize=6, loc="best")
    if title:
        fig.suptitle(title)
    return Plot(fig, ax, artists)
