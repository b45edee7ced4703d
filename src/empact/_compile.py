"""Compile the package's numba code once, ahead of the first command (private).

`compile_all` calls every compiled entry point of `empact.nonlinear` with the argument types
the package uses (real and complex right-hand sides, Jacobians, the integrator, the batch
routines of trims and families) and the sampled loop law's core (`empact.control._law_core`),
so that numba writes its cache (``cache=True``) beside the sources.  It sits above both
subpackages (the model must not import the control layer).  ``make`` runs it right after
installing; a later first command then loads the cache (about 1 s) instead of compiling
(about 20 s).
"""
from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from .control import _law_core
from .control.closed_loop import build_law, control_example_path, run_closed_loop
from .nonlinear.equilibrium import trim
from .nonlinear.linearization import linearize_many, plant
from .nonlinear.model import nonlinear_model
from .nonlinear.scenario import load_scenario
from .nonlinear.simulation import simulate
from .params import OperatingPoint, default_params
from .variator.geometry import secondary_radius
from .variator.traction import TabulatedTraction

__all__ = ["compile_all", "drop_stale_cache"]


def drop_stale_cache(folder: Path | None = None) -> int:
    """Delete numba's cache of `empact.nonlinear` (and of the compiled closed loop) when any
    of its sources is newer than the oldest cache index; returns the number of files
    deleted.

    numba keys a function's cache on its own file only: the integrators of ``_rodas.py`` and
    ``_rosenbrock.py`` inline the right-hand side and Jacobian of ``_kernel.py`` and keep the
    version they were compiled with after ``_kernel.py`` changes (numba issue 6845); so do
    the kernel with the variator's compiled laws (``variator/_laws.py``,
    ``variator/_compiled.py``) and the tabulated traction law (``variator/_traction_table.py``),
    the law's sample (``control/_law_core.py``) with those and the kernel's traction peak and
    creep law, and the compiled closed loop (``control/_loop_core.py``) with the kernel, the
    integrators and the law's sample: their caches are dropped likewise.  The test session
    calls this first, so that an edited kernel is never tested through stale integrators;
    the price is one compile (about 20 s) after a source changed.

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
    # the variator's laws, compiled into the kernel and the law's sample, and the tabulated
    # traction law the kernel compiles in
    laws = [here / "variator" / "_laws.py", here / "variator" / "_compiled.py",
            here / "variator" / "_traction_table.py"]
    nonlinear = list((here / "nonlinear").glob("*.py")) + laws
    # the law's sample calls the kernel (traction peak, creep law)
    law_core = [here / "control" / "_law_core.py"] + nonlinear
    # the compiled closed loop calls the kernel, the integrator and the law's sample
    loop_sources = law_core + [here / "control" / "_loop_core.py"]
    return (_drop_stale(here / "nonlinear" / "__pycache__", "*", nonlinear)
            + _drop_stale(here / "control" / "__pycache__", "_law_core.*", law_core)
            + _drop_stale(here / "control" / "__pycache__", "_loop_core.*", loop_sources))


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
        model.jacobian(tr.x, tr.u)
        for method in ("rodas4", "ros2") if not options else ("rodas4",):
            simulate(model, tr.x, {model.inputs[1]: np.array([[0.0, tr.u[1]],
                                                                [0.002, tr.u[1]]])},
                     0.002, u0=tr.u, method=method)
        if "T_mp" in model.inputs and not options.get("belt"):
            linearize_many(model, tr.x[None], tr.u[None], np.array([tr.r_g]),
                           np.array([tr.nu]))
    plant(params)
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
    law.sense(law.z0[:law.n_pre - 2].reshape(len(law.raw0), -1))
    # the safety-factor clamping's torque at rest (a safety-factor law's set-up)
    _law_core.safety_torque(law.raw0[3], law.raw0[0], law._c, law._tb, law._wk)
    if law.controller.schedule is not None:
        law.controller.schedule.gains_at([1.0] * len(law.controller.schedule.axes))
    return time.perf_counter() - t0


if __name__ == "__main__":  # pragma: no cover - ``python -m empact._compile``
    print(f"compiled the nonlinear model and the loop law in {compile_all():.1f} s")
