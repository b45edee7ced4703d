"""What a report section gets and how it writes: `Section`, `Context` (private to the report).

A section is a title, an anchor, a ``compute(params)`` function from `empact.reproduction`
(its result carries ``claims``) and a ``render(ctx, result)`` function that draws the figures
with `empact.plotting`, writes tables and returns an HTML fragment.
"""
from __future__ import annotations

import csv
import html
import io
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Sequence

import numpy as np

from .._io import atomic_write_text
from ..params import Params
from ..plotting import Plot, save_figure
from ..reproduction.claims import Claim

__all__ = ["Section", "Context", "fmt_cell", "csv_slip_columns"]


@dataclass(frozen=True)
class Section:
    """One report section.

    Attributes
    ----------
    title : str
        Heading.
    anchor : str
        HTML id (also the table-of-contents link); the ids of the page are unique:
        sections by their anchor, figures ``fig-<stem>``, tables ``tab-<stem>``, claims
        ``claim-<key>``.
    compute : callable
        ``params -> result`` with a ``claims`` attribute (`empact.reproduction`).
    render : callable
        ``(Context, result) -> html``.
    cost : float
        Rough build time [s] on one core; the parallel build starts the costly sections
        first.
    """

    title: str
    anchor: str
    compute: Callable[[Params], Any]
    render: Callable[["Context", Any], str]
    cost: float = 1.0


#: a slip column given in percent or percentage points: "nu [%]", "peak slip [%]", and every
#: column in percentage points (a difference of slips: "max |nu - nu*| [pp]", "reserve to the
#: peak [pp]")
_SLIP_PERCENT = re.compile(r"^(.*\bslip\b.*|\|?nu\b.*) \[%\]$|^.* \[pp\]$")


def csv_slip_columns(header: Sequence[str], rows: Sequence[Sequence[object]]
                     ) -> list[list[object]]:
    """Header and rows for a CSV file, a slip column in % or percentage points as a fraction.

    A slip column has a header ``... slip ... [%]``, ``nu [%]`` or ``... [pp]`` (percentage
    points: ``max |nu - nu*| [pp]``, ``reserve to the peak [pp]``); it
    becomes a fraction ``[-]`` (one unit per quantity in machine-readable output; % is for the
    page).

    Parameters
    ----------
    header : sequence of str
        Column headers with their units (``"nu [%]"``, ``"F_s [kN]"``).
    rows : sequence of sequence
        The table's rows, one cell per header.

    Returns
    -------
    list of list
        The header, its slip columns' unit ``[%]`` or ``[pp]`` replaced by ``[-]``, then the rows,
        their numeric slip cells divided by 100 (other cells, and booleans, as given).
    """
    slip = [bool(_SLIP_PERCENT.match(str(h))) for h in header]
    head: list[object] = [re.sub(r" \[(%|pp)\]$", " [-]", str(h)) if s else h
                          for h, s in zip(header, slip)]
    return [head] + [[c / 100 if s and isinstance(c, (int, float, np.number))
                      and not isinstance(c, bool) else c for c, s in zip(row, slip)]
                     for row in rows]


def fmt_cell(value: object) -> str:
    """A table cell: floats with 4 significant digits (NaN, no value, as a dash), everything
    else as text (escaped).

    Parameters
    ----------
    value : object
        The cell's value.

    Returns
    -------
    str
        HTML text of the cell (``f"{value:.4g}"`` for a float, an en dash for NaN, else
        ``str`` HTML-escaped).
    """
    if isinstance(value, (float, np.floating)):
        return "\u2013" if value != value else f"{value:.4g}"
    return html.escape(str(value))


@dataclass
class Context:
    """The parameters, the output folder and the figure formats of a report build.

    `figures` collects the figure files written (for the build's completeness check).

    Attributes
    ----------
    params : Params
        The parameter set the report is computed from.
    out : pathlib.Path
        The folder the figures and tables are written to.
    formats : tuple of str
        The figure formats (`empact.plotting.FORMATS`); the page shows the PNG if there is one.
    figures : list of pathlib.Path
        The figure files written so far (by `figure`).
    """

    params: Params
    out: Path
    formats: tuple[str, ...] = ("png",)
    figures: list[Path] = field(default_factory=list)

    def figure(self, plot: Plot, stem: str, caption: str) -> str:
        """Save a plot in the build's formats; return its HTML (caption is HTML).

        Parameters
        ----------
        plot : Plot
            The plot (`empact.plotting`); its figure is saved as ``out/<stem>.<fmt>``.
        stem : str
            File name without suffix, also the figure's id ``fig-<stem>``.
        caption : str
            The caption (HTML).

        Returns
        -------
        str
            A ``<figure>`` showing the PNG (or the first format), linking the other formats.
        """
        self.figures += save_figure(plot.figure, self.out / stem, self.formats)
        shown = "png" if "png" in self.formats else self.formats[0]
        others = " ".join(f'<a href="{stem}.{fmt}">{fmt.upper()}</a>' for fmt in self.formats
                          if fmt != shown)
        return (f'<figure id="fig-{stem}"><img src="{stem}.{shown}" alt="{html.escape(stem)}">'
                f'<figcaption>{caption}{f" ({others})" if others else ""}</figcaption>'
                f"</figure>\n")

    def table(self, stem: str, header: Sequence[str], rows: Sequence[Sequence[object]],
              caption: str) -> str:
        """Write a CSV table; return it as an HTML table (caption is HTML).

        The page shows a slip in % or percentage points where the section gives it so; the
        CSV, machine-readable, has it as a fraction (`csv_slip_columns`).

        Parameters
        ----------
        stem : str
            File name of the CSV without suffix, also the table's id ``tab-<stem>``.
        header : sequence of str
            Column headers with their units.
        rows : sequence of sequence
            The rows, one cell per header.
        caption : str
            The caption (HTML).

        Returns
        -------
        str
            A ``<table>`` with its caption and a link to the CSV.
        """
        buf = io.StringIO()
        writer = csv.writer(buf, lineterminator="\n")
        writer.writerows(csv_slip_columns(header, rows))
        atomic_write_text(self.out / f"{stem}.csv", buf.getvalue())
        head = "".join(f"<th>{html.escape(str(h))}</th>" for h in header)
        body = "".join("<tr>" + "".join(f"<td>{fmt_cell(c)}</td>" for c in row) + "</tr>\n"
                       for row in rows)
        return (f'<table id="tab-{stem}"><caption>{caption} (<a href="{stem}.csv">CSV</a>)'
                f"</caption><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>\n")

    @staticmethod
    def verdict(claims: Sequence[Claim]) -> str:
        """HTML mark for a group of claims: shown when all are.

        Parameters
        ----------
        claims : sequence of Claim
            The claims.

        Returns
        -------
        str
            ``shown`` (green) or ``NOT shown`` (red), bold.
        """
        ok = all(c.shown for c in claims)
        return '<b class="ok">shown</b>' if ok else '<b class="bad">NOT shown</b>'

    @staticmethod
    def claims(claims: Sequence[Claim]) -> str:
        """The claims as an HTML list: claim, computed, verdict, explanation.

        Parameters
        ----------
        claims : sequence of Claim
            The claims.

        Returns
        -------
        str
            A ``<ul>`` with one item per claim, its id ``claim-<key>``.
        """
        items = []
        for c in claims:
            mark = '<b class="ok">shown</b>' if c.shown else '<b class="bad">NOT shown</b>'
            why = f' <span class="why">{html.escape(c.explanation)}</span>' \
                if c.explanation and not c.shown else ""
            reading = f" <i>[{html.escape(c.reading)}]</i>" if c.reading else ""
            items.append(f'<li id="claim-{html.escape(c.key)}">{html.escape(c.claim)}{reading}: '
                         f"{html.escape(c.computed)} &mdash; {mark}{why}</li>")
        return f'<ul class="claims">{"".join(items)}</ul>\n'
