"""Figures drawn from result objects (the only module of the core that imports matplotlib).

Every function takes result objects, draws on new or given axes, and returns the figure;
`save_figure` writes PNG and SVG atomically.
"""
from __future__ import annotations

import os
import tempfile
from pathlib import Path
from typing import Sequence

import numpy as np
from matplotlib.figure import Figure  # figures are built without pyplot: no global state

from .lumped import FrequencyResponse, Modes

__all__ = ["plot_mode_shapes", "plot_modal_energy", "plot_bode", "save_figure", "save_single",
           "new_figure"]

STYLES = ("-", "-.", "--", ":", (0, (5, 1, 1, 1)))


def new_figure(nrows: int = 1, ncols: int = 1, size: tuple[float, float] = (7.0, 4.0), **kw):
    """A new figure and axes (no pyplot state kept)."""
    fig = Figure(figsize=size, layout="constrained")
    axes = fig.subplots(nrows, ncols, squeeze=False, **kw)
    return fig, axes


def save_figure(fig: Figure, stem: str | os.PathLike[str], formats: Sequence[str] = ("png", "svg"),
                dpi: int = 150) -> list[Path]:
    """Save `fig` as ``stem.png`` and ``stem.svg`` (each written to a temporary file first)."""
    stem = Path(stem)
    paths = []
    for fmt in formats:
        path = stem.with_suffix(f".{fmt}")
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=f".{fmt}")
        os.close(fd)
        try:
            fig.savefig(tmp, format=fmt, dpi=dpi)
            os.replace(tmp, path)
        except BaseException:
            Path(tmp).unlink(missing_ok=True)
            raise
        paths.append(path)
    return paths


def save_single(fig: Figure, path: str | os.PathLike[str], dpi: int = 150) -> Path:
    """Save `fig` to one file whose format follows its suffix (atomic)."""
    path = Path(path)
    fmt = path.suffix.lstrip(".") or "png"
    return save_figure(fig, path.with_suffix(""), formats=(fmt,), dpi=dpi)[0]


def _mode_bars(ax, modes: Modes, idx: Sequence[int], values: np.ndarray, labels: Sequence[str]):
    width = 0.8 / max(len(idx), 1)
    x = np.arange(len(labels))
    for k, j in enumerate(idx):
        ax.bar(x + (k - (len(idx) - 1) / 2) * width, values[:, j] if values.shape[1] > j else 0,
               width, label=f"mode {j + 1}: {modes.frequencies_hz[j]:.3g} Hz")
    ax.set_xticks(x, labels)
    ax.axhline(0, color="k", lw=0.6)
    ax.legend(fontsize=7)


def plot_mode_shapes(modes: Modes, split: int | None = None, title: str = "") -> Figure:
    """Normalised mode shapes as bars per coordinate (Fig. 4 / Fig. 8 left).

    Modes with index >= `split` (default: none) are drawn in a second panel, for the
    high-frequency modes.
    """
    n = modes.shapes.shape[1]
    groups = [list(range(n))] if split is None else [list(range(split)), list(range(split, n))]
    fig, axes = new_figure(1, len(groups), size=(4.5 * len(groups) + 1, 3.6))
    labels = [f"q{i + 1}\n{name}" for i, name in enumerate(modes.coordinates)]
    for ax, idx in zip(axes[0], groups):
        _mode_bars(ax, modes, idx, modes.normalised_shapes, labels)
        ax.set_ylabel("normalised displacement [-]")
        ax.tick_params(axis="x", labelsize=7)
    if title:
        fig.suptitle(title)
    return fig


def plot_modal_energy(modes: Modes, title: str = "") -> Figure:
    """Signed, normalised potential energy per spring and mode (Fig. 5 / Fig. 8 right)."""
    fig, axes = new_figure(size=(7, 3.6))
    ax = axes[0, 0]
    idx = [j for j in range(len(modes.omega)) if modes.omega[j] > 0]
    labels = [f"{i + 1}\n{name}" for i, name in enumerate(modes.springs)]
    _mode_bars(ax, modes, idx, modes.energy_fraction.T, labels)
    ax.set_ylabel("normalised potential energy [-]")
    ax.set_xlabel("spring")
    ax.set_ylim(-1.05, 1.05)
    if title:
        ax.set_title(title)
    return fig


def plot_bode(responses: Sequence[FrequencyResponse], pairs: Sequence[tuple[str, str]],
              title: str = "", phase: bool = True) -> Figure:
    """Bode plot (magnitude [dB], phase [deg] over frequency [Hz]) of several responses.

    Parameters
    ----------
    responses : the responses to overlay (one line style each, labelled by ``label``)
    pairs : ``(output, input)`` pairs, one column of panels each
    title : figure title
    phase : draw the phase row under the magnitude row
    """
    rows = 2 if phase else 1
    fig, axes = new_figure(rows, len(pairs), size=(4.2 * len(pairs) + 1, 2.6 * rows + 0.8),
                           sharex="col")
    for col, (out, inp) in enumerate(pairs):
        for k, resp in enumerate(responses):
            h = resp.response(out, inp)
            style = STYLES[k % len(STYLES)]
            axes[0, col].semilogx(resp.frequencies_hz, 20 * np.log10(np.abs(h)), ls=style,
                                  label=resp.label)
            if phase:
                axes[1, col].semilogx(resp.frequencies_hz, np.degrees(np.unwrap(np.angle(h))),
                                      ls=style)
        axes[0, col].set_title(f"{inp} -> {out}", fontsize=9)
        axes[0, col].set_ylabel("magnitude [dB]")
        axes[-1, col].set_xlabel("frequency [Hz]")
        if phase:
            axes[1, col].set_ylabel("phase [deg]")
        for ax in axes[:, col]:
            ax.grid(True, which="both", lw=0.3)
    if any(r.label for r in responses):
        axes[0, 0].legend(fontsize=7)
    if title:
        fig.suptitle(title)
    return fig
