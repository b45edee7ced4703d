"""Claims of the paper, checked: the record every reproduction function returns.

A `Claim` states what the paper says (with its section), what empact computed (numbers with
units), the verdict and why.  The report renders claims (its verdict summary, the lists under
each figure) and the tests assert on them; ``claims.json`` in the report folder holds them all
for scripts.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Any, Iterable, Mapping

from .._deprecate import warn_renamed

__all__ = ["Claim", "claims_table"]


@dataclass(frozen=True)
class Claim:
    """One checked statement of the paper.

    Attributes
    ----------
    key : str
        Stable identifier, e.g. ``"table2.max_error"`` (tests and scripts use it).
    source : str
        Where the paper says it, e.g. ``"Sec. 2.2, Fig. 9"``.
    claim : str
        What the paper says (or what empact checks on its behalf), one sentence.
    computed : str
        What empact computed, with numbers and units.
    shown : bool
        The verdict: True when the computed result shows the claim.
    explanation : str
        Why the verdict is what it is (always given when not shown).
    reading : str
        Which reading of the paper or which model the result belongs to (e.g.
        ``"machine (equal translation)"``, ``"Sec. 2.1 as published"``); empty when there is
        only one.
    values : mapping
        The numbers behind `computed`, by name (SI unless the name says otherwise).
    """

    key: str
    source: str
    claim: str
    computed: str
    shown: bool
    explanation: str = ""
    reading: str = ""
    values: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        object.__setattr__(self, "shown", bool(self.shown))
        if not self.shown and not self.explanation:
            raise ValueError(f"claim {self.key!r} is not shown and has no explanation")

    @property
    def verdict(self) -> str:
        """``"shown"`` or ``"NOT shown"``."""
        return "shown" if self.shown else "NOT shown"

    def to_dict(self) -> dict[str, Any]:
        """Plain dictionary (for JSON)."""
        d = asdict(self)
        d["values"] = dict(self.values)
        d["verdict"] = self.verdict
        return d

    def as_dict(self) -> dict[str, Any]:
        """Deprecated: `to_dict`."""
        warn_renamed("Claim.as_dict", "to_dict")
        return self.to_dict()


def claims_table(claims: Iterable[Claim]) -> list[dict[str, Any]]:
    """The claims as plain dictionaries, in order.

    Parameters
    ----------
    claims : iterable of Claim
        The claims.

    Returns
    -------
    list of dict
        `Claim.to_dict` of each claim (its fields, ``values`` as a plain dict, and ``verdict``).
    """
    return [c.to_dict() for c in claims]
