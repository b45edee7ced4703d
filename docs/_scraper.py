"""Sphinx-gallery image scrapers for empact's figures.

empact's plotting functions draw on a `matplotlib.figure.Figure` of their own (no pyplot
state) unless given axes, so sphinx-gallery's matplotlib scraper, which asks pyplot, does not
see them. `plot_scraper` saves every figure of a `empact.plotting.Plot` (or a bare Figure)
bound in the example's namespace, once, in the order they appear; `pyplot_scraper` passes
pyplot's own figures to sphinx-gallery's matplotlib scraper.

Both refuse a figure with a label, title or tick cut off at its edge (`check_inside`: the
tight bounding box of what is drawn must lie within the figure), so that the build (warnings
are errors) fails on a figure a reader would see clipped (issue 35: the Monte Carlo example's
axis labels)."""
from __future__ import annotations

import matplotlib.pyplot as plt
from matplotlib.figure import Figure
from sphinx_gallery.scrapers import figure_rst, matplotlib_scraper

_SAVED: dict[str, set[int]] = {}

#: how far what is drawn may stand beyond the figure's edge [inch] (a pixel at 100 dpi)
TOLERANCE = 0.01


def check_inside(fig: Figure, where: str) -> None:
    """Raise RuntimeError naming `where` and the edge when something drawn on `fig` (a
    label, a title, tick labels, a legend) reaches beyond the figure's edge: it would be cut
    off in the saved image."""
    fig.draw_without_rendering()  # (its layout too; empact's figures have no canvas of their own)
    tight = fig.get_tightbbox()
    w, h = fig.get_size_inches()
    edges = {"left": -tight.x0, "bottom": -tight.y0, "right": tight.x1 - w, "top": tight.y1 - h}
    cut = {k: v for k, v in edges.items() if v > TOLERANCE}
    if cut:
        raise RuntimeError(f"{where}: a figure's labels are cut off at its "
                           + ", ".join(f"{k} edge ({v:.2f} in)" for k, v in cut.items())
                           + "; draw it with layout='constrained'")


def plot_scraper(block, block_vars, gallery_conf, **kwargs):
    saved = _SAVED.setdefault(str(block_vars["src_file"]), set())
    figures = []
    for value in list(block_vars["example_globals"].values()):
        fig = value if isinstance(value, Figure) else getattr(value, "figure", None)
        if not isinstance(fig, Figure) or id(fig) in saved:
            continue
        if getattr(fig.canvas, "manager", None) is not None:   # pyplot's: the other scraper
            continue
        saved.add(id(fig))
        figures.append(fig)
    paths = []
    for fig, path in zip(figures, block_vars["image_path_iterator"]):
        check_inside(fig, str(block_vars["src_file"]))
        fig.savefig(path, dpi=100)
        paths.append(path)
    return figure_rst(paths, gallery_conf["src_dir"])


def pyplot_scraper(block, block_vars, gallery_conf, **kwargs):
    """sphinx-gallery's matplotlib scraper, after `check_inside` on each pyplot figure."""
    for num in plt.get_fignums():
        check_inside(plt.figure(num), str(block_vars["src_file"]))
    return matplotlib_scraper(block, block_vars, gallery_conf, **kwargs)
