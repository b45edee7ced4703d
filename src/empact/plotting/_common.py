"""Shared plotting machinery (private): the `Plot` result, axes handling, one style, saving.

Every plotting function of `empact.plotting` takes result objects and optional axes (``ax``,
to draw into a figure of the caller's), draws inside `STYLE`, and returns a
`Plot` with the figure, the axes and the artists it made.  Figures are built without pyplot
(no global state); `save_figure` writes PNG and SVG atomically.
"""
from __future__ import annotations

import functools
import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Sequence

import matplotlib as mpl
import numpy as np
from matplotlib.figure import Figure

from .._deprecate import warn_renamed
from .._io import atomic_file
from .._validate import check_choice

__all__ = ["Plot", "STYLE", "STYLES", "new_axes", "save_figure", "save_plot", "symbol", "styled",
           "FORMATS"]

#: Line styles cycled over overlaid responses.
STYLES = ("-", "-.", "--", ":", (0, (5, 1, 1, 1)))

#: The one figure style (matplotlib rcParams), applied to every plotting function.
STYLE: dict[Any, Any] = {
    "font.size": 9, "axes.titlesize": 9, "axes.labelsize": 9, "xtick.labelsize": 8,
    "ytick.labelsize": 8, "legend.fontsize": 7, "figure.titlesize": 10, "axes.grid": True,
    "grid.linewidth": 0.3, "lines.linewidth": 1.2, "svg.fonttype": "none",
    "legend.framealpha": 0.85}

#: File formats `save_figure` writes.
FORMATS = ("png", "svg", "pdf")


@dataclass
class Plot:
    """What a plotting function drew.

    Attributes
    ----------
    figure : matplotlib.figure.Figure
        The figure drawn into (the caller's, with ``ax=``, or a new one).
    axes : numpy.ndarray of Axes, shape (nrows, ncols)
        The axes drawn into.
    artists : list
        The artists drawn (lines, collections, images).
    """

    figure: Figure
    axes: np.ndarray
    artists: list[Any] = field(default_factory=list)

    def save(self, path: str | os.PathLike[str], dpi: int = 150) -> Path:
        """Save to one file whose format follows its suffix (atomic).

        Parameters
        ----------
        path : str or path-like
            The file; its suffix chooses the format (`FORMATS`).
        dpi : int
            Resolution of the raster formats [dots per inch].

        Returns
        -------
        pathlib.Path
            The file written.
        """
        return save_plot(self.figure, path, dpi=dpi)


def styled(fn: Callable[..., Plot]) -> Callable[..., Plot]:
    """Decorator: draw inside ``matplotlib.rc_context(STYLE)``; the keyword ``axes=`` of empact
    0.1 still works for one release (a DeprecationWarning names ``ax=``)."""
    @functools.wraps(fn)
    def wrapper(*args: Any, **kwargs: Any) -> Plot:
        if "axes" in kwargs:
            warn_renamed(f"{fn.__name__}(axes=...)", "ax=")
            kwargs["ax"] = kwargs.pop("axes")
        with mpl.rc_context(STYLE):
            return fn(*args, **kwargs)
    return wrapper


def new_axes(axes: Any, nrows: int = 1, ncols: int = 1, size: tuple[float, float] = (7.0, 4.0),
             **kw: Any) -> tuple[Figure, np.ndarray]:
    """The caller's `axes` (one Axes or an array of shape (nrows, ncols)) with their figure,
    or a new figure (constrained layout) and axes of that shape."""
    if axes is None:
        fig = Figure(figsize=size, layout="constrained")
        return fig, fig.subplots(nrows, ncols, squeeze=False, **kw)
    arr = np.asarray(axes, dtype=object).reshape(-1)
    if arr.size != nrows * ncols:
        raise ValueError(f"need {nrows} x {ncols} axes, got {arr.size}")
    return arr[0].get_figure(), arr.reshape(nrows, ncols)


def save_figure(fig: Figure, stem: str | os.PathLike[str],
                formats: Sequence[str] = ("png", "svg"), dpi: int = 150) -> list[Path]:
    """Save `fig` as ``stem.<fmt>`` for each format, each written atomically.

    The layout is computed by the first format's drawing (constrained layout is about half of
    a figure's drawing time) and frozen for the others: they are drawn once each, with no
    layout pass.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure (e.g. ``Plot.figure``); its layout engine is removed after the first
        format.
    stem : str or path-like
        The file path without suffix; ``.<fmt>`` is appended for each format.
    formats : sequence of {"png", "svg", "pdf"}
        The formats to write (`FORMATS`), in order.
    dpi : int
        Resolution of the raster formats [dots per inch].

    Returns
    -------
    list of pathlib.Path
        The files written, one per format, in the order of `formats`.
    """
    stem = Path(stem)
    paths = []
    for fmt in formats:
        check_choice("format", fmt, FORMATS)
    _lighten_log_axes(fig)
    for fmt in formats:
        path = stem.with_name(f"{stem.name}.{fmt}")
        with atomic_file(path) as tmp:
            fig.savefig(tmp, format=fmt, dpi=dpi)
        if fig.get_layout_engine() is not None:
            # None, not "none": "none" leaves a placeholder engine, and any engine makes
            # savefig draw the figure twice (a layout pass, then the output)
            with mpl.rc_context({"figure.autolayout": False,
                                 "figure.constrained_layout.use": False}):
                fig.set_layout_engine(None)
        paths.append(path)
    return paths


#: superscript digits and minus (DejaVu Sans, matplotlib's default font, has them all)
_SUPERSCRIPT = str.maketrans("0123456789-\u2212", "\u2070\u00b9\u00b2\u00b3\u2074\u2075"
                             "\u2076\u2077\u2078\u2079\u207b\u207b")
#: a log formatter's mathtext label: ``$\mathdefault{10^{-2}}$``, ``$\mathdefault{2\times10^{1}}$``
_SCI_LABEL = re.compile(r"^\$\\mathdefault\{(?:([0-9.]+)\\times\s*)?10\^\{([-\u2212]?\d+)\}\}\$$")


class _PlainLogFormatter(mpl.ticker.Formatter):
    """A log axis's labels as plain text with superscripts (``10⁻²``, ``2×10¹``) instead of
    mathtext: the same text, without a mathtext parse per label and renderer (a fifth of the
    report's drawing time).  Anything else the wrapped formatter returns passes unchanged."""

    def __init__(self, base: mpl.ticker.Formatter) -> None:
        self.base = base

    def set_axis(self, axis: Any) -> None:
        super().set_axis(axis)
        self.base.set_axis(axis)

    def set_locs(self, locs: Any) -> None:
        self.base.set_locs(locs)

    def __call__(self, x: float, pos: int | None = None) -> str:
        label = self.base(x, pos)
        m = _SCI_LABEL.match(label)
        if m is None:
            return label
        return (f"{m.group(1)}\u00d7" if m.group(1) else "") + "10" + \
            m.group(2).translate(_SUPERSCRIPT)


def _lighten_log_axes(fig: Figure) -> None:
    """Make log axes cheaper to lay out and draw, with the same information.

    * Tick labels as plain text with superscripts instead of mathtext (`_PlainLogFormatter`).
    * No labels at the minor ticks of an axis spanning more than two decades (the major
      labels suffice), and no minor ticks (nor minor grid lines) on a value (y) axis spanning
      more than four decades, where eight per decade are clutter; frequency (x) axes keep
      theirs to read frequencies off.
    """
    for ax in fig.axes:
        for axis, lim in ((ax.xaxis, ax.get_xlim()), (ax.yaxis, ax.get_ylim())):
            lo, hi = sorted(lim)
            if axis.get_scale() != "log" or lo <= 0:
                continue
            if axis is ax.yaxis and hi / lo > 1e4:
                axis.set_minor_locator(mpl.ticker.NullLocator())
            elif hi / lo > 100:
                axis.set_minor_formatter(mpl.ticker.NullFormatter())
            for get, put in ((axis.get_major_formatter, axis.set_major_formatter),
                             (axis.get_minor_formatter, axis.set_minor_formatter)):
                if isinstance(get(), mpl.ticker.LogFormatterSciNotation):
                    put(_PlainLogFormatter(get()))


def save_plot(fig: Figure, path: str | os.PathLike[str], dpi: int = 150) -> Path:
    """Save `fig` to one file whose format follows its suffix (.png, .svg, .pdf), atomically.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure (e.g. ``Plot.figure``).
    path : str or path-like
        The file; its suffix (case-insensitive) chooses the format (`FORMATS`).
    dpi : int
        Resolution of the raster formats [dots per inch].

    Returns
    -------
    pathlib.Path
        The file written.
    """
    path = Path(path)
    fmt = check_choice("plot file suffix", path.suffix.lstrip(".").lower(), FORMATS)
    return save_figure(fig, path.with_suffix(""), formats=(fmt,), dpi=dpi)[0]


_GREEK = {"theta": r"\theta", "omega": r"\omega", "nu": r"\nu", "mu": r"\mu", "phi": r"\phi",
          "beta": r"\beta", "tau": r"\tau", "kappa": r"\kappa", "Delta": r"\Delta"}


def symbol(name: str) -> str:
    """A signal name as mathtext: ``T_mp`` -> ``$T_\\mathrm{mp}$``, ``omega_p`` ->
    ``$\\omega_\\mathrm{p}$``, ``nu`` -> ``$\\nu$``; ``_ref`` / ``_act`` become a superscript,
    ``_dot`` a dot; words (``belt_elongation``) stay words.

    Parameters
    ----------
    name : str
        A signal, state or input name of the models (``r_g``, ``T_ms_act``, ``omega_p_dot``).

    Returns
    -------
    str
        The mathtext label (``$...$``), or for a word the name with spaces for underscores.
    """
    dot = name.endswith("_dot")
    core = name[:-4] if dot else name
    m = re.fullmatch(r"([A-Za-z]+)(?:_([A-Za-z0-9]+))?(?:_([A-Za-z0-9]+))?", core)
    if not m or (m.group(1) not in _GREEK and len(m.group(1)) > 2):
        return name.replace("_", " ")
    base, sub, extra = m.groups()
    if sub in ("ref", "act") and extra is None:
        sub, extra = None, sub
    text = _GREEK.get(base, base)
    if dot:
        text = rf"\dot{{{text}}}"
    if sub:
        text += rf"_\mathrm{{{sub}}}"
    if extra:
        text += rf"^\mathrm{{{extra}}}"
    return f"${text}$"
