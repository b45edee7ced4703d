"""The reproduction page's table: each report section (`empact.report.sections.SECTIONS`), the
function that computes it and the keys of the claims it checks, read from that function's
source (``Claim(key=...)`` and the ``_checks`` / ``_claims`` helpers' first argument), so that
the page follows the code without running the paper."""
from __future__ import annotations

import ast
import inspect
import textwrap
from pathlib import Path


def _text(node: ast.AST) -> str | None:
    """A string literal, or an f-string with each placeholder shown as ``*``."""
    if isinstance(node, ast.Constant) and isinstance(node.value, str):
        return node.value
    if isinstance(node, ast.JoinedStr):
        return "".join(v.value if isinstance(v, ast.Constant) else "*" for v in node.values)
    return None


def claim_keys(fn) -> list[str]:
    tree = ast.parse(textwrap.dedent(inspect.getsource(fn)))
    keys: list[str] = []
    for node in ast.walk(tree):
        if not isinstance(node, ast.Call):
            continue
        name = getattr(node.func, "id", getattr(node.func, "attr", ""))
        key = None
        if name == "Claim":
            key = next((_text(k.value) for k in node.keywords if k.arg == "key"), None)
        elif name in ("_checks", "_claims") and node.args:
            key = _text(node.args[0])
            key = key + ".N" if key else None
        if key and key not in keys:
            keys.append(key)
    return keys


def write_sections_table(path: Path) -> None:
    from empact.report.sections import SECTIONS

    rows = []
    for s in SECTIONS:
        fn = s.compute
        summary = (inspect.getdoc(fn) or "").split("\n\n")[0].replace("\n", " ")
        keys = claim_keys(fn)
        rows.append((s.title, f"``{s.anchor}``",
                     f":func:`{fn.__module__}.{fn.__name__}`", summary,
                     ", ".join(f"``{k}``" for k in keys)
                     or "(keys built in a loop: see ``claims.json``)"))
    out = [".. list-table::", "   :header-rows: 1", "   :widths: 28 10 18 24 20", "",
           "   * - Section", "     - Anchor", "     - Computed by", "     - What it computes",
           "     - Claims (keys)"]
    for row in rows:
        out.append(f"   * - {row[0]}")
        out += [f"     - {c}" for c in row[1:]]
    text = "\n".join(out) + "\n"
    if not path.exists() or path.read_text() != text:
        path.write_text(text)
