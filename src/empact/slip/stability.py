"""Stability of the variator coupling over a grid of operating points.

`stability_map` evaluates the largest pole real part and the smallest damping ratio of the slip
model over two operating-point variables: the system matrices of a chunk of points are built
stacked and all their eigenvalues come from one `numpy.linalg.eigvals` call.  With the exact
5 x 5 reduction (`empact.slip.model.reduced_matrices`) no rule is needed for telling the three
structural zeros apart; on the full 8 x 8 matrices `stability_measures` drops the three
eigenvalues of smallest magnitude.  (A compiled polynomial-root path was tried and removed: its
compile and cache load cost more than a whole map, see ``bench/RESULTS.md``.)
"""
from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._progress import progress as progress_bar
from .._results import Result
from .._validate import check_choice, check_int
from ..errors import ParameterError
from ..lti import damping_ratio
from ..params import OperatingPoint, Params, ResolvedPoint
from ..sweep import SweepOptions, plan_chunks, run_chunks
from ..variator.traction import TractionModel, traction_from_params
from .coupling import VARIABLES, linearisation_terms
from .loci import Variable, grid_values
from .model import N_STRUCTURAL_ZEROS, assemble_A, assemble_reduced, mass_stiffness

__all__ = ["StabilityMap", "stability_map", "stability_measures", "dynamic_poles"]

MapMethod = Literal["reduced", "full"]
METHODS = ("reduced", "full")


def dynamic_poles(eigs: ArrayLike) -> NDArray[np.complex128]:
    """Drop the `N_STRUCTURAL_ZEROS` eigenvalues of smallest magnitude (last axis).

    Parameters
    ----------
    eigs : array_like, shape S + (n,)
        Eigenvalues of slip models [rad/s] (n = 8 for `empact.slip.model.state_matrices`).

    Returns
    -------
    ndarray of complex, shape S + (n - 3,)
        The remaining eigenvalues [rad/s], ascending in magnitude along the last axis.
    """
    e = np.asarray(eigs, complex)
    order = np.argsort(np.abs(e), axis=-1)[..., N_STRUCTURAL_ZEROS:]
    return np.take_along_axis(e, order, axis=-1)


def stability_measures(eigs: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Largest real part [1/s] and smallest damping ratio [-] of the non-structural poles.

    Parameters
    ----------
    eigs : eigenvalues of slip models, shape S + (8,)

    Returns
    -------
    max_real : shape S;  min_damping : shape S, ``min(-Re(p) / |p|)`` (a real stable pole
        counts as 1, a real unstable one as -1)
    """
    return _measures(dynamic_poles(eigs))


def _measures(p: NDArray[np.complex128]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Largest real part and smallest damping ratio of poles `p` (last axis)."""
    return p.real.max(axis=-1), damping_ratio(p).min(axis=-1)


@dataclass(frozen=True)
class StabilityMap(Result):
    """Largest pole real part and smallest damping ratio over a grid of two variables.

    Attributes
    ----------
    x_name, y_name : the two variables (from `VARIABLES`)
    x : shape (nx,);  y : shape (ny,)   [units of the variables]
    base : operating point of the other two variables
    max_real : largest real part of the non-structural poles [1/s], shape (ny, nx)
    min_damping : smallest damping ratio [-], shape (ny, nx)
    tol : real parts above ``tol`` [1/s] count as unstable
    method : the method that computed the map ("reduced" or "full")
    """

    x_name: str
    y_name: str
    x: NDArray[np.float64]
    y: NDArray[np.float64]
    base: ResolvedPoint
    max_real: NDArray[np.float64]
    min_damping: NDArray[np.float64]
    tol: float
    method: str = "reduced"

    @property
    def unstable(self) -> NDArray[np.bool_]:
        """Points with a pole in the right half-plane, shape (ny, nx)."""
        return self.max_real > self.tol

    @property
    def unstable_fraction(self) -> float:
        """Fraction of grid points that are unstable [-]."""
        return float(self.unstable.mean())


def stability_map(params: Params, x_name: Variable, x: ArrayLike, y_name: Variable,
                  y: ArrayLike, *, base: OperatingPoint | None = None,
                  traction: TractionModel | None = None, method: MapMethod = "reduced",
                  chunk_size: int = 4096, workers: int | None = None,
                  tol: float = 1e-6, sweep: SweepOptions | None = None) -> StabilityMap:
    """Stability of the slip model over a grid of two operating-point variables.

    The grid (``len(y) * len(x)`` points) is processed in chunks of `chunk_size` points: for
    each chunk the system matrices are built stacked and all their eigenvalues come from one
    `numpy.linalg.eigvals` call; memory stays O(chunk_size) beyond the two result arrays.

    Parameters
    ----------
    params : the parameter set
    x_name, y_name : two different variables of "nu", "F_s", "omega_p", "r_g"
    x, y : their values, shapes (nx,), (ny,)
    base : the other two variables (default: the ``[operating]`` point of `params`)
    traction : traction model (default `traction_from_params(params)`)
    method : {"reduced", "full"}
        ``"reduced"`` (default): the stacked matrices of `reduced_matrices`, shape
        (chunk, 5, 5), whose eigenvalues are exactly the five non-structural ones.
        ``"full"``: the stacked ``A`` of `state_matrices`, shape (chunk, 8, 8), with the three
        eigenvalues of smallest magnitude dropped as the structural zeros (about twice as
        slow).  Both give the same map to rounding.
    chunk_size : points per eigenvalue call (>= 1)
    workers : threads working on chunks in parallel (>= 1; default: one per CPU core; numpy's
        eigenvalue routine releases the GIL)
    tol : real parts above this [1/s] count as unstable (absorbs rounding only)
    sweep : SweepOptions, optional
        Run the chunks on Dask (`empact.sweep`); then `workers` is ignored (the cluster's
        workers are ``sweep.workers``).  Default: in process, with `workers` threads.  The map
        is bitwise the same either way (each point's eigenvalues are its own LAPACK call).

    Returns
    -------
    StabilityMap
        ``max_real`` and ``min_damping`` of shape (ny, nx).
    """
    xv, yv = grid_values(x_name, x), grid_values(y_name, y)
    if x_name == y_name:
        raise ParameterError(f"stability map over {x_name!r} twice: choose two different "
                             f"variables of {', '.join(VARIABLES)}")
    check_choice("method", method, METHODS)
    chunk_size = check_int("chunk_size", chunk_size, 1)
    workers = check_int("workers", (os.cpu_count() or 1) if workers is None else workers, 1)
    base = (params.operating if base is None else base).resolve(params, traction)
    fixed: dict[str, Any] = dict(base.to_dict())
    # Every variable is valid or not on its own: checking the two axes checks the whole grid,
    # so a bad value is reported at once, before any chunk is computed.
    for name, values in ((x_name, xv), (y_name, yv)):
        linearisation_terms(params, **{**fixed, name: values}, traction=traction)
    tr = traction_from_params(params) if traction is None else traction
    J, K = mass_stiffness(params)
    nx = xv.size
    n = nx * yv.size
    task = (params, tr, J, K, method, x_name, y_name, xv, yv, fixed)
    if sweep is not None and sweep.scheduler != "none":
        # chunks of >= 50 ms for the Dask task overhead; the points of a chunk are still
        # computed `chunk_size` at a time, so memory stays bounded on every worker
        parts = run_chunks(_map_chunk, [(task, sl.start, sl.stop, chunk_size)
                                        for sl in plan_chunks(n, SECONDS_PER_POINT, sweep)],
                           sweep, desc="stability map")
        max_real, min_damp = (np.concatenate([p[k] for p in parts]) for k in (0, 1))
    else:
        max_real, min_damp = np.empty(n), np.empty(n)
        bounds = [(s0, min(s0 + chunk_size, n)) for s0 in range(0, n, chunk_size)]

        def work(b: tuple[int, int]) -> None:
            max_real[b[0]:b[1]], min_damp[b[0]:b[1]] = _map_points(task, *b)

        with progress_bar(total=len(bounds), desc="stability map", unit="chunk",
                          enabled=sweep is not None and sweep.progress) as bar:
            if workers == 1:
                for b in bounds:
                    work(b)
                    bar.update(1)
            else:
                pool = ThreadPoolExecutor(workers)
                try:
                    for _ in pool.map(work, bounds):
                        bar.update(1)
                finally:  # a Ctrl-C or an error: the chunks not started are dropped
                    pool.shutdown(wait=True, cancel_futures=True)
    shape = (yv.size, nx)
    return StabilityMap(x_name=x_name, y_name=y_name, x=xv, y=yv, base=base,
                        max_real=max_real.reshape(shape), min_damping=min_damp.reshape(shape),
                        tol=float(tol), method=method)


#: measured cost of one map point (reduced method, stacked eigenvalues), for sizing chunks [s]
SECONDS_PER_POINT = 3e-6


def _map_points(task, start: int, stop: int) -> tuple[NDArray, NDArray]:
    """Largest real part and smallest damping of the flat grid points ``start:stop``."""
    params, tr, J, K, method, x_name, y_name, xv, yv, fixed = task
    idx = np.arange(start, stop)
    nx = xv.size
    op = dict(fixed)
    op[x_name], op[y_name] = xv[idx % nx], yv[idx // nx]
    t = linearisation_terms(params, op["r_g"], op["nu"], op["F_s"], op["omega_p"], tr)
    r, rho, c_s = (np.broadcast_to(t[k], idx.shape) for k in ("r_g", "rho", "c_s"))
    if method == "full":
        return stability_measures(np.linalg.eigvals(assemble_A(J, K, r, rho, c_s)))
    return _measures(np.linalg.eigvals(assemble_reduced(J, K, r, rho, c_s)).astype(np.complex128))


def _map_chunk(arg) -> tuple[NDArray, NDArray]:
    """A sweep chunk of the map (module level, picklable): its points `chunk_size` at a time,
    each from its own eigenvalue problem, so the result does not depend on the chunking."""
    task, start, stop, chunk_size = arg
    parts = [_map_points(task, a, min(a + chunk_size, stop))
             for a in range(start, stop, chunk_size)]
    return tuple(np.concatenate([p[k] for p in parts]) for k in (0, 1))  # type: ignore
