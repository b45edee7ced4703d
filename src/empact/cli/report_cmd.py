"""``empact reproduce``."""
from __future__ import annotations

import click

from ..report import build_report
from ._common import get_params, params_option


@click.command("reproduce")
@click.option("--out", "out", default="report", show_default=True,
              type=click.Path(file_okay=False), help="Report folder (replaced when complete).")
@params_option
@click.option("--quiet", is_flag=True, help="No progress bar on stderr.")
def reproduce(out: str, params_file: str | None, quiet: bool) -> None:
    """Reproduce every table and figure of the paper into OUT/index.html."""
    path = build_report(get_params(params_file), out, progress=not quiet)
    click.echo(str(path / "index.html"))
