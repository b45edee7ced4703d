"""The one way a public name of empact is retired: `warn_renamed` issues the
`DeprecationWarning`, naming the replacement and the release that removes the old name.

A renamed name keeps working for one minor release (CONTRIBUTING.md, "Changes"): the names
deprecated up to 0.2.0 are removed in `REMOVAL`.  A deprecated name stays importable but
leaves its module's ``__all__`` (and so the API pages and ``from ... import *``).
"""
from __future__ import annotations

import warnings

__all__ = ["REMOVAL", "deprecation_message", "warn_renamed"]

#: the release that removes every name deprecated up to empact 0.2.0
REMOVAL = "0.3.0"


def deprecation_message(old: str, new: str, removal: str = REMOVAL) -> str:
    """The one wording of a deprecation.

    Parameters
    ----------
    old : str
        The deprecated name or form, as the user wrote it (``"PlantFamily.at"``,
        ``"trim(model, r_g, omega_p, ...)"``, ``"empact.geometry"``).
    new : str
        What to use instead.
    removal : str, optional
        The release that removes `old` (default `REMOVAL`).

    Returns
    -------
    str
        ``"<old> is deprecated and will be removed in empact <removal>; use <new>"``.
    """
    return f"{old} is deprecated and will be removed in empact {removal}; use {new}"


def warn_renamed(old: str, new: str, *, removal: str = REMOVAL, stacklevel: int = 2) -> None:
    """Warn (`DeprecationWarning`) that `old` is deprecated in favour of `new`.

    Parameters
    ----------
    old : str
        The deprecated name or form.
    new : str
        Its replacement.
    removal : str, optional
        The release that removes `old` (default `REMOVAL`).
    stacklevel : int, optional
        As `warnings.warn`'s, counted from the caller of `warn_renamed` (2: the warning points
        at whoever called the deprecated function).
    """
    warnings.warn(deprecation_message(old, new, removal), DeprecationWarning,
                  stacklevel=stacklevel + 1)
