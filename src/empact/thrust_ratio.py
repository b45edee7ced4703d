"""Deprecated since 0.2.0, removed in empact 0.3.0: import `empact.variator.thrust_ratio` (importing
this module warns, naming the new path and the removal)."""
from __future__ import annotations

from ._deprecate import warn_renamed
from .variator.thrust_ratio import *  # noqa: F401,F403
from .variator.thrust_ratio import __all__  # noqa: F401

warn_renamed("empact.thrust_ratio", "empact.variator.thrust_ratio", removal="0.3.0")
