"""Figures of the linear models: mode shapes and modal energy (Figs. 4, 5, 8) and Bode plots
(Fig. 6, and every other frequency response of the package)."""
from __future__ import annotations

from typing import Any, Sequence

import numpy as np

from ..linear.lumped import Modes
from ..lti import FrequencyResponse, unwrapped_phase_deg
from ._common import STYLES, Plot, new_axes, styled, symbol

__all__ = ["plot_mode_shapes", "plot_modal_energy", "plot_bode"]


def _mode_bars(ax, modes: Modes, idx: Sequence[int], values: np.ndarray,
               labels: Sequence[str]) -> list[Any]:
    width = 0.8 / max(len(idx), 1)
    x = np.arange(len(labels))
    bars = []
    for k, j in enumerate(idx):
        bars.append(ax.bar(x + (k - (len(idx) - 1) / 2) * width,
                           values[:, j] if values.shape[1] > j else 0, width,
                           label=f"mode {j + 1}: {modes.frequencies_hz[j]:.3g} Hz"))
    ax.set_xticks(x, labels)
    ax.axhline(0, color="k", lw=0.6)
    ax.grid(False, axis="x")
    ax.legend(loc="best")
    return bars


@styled
def plot_mode_shapes(modes: Modes, split: int | None = None, title: str = "",
                     ax: Any = None) -> Plot:
    """Normalised mode shapes as bars per coordinate (Fig. 4 / Fig. 8 left).

    Parameters
    ----------
    modes : Modes
        The modes (`empact.linear.lumped.Modes`, e.g. ``actuation_model(...).modes()``);
        their ``normalised_shapes`` are drawn.
    split : int, optional
        Modes with index >= `split` (default: none) go to a second panel (the
        high-frequency modes).
    title : str
        Figure title.
    ax : Axes or array of Axes, optional
        One Axes, or two (shape (1, 2)) with `split`; default a new figure.

    Returns
    -------
    Plot
        The figure, the axes (shape (1, 1), or (1, 2) with `split`) and the bars drawn.
    """
    n = modes.shapes.shape[1]
    groups = [list(range(n))] if split is None else [list(range(split)), list(range(split, n))]
    fig, ax = new_axes(ax, 1, len(groups), size=(4.8 * len(groups) + 1, 3.8))
    labels = [f"q{i + 1}\n{symbol(name)}" for i, name in enumerate(modes.coordinates)]
    artists = []
    for a, idx in zip(ax[0], groups):
        artists += _mode_bars(a, modes, idx, modes.normalised_shapes, labels)
        a.set_ylabel("normalised displacement [-]")
        a.set_xlabel("coordinate")
    if title:
        fig.suptitle(title)
    return Plot(fig, ax, artists)


@styled
def plot_modal_energy(modes: Modes, title: str = "", ax: Any = None) -> Plot:
    """Signed, normalised potential energy per spring and mode (Fig. 5 / Fig. 8 right).

    Each bar is ``sign(e) k e^2 / sum k e^2`` for the spring's elongation ``e`` in the mode:
    the magnitudes of a mode add up to 1, the sign says whether the spring is elongated (+) or
    shortened (-).

    Parameters
    ----------
    modes : Modes
        The modes (`empact.linear.lumped.Modes`); their ``energy_fraction`` is drawn for
        the elastic modes (non-zero natural frequency).
    title : str
        Axes title.
    ax : Axes, optional
        One Axes; default a new figure.

    Returns
    -------
    Plot
        The figure, the axes (shape (1, 1)) and the bars drawn.
    """
    fig, axs = new_axes(ax, size=(7, 3.8))
    a = axs[0, 0]
    idx = [j for j in range(len(modes.omega)) if modes.omega[j] > 0]
    labels = [f"{i + 1}\n{name.replace('_', ' ')}" for i, name in enumerate(modes.springs)]
    artists = _mode_bars(a, modes, idx, modes.energy_fraction.T, labels)
    a.set_ylabel("signed energy fraction [-]")
    a.set_xlabel("spring")
    a.set_ylim(-1.05, 1.05)
    if title:
        a.set_title(title)
    return Plot(fig, axs, artists)


@styled
def plot_bode(responses: Sequence[FrequencyResponse], pairs: Sequence[tuple[str, str]],
              title: str = "", phase: bool = True, units: str = "", ax: Any = None) -> Plot:
    """Bode plot (magnitude [dB], phase [deg] over frequency [Hz]) of several responses.

    Parameters
    ----------
    responses : sequence of FrequencyResponse
        The responses to overlay (one line style each, labelled by ``label``).
    pairs : sequence of (output, input)
        ``(output, input)`` signal names, one column of panels each.
    title : str
        Figure title.
    phase : bool
        Draw the phase row under the magnitude row.
    units : str
        Unit of the response for the magnitude label (e.g. ``"rad/(N m)"``; empty: none).
    ax : array of Axes, shape (2, len(pairs)), optional
        The magnitude row over the phase row, one column per pair (shape (1, len(pairs))
        without phase); default a new figure.

    Returns
    -------
    Plot
        The figure, the axes (shape (2, len(pairs)), or (1, len(pairs)) without phase) and the lines
        drawn.

    Notes
    -----
    The phase is unwrapped along frequency and starts in (-180, 180] deg at the lowest
    frequency (`empact.lti.unwrapped_phase_deg`).
    """
    rows = 2 if phase else 1
    fig, ax = new_axes(ax, rows, len(pairs), size=(4.4 * len(pairs) + 1, 2.7 * rows + 0.8),
                       sharex="col")
    artists = []
    for col, (out, inp) in enumerate(pairs):
        for k, resp in enumerate(responses):
            h = resp.response(out, inp)
            style = STYLES[k % len(STYLES)]
            artists += ax[0, col].semilogx(resp.frequencies_hz, 20 * np.log10(np.abs(h)),
                                           ls=style, label=resp.label)
            if phase:
                artists += ax[1, col].semilogx(resp.frequencies_hz, unwrapped_phase_deg(h),
                                               ls=style)
        ax[0, col].set_title(f"{symbol(inp)} $\\rightarrow$ {symbol(out)}")
        unit = f" re 1 {units}" if units else ""
        ax[0, col].set_ylabel(f"magnitude [dB{unit}]")
        ax[-1, col].set_xlabel("frequency [Hz]")
        if phase:
            ax[1, col].set_ylabel("phase [deg]")
    if any(r.label for r in responses):
        ax[0, 0].legend(loc="best")
    if title:
        fig.suptitle(title)
    return Plot(fig, ax, artists)
