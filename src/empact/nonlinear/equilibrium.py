"""Steady operating points (trim) of the nonlinear model.

A trimmed point is an equilibrium of the model's state (the driveline is in the rotating frame:
constant shaft speeds, constant twists), with every derivative zero.  It is requested by an
`~empact.params.OperatingPoint`: the ratio ``r_g``, the primary speed ``omega_p`` [rad/s] and
exactly two of the slip (``nu``, or the torque ratio ``tau = mu(nu) / mu_max``), the clamping
force ``F_s`` [N] and the load torque ``T_l`` [N m]; the third follows from the traction
balance ``T_b = 2 mu(nu, r_g) F_s R_s / cos(beta) = T_l + T_drag(omega_s)`` (eq. 1, with
the secondary's drag of `empact.variator.losses`); the drive torque carries the variator's
input power, ``T_d omega_p = P_var_in`` (its losses included).

The point is built in closed form plus scalar root finds, vectorised over many points at once
(`trim_grid`; `trim` is its one-point case): the radii of the stretched belt
(`empact.variator.geometry.stretched_radii`), the slip on the rising branch of the traction
curve (bisection), and the fixed point of the creep law's static force.  Every point is then
checked: the normalised residual of ``dx/dt`` must be below ``1e-8``, else it is marked (and
`trim` raises `TrimError` naming the request).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._deprecate import warn_renamed
from .._results import Result
from ..errors import ParameterError, TrimError
from ..operating import CruisePoint
from ..params import OperatingPoint, ResolvedPoint, check_clamping, check_one_slip
from ..variator import _laws
from ..variator.geometry import check_ratio, radii, ratio_range, stretched_radii
from ..vehicle import road_load
from . import _batch as KB
from .model import EmpactModel

__all__ = ["TrimError", "TrimResult", "TrimGrid", "trim", "trim_grid", "trim_cruise",
           "traction_peak",
           "smallest_slip_reserve", "slip_at_torque_ratio", "RESIDUAL_TOL"]

RESIDUAL_TOL = 1e-8


@dataclass(frozen=True, eq=False)
class TrimResult:
    """A trimmed operating point.

    Attributes
    ----------
    model : EmpactModel
    x : array, shape (n,)
        State, ordered as ``model.states``.
    u : array, shape (4,)
        Inputs, ordered as ``model.inputs``.
    r_g, nu, tau : float
        Ratio, slip and torque ratio ``mu / mu_max`` [-].
    F_s, F_p : float
        Secondary and primary clamping forces [N].
    omega_p, omega_s : float
        Pulley speeds [rad/s].
    T_b, T_d, T_l : float
        Traction torque on the secondary, drive and load torques [N m].
    T_mp, T_ms : float
        Servo holding torques [N m].
    mu : float
        Traction coefficient [-].
    residual : float
        Largest normalised ``|dx/dt|`` at `x` [-].
    request : OperatingPoint
        What was asked for.
    """

    model: EmpactModel
    x: NDArray[np.float64]
    u: NDArray[np.float64]
    r_g: float
    nu: float
    F_s: float
    F_p: float
    omega_p: float
    omega_s: float
    T_b: float
    T_d: float
    T_l: float
    T_mp: float
    T_ms: float
    mu: float
    residual: float
    tau: float = float("nan")
    request: OperatingPoint | None = None

    def to_dict(self) -> dict[str, float]:
        """The scalar fields by name (SI)."""
        return {k: getattr(self, k) for k in ("r_g", "nu", "F_s", "F_p", "omega_p", "omega_s",
                                              "T_b", "T_d", "T_l", "T_mp", "T_ms", "mu",
                                              "tau")}

    def as_dict(self) -> dict[str, float]:
        """Deprecated: `to_dict`."""
        warn_renamed("TrimResult.as_dict", "to_dict")
        return self.to_dict()

    @property
    def point(self) -> ResolvedPoint:
        """The trimmed point given by slip and clamping force (its fields are floats)."""
        return ResolvedPoint(r_g=self.r_g, nu=self.nu, F_s=self.F_s, omega_p=self.omega_p)


@dataclass(frozen=True, eq=False)
class TrimGrid(Result):
    """Trimmed operating points of one model, many at once (`trim_grid`).

    Attributes
    ----------
    model : EmpactModel
    x : array, shape (N, n)
        States (NaN where ``ok`` is False).
    u : array, shape (N, 4)
        Inputs.
    r_g, omega_p, nu, F_s, T_l, tau : arrays, shape (N,)
        The operating variables (requested and solved).
    ok : bool array, shape (N,)
        Trimmed with a normalised residual below `RESIDUAL_TOL`.
    reason : tuple of str, length N
        Why a point failed ('' where ok).
    residual : array, shape (N,)
        Largest normalised ``|dx/dt|`` (inf where the point was not assembled).
    y : array, shape (N, n_y)
        Outputs at the trimmed points.
    """

    _not_data = ("model",)  # to_dict: the arrays (the model is not data)

    model: EmpactModel
    x: NDArray[np.float64]
    u: NDArray[np.float64]
    r_g: NDArray[np.float64]
    omega_p: NDArray[np.float64]
    nu: NDArray[np.float64]
    F_s: NDArray[np.float64]
    T_l: NDArray[np.float64]
    ok: NDArray[np.bool_]
    reason: tuple[str, ...]
    residual: NDArray[np.float64] | None = None
    tau: NDArray[np.float64] | None = None
    y: NDArray[np.float64] | None = None


def traction_peak(model: EmpactModel, r_g: ArrayLike) -> tuple[Any, Any]:
    """Slip at the peak of the kernel's traction curve and the peak value ``(nu_peak,
    mu_peak)`` at ratio(s) `r_g` (golden-section search on [0, 0.99], to rounding; the
    curve is unimodal in slip; compiled: `_batch.traction_peak_many`, bitwise the
    vectorised search `_traction_peak_numpy`).

    Parameters
    ----------
    model : EmpactModel
        Its compiled traction curve is searched.
    r_g : float or array_like
        Geometric ratio(s) [-], > 0, any shape.

    Returns
    -------
    nu_peak, mu_peak : float or ndarray
        Slip [-] at the peak and the peak traction coefficient [-]: floats for a scalar
        `r_g`, else arrays of its shape.

    Raises
    ------
    ValueError
        If a ratio is not positive.
    """
    r = np.atleast_1d(np.asarray(r_g, float))
    if np.any(r <= 0):
        raise ValueError(f"r_g = {r[r <= 0].flat[0]:g}: must be positive")
    flat = np.ascontiguousarray(r.ravel())
    nu, mu = np.empty(flat.size), np.empty(flat.size)
    KB.traction_peak_many(flat, _GOLDEN, model.p, nu, mu)
    if np.ndim(r_g) == 0:
        return float(nu[0]), float(mu[0])
    return nu.reshape(r.shape), mu.reshape(r.shape)


#: the golden section's ratio
_GOLDEN = float((np.sqrt(5) - 1) / 2)


def smallest_slip_reserve(model: EmpactModel, r_g: ArrayLike, nu: ArrayLike,
                          grid: int = 129, candidates: int = 16) -> tuple[float, int]:
    """The smallest distance ``nu_peak(r_g[k]) - nu[k]`` of a slip record to the traction
    peak's slip at its ratio, and its sample ``k``: what `traction_peak` at every sample
    gives, from `grid` + `candidates` peak searches instead of one per sample.

    The peak's slip is interpolated (linearly in ``ln r_g``) from `grid` searches spanning
    the record's ratios; the `candidates` samples of smallest interpolated reserve are then
    searched exactly, and the smallest exact reserve among them is returned.  The answer is
    the per-sample search's unless a sample outside the candidates lies closer to the peak
    than they do by more than the interpolation's error (below 1e-9 in slip on the shipped
    curves; `tests/test_loop.py` compares the two on every shipped closed-loop run).

    Parameters
    ----------
    model : EmpactModel
    r_g : array_like, shape (n,)
        Geometric ratios [-], > 0.
    nu : array_like, shape (n,)
        Slips [-] at those ratios.
    grid, candidates : int
        Searches of the interpolation grid and of the exact refinement.

    Returns
    -------
    reserve : float
        ``min_k (nu_peak(r_g[k]) - nu[k])`` [-].
    k : int
        Its sample.
    """
    r = np.asarray(r_g, float).ravel()
    s = np.asarray(nu, float).ravel()
    if r.shape != s.shape or r.size == 0:
        raise ValueError(f"r_g and nu: equal, non-empty lengths (got {r.size}, {s.size})")
    if r.size <= grid + candidates:
        res = np.asarray(traction_peak(model, r)[0]) - s
        k = int(np.argmin(res))
        return float(res[k]), k
    lr = np.log(r)
    q = np.exp(np.linspace(lr.min(), lr.max(), grid))
    approx = np.interp(lr, np.log(q), np.asarray(traction_peak(model, q)[0])) - s
    pick = np.argpartition(approx, candidates - 1)[:candidates]
    pick.sort()
    exact = np.asarray(traction_peak(model, r[pick])[0]) - s[pick]
    j = int(np.argmin(exact))
    return float(exact[j]), int(pick[j])


def _traction_peak_numpy(model: EmpactModel, r_g: ArrayLike) -> tuple[Any, Any]:
    """`traction_peak` as a vectorised NumPy search (the reference its compiled search is
    checked against)."""
    r = np.atleast_1d(np.asarray(r_g, float))
    g = (np.sqrt(5) - 1) / 2
    a, b = np.zeros(r.shape), np.full(r.shape, 0.99)
    c, d = b - g * (b - a), a + g * (b - a)
    fc, fd = model.traction(c, r), model.traction(d, r)
    for _ in range(90):
        left = fc > fd  # the peak lies in [a, d]
        b, a = np.where(left, d, b), np.where(left, a, c)
        c, d = np.where(left, b - g * (b - a), d), np.where(left, c, a + g * (b - a))
        fc, fd = model.traction(c, r), model.traction(d, r)
    nu = 0.5 * (a + b)
    mu = model.traction(nu, r)
    if np.ndim(r_g) == 0:
        return float(nu[0]), float(mu[0])
    return nu, mu


def trim(model: EmpactModel, op: OperatingPoint | float, omega_p: float | None = None, *,
         nu: float | None = None, F_s: float | None = None,
         T_l: float | None = None) -> TrimResult:
    """Steady operating point of `model`.

    Parameters
    ----------
    model : EmpactModel
    op : OperatingPoint
        The request: ``r_g`` inside the variator's range, ``omega_p`` > 0 and two of the
        slip (``nu`` or ``tau``), ``F_s`` > 0 and ``T_l``.  With ``belt="locked"`` give
        ``F_s`` and ``T_l`` (the slip is 0).
    omega_p, nu, F_s, T_l : float, optional
        The deprecated form ``trim(model, r_g, omega_p, nu=..., F_s=..., T_l=...)`` of empact
        0.1 (a DeprecationWarning); give an `OperatingPoint` instead.

    Returns
    -------
    TrimResult

    Raises
    ------
    TrimError
        Naming the request, when no steady point exists (load beyond the traction capacity,
        slip that cannot carry the load, slack belt) or the residual check fails.

    Examples
    --------
    >>> from empact import OperatingPoint, default_params, nonlinear_model
    >>> m = nonlinear_model(default_params())
    >>> op = trim(m, OperatingPoint(r_g=1.0, omega_p=300.0, F_s=10e3, T_l=50.0))
    >>> bool(op.residual < 1e-8), round(op.T_b, 6)
    (True, 50.0)
    """
    if isinstance(op, CruisePoint):
        if omega_p is not None or nu is not None or F_s is not None or T_l is not None:
            raise ParameterError("trim: give a CruisePoint alone")
        if not model.vehicle:
            raise ParameterError("trim: a CruisePoint needs the vehicle driveline (model "
                                 "option driveline = 'vehicle'): the road load sets T_l")
    elif not isinstance(op, OperatingPoint):
        warn_renamed("trim(model, r_g, omega_p, nu=, F_s=, T_l=)", "trim(model, op) with an "
                     "OperatingPoint")
        if omega_p is None:
            raise ParameterError("operating point: omega_p (primary speed [rad/s]) is missing")
        op = OperatingPoint(r_g=op, omega_p=omega_p, nu=nu, F_s=F_s, T_l=T_l)
    elif omega_p is not None or nu is not None or F_s is not None or T_l is not None:
        raise ParameterError("trim: give an OperatingPoint alone")
    check_ratio(op.r_g, model.params.variator)
    if op.nu is not None:
        lo, hi = model.traction_law.nu_range
        if not lo <= op.nu <= hi:
            raise ParameterError(f"nu = {op.nu:g}: outside the valid slip range [{lo:g}, "
                                 f"{hi:g}] of the traction curve")
    if op.F_s is not None:
        check_clamping("F_s", op.F_s)
    request = "trim request (" + ", ".join(f"{k} = {v:g}" for k, v in op.to_dict().items()) \
        + ")"
    if isinstance(op, CruisePoint):
        grid = trim_cruise(model, op.r_g, op.omega_p, nu=op.nu, F_s=op.F_s, tau=op.tau)
    else:
        grid = trim_grid(model, op.r_g, op.omega_p, nu=op.nu, F_s=op.F_s, T_l=op.T_l,
                         tau=op.tau)
    if not grid.ok[0]:
        raise TrimError(f"{request}: {grid.reason[0]}")
    assert grid.y is not None and grid.residual is not None  # trim_grid fills both
    y = dict(zip(model.outputs, grid.y[0]))
    return TrimResult(model=model, x=grid.x[0], u=grid.u[0], r_g=y["r_g"], nu=y["nu"],
                      F_s=y["F_s"], F_p=y["F_p"], omega_p=float(grid.omega_p[0]),
                      omega_s=y["omega_s"], T_b=y["T_b"], T_d=y["T_d_act"], T_l=y["T_l_act"],
                      T_mp=y["T_mp_act"], T_ms=y["T_ms_act"], mu=y["mu"],
                      residual=float(grid.residual[0]), tau=y["tau"], request=op)


def slip_at_torque_ratio(model: EmpactModel, tau: ArrayLike, r_g: ArrayLike, *,
                         peak: tuple[ArrayLike, ArrayLike] | None = None
                         ) -> NDArray[np.float64]:
    """The slip on the rising branch of the kernel's traction curve where ``mu = tau mu_max``
    (a set-point with the torque reserve ``1 - tau``), at ratio(s) `r_g` (broadcast; to
    rounding).

    Parameters
    ----------
    model : EmpactModel
        Its compiled traction curve is used.
    tau : array_like
        Torque ratio(s) ``mu / mu_max`` [-] in [0, 1] (the torque reserve is ``1 - tau``).
    r_g : array_like
        Geometric ratio(s) [-], broadcast with `tau`.
    peak : (array_like, array_like), optional
        The traction peak ``(nu_peak, mu_peak)`` at `r_g` (`traction_peak`'s, broadcast with
        it) when the caller has searched it already (not searched again: the same result).

    Returns
    -------
    ndarray
        The slip ``nu`` [-] (>= 0, at most the peak's), the broadcast shape of `tau` and
        `r_g`.

    Raises
    ------
    ParameterError
        If a `tau` is not in [0, 1].
    """
    t, r = np.broadcast_arrays(np.asarray(tau, float), np.asarray(r_g, float))
    if np.any(~((t >= 0) & (t <= 1))):
        bad = t[~((t >= 0) & (t <= 1))].flat[0]
        raise ParameterError(f"tau = {bad:g}: a torque ratio lies in [0, 1]")
    shape = t.shape
    t, r = t.ravel(), r.ravel()
    nu_pk, mu_pk = _peak_at(model, r, peak, shape)
    goal = np.minimum(t * model.mu_max(r), mu_pk)
    return _bisect_rising(model, r, goal, np.atleast_1d(nu_pk)).reshape(shape)


def _peak_at(model: EmpactModel, r: NDArray, peak: tuple[ArrayLike, ArrayLike] | None,
             shape: tuple[int, ...]) -> tuple[NDArray, NDArray]:
    """The traction peak ``(nu_peak, mu_peak)`` at the ratios `r` (1-D): `peak` (given at
    ratios of the broadcast shape `shape`, flattened), else searched (`traction_peak`)."""
    if peak is None:
        nu_pk, mu_pk = traction_peak(model, r)
        return np.atleast_1d(nu_pk), np.atleast_1d(mu_pk)
    return tuple(np.broadcast_to(np.asarray(v, float), shape).ravel()  # type: ignore[return-value]
                 for v in peak)


def _bisect_rising(model: EmpactModel, r: NDArray, target: NDArray, nu_pk: NDArray) -> NDArray:
    """The slip in ``[0, nu_pk]`` where the kernel's curve reaches ``|target|`` (64 bisection
    steps: to rounding, compiled: `_batch.bisect_rising_many`), with the sign of `target`
    (arrays of one shape)."""
    if np.any(r <= 0):
        raise ValueError(f"r_g = {r[r <= 0].flat[0]:g}: must be positive")
    shape = np.shape(r)
    r_, goal, top = (np.ascontiguousarray(np.broadcast_to(np.asarray(v, float), shape)).ravel()
                     for v in (r, np.abs(target), nu_pk))
    out = np.empty(r_.size)
    KB.bisect_rising_many(r_, goal, top, model.p, out)
    return np.sign(target) * out.reshape(shape)


def _contact(model: EmpactModel, r, F_contact, tau_of):
    """Radii of the stretched belt whose secondary *clamping* force (the belt element's minus
    the creep law's static force) is `F_contact`: a fixed point on the belt element's force
    ``F_el = F_s (a + kappa* b) / (a + kappa_geo b)``, each point stopping on its own
    convergence.  `tau_of(R_s, F_el)` gives the torque ratio."""
    v, c = model.params.variator, model.constants
    radii = lambda F: stretched_radii(r, F, v.L_belt, v.a, v.beta, c.k_belt)  # noqa: E731
    F_el = np.array(F_contact, float)
    if not model.creep:
        return radii(F_el)
    active = np.ones(r.shape, dtype=bool)
    for _ in range(60):
        R_p, R_s, phi, e = radii(F_el)
        kgeo = _laws.kappa_geo(phi)
        _, keq = model.static_creep(r, R_p, R_s, phi, F_el, tau_of(R_s, F_el))
        a, b = r / (c.tan_beta * R_p), r / (c.tan_beta * R_s)
        new = np.where(active, F_contact * (a + keq * b) / (a + kgeo * b), F_el)
        active &= np.abs(new - F_el) > 1e-13 * np.abs(F_contact)
        F_el = new
        if not active.any():
            break
    return radii(F_el)


def trim_grid(model: EmpactModel, r_g, omega_p, *, nu=None, F_s=None, T_l=None,
              tau=None, peak=None) -> TrimGrid:
    """`trim` at many points at once (1-D arrays, broadcast): the closed-form assembly and
    the root finds of the module notes, vectorised, then the residual check.  Points that
    cannot be trimmed are marked (``ok``, ``reason``), never dropped.

    Parameters as `OperatingPoint`: exactly two of the slip (`nu` or `tau`), `F_s`, `T_l`.

    Parameters
    ----------
    model : EmpactModel
    r_g : array_like, shape (N,)
        Geometric ratios [-].
    omega_p : array_like, shape (N,)
        Primary speeds [rad/s], > 0.
    nu : array_like, shape (N,), optional
        Slips [-].
    F_s : array_like, shape (N,), optional
        Secondary clamping forces [N], > 0.
    T_l : array_like, shape (N,), optional
        Load torques [N m].
    tau : array_like, shape (N,), optional
        Torque ratios ``mu / mu_max`` [-] (a slip on the rising branch of the traction
        curve), in place of `nu`.
    peak : (array_like, array_like), shape (N,) each, optional
        The traction peak ``(nu_peak, mu_peak)`` at `r_g` (`traction_peak`'s) when the
        caller has searched it already (not searched again: the same result).

    Returns
    -------
    TrimGrid
        All N points (the broadcast size of the arguments, scalars as length 1): states,
        inputs, outputs and the solved operating variables, with ``ok``, ``reason`` and
        ``residual`` per point.

    Raises
    ------
    TrimError
        When the arguments do not give exactly two of the slip, `F_s` and `T_l` (with
        ``belt="locked"``: `F_s`, optionally `T_l`, and no slip).
    """
    locked = model.options.belt == "locked"
    check_one_slip(nu is not None, tau is not None, where="trim_grid: ", error=TrimError)
    slip_given = nu is not None or tau is not None
    if locked:
        if F_s is None or slip_given:
            raise TrimError("trim with belt = 'locked': give F_s (and T_l); the slip is 0")
        T_l = 0.0 if T_l is None else T_l
    elif sum(v is not None for v in (nu if nu is not None else tau, F_s, T_l)) != 2:
        raise TrimError("trim: give exactly two of nu (or tau), F_s, T_l")
    nan = np.nan
    arrays = [np.atleast_1d(np.asarray(v if v is not None else nan, float))
              for v in (r_g, omega_p, nu, F_s, T_l, tau)]
    r, w, nu_, Fs, Tl, tau_ = (np.array(a, float) for a in np.broadcast_arrays(*arrays))
    N = r.size
    c = model.constants
    cosb = c.cos_beta
    lo, hi = ratio_range(model.params.variator)
    reason = np.full(N, "", dtype=object)
    reason[~((r >= lo * (1 - 1e-12)) & (r <= hi * (1 + 1e-12)))] = \
        f"r_g outside the variator's range [{lo:.4g}, {hi:.4g}]"
    reason[~(w > 0)] = "omega_p must be > 0 [rad/s]"
    if F_s is not None:
        reason[(reason == "") & ~(Fs > 0)] = "F_s must be > 0 [N]"
    good = reason == ""
    r = np.where(good, r, 1.0)
    mu_max = model.mu_max(r)
    if tau is not None:  # the slip where mu = tau mu_max, on the rising branch
        nu_pk, mu_pk = _peak_at(model, r, peak, r.shape)
        for k in np.flatnonzero(good & ~(np.abs(tau_) * mu_max <= mu_pk)):
            reason[k] = (f"tau = {tau_[k]:g} needs mu = {abs(tau_[k]) * mu_max[k]:.4g}, above "
                         f"the traction peak {mu_pk[k]:.4g} at r_g = {r[k]:g}")
        good = reason == ""
        nu_ = np.where(good, _bisect_rising(model, r, tau_ * mu_max, nu_pk), 0.0)
        nu = nu_
    mu = model.traction(np.nan_to_num(nu_), r) if nu is not None else np.full(N, nan)

    # the belt torque Tb on the secondary: the load torque and the secondary's drag
    # (`_kernel._losses`) where T_l is given, which depends on the slip through omega_s
    def belt_torque(slip):
        return Tl + _drag(c, (1.0 - slip) * r * w)

    if locked:
        nu_ = np.zeros(N)
        Tb = belt_torque(nu_)
        R_p, R_s, phi, e = _contact(model, r, Fs,
                                    lambda R_s, F_el: Tb * cosb / (2 * mu_max * F_el * R_s))
        tau_kernel = lambda R_s, F_el: Tb * cosb / (2 * mu_max * F_el * R_s)  # noqa: E731
    elif nu is not None and F_s is not None:
        R_p, R_s, phi, e = _contact(model, r, Fs, lambda R_s, F_el: mu / mu_max)
        Tb = 2 * mu * Fs * R_s / cosb
        tau_kernel = lambda R_s, F_el: mu / mu_max  # noqa: E731
    elif nu is not None:  # nu and T_l: find F_s (R_s depends weakly on F_s: fixed point)
        for k in np.flatnonzero(good & ~(mu * Tl > 0)):
            reason[k] = (f"mu(nu) = {mu[k]:.4g} cannot carry T_l = {Tl[k]:g} N m with a "
                         "positive clamping force")
        good = reason == ""
        Tb = belt_torque(np.nan_to_num(nu_))
        R_s = np.array(radii(r, model.params.variator.L_belt, model.params.variator.a)[1])
        active = good.copy()
        for _ in range(40):
            Fs = np.where(good, Tb * cosb / (2 * mu * R_s), 1e4)
            R_p, R_s_new, phi, e = _contact(model, r, Fs, lambda R_s, F_el: mu / mu_max)
            R_s_new = np.where(active, R_s_new, R_s)
            active &= np.abs(R_s_new - R_s) >= 1e-15
            R_s = R_s_new
            if not active.any():
                break
        Fs = np.where(good, Tb * cosb / (2 * mu * R_s), 1e4)
        R_p, R_s, phi, e = _contact(model, r, Fs, lambda R_s, F_el: mu / mu_max)
        tau_kernel = lambda R_s, F_el: mu / mu_max  # noqa: E731
    else:  # F_s and T_l: the slip on the rising branch (with the drag at that slip: a fixed
        # point that contracts by ~1e-5 per pass, the drag's slope in the slip being small)
        nu_pk, mu_pk = _peak_at(model, r, peak, r.shape)
        nu_ = np.zeros(N)
        for _ in range(4):
            Tb = belt_torque(nu_)
            R_p, R_s, phi, e = _contact(model, r, Fs,
                                        lambda R_s, F_el: Tb * cosb / (2 * Fs * R_s) / mu_max)
            need = Tb * cosb / (2 * Fs * R_s)
            fits = good & (np.abs(need) <= mu_pk)
            nu_ = np.where(fits, _bisect_rising(model, r, np.where(fits, need, 0.0), nu_pk),
                           0.0)
        for k in np.flatnonzero(good & ~(np.abs(need) <= mu_pk) & np.isfinite(R_s)):
            reason[k] = (f"T_l = {Tl[k]:g} N m needs mu = {abs(need[k]):.4g}, above the "
                         f"traction peak {mu_pk[k]:.4g} at F_s = {Fs[k]:g} N (slip would run "
                         "away)")
        good = reason == ""
        mu = model.traction(nu_, r)
        tau_kernel = lambda R_s, F_el: mu / mu_max  # noqa: E731
    belt = "actuation" if model.options.kinematics == "equal-translation" else "paper_sec21"
    reason[(reason == "") & ~np.isfinite(R_s)] = "no belt geometry carries the clamping " \
        f"force (belt stretch too large for {belt}.k_belt)"
    good = reason == ""
    x, u, F_p_act = _assemble(model, r, w, nu_, Tb, R_p, R_s, phi, e, tau_kernel)
    # the drive and load torques that hold the variator's shafts (its losses included:
    # T_d omega_p = P_var_in, T_l omega_s = P_var_out), then the check: every derivative
    # zero, normalised by the forces on each body
    residual = np.full(N, np.inf)
    g = np.flatnonzero(good)
    y = np.full((N, len(model.outputs)), nan)
    if g.size:
        _, y[g] = model.evaluate_many(x[g], u[g])
        omega_s = (1 - nu_) * r * w
        if T_l is None:  # the load torque: the belt's less the secondary's drag
            Tl = Tb - _drag(c, omega_s)
        # the drive torque: the belt's on the primary and the primary's losses (each exactly
        # zero without [losses]: then the trim is the lossless one to the bit)
        lp = (y[:, model.output_index("P_loss_clamp")]
              + y[:, model.output_index("P_loss_load")]
              + y[:, model.output_index("P_loss_map")]) / w
        T_d = np.where(good, r * Tb + lp + _drag(c, w), r * Tb)
        _driveline(model, x, u, T_d, Tl, w, omega_s)
        if model.vehicle:  # the load torque beyond the road load and the final drive's
            # loss (which the kernel adds, `_kernel._vehicle_load`): T_l_act = T_l
            _, y[g] = model.evaluate_many(x[g], u[g])
            u[g, 3] -= y[g, model.output_index("T_l_act")] - u[g, 3]
        dx, y[g] = model.evaluate_many(x[g], u[g])
        residual[g] = _residual(model, dx, y[g], F_p_act[g], u[g])
    for k in np.flatnonzero(good & ~(residual < RESIDUAL_TOL)):
        reason[k] = (f"steady-state residual {residual[k]:.3g} above {RESIDUAL_TOL:g} (no "
                     "equilibrium found)")
    good = reason == ""
    x[~good] = nan
    u[~good] = nan
    tau_out = y[:, model.output_index("tau")]
    return TrimGrid(model=model, x=x, u=u, r_g=r, omega_p=w, nu=nu_, F_s=Fs, T_l=Tl, ok=good,
                    reason=tuple(reason.tolist()), residual=residual, tau=tau_out, y=y)


def trim_cruise(model: EmpactModel, r_g, omega_p, *, nu=None, F_s=None,
                tau=None) -> TrimGrid:
    """The car's steady cruise at many points (the vehicle driveline; 1-D arrays,
    broadcast): `trim_grid` at the load torque the road load and the final drive's loss ask
    at the speed the point drives, no brake (the input ``T_l``, the load torque beyond them,
    zero to rounding: below 1e-12 of the load torque).

    The load torque ``T_l`` solves ``T_l = T_road(omega_s) + T_fd(T_l, omega_s)`` (the
    kernel's `_kernel._vehicle_load`, read from the model's outputs, so the law is written
    once) with the secondary speed ``omega_s = (1 - nu) r_g omega_p`` of the trim at that
    load: a fixed point that contracts by the final drive's loss slope (``1 - eta_fd``) and
    the slip's change with the load, iterated to 1e-13 of the load torque.

    Parameters
    ----------
    model : EmpactModel
        A model of the vehicle driveline (``driveline = "vehicle"``).
    r_g, omega_p : array_like, shape (N,)
        Ratios [-] and primary (engine) speeds [rad/s].
    nu, F_s, tau : array_like, shape (N,), optional
        Exactly one: the slip [-], the clamping force [N] or the torque ratio [-].

    Returns
    -------
    TrimGrid
        As `trim_grid`'s, ``T_l`` the road's load torque [N m].

    Raises
    ------
    TrimError
        For a bench model, or not exactly one of `nu` (or `tau`) and `F_s`.
    """
    if not model.vehicle:
        raise TrimError("trim_cruise: the road load needs the vehicle driveline (model "
                        "option driveline = 'vehicle')")
    check_one_slip(nu is not None, tau is not None, where="trim_cruise: ", error=TrimError)
    if (nu is not None or tau is not None) == (F_s is not None):
        raise TrimError("trim_cruise: give exactly one of nu (or tau), F_s (the road load "
                        "sets T_l)")
    one = {k: v for k, v in (("nu", nu), ("tau", tau), ("F_s", F_s)) if v is not None}
    arrays = [np.atleast_1d(np.asarray(v, float)) for v in (r_g, omega_p, *one.values())]
    r, w, *rest = np.broadcast_arrays(*arrays)
    one = dict(zip(one, rest))
    c = model.constants
    v0 = c.vehicle_gear * r * w  # the start: the road load without slip, through eta_fd
    T = c.vehicle_gear * road_load(model.params.vehicle, v0) / c.eta_fd
    g = trim_grid(model, r, w, T_l=T, **one)
    for _ in range(60):
        brake = np.where(g.ok, g.u[:, 3], 0.0)
        T = T - brake  # the road's torque at this state: T_l less the brake that held it
        g = trim_grid(model, r, w, T_l=T, **one)
        if np.all(~g.ok | (np.abs(g.u[:, 3]) <= 1e-13 * (np.abs(T) + 1.0))):
            break
    return g


def _servo_statics(model: EmpactModel, F_p_act, F_s_act, q5, q6):
    """Servo-side coordinates q1..q4 [rad] and holding torques T_mp, T_ms [N m] that carry the
    actuator forces `F_p_act`, `F_s_act` [N] with the sheaves at `q5`, `q6` [m]."""
    a, c = model.params.actuation, model.constants
    sig = c.sheave_sense
    q3 = (-F_p_act / c.k_tp - q5) / a.s
    q4 = q3 + (sig * F_s_act / c.k_ts - q6) / a.s
    T_c = a.i_e * a.s * sig * F_s_act
    q2 = a.i_c * (T_c / c.k_c + q4 / a.i_e)
    T_w = -a.i_e * a.s * (F_p_act + sig * F_s_act)
    q1 = a.i_w * (T_w / c.k_w + q3 / a.i_e)
    return q1, q2, q3, q4, T_w / a.i_w, T_c / a.i_c


def _drag(c, omega):
    """The drag torque of a pulley shaft at speed `omega` [rad/s] (`_kernel._losses`:
    ``c_v omega + c_q omega^2 tanh(omega / coulomb_omega)``; `c` the kernel constants); none
    with a measured loss map, whose loss acts on the primary alone (``P_loss_map``)."""
    if c.loss_table != 0.0:
        return 0.0 * omega
    return c.loss_c_v * omega + c.loss_c_q * omega * omega * np.tanh(omega / c.coulomb_omega)


def _driveline(model: EmpactModel, x, u, T_d, T_l, w, omega_s) -> None:
    """Set the driveline's twists, torques and speed-loop integrals of the points `x`, `u` (in
    place) to the drive torque `T_d` and the load torque `T_l` [N m] at the speeds `w`,
    `omega_s` [rad/s] (the kernel's driveline: the bench's or the car's)."""
    d, si = model.constants, model.state_index
    x[:, si("twist_tc")] = T_d / d.k_tc
    x[:, si("twist_ds")] = T_l / d.k_ds
    u[:, 2], u[:, 3] = T_d, T_l
    if "z_d" in model.states:
        x[:, si("z_d")], u[:, 2] = T_d, w
    if "z_l" in model.states:
        x[:, si("z_l")], u[:, 3] = T_l, omega_s


def _assemble(model: EmpactModel, r, w, nu, Tl, R_p, R_s, phi, e, tau_of):
    """States and inputs of the trimmed points (arrays): the actuator forces carry the
    clamping forces (the belt element's and the static creep force at the torque ratio the
    kernel computes), the driveline turns at the slip's speeds with its twists carrying the
    belt torque `Tl` (without the variator's losses: `trim_grid` then sets the driveline's
    torques, `_driveline`).  Returns ``(x, u, F_p_act)``."""
    v, c = model.params.variator, model.constants
    d = c  # the kernel's driveline (the bench's or the car's)
    tb = c.tan_beta
    N_b = c.k_belt * e
    F_p = N_b * (np.pi + 2 * phi) / tb
    F_el = N_b * (np.pi - 2 * phi) / tb
    q5 = (R_p - v.R_min) * tb
    q6 = c.sheave_sense * (c.R_s0 - R_s) * tb
    lam, _ = model.static_creep(r, R_p, R_s, phi, F_el, tau_of(R_s, F_el))
    F_p_act = F_p + lam * r / (tb * R_p)
    F_s_act = F_el - lam * r / (tb * R_s)
    q1, q2, q3, q4, T_mp, T_ms = _servo_statics(model, F_p_act, F_s_act, q5, q6)
    omega_s = (1 - nu) * r * w
    T_d = r * Tl
    N = r.size
    x = np.zeros((N, model.n))
    si = model.state_index
    for name, value in (("theta_mp", q1), ("theta_ms", q2), ("theta_sp", q3),
                        ("theta_ss", q4), ("x_p", q5), ("x_s", q6),
                        ("twist_tc", T_d / d.k_tc), ("twist_ds", Tl / d.k_ds),
                        ("omega_d", w), ("omega_p", w), ("omega_s", omega_s),
                        ("omega_l", omega_s)):
        x[:, si(name)] = value
    u = np.column_stack([T_mp, T_ms, T_d, Tl])
    states = model.states
    if "s_b" in states:
        x[:, si("s_b")] = Tl / (R_s * c.k_belt_driveline)
    if "z_d" in states:
        x[:, si("z_d")], u[:, 2] = T_d, w
    if "z_l" in states:
        x[:, si("z_l")], u[:, 3] = Tl, omega_s
    if "z_r" in states:  # the integral carries the holding torque
        x[:, si("z_r")], u[:, 0] = T_mp, r
    return x, u, F_p_act


def _residual(model: EmpactModel, dx, y, F_p_act, u) -> NDArray[np.float64]:
    """Largest ``|dx_i/dt|`` of each point normalised by the size of the forces on each body
    (positions and twist rates: absolute, they are exactly zero at a trim)."""
    a, d = model.params.actuation, model.constants
    F = np.abs(F_p_act) + np.abs(y[:, model.output_index("F_s")]) + 1.0
    torque_act = a.s * F
    torque_dl = np.abs(y[:, model.output_index("T_d_act")]) + np.abs(u[:, 3]) + 1.0
    scale = np.ones_like(dx)
    si = model.state_index
    for name, value in (("omega_mp", torque_act / a.J_mp), ("omega_ms", torque_act / a.J_ms),
                        ("omega_sp", torque_act / a.J_sp), ("omega_ss", torque_act / a.J_ss),
                        ("v_p", F / a.m_p), ("v_s", F / a.m_s),
                        ("omega_d", torque_dl / d.J_d), ("omega_p", torque_dl / d.J_p),
                        ("omega_s", torque_dl / d.J_s), ("omega_l", torque_dl / d.J_l)):
        scale[:, si(name)] = value
    return np.max(np.abs(dx) / scale, axis=1)
