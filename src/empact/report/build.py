"""Building the report: compute every section, render, write one HTML page with a table of
contents and a verdict summary, and move the folder into place when complete."""
from __future__ import annotations

import html
import json
import os
from pathlib import Path
from typing import Sequence

from .._io import atomic_folder
from .._parallel import run_forked
from .._progress import progress as progress_bar
from .._validate import check_int
from ..params import Params, dumps_params
from ..reproduction.claims import Claim, claims_table
from .context import Context, Section
from .sections import SECTIONS

__all__ = ["build_report", "STYLE_CSS", "IMAGE_CHECK"]

STYLE_CSS = """body{font-family:sans-serif;max-width:1100px;margin:2em auto;color:#222;
line-height:1.4}table{border-collapse:collapse;margin:1em 0;display:block;max-width:100%;
overflow-x:auto}td,th{border:1px solid #bbb;
padding:3px 8px;text-align:right}caption{text-align:left;font-weight:bold;margin-bottom:4px}
img{max-width:100%}figcaption{font-size:90%;color:#444}.ok{color:#060}.bad{color:#a00}
nav ol{columns:2}.summary td{text-align:left}.summary td.v{white-space:nowrap}
ul.claims li{margin:2px 0}.why{color:#555;font-size:90%}section{margin-top:2em}"""


#: Marks the page once loaded: ``data-images`` (count), ``data-broken-images`` (images that
#: did not load) and ``data-duplicate-ids`` (elements whose id an earlier one has), for a
#: reader's browser console and the test that renders the page.
IMAGE_CHECK = ("<script>window.addEventListener('load',function(){var i=document.images,b=0;"
               "for(var k=0;k<i.length;k++){if(!i[k].complete||i[k].naturalWidth===0){b++;"
               "i[k].classList.add('broken');}}document.body.dataset.images=i.length;"
               "document.body.dataset.brokenImages=b;var e=document.querySelectorAll('[id]'),"
               "s={},d=0;for(var k=0;k<e.length;k++){if(s[e[k].id]){d++;}s[e[k].id]=1;}"
               "document.body.dataset.duplicateIds=d;});</script>")


def _summary(done: Sequence[tuple[Section, Sequence[Claim]]]) -> str:
    rows = []
    for sec, claims in done:
        for c in claims:
            mark = '<b class="ok">shown</b>' if c.shown else '<b class="bad">NOT shown</b>'
            why = html.escape(c.explanation if not c.shown else c.computed)
            rows.append(f'<tr><td><a href="#{sec.anchor}">{html.escape(c.source)}</a></td>'
                        f"<td>{html.escape(c.claim)}</td><td class='v'>{mark}</td>"
                        f"<td>{why}</td></tr>")
    n = sum(len(c) for _, c in done)
    bad = sum(not x.shown for _, c in done for x in c)
    return (f'<h2 id="summary">Verdicts</h2><p>{n} claims checked: {n - bad} shown, '
            f'{bad} NOT shown (<a href="claims.json">claims.json</a>).</p>'
            '<table class="summary"><thead><tr><th>source</th><th>claim</th><th>verdict</th>'
            "<th>computed / why not</th></tr></thead><tbody>" + "\n".join(rows)
            + "</tbody></table>\n")


def _build_section(sec: Section, params: Params, out: Path,
                   formats: tuple[str, ...]) -> tuple[str, tuple[Claim, ...]]:
    """Compute and render one section into `out`; its HTML and claims."""
    ctx = Context(params=params, out=out, formats=formats)
    result = sec.compute(params)
    body = sec.render(ctx, result)
    return (f'<section id="{sec.anchor}"><h2>{html.escape(sec.title)}</h2>\n{body}</section>',
            tuple(result.claims))


def build_report(params: Params, out: str | os.PathLike[str], *, progress: bool = True,
                 sections: Sequence[Section] | None = None,
                 formats: Sequence[str] = ("png",), workers: int | None = None) -> Path:
    """Compute every section and write ``out/index.html`` with its figures and tables.

    Parameters
    ----------
    params : Params
        The parameter set.
    out : str or path-like
        The report folder; written in a temporary sibling and moved into place when complete.
    progress : bool
        A progress bar on stderr.
    sections : sequence of Section, optional
        The sections (default: all, `empact.report.sections.SECTIONS`).
    formats : sequence of {"png", "svg", "pdf"}
        Figure formats; the page shows the PNG (vector formats on request: the SVGs add
        about 13 % to a whole build, `bench/RESULTS.md`).
    workers : int, optional
        Processes building sections in parallel (default: one per CPU core, at most
        the number of sections; 1 builds in this process).  Sections are independent: each
        computes its results and draws its figures (the slow part) into its own files.

    Returns
    -------
    pathlib.Path
        The report folder.
    """
    todo = list(SECTIONS if sections is None else sections)
    n_workers = min(len(todo), os.cpu_count() or 1) if workers is None else \
        check_int("workers", workers, 1, 64)
    fmts = tuple(formats)
    with atomic_folder(out) as tmp, progress_bar(total=len(todo), desc="report",
                                                 unit="section", enabled=progress) as bar:
        built: dict[str, tuple[str, tuple[Claim, ...]]] = {}
        if n_workers <= 1:
            for sec in todo:
                built[sec.anchor] = _build_section(sec, params, tmp, fmts)
                bar.update(1)
        else:
            # fork: the children start with everything imported (no second start-up); a
            # Ctrl-C terminates them at once (`run_forked`)
            order = sorted(todo, key=lambda s: -s.cost)
            for sec, result in zip(order, run_forked(
                    _build_section, [(sec, params, tmp, fmts) for sec in order], n_workers,
                    done=lambda k, r: bar.update(1))):
                built[sec.anchor] = result
        done = [(sec, built[sec.anchor][1]) for sec in todo]
        parts = [built[sec.anchor][0] for sec in todo]
        toc = "".join(f'<li><a href="#{s.anchor}">{html.escape(s.title)}</a></li>'
                      for s in todo)
        page = ("<!doctype html><html lang='en'><head><meta charset='utf-8'>"
                "<title>empact report</title>"
                f"<style>{STYLE_CSS}</style>{IMAGE_CHECK}</head><body><h1>Dynamic analysis of "
                "the Empact CVT: reproduced with empact</h1>\n<p>Reference: “Dynamic analysis "
                "of the Empact CVT: ratio and slip dependent, non-minimum phase dynamics”. Every "
                "number below is computed from the parameter set in "
                "<a href='params.toml'>params.toml</a>.</p>\n"
                f'<nav><h2 id="contents">Contents</h2><ol><li><a href="#summary">Verdicts</a>'
                f"</li>{toc}</ol></nav>\n" + _summary(done) + "\n".join(parts)
                + "</body></html>\n")
        claims = [dict(section=s.anchor, **c) for s, cs in done for c in claims_table(cs)]
        (tmp / "claims.json").write_text(json.dumps(claims, indent=1, default=float))
        (tmp / "params.toml").write_text(dumps_params(params))
        (tmp / "index.html").write_text(page)
    return Path(out).resolve()
