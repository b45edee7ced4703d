"""Compile the package's numba code once, ahead of the first command (private).

`compile_all` calls every compiled entry point of `empact.nonlinear` with the argument types
the package and its tests use (real and complex right-hand sides, Jacobians and their
complex-step references, the three integrators, the batch routines of trims and families),
the sampled loop law's core (`empact.control._law_core`) and the integrators' stiff linear
test problem (`empact._stiff_linear`), so that numba writes its cache (``cache=True``) beside
the sources.  It sits above both subpackages (the model must not import the control layer).
``make`` runs it right after installing; a later first command or test run then loads the
cache (about 1 s) instead of compiling (about 20 s for a command, more for the tests).
`loaded_signatures` lists what a process holds compiled: ``tests/test_compile.py`` checks
that a run of the commands and of the test suite loads nothing `compile_all` does not
(``python -m empact._compile --json`` prints what it loads).
"""
from __future__ import annotations

import ast
import gc
import hashlib
import json
import os
import platform
import sys
import time
from pathlib import Path

import llvmlite
import numba
import numpy as np
from numba.core.registry import CPUDispatcher

from . import _stiff_linear
from .control import _driver_core, _law_core
from .control.closed_loop import build_law, control_example_path, run_closed_loop
from .cycles import Cycle
from .dynamic_cycle import dynamic_cycle
from .nonlinear import _batch as KB
from .nonlinear import _kernel as K
from .nonlinear import _tangent as KT
from .nonlinear.equilibrium import trim
from .nonlinear.linearization import linearize_many, plant
from .nonlinear.model import nonlinear_model
from .nonlinear.scenario import load_scenario
from .nonlinear.simulation import simulate
from .params import OperatingPoint, default_params
from .variator import _loss_table as LT
from .variator import _traction_table as TT
from .variator.geometry import secondary_radius
from .variator.losses import LossMap
from .variator.thrust_ratio import TabulatedThrustRatio
from .variator.traction import TabulatedTraction

__all__ = ["compile_all", "compiled_sources", "cold_signatures", "drop_stale_cache",
           "loaded_signatures", "record_if_cold", "record_path", "sources_digest"]


def drop_stale_cache(folder: Path | None = None) -> int:
    """Delete numba's cache of `empact.nonlinear` (and of the compiled closed loop) when any
    of its sources is newer than the oldest cache index; returns the number of files
    deleted.

    numba keys a function's cache on its own file only: the integrators of ``_rodas.py`` and
    ``_rosenbrock.py`` inline the right-hand side and Jacobian of ``_kernel.py`` and keep the
    version they were compiled with after ``_kernel.py`` changes (numba issue 6845); so do
    the kernel with the variator's compiled laws (``variator/_laws.py``,
    ``variator/_compiled.py``), the tabulated traction law (``variator/_traction_table.py``)
    and the measured loss map (``variator/_loss_table.py``),
    the law's sample (``control/_law_core.py``) with those and the kernel's traction peak and
    creep law, and the compiled closed loop (``control/_loop_core.py``) with the kernel, the
    integrators and the law's sample: their caches are dropped likewise.  The test session
    calls this first, so that an edited kernel is never tested through stale integrators;
    the price is one compile (about 20 s, more for the test suite's entries) after a source
    changed.  The sources are the compiled modules and what they import from
    (`compiled_sources`): editing the trims or the simulator's Python leaves the cache.

    Parameters
    ----------
    folder : Path, optional
        A package folder whose ``__pycache__`` is checked against its sources (default:
        `empact.nonlinear`'s, and ``_loop_core``'s cache in `empact.control`'s against the
        sources it compiles in).

    Returns
    -------
    int
        The number of cache files (``.nbi`` and ``.nbc``) deleted; 0 when none was stale.
    """
    if folder is not None:
        return _drop_stale(Path(folder) / "__pycache__", "*", list(Path(folder).glob("*.py")))
    here = Path(__file__).resolve().parent
    # the kernel, its tangent, batches and integrators with what they compile in (the
    # variator's laws, the tabulated traction law) and take constants from
    compiled = [f for f in (here / "nonlinear").glob("*.py") if _compiles(f)]
    nonlinear = compiled_sources(compiled)
    # the law's sample calls the kernel (traction peak, creep law); the compiled closed loop
    # the kernel, the integrator and the law's sample
    law_core = compiled_sources([here / "control" / "_law_core.py"])
    driver = compiled_sources([here / "control" / "_driver_core.py"])
    loop_sources = compiled_sources([here / "control" / "_loop_core.py"])
    return (_drop_stale(here / "nonlinear" / "__pycache__", "*", nonlinear)
            + _drop_stale(here / "control" / "__pycache__", "_law_core.*", law_core)
            + _drop_stale(here / "control" / "__pycache__", "_driver_core.*", driver)
            + _drop_stale(here / "control" / "__pycache__", "_loop_core.*", loop_sources))


def _compiles(path: Path) -> bool:
    """Whether the module at `path` imports numba (defines compiled code)."""
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import) and any(a.name.split(".")[0] == "numba"
                                                for a in node.names):
            return True
        if isinstance(node, ast.ImportFrom) and (node.module or "").split(".")[0] == "numba" \
                and not node.level:
            return True
    return False


def compiled_sources(modules: list[Path]) -> list[Path]:
    """The source files whose change makes numba's cache of the compiled `modules` stale:
    the modules and, transitively, the package modules they import from (``from .x import
    f``: a compiled callee is compiled into its caller, a module constant frozen into it;
    numba keys a function's cache on its own file only).  A module of the package that the
    compiled code does not import from (the trims, the simulator's Python loop, the model's
    set-up) is not one: editing it leaves the compiled code as it is.

    Parameters
    ----------
    modules : list of Path
        Source files of compiled modules.

    Returns
    -------
    list of Path
        Those files and the package's files they import from, sorted.
    """
    seen: set[Path] = set()
    todo = [Path(m).resolve() for m in modules]
    while todo:
        path = todo.pop()
        if path in seen:
            continue
        seen.add(path)
        for node in ast.walk(ast.parse(path.read_text())):
            if not isinstance(node, ast.ImportFrom) or not node.level:
                continue
            base = path.parent
            for _ in range(node.level - 1):
                base = base.parent
            target = base.joinpath(*(node.module.split(".") if node.module else []))
            for alias in node.names:  # a submodule imported by name, or a name of a module
                sub = target / f"{alias.name}.py"
                todo += [sub] if sub.is_file() else [f for f in (
                    target.with_suffix(".py"), target / "__init__.py") if f.is_file()][:1]
    return sorted(seen)


def _drop_stale(cache: Path, pattern: str, sources: list[Path]) -> int:
    """Delete the numba cache files `pattern` in `cache` when any of `sources` is newer than
    the oldest of their indexes; the number deleted."""
    index = list(cache.glob(f"{pattern}.nbi"))
    if not index:
        return 0
    if max(p.stat().st_mtime for p in sources) <= min(p.stat().st_mtime for p in index):
        return 0
    stale = index + list(cache.glob(f"{pattern}.nbc"))
    for path in stale:
        path.unlink(missing_ok=True)
    return len(stale)


def _complex_step_references(model, x: np.ndarray, u: np.ndarray) -> None:
    """The kernel's entry points the tests call directly (the complex-step references, the
    forward-mode routines, the laws' piecewise helpers for real and complex arguments), at
    the trimmed point (x, u) of `model`."""
    n, p, ix = model.n, model.p, model.ix
    dx, y = np.empty(n), np.empty(K.NY)
    K._eval(x, u, p, ix, dx, y)
    Sx, Su, Fd, Yd = (np.zeros((n, n + 4)), np.zeros((4, n + 4)), np.empty((n, n + 4)),
                      np.empty((K.NY, n + 4)))
    KT._eval_tangent(x, u, p, ix, Sx, Su, dx, y, Fd, Yd)
    for jacobian in (KT._jacobian, K._jacobian_cs):
        jacobian(x, u, p, ix, np.empty((n, n)), np.empty((n, 4)), np.empty((K.NY, n)),
                 np.empty((K.NY, 4)))
    for state_jacobian in (KT._state_jacobian, K._state_jacobian_cs):
        state_jacobian(x, u, p, ix, np.zeros((n, n)), np.arange(n))
    for direction in (KT._input_direction, K._input_direction_cs):
        direction(x, u, np.zeros(4), p, ix, np.empty(n))
    X, U = x[None], u[None]
    for batch in (KB.linearize_batch, KB.linearize_batch_cs):
        batch(X, U, p, ix, np.empty((1, n)), np.empty((1, n, n)), np.empty((1, n, 4)),
              np.empty((1, K.NY, n)), np.empty((1, K.NY, 4)))
    knots = np.array([-0.8, 0.1, 0.8, 2.0, 3.0, 1.5])
    table = TabulatedThrustRatio((0.5, 2.0), (np.array([0.0, 1.0]), np.array([0.0, 1.0])),
                                 (np.array([1.0, 1.1]), np.array([1.2, 1.3])),
                                 source="compile").encode()
    for v in (0.1, 0.1 + 1e-30j):
        K.law.knots_at(v, knots, 0, 3, 3)
        K.law.table_at(v, v, table, 0)
    KT._full_seeds(n, 4)
    # the traction and creep laws alone (the tests check them against the NumPy model)
    K.traction_mu(0.01, 1.0, p)
    K.traction_mu_d(0.01, 1.0, p)
    K.mu_peak(1.0, 0.0, p)
    # their complex steps in nu and in ln r_g, and the peak's slope (``test_traction_registry``)
    K.traction_mu(0.01 + 1e-30j, 1.0, p)
    K.traction_mu(0.01, 1.0 + 1e-30j, p)
    K.mu_max_d(1.0, 0.0, p)
    K.mu_peak(1.0 + 1e-30j, 1e-30j, p)
    K.creep_coefficient(1.0, 0.06, 1e4, p)
    K.log_kappa_eq(0.5, 0.0, 1.0, p)
    # the tabulated traction law's helpers, real and complex (against the complex step)
    curves = TabulatedTraction.from_curves({0.5: ([0.0, 0.01, 0.02], [0.0, 0.05, 0.08]),
                                            2.0: ([0.0, 0.01, 0.02], [0.0, 0.04, 0.07])},
                                           source="compile").encode()
    TT.table_mu(0.01 + 1e-30j, 1.0 + 0j, curves, 0)
    TT.table_mu_d(0.01, 1.0, curves, 0)
    TT.table_mu_max(1.0 + 1e-30j, curves, 0)
    TT.table_peak(1.0, curves, 0)
    # the measured loss map's law, real and complex (against the complex step)
    lmap = LossMap(r_g=np.array([0.5, 2.0]), omega_in=np.array([100.0, 400.0]),
                   T_in=np.array([0.0, 200.0]), F_s=np.array([5e3, 3e4]),
                   T_loss=np.ones((2, 2, 2, 2)), source="compile").encode()
    LT.table_loss(50.0, 0.0, 300.0, 1e4, 1.0, lmap, 0)
    LT.table_loss(50.0 + 1e-30j, 0j, 300.0 + 0j, 1e4 + 0j, 1.0 + 0j, lmap, 0)
    LT.table_loss_d(50.0, 0.0, 300.0, 1e4, 1.0, lmap, 0)
    model.torque_loss(1.0, 300.0, 50.0, 1e4)


def compile_all() -> float:
    """Compile (or load from the cache) every compiled routine; returns the wall time [s]."""
    t0 = time.perf_counter()
    drop_stale_cache()
    params = default_params()
    for options in ({}, {"drive": "speed"}, {"drive": "speed", "ratio_control": True},
                    {"belt": "locked"}, {"load": "speed"}):
        model = nonlinear_model(params, **options)
        op = (OperatingPoint(r_g=1.0, omega_p=300.0, F_s=1e4, T_l=10.0) if options.get("belt")
              else params.operating)
        tr = trim(model, op)
        if not options:
            base = (model, tr.x, tr.u)
        model.jacobian(tr.x, tr.u)
        for method in ("rodas4", "rodas5p", "ros2") if not options else ("rodas4",):
            simulate(model, tr.x, {model.inputs[1]: np.array([[0.0, tr.u[1]],
                                                                [0.002, tr.u[1]]])},
                     0.002, u0=tr.u, method=method)
        if "T_mp" in model.inputs and not options.get("belt"):
            linearize_many(model, tr.x[None], tr.u[None], np.array([tr.r_g]),
                           np.array([tr.nu]))
    plant(params)
    _complex_step_references(*base)
    # the integrators' stiff linear test problem on the driver's own code
    solve, _ = _stiff_linear.stepper()
    solve("rodas4", 0.5, [0.5])
    # the tabulated traction law's own entry point (`TabulatedTraction.peak`)
    TabulatedTraction.from_curves({1.0: ([0.0, 0.01, 0.02], [0.0, 0.05, 0.08])}).mu_max(1.0)
    # the compiled belt-length Newton solve a sampled law's Python path calls
    secondary_radius(1.0, params.variator.L_belt, params.variator.a)
    # the sampled loop law's compiled arithmetic (`empact.control._law_core`): a sample,
    # the linearisation's ideal sample, the sensors alone, the gain schedule
    sc = load_scenario(control_example_path("slip-load-step-r1"))
    # the compiled closed loop (`empact.control._loop_core`), then a sample alone
    run_closed_loop(sc.with_duration(0.002), params)
    law = build_law(sc, params)
    law.step(0.0, law.raw0)
    law.update(law.z0, law.raw0, 0, ideal=True)
    law.preprocess(law.z0[:law.n_pre], law.raw0, 0, np.array([law.point["r_g"], 0.01, 0.05,
                                                                 0.0]), ideal=True)
    law.sense(law.z0[:law._nb].reshape(len(law.raw0), -1))  # the buffers
    # the safety-factor clamping's torque at rest (a safety-factor law's set-up)
    _law_core.safety_torque(law.raw0[3], law.raw0[0], law._c, law._tb, law._wk)
    if law.controller.schedule is not None:
        law.controller.schedule.gains_at([1.0] * len(law.controller.schedule.axes))
    # the car: the dynamic cycle's compiled loop with the driver
    # (`empact.control._loop_core.run_samples_driven`) and the driver's sample alone
    trace = Cycle("compile", np.arange(3.0), np.array([5.0, 5.5, 6.0]), ("all",) * 3)
    dynamic_cycle(params, trace, strategies=("slip", "sf1.3"))
    # (at a ratio of 1 and unit constants: its arithmetic divides by both)
    _driver_core.driver_sample(np.ones(len(_driver_core.CONSTANTS)), np.zeros((1, 2)),
                               np.zeros(2), np.ones(K.NY), 0, np.zeros(2))
    return time.perf_counter() - t0


def loaded_signatures(roots: tuple[Path, ...] | None = None) -> set[tuple[str, str, str]]:
    """What this process holds compiled: ``(module, function, signature)`` of every
    signature of every numba dispatcher whose source lies under `roots`.

    A signature is held once it was compiled or loaded from the cache; one that a process
    holds after `compile_all` and that `compile_all` alone does not is compiled on a fresh
    install's first use (a callee compiled into its caller is held by neither).

    Parameters
    ----------
    roots : tuple of Path, optional
        Folders whose dispatchers count (default: the package's).

    Returns
    -------
    set of (str, str, str)
        The module, the qualified name and the signature (numba's argument types) of each.
    """
    roots = tuple(Path(r).resolve() for r in (roots or (Path(__file__).resolve().parent,)))
    out: set[tuple[str, str, str]] = set()
    for obj in gc.get_objects():
        if issubclass(type(obj), CPUDispatcher) and obj.overloads:  # (not a weak proxy)
            src = Path(obj.py_func.__code__.co_filename).resolve()
            if any(r in src.parents for r in roots):
                out.update((obj.py_func.__module__, obj.py_func.__qualname__, str(sig))
                           for sig in obj.overloads)
    return out


def sources_digest() -> str:
    """A digest of what `compile_all` compiles from: every file of the package (sources and
    data, not caches) with the versions of Python, numba, llvmlite and numpy.

    Returns
    -------
    str
        The SHA-256 hex digest.
    """
    root = Path(__file__).resolve().parent
    h = hashlib.sha256(" ".join([sys.version, platform.machine(), numba.__version__,
                                 llvmlite.__version__, np.__version__]).encode())
    for path in sorted(root.rglob("*")):
        if path.is_file() and "__pycache__" not in path.parts and path.suffix != ".pyc":
            h.update(path.relative_to(root).as_posix().encode() + b"\0" + path.read_bytes())
    return h.hexdigest()


def record_path() -> Path:
    """Where a compile on an empty cache records what it held (`record_if_cold`): numba's
    cache folder.

    Returns
    -------
    Path
        The record's file (it may not exist).
    """
    folder = getattr(numba.config, "CACHE_DIR", "")
    return (Path(folder) if folder else Path(__file__).resolve().parent / "__pycache__") \
        / "empact-compile-all.json"


def record_if_cold() -> bool:
    """After `compile_all`: when this process loaded nothing from numba's cache (it compiled
    every routine, as ``make`` does on a fresh install), record the signatures it holds
    with `sources_digest` (`cold_signatures` reads them); returns whether it recorded."""
    dispatchers = [obj for obj in gc.get_objects()
                   if issubclass(type(obj), CPUDispatcher) and obj.overloads
                   and Path(obj.py_func.__code__.co_filename).resolve().is_relative_to(
                       Path(__file__).resolve().parent)]
    if not dispatchers or any(d.stats.cache_hits for d in dispatchers):
        return False
    path = record_path()
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(f".{os.getpid()}.tmp")
    tmp.write_text(json.dumps({"digest": sources_digest(),
                               "signatures": sorted(loaded_signatures())}))
    tmp.replace(path)
    return True


def cold_signatures() -> set[tuple[str, str, str]] | None:
    """The signatures `compile_all` holds on an empty cache, as recorded by the last compile
    on an empty cache (``make``'s, `record_if_cold`) if it compiled these sources
    (`sources_digest`); None when there is no such record.

    Returns
    -------
    set of (str, str, str) or None
        As `loaded_signatures`.
    """
    try:
        doc = json.loads(record_path().read_text())
    except (OSError, ValueError):
        return None
    if doc.get("digest") != sources_digest():
        return None
    return {tuple(s) for s in doc["signatures"]}


if __name__ == "__main__":  # pragma: no cover - ``python -m empact._compile [--json]``
    seconds = compile_all()
    record_if_cold()
    if "--json" in sys.argv[1:]:  # what it loaded (``tests/test_compile.py``)
        print(json.dumps({"seconds": seconds, "signatures": sorted(loaded_signatures())}))
    else:
        print(f"compiled the nonlinear model and the loop law in {seconds:.1f} s")
