"""Frozen, validated parameter blocks (private).

`param` declares a float field with its unit, description and allowed interval; a block is a
frozen dataclass that mixes in `Section`, which checks every such field on construction with
the project's one message format (`empact._validate`).  The blocks of a parameter file
(``[variator]``, ``[traction]``, ...) live with the concept they parameterise
(`empact.variator`, `empact.params`); `empact.params.Params` composes them.
"""
from __future__ import annotations

import math
from dataclasses import MISSING, field, fields
from typing import Any, Mapping

from ._validate import check_number, interval

__all__ = ["param", "Section", "describe_interval"]


def param(unit: str, doc: str, lo: float = 0.0, hi: float = math.inf, *, lo_open: bool = True,
          hi_open: bool = False, note: str = "", default: Any = MISSING,
          source: str = "") -> Any:
    """A float field: unit, description, allowed interval ``lo..hi`` (open or closed ends),
    an optional note for messages, the source of its default value, and an optional default
    (``None`` makes the field optional: it is then checked only when given)."""
    meta = dict(unit=unit, doc=doc, lo=lo, hi=hi, lo_open=lo_open, hi_open=hi_open, note=note,
                source=source)
    if default is MISSING:
        return field(metadata=meta)
    return field(default=default, metadata=meta)


def describe_interval(meta: Mapping[str, Any]) -> str:
    """The allowed interval of a field's metadata, as messages print it."""
    return interval(meta["lo"], meta["hi"], lo_open=meta["lo_open"], hi_open=meta["hi_open"])


class Section:
    """Mixin: range-checks every `param` field after construction (a field left ``None`` is
    optional and not checked)."""

    _name = "section"

    def __post_init__(self) -> None:
        for f in fields(self):  # type: ignore[arg-type]
            meta = f.metadata
            if "unit" not in meta:
                continue
            value = getattr(self, f.name)
            if value is None and f.default is None:
                continue
            value = check_number(f"{self._name}.{f.name}", value, meta["lo"], meta["hi"],
                                 lo_open=meta["lo_open"], hi_open=meta["hi_open"],
                                 unit=meta["unit"], note=meta["note"])
            object.__setattr__(self, f.name, value)

    @classmethod
    def describe(cls) -> list[tuple[str, str, str, str]]:
        """(name, unit, allowed interval, description) for every field."""
        return [(f.name, f.metadata["unit"], describe_interval(f.metadata), f.metadata["doc"])
                for f in fields(cls) if "unit" in f.metadata]  # type: ignore[arg-type]
