"""Lazily imported heavy modules (private).

python-control imports ``matplotlib.pyplot`` and ``scipy.stats`` when it is imported, and
``scipy.signal`` imports ``scipy.stats``: about 1-2 s that a command which makes no figure or
control object should not pay.  Modules that return such objects name the dependency at their
top with `lazy_module`; the module is executed on first attribute access
(`importlib.util.LazyLoader`, the standard library's lazy import).
"""
from __future__ import annotations

import importlib.util
import sys
from types import ModuleType

__all__ = ["lazy_module"]


def lazy_module(name: str) -> ModuleType:
    """The module `name`, imported on first attribute access (at once if already imported)."""
    if name in sys.modules:
        return sys.modules[name]
    spec = importlib.util.find_spec(name)
    if spec is None or spec.loader is None:
        raise ModuleNotFoundError(f"No module named {name!r}", name=name)
    loader = importlib.util.LazyLoader(spec.loader)
    spec.loader = loader
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    loader.exec_module(module)
    return module
