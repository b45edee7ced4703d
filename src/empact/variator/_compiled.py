"""The variator's laws (`empact.variator._laws`) compiled by numba (private): the scalar
functions the nonlinear kernel (`empact.nonlinear._kernel`) and the sampled loop law's core
(`empact.control._law_core`) call, real or complex.

Each is ``njit(cache=True)`` of the law's own code (most inlined into their callers, as the
kernel's own helpers are), with the law's module namespace in which
every law is replaced by its compiled twin, so that a compiled law calls compiled laws (the
same code: one source).  numba caches them beside ``_laws.py`` and re-checks that file's time
stamp; the caches of their compiled callers are dropped by `empact._compile.drop_stale_cache`
when ``_laws.py`` changes.
"""
from __future__ import annotations

import types
from typing import Any, Callable, Literal

from numba import njit

from . import _laws

__all__ = list(_laws.__all__)

_NAMESPACE: dict[str, Any] = dict(vars(_laws))


def _compile(law: Callable[..., Any], inline: Literal["always", "never"] = "always") -> Any:
    """`law` compiled, resolving the laws it calls to their compiled twins; inlined into its
    callers (numba IR) unless `inline` is ``"never"`` (the loops and the tables' rare path:
    inlined, they would crowd the kernel's common path)."""
    twin = types.FunctionType(law.__code__, _NAMESPACE, law.__name__, law.__defaults__)
    twin.__qualname__ = law.__qualname__
    twin.__module__ = law.__module__
    twin.__doc__ = law.__doc__
    compiled = njit(cache=True, inline=inline)(twin)
    _NAMESPACE[law.__name__] = compiled
    return compiled


wrap_angle = _compile(_laws.wrap_angle)
belt_geometry = _compile(_laws.belt_geometry)
belt_newton_step = _compile(_laws.belt_newton_step)
radius_at_zero_wrap = _compile(_laws.radius_at_zero_wrap)
secondary_radius = _compile(_laws.secondary_radius, "never")
kappa_geo = _compile(_laws.kappa_geo)
magic_angle = _compile(_laws.magic_angle)
magic_formula = _compile(_laws.magic_formula)
magic_formula_d = _compile(_laws.magic_formula_d)
lerp = _compile(_laws.lerp)
knots_at = _compile(_laws.knots_at)
_curve_at = _compile(_laws._curve_at, "never")
table_at = _compile(_laws.table_at, "never")
log_kappa_eq = _compile(_laws.log_kappa_eq)
creep_factors = _compile(_laws.creep_factors)
creep_coefficient = _compile(_laws.creep_coefficient)
creep_coefficient_d = _compile(_laws.creep_coefficient_d)
