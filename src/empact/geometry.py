"""Deprecated: `empact.variator.geometry` (kept for one release; importing warns)."""
from __future__ import annotations

import warnings

from .variator.geometry import *  # noqa: F401,F403
from .variator.geometry import __all__  # noqa: F401

warnings.warn("empact.geometry is deprecated; import empact.variator.geometry", DeprecationWarning,
              stacklevel=2)
