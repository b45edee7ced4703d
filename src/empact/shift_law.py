"""Deprecated: `empact.variator.shift_law` (kept for one release; importing warns)."""
from __future__ import annotations

import warnings

from .variator.shift_law import *  # noqa: F401,F403
from .variator.shift_law import __all__  # noqa: F401

warnings.warn("empact.shift_law is deprecated; import empact.variator.shift_law",
              DeprecationWarning, stacklevel=2)
