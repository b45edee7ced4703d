"""A sphinx-gallery image scraper for empact's figures.

empact's plotting functions draw on a `matplotlib.figure.Figure` of their own (no pyplot
state) unless given axes, so sphinx-gallery's matplotlib scraper, which asks pyplot, does not
see them. This one saves every figure of a `empact.plotting.Plot` (or a bare Figure) bound in
the example's namespace, once, in the order they appear; pyplot's own figures are left to the
matplotlib scraper."""
from __future__ import annotations

from matplotlib.figure import Figure
from sphinx_gallery.scrapers import figure_rst

_SAVED: dict[str, set[int]] = {}


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
        fig.savefig(path, dpi=100)
        paths.append(path)
    return figure_rst(paths, gallery_conf["src_dir"])
