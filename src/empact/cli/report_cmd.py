"""``empact reproduce``."""
from __future__ import annotations

import click

from .. import paper
from ..report import SECTIONS, build_report
from ..variator.geometry import ratio_range
from ._common import (
    PLOT_SUFFIXES,
    InputError,
    force_option,
    formats_option,
    get_params,
    output_folder,
    params_option,
    parse_choices,
)

#: the ratios the report evaluates: the paper's LOW and OD (Fig. 10) and Tables 1-2
REPORT_RATIOS = (*paper.FIG10_RATIOS, *paper.TABLE2_HZ)


@click.command("reproduce")
@click.option("--out", "out", default="report", show_default=True,
              type=click.Path(file_okay=False),
              help="Report folder; new or empty unless --force (then only empact's own files "
                   "in it are replaced).")
@formats_option
@click.option("--sections", default=None,
              help="Only these sections, comma-separated anchors (default: all; e.g. "
                   "table1,table2,fig9).")
@params_option
@force_option
@click.option("--quiet", is_flag=True, help="No progress bar on stderr.")
def reproduce(out: str, formats: str, sections: str | None, params_file: str | None,
              force: bool, quiet: bool) -> None:
    """Reproduce every table and figure of the paper into OUT/index.html (the page shows the
    PNG figures; --formats adds vector ones beside them)."""
    fmts = parse_choices("--formats", formats, PLOT_SUFFIXES)
    anchors = [s.anchor for s in SECTIONS]
    chosen = None if sections is None else parse_choices("--sections", sections, anchors)
    dest = output_folder(out, "--out", force=force)
    params = get_params(params_file)
    lo, hi = ratio_range(params.variator)
    need = (min(REPORT_RATIOS), max(REPORT_RATIOS))
    if lo > need[0] or hi < need[1]:
        raise InputError(f"{params_file or 'default.toml'}: variator (R_min = "
                         f"{params.variator.R_min:g} m, R_max = {params.variator.R_max:g} m) "
                         f"gives the ratio range [{lo:.4g}, {hi:.4g}]; the report needs "
                         f"[{need[0]:g}, {need[1]:g}] (the paper's LOW and OD)")
    todo = None if chosen is None else [s for s in SECTIONS if s.anchor in chosen]
    build_report(params, dest, progress=not quiet, formats=fmts, sections=todo)
