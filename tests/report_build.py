"""Builds the suite's one full report (`empact reproduce`) in the background: the test session
starts it as soon as it knows a test reads it (`conftest.py`), so it overlaps the rest of the
suite.  ``python report_build.py OUT RESULTS [STEM ...]`` runs ``empact reproduce --out OUT
--quiet --formats png,svg`` (the vector figures on request, so that the tests read both) in
this process and writes its exit status and output to RESULTS (JSON).  Every
section is computed and every table, page and claim written; of the figures only the STEMs
given (the ones the tests read) are drawn to files, the others keep their place in the page.
"""
import json
import os
import sys
from pathlib import Path

os.environ.setdefault("MPLBACKEND", "Agg")


def main(out: str, results: str, stems: list[str]) -> None:
    from click.testing import CliRunner

    from empact.cli import main as cli
    from empact.report import context

    if stems:
        save, keep = context.save_figure, set(stems)

        def some_figures(fig, stem, formats=("png", "svg"), **kw):
            return save(fig, stem, formats, **kw) if Path(stem).name in keep else []

        context.save_figure = some_figures  # the forked section builders inherit it
    res = CliRunner().invoke(cli, ["reproduce", "--out", out, "--quiet", "--formats",
                                   "png,svg"])
    Path(results).write_text(json.dumps({"exit_code": res.exit_code, "output": res.output}))


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2], sys.argv[3:])
