"""Deprecated: `empact.variator.traction` (kept for one release; importing warns)."""
from __future__ import annotations

import warnings

from .variator.traction import *  # noqa: F401,F403
from .variator.traction import __all__  # noqa: F401

warnings.warn("empact.traction is deprecated; import empact.variator.traction", DeprecationWarning,
              stacklevel=2)
