"""The paper's report: every table and figure, computed, with the verdict on each claim.

Modules
-------
build
    `build_report`: one HTML page (contents, verdict summary, sections) with PNG/SVG figures,
    CSV tables, ``claims.json`` and ``params.toml``.
sections
    The ordered list of sections (`SECTIONS`).
context
    `Section` and `Context` (figure, table and claim writers).
linear, slip, nonlinear, identification
    Rendering of each section from the results of `empact.reproduction`.
"""
from .build import build_report
from .context import Context, Section
from .sections import SECTIONS

__all__ = ["build_report", "Context", "Section", "SECTIONS"]
