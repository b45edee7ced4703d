"""Deprecated: `empact.variator.thrust_ratio` (kept for one release; importing warns)."""
from __future__ import annotations

import warnings

from .variator.thrust_ratio import *  # noqa: F401,F403
from .variator.thrust_ratio import __all__  # noqa: F401

warnings.warn("empact.thrust_ratio is deprecated; import empact.variator.thrust_ratio",
              DeprecationWarning, stacklevel=2)
