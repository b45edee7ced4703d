"""Deprecated since 0.2.0, removed in empact 0.3.0: import `empact.variator.shift_law` (importing
this module warns, naming the new path and the removal)."""
from __future__ import annotations

from ._deprecate import warn_renamed
from .variator.shift_law import *  # noqa: F401,F403
from .variator.shift_law import __all__  # noqa: F401

warn_renamed("empact.shift_law", "empact.variator.shift_law", removal="0.3.0")
