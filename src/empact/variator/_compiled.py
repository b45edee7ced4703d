"""The variator's laws (`empact.variator._laws`) compiled by numba (private): the scalar
functions the nonlinear kernel (`empact.nonlinear._kernel`) and the sampled loop law's core
(`empact.control._law_core`) call, real or complex, and the traction laws' dispatch generated
from the registry (`empact.variator._laws.TRACTION_LAWS`).

Each law of `empact.variator._laws.LAWS` and each registered traction law's functions is
``njit(cache=True)`` of the law's own code (most inlined into their callers, as the kernel's
own helpers are), with the law's module namespace in which every law is replaced by its
compiled twin, so that a compiled law calls compiled laws (the same code: one source).  numba
caches them beside ``_laws.py`` and re-checks that file's time stamp; the caches of their
compiled callers are dropped by `empact._compile.drop_stale_cache` when ``_laws.py`` changes.

The dispatch (`traction_law_mu`, `traction_law_mu_d`, `traction_law_peak`,
`traction_law_peak_d`) is source generated here from the registry, one branch per law on the
law's index ``p[k]`` (none with one law), each branch the law's coefficients interpolated at
their knots (`empact.variator._laws.knots_at`) and the law's function: only the
coefficients the function reads, and the value passes (`traction_law_mu`,
`traction_law_peak`) without the slopes' divisions, so that the kernel computes what the
hand-written dispatch did and no more; it is compiled with
``inline="always"``: only ever inlined into the kernel's functions, whose numba cache holds
it (the kernel's sources include ``_laws.py``, where laws are registered).
"""
from __future__ import annotations

import dis
import linecache
import types
from typing import Any, Callable, Literal

from numba import njit

from . import _laws

#: the generated dispatch over the traction laws (`TRACTION_SOURCE`): value, value and
#: partials, peak, peak and slope
DISPATCH = ("traction_law_mu", "traction_law_mu_d", "traction_law_peak", "traction_law_peak_d")

__all__ = list(_laws.LAWS) + list(DISPATCH) + ["DISPATCH", "traction_layout", "TRACTION_SOURCE"]

_NAMESPACE: dict[str, Any] = dict(vars(_laws))


def _compile(law: Callable[..., Any], inline: Literal["always", "never"] = "always") -> Any:
    """`law` compiled, resolving the laws it calls to their compiled twins; inlined into its
    callers (numba IR) unless `inline` is ``"never"``.  A law defined outside `_laws` (a
    traction law registered elsewhere) keeps its own module's names beside the laws."""
    namespace = _NAMESPACE
    if law.__module__ != _laws.__name__:
        namespace = {**law.__globals__, **_NAMESPACE}
    twin = types.FunctionType(law.__code__, namespace, law.__name__, law.__defaults__)
    twin.__qualname__ = law.__qualname__
    twin.__module__ = law.__module__
    twin.__doc__ = law.__doc__
    compiled = njit(cache=True, inline=inline)(twin)
    _NAMESPACE[law.__name__] = compiled
    return compiled


for _name in _laws.LAWS:
    globals()[_name] = _compile(getattr(_laws, _name),
                                "never" if _name in _laws.NOT_INLINED else "always")
for _law in _laws.TRACTION_LAWS.values():
    for _f in (_law.mu, _law.mu_d, _law.peak_d):
        if _f.__name__ not in _laws.LAWS:
            _compile(_f)
_laws._FROZEN.append(__name__)


def traction_layout() -> dict[str, tuple[int, tuple[int, ...]]]:
    """Each registered traction law's index and its coefficients' offsets (the first knot's)
    in the traction part of the kernel's parameter vector
    (`empact.variator._laws.traction_parameter_names`, counted from ``traction_law``)."""
    names = _laws.traction_parameter_names()
    knot = f"_{_laws.TRACTION_KNOTS[0]}"
    return {law.name: (i, tuple(names.index(c + knot) for c in law.coefficients))
            for i, law in enumerate(_laws.TRACTION_LAWS.values())}


def _used(f: Callable[..., Any], skip: int) -> list[bool]:
    """Whether each coefficient argument of `f` (after the first `skip`) is read by its code:
    the dispatch interpolates only those (the magic formula's peak reads D alone)."""
    read = {ins.argval for ins in dis.get_instructions(f) if ins.opname.startswith("LOAD_FAST")}
    return [name in read for name in f.__code__.co_varnames[skip:f.__code__.co_argcount]]


def _source() -> str:
    """The dispatch's source: for each quantity, one branch per law on ``p[k]`` (the law's
    index; the first law without a test, so that one law has no branch at all); only the
    coefficients the law's function reads are interpolated (a value or slope it does not read
    is passed as 0.0)."""
    layout = traction_layout()
    laws = list(_laws.TRACTION_LAWS.values())
    heads = {"traction_law_mu": "(nu, lr, p, k)", "traction_law_mu_d": "(nu, lr, p, k)",
             "traction_law_peak": "(lr, p, k)", "traction_law_peak_d": "(lr, p, k)"}
    lines: list[str] = []
    for fname, head in heads.items():
        lines.append(f"def {fname}{head}:")
        for i in list(range(1, len(laws))) + [0]:
            law = laws[i]
            pad = "        " if i else "    "
            if i:
                lines.append(f"    if p[k] == {float(i)!r}:")
            offsets = layout[law.name][1]
            m = len(offsets)
            f = {"traction_law_mu": law.mu, "traction_law_mu_d": law.mu_d,
                 "traction_law_peak": law.peak_d, "traction_law_peak_d": law.peak_d}[fname]
            used = _used(f, 1 if f in (law.mu, law.mu_d) else 0)
            slopes = fname in ("traction_law_mu_d", "traction_law_peak_d")
            need = [used[j] or (slopes and len(used) > m and used[m + j]) for j in range(m)]
            for j, o in enumerate(offsets):
                if need[j]:
                    lines.append(f"{pad}c{j} = knots_at(lr, p, k + 1, k + {o}, 3)")
            value = ", ".join(f"c{j}[0]" if need[j] else "0.0" for j in range(m))
            slope = ", ".join(f"c{j}[1] / c{j}[2]" if need[j] and slopes else "0.0"
                              for j in range(m))
            args = value if f in (law.mu,) else f"{value}, {slope}"
            call = f"{f.__name__}(nu, {args})" if f in (law.mu, law.mu_d) \
                else f"{f.__name__}({args})"
            lines.append(f"{pad}return {call}" + ("[0]" if fname == "traction_law_peak" else ""))
        lines.append("")
    return "\n".join(lines)


#: the generated source of the traction laws' dispatch (readable: ``print`` it)
TRACTION_SOURCE = _source()
_FILE = "<empact.variator._compiled: traction dispatch>"
linecache.cache[_FILE] = (len(TRACTION_SOURCE), None, TRACTION_SOURCE.splitlines(True), _FILE)
_generated: dict[str, Any] = {}
exec(compile(TRACTION_SOURCE, _FILE, "exec"), _NAMESPACE, _generated)
for _name, _f in _generated.items():
    _f.__doc__ = f"Generated dispatch over the registered traction laws ({_name})."
    globals()[_name] = njit(inline="always")(_f)


def __getattr__(name: str) -> Any:
    """The compiled laws are set in a loop (their names are `empact.variator._laws.LAWS`):
    typed as Any for the type checker."""
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
