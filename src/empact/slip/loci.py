"""Poles and zeros of the slip model along a parameter: the paper's Figs. 9, 11, 12 and 13.

* `belt_root_locus` (Fig. 9): poles over the belt damping ``c_b`` from 0 (two uncoupled sides)
  to infinity (`coupled_limit`, the kinematically coupled driveline of Table 2).
* `pole_sweep` (Fig. 11): the five non-structural poles over one operating-point variable.
* `slip_frequency_responses` (Fig. 12): ``F_s -> nu`` at several operating points.
* `zero_locus` (Fig. 13): the zeros of ``F_s -> nu`` over the ratio.

Compute only; figures are drawn by `empact.plotting.slip`.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Literal, Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.linalg import eigvals as generalized_eigvals
from scipy.linalg import null_space

from .._results import Result
from .._validate import check_choice, check_number
from ..errors import ParameterError
from ..lti import (
    FrequencyResponse,
    RootLocus,
    damping_ratio,
    oscillatory,
    root_locus,
    track_branches,
)
from ..params import OperatingPoint, Params, ResolvedPoint
from ..variator.geometry import variator_state
from ..variator.traction import TractionModel
from .coupling import VARIABLES, check_slip, linearisation_terms
from .model import assemble_A, assemble_reduced, mass_stiffness, slip_model

__all__ = ["BeltRootLocus", "PoleSweep", "ZeroLocus", "coupled_limit", "belt_root_locus",
           "pole_sweep", "slip_frequency_responses", "zero_locus", "grid_values"]

Variable = Literal["r_g", "nu", "F_s", "omega_p"]


def coupled_limit(params: Params, r_g: float, nu0: float = 0.0) -> NDArray[np.complex128]:
    """Finite poles of the slip model as ``c_b -> inf`` [rad/s], shape (7,), by magnitude.

    The slip velocity is then held at zero (``omega_s = rho omega_p``): the constrained system
    ``M q'' + K q = b lambda``, ``a^T q' = 0``, reduced with ``q = N y`` (``a^T N = 0``) and
    projected with ``W`` (``b^T W = 0``).  Its eigenvalues ``+-sqrt(-w^2)`` are the coupled
    driveline's (Table 2 with a rigid belt), plus the three structural zeros; the eighth pole
    goes to ``-inf``.

    Parameters
    ----------
    params : Params
        Parameter set (driveline inertias and stiffnesses; variator range).
    r_g : float
        Geometric ratio [-] (checked against the variator's range).
    nu0 : float
        Operating slip [-] of the kinematic ratio ``rho = r_g (1 - nu0)``.

    Returns
    -------
    ndarray of complex, shape (7,)
        The finite poles [rad/s] (three of them exact zeros), ascending in magnitude.
    """
    variator_state(r_g, params.variator)  # range check
    J, K = mass_stiffness(params)
    rho = r_g * (1 - float(check_slip(nu0)))
    a = np.array([[0.0, rho, -1.0, 0.0]])
    b = np.array([[0.0, r_g, -1.0, 0.0]])
    Nq, W = null_space(a), null_space(b)
    lam = generalized_eigvals(W.T @ K @ Nq, W.T @ np.diag(J) @ Nq)  # w^2
    lam = np.real_if_close(lam, tol=1e6)
    s = np.sqrt(-np.asarray(lam, complex))
    poles = np.concatenate([s, -s, [0.0]])
    poles[np.abs(poles) < 1e-6 * np.abs(poles).max()] = 0.0
    return poles[np.argsort(np.abs(poles))]


@dataclass(frozen=True)
class BeltRootLocus(Result):
    """Root locus of the slip model over the paper's ``c_b`` from 0 to infinity (Fig. 9).

    Attributes
    ----------
    r_g, nu0 : ratio [-] and slip [-] of the kinematic ratio ``rho = r_g (1 - nu0)``
    locus : branches over ``c_b`` [N m s/rad] on a log grid, ``poles`` shape (n_steps, 8)
    start : exact poles at ``c_b = 0`` (the two uncoupled sides) [rad/s], shape (8,)
    stop : exact finite poles at ``c_b -> inf`` (kinematically coupled) [rad/s], shape (7,);
        the eighth pole goes to ``-inf``
    uncoupled_hz : natural frequencies of the oscillatory start poles [Hz], ascending, (2,)
    coupled_hz : natural frequencies of the oscillatory end poles [Hz], ascending, (2,)
    """

    r_g: float
    nu0: float
    locus: RootLocus
    start: NDArray[np.complex128]
    stop: NDArray[np.complex128]
    uncoupled_hz: NDArray[np.float64]
    coupled_hz: NDArray[np.float64]


def _oscillatory_hz(poles: NDArray[np.complex128], tol: float = 1e-6) -> NDArray[np.float64]:
    p = poles[poles.imag > tol * max(np.abs(poles).max(), 1.0)]
    return np.sort(np.abs(p)) / (2 * np.pi)


def belt_root_locus(params: Params, r_g: float = 1.0, nu0: float = 0.0, *,
                    c_b_range: tuple[float, float] = (1e-3, 1e4), max_move: float = 0.05) \
        -> BeltRootLocus:
    """Root locus of the slip model over ``c_b`` in ``[0, inf)`` (Fig. 9).

    The locus itself runs over `c_b_range` [N m s/rad] (log spacing, `empact.lti.root_locus`);
    the end points ``c_b = 0`` (uncoupled sides) and ``c_b -> inf`` (`coupled_limit`) are
    computed exactly.  The model damping is ``c_s = c_b / r_g`` (module
    docstring).  The clamping-force gain does not enter the poles.

    Parameters
    ----------
    params : Params
    r_g : float
        Geometric ratio [-].
    nu0 : float
        Operating slip [-] of the model around which the locus is drawn.
    c_b_range : (float, float)
        Smallest and largest ``c_b`` [N m s/rad] of the traced locus.
    max_move : float
        Largest relative pole movement between two traced points (refines the steps).

    Returns
    -------
    BeltRootLocus
        ``locus`` (the traced branches over ``c_b``), ``start`` and ``stop`` (the exact end
        points [rad/s]), ``uncoupled_hz`` and ``coupled_hz`` [Hz].
    """
    lo = check_number("c_b_min", c_b_range[0], 0.0, lo_open=True, unit="N m s/rad")
    hi = check_number("c_b_max", c_b_range[1], lo, lo_open=True, unit="N m s/rad")
    variator_state(r_g, params.variator)
    nu0 = float(check_slip(nu0))
    J, K = mass_stiffness(params)
    r = np.array([float(r_g)])
    rho = r * (1 - nu0)

    def A_of(c_b: float) -> NDArray[np.float64]:
        return assemble_A(J, K, r, rho, np.array([c_b / r_g]))[0]

    loc = root_locus(A_of, lo, hi, spacing="log", max_move=max_move, name="c_b [N m s/rad]")
    start = np.sort_complex(np.linalg.eigvals(A_of(0.0)).astype(np.complex128))
    stop = coupled_limit(params, r_g, nu0)
    return BeltRootLocus(r_g=float(r_g), nu0=nu0, locus=loc, start=start, stop=stop,
                         uncoupled_hz=_oscillatory_hz(start), coupled_hz=_oscillatory_hz(stop))


# --------------------------------------------------------------------------------------------
# Fig. 11: poles over an operating-point variable
# --------------------------------------------------------------------------------------------
def grid_values(name: str, values: ArrayLike) -> NDArray[np.float64]:
    """Values of one operating-point variable `name` as a non-empty 1-d array.

    Parameters
    ----------
    name : str
        An operating-point variable (one of `VARIABLES`).
    values : array_like
        Its value(s), a scalar or a 1-d sequence, in the variable's unit.

    Returns
    -------
    ndarray, shape (n,)
        The values as floats (a scalar becomes shape (1,)).

    Raises
    ------
    ParameterError
        For an unknown variable, or values that are empty or not 1-d.
    """
    check_choice("operating-point variable", name, VARIABLES)
    v = np.atleast_1d(np.asarray(values, float))
    if v.ndim != 1 or v.size == 0:
        raise ParameterError(f"{name}: need a non-empty 1-d array of values")
    return v


@dataclass(frozen=True)
class PoleSweep(Result):
    """Non-structural poles of the slip model along one operating-point variable (Fig. 11).

    Attributes
    ----------
    name : the swept variable (one of `VARIABLES`)
    values : its values, shape (n,) [unit of the variable]
    base : the operating point of the other variables
    poles : the five non-structural poles [rad/s], shape (n, 5), one branch per column
    c_b : the paper's damping constant at each point [N m s/rad], shape (n,)
    dmu : traction slope at each point [-], shape (n,)
    """

    name: str
    values: NDArray[np.float64]
    base: ResolvedPoint
    poles: NDArray[np.complex128]
    c_b: NDArray[np.float64]
    dmu: NDArray[np.float64]

    @property
    def natural_hz(self) -> NDArray[np.float64]:
        """Natural frequencies ``|p| / (2 pi)`` [Hz], shape (n, 5)."""
        return np.abs(self.poles) / (2 * np.pi)

    @property
    def damping(self) -> NDArray[np.float64]:
        """Damping ratios ``-Re(p) / |p|`` [-] (1 for a pole at 0), shape (n, 5)."""
        return damping_ratio(self.poles)

    @property
    def max_real(self) -> NDArray[np.float64]:
        """Largest real part at each point [1/s], shape (n,)."""
        return self.poles.real.max(axis=1)

    @property
    def min_damping(self) -> NDArray[np.float64]:
        """Smallest damping ratio at each point [-], shape (n,)."""
        return self.damping.min(axis=1)

    def oscillatory(self, k: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Natural frequency [Hz] and damping [-] of the oscillatory pair(s) at point `k`,
        ascending in frequency (upper-half-plane poles only).

        Parameters
        ----------
        k : int
            Index of the sweep point.
        """
        return oscillatory(self.poles[k])


def pole_sweep(params: Params, name: Variable, values: ArrayLike,
               base: OperatingPoint | None = None,
               traction: TractionModel | None = None) -> PoleSweep:
    """Poles of the slip model over one variable of the operating point (batched).

    Parameters
    ----------
    params : the parameter set
    name : "nu", "F_s", "omega_p" or "r_g"
    values : values of that variable, shape (n,)
    base : the other variables (default: the ``[operating]`` point of `params`)
    traction : traction model (default `traction_from_params(params)`)

    Returns
    -------
    PoleSweep
        ``poles``, the five non-structural poles [rad/s], shape (n, 5); ``max_real`` [1/s],
        ``min_damping`` [-] and ``natural_hz`` [Hz] per value; ``c_b`` [N m s/rad] and ``dmu``
        [-] of each point.
    """
    v = grid_values(name, values)
    base = (params.operating if base is None else base).resolve(params, traction)
    op: dict[str, Any] = dict(base.to_dict())
    op[name] = v
    terms = linearisation_terms(params, op["r_g"], op["nu"], op["F_s"], op["omega_p"], traction)
    t = {k: np.broadcast_to(a, v.shape) for k, a in terms.items()}
    J, K = mass_stiffness(params)
    A = assemble_reduced(J, K, t["r_g"], t["rho"], t["c_s"])
    poles = track_branches(np.linalg.eigvals(A))
    return PoleSweep(name=name, values=v, base=base, poles=poles,
                     c_b=np.broadcast_to(t["c_b"], v.shape).copy(),
                     dmu=np.broadcast_to(t["dmu"], v.shape).copy())


# --------------------------------------------------------------------------------------------
# Fig. 12: F_s -> nu transfer functions
# --------------------------------------------------------------------------------------------
def slip_frequency_responses(params: Params, ops: Sequence[OperatingPoint],
                             omega: ArrayLike, labels: Sequence[str] | None = None,
                             traction: TractionModel | None = None, input: str = "F_s",
                             output: str = "nu") -> list[FrequencyResponse]:
    """``input -> output`` responses at several operating points (Fig. 12: ``F_s -> nu``).

    Returns one `~empact.lti.FrequencyResponse` per point, ``H`` shape (1, 1, n_f) in
    output units per input unit (``nu`` per N for ``F_s -> nu``); `omega` [rad/s].

    Parameters
    ----------
    params : Params
        Parameter set (variator, driveline, traction).
    ops : sequence of OperatingPoint
        The operating points (each resolved as `empact.slip.model.slip_model` does).
    omega : array_like, shape (n_f,)
        Angular frequencies [rad/s], > 0.
    labels : sequence of str, optional
        One label per point (default: ``"r_g = ..., nu = ... %"``).
    traction : TractionModel, optional
        Traction model (default `traction_from_params(params)`).
    input : {"F_s", "T_d", "T_l"}
        The input of the responses.
    output : {"nu", "omega_p", "omega_s", "T_b"}
        The output of the responses.

    Returns
    -------
    list of FrequencyResponse
        One per point of `ops`, in order, ``H`` of shape (1, 1, n_f).

    Raises
    ------
    ValueError
        When `labels` does not have one entry per point, or for an unknown input or output.
    """
    if labels is not None and len(labels) != len(ops):
        raise ValueError(f"{len(labels)} labels for {len(ops)} operating points")
    out = []
    for k, point in enumerate(ops):
        op = point.resolve(params, traction)
        label = labels[k] if labels is not None else \
            f"r_g = {op.r_g:g}, nu = {100 * op.nu:g} %"
        out.append(slip_model(params, op, traction).frequency_response(omega, [input], [output],
                                                                       label=label))
    return out


# --------------------------------------------------------------------------------------------
# Fig. 13: zeros of F_s -> nu over the ratio
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class ZeroLocus(Result):
    """Zeros of ``F_s -> nu`` away from the origin, over the ratio (Fig. 13).

    Attributes
    ----------
    r_g : ratios [-], shape (n,)
    base : operating point of the other variables
    zeros : nonzero finite zeros [rad/s], shape (n, m), one branch per column (NaN where a
        point has fewer)
    n_origin : number of zeros at the origin at each ratio, shape (n,)
    coupled : finite nonzero poles of the coupled limit ``c_b -> inf`` [rad/s], shape (n, 4)
    """

    r_g: NDArray[np.float64]
    base: ResolvedPoint
    zeros: NDArray[np.complex128]
    n_origin: NDArray[np.int64]
    coupled: NDArray[np.complex128]

    @property
    def zero_hz(self) -> NDArray[np.float64]:
        """``|z| / (2 pi)`` of the upper-half-plane zeros [Hz], shape (n, m // 2), ascending."""
        z = np.where(self.zeros.imag > 0, np.abs(self.zeros), np.nan)
        return np.sort(z, axis=1)[:, : self.zeros.shape[1] // 2] / (2 * np.pi)


def zero_locus(params: Params, r_g: ArrayLike, base: OperatingPoint | None = None,
               traction: TractionModel | None = None, origin_tol: float = 1e-5) -> ZeroLocus:
    """Invariant zeros of ``F_s -> nu`` at each ratio of `r_g` (shape (n,)).

    Zeros with ``|z| < origin_tol * max |z|`` count as zeros at the origin.

    Parameters
    ----------
    params : Params
    r_g : array_like
        Geometric ratios [-], shape (n,).
    base : OperatingPoint, optional
        Slip, clamping force and primary speed (default ``params.operating``).
    traction : TractionModel, optional
        Default `traction_from_params(params)`.
    origin_tol : float
        Relative size below which a zero counts as at the origin [-].

    Returns
    -------
    ZeroLocus
        ``zeros`` [rad/s], shape (n, m), one branch per column; ``n_origin`` per ratio, shape
        (n,); the ``coupled`` limit's poles [rad/s], shape (n, 4).
    """
    r = grid_values("r_g", r_g)
    base = (params.operating if base is None else base).resolve(params, traction)
    found, origin, coupled = [], [], []
    for rk in r:
        m = slip_model(params, base.replace(r_g=float(rk)), traction)
        z = m.zeros("F_s", "nu")
        small = np.abs(z) < origin_tol * max(np.abs(z).max(), 1.0)
        found.append(z[~small])
        origin.append(int(small.sum()))
        c = coupled_limit(params, float(rk), base.nu)
        coupled.append(c[np.abs(c) > 0][:4])
    width = max(len(z) for z in found)
    Z = np.full((len(r), width), np.nan + 0j)
    for k, z in enumerate(found):
        Z[k, :len(z)] = np.sort_complex(z)
    if width and all(len(z) == width for z in found):
        Z = track_branches(Z)
    return ZeroLocus(r_g=r, base=base, zeros=Z, n_origin=np.array(origin),
                     coupled=np.array([np.sort_complex(c) for c in coupled]))


