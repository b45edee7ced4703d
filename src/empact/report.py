"""The paper's report: every table and figure, computed, in one HTML page.

`build_report` runs the registered sections in order; each section computes its results
through the public API, writes its figures (PNG and SVG) and tables (CSV) into the output
folder, and returns an HTML fragment.  The report is written into a temporary folder beside
the destination and moved into place only when complete.

Later capabilities add sections with `register`.
"""
from __future__ import annotations

import csv
import html
import io
import os
import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from .params import Params

__all__ = ["Section", "register", "build_report", "SECTIONS", "Context"]


@dataclass(frozen=True)
class Context:
    """What a section gets: the parameters and the folder to write into."""

    params: Params
    out: Path

    def figure(self, fig, stem: str, caption: str) -> str:
        """Save a figure as PNG + SVG; return its HTML."""
        from .plotting import save_figure

        save_figure(fig, self.out / stem)
        return (f'<figure><img src="{stem}.png" alt="{html.escape(stem)}">'
                f'<figcaption>{caption} (<a href="{stem}.svg">SVG</a>)</figcaption></figure>\n')

    def table(self, stem: str, header: Sequence[str], rows: Sequence[Sequence[object]],
              caption: str) -> str:
        """Write a CSV table; return it as an HTML table."""
        buf = io.StringIO()
        writer = csv.writer(buf, lineterminator="\n")
        writer.writerow(header)
        writer.writerows(rows)
        (self.out / f"{stem}.csv").write_text(buf.getvalue())
        head = "".join(f"<th>{html.escape(str(h))}</th>" for h in header)
        body = "".join("<tr>" + "".join(f"<td>{_fmt(c)}</td>" for c in row) + "</tr>\n"
                       for row in rows)
        return (f'<table><caption>{caption} (<a href="{stem}.csv">CSV</a>)</caption>'
                f"<thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>\n")


def _fmt(value: object) -> str:
    if isinstance(value, (float, np.floating)):
        return f"{value:.4g}"
    return html.escape(str(value))


@dataclass(frozen=True)
class Section:
    """A report section: a title and a function ``(Context) -> html``."""

    title: str
    build: Callable[[Context], str]


SECTIONS: list[Section] = []


def register(title: str) -> Callable[[Callable[[Context], str]], Callable[[Context], str]]:
    """Decorator: add a section to the report (in definition order)."""
    def deco(fn: Callable[[Context], str]) -> Callable[[Context], str]:
        SECTIONS.append(Section(title, fn))
        return fn
    return deco


_STYLE = """body{font-family:sans-serif;max-width:1100px;margin:2em auto;color:#222}
table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #bbb;padding:3px 8px;
text-align:right}caption{text-align:left;font-weight:bold;margin-bottom:4px}
img{max-width:100%}figcaption{font-size:90%;color:#444}.ok{color:#060}.bad{color:#a00}"""


def verdict(ok: bool) -> str:
    """HTML for a shown / not shown mark."""
    return '<b class="ok">shown</b>' if ok else '<b class="bad">NOT shown</b>'


def build_report(params: Params, out: str | os.PathLike[str], *, progress: bool = True,
                 sections: Sequence[Section] | None = None) -> Path:
    """Compute every section and write ``out/index.html`` with its figures and tables.

    The folder is assembled in a temporary sibling and renamed into place when complete; an
    existing `out` is replaced only then.
    """
    _load_sections()
    from tqdm import tqdm

    out = Path(out).resolve()
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(dir=out.parent, prefix=f".{out.name}.tmp-"))
    try:
        ctx = Context(params=params, out=tmp)
        parts = []
        todo = list(SECTIONS if sections is None else sections)
        for sec in tqdm(todo, desc="report", unit="section", disable=not progress,
                        file=__import__("sys").stderr):
            parts.append(f"<section><h2>{html.escape(sec.title)}</h2>\n{sec.build(ctx)}</section>")
        page = (f"<!doctype html><html><head><meta charset='utf-8'><title>empact report</title>"
                f"<style>{_STYLE}</style></head><body><h1>Dynamic analysis of the Empact CVT: "
                f"reproduced with empact</h1>\n<p>Reference: “Dynamic analysis of the Empact CVT: "
                f"ratio and slip dependent, non-minimum phase dynamics”. Every number below is "
                f"computed from the parameter set in <a href='params.toml'>params.toml</a>.</p>\n"
                + "\n".join(parts) + "</body></html>\n")
        from .params import dumps_params
        (tmp / "params.toml").write_text(dumps_params(params))
        (tmp / "index.html").write_text(page)
        if out.exists():
            old = out.with_name(f".{out.name}.old-{os.getpid()}")
            out.rename(old)
            tmp.rename(out)
            shutil.rmtree(old)
        else:
            tmp.rename(out)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return out


def _load_sections() -> None:
    """Import the modules that register report sections (in report order)."""
    from . import report_sections  # noqa: F401
    from . import report_slip  # noqa: F401
    from . import report_nonlinear  # noqa: F401
    from . import report_identification  # noqa: F401

