"""Steady operating points (trim) of the nonlinear model.

A trimmed point is an equilibrium of the model's state (the driveline is in the rotating frame:
constant shaft speeds, constant twists), with every derivative zero.  It is requested by the
ratio ``r_g``, the primary speed ``omega_p`` [rad/s] and exactly two of slip ``nu``, clamping
force ``F_s`` [N] and load torque ``T_l`` [N m]; the third follows from the traction balance
``T_b = 2 mu(nu, r_g) F_s R_s / cos(beta) = T_l`` (eq. 1).

The point is built in closed form plus two scalar root finds (the radii of the stretched belt,
and ``mu(nu) = mu_required`` on the rising branch of the traction curve), then checked: the
normalised residual of ``dx/dt`` must be below ``1e-8``, else `TrimError`.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import brentq, minimize_scalar

from .._validate import check_number
from ..errors import TrimError
from ..geometry import belt_length, check_ratio, radii, ratio_range, wrap_angle
from ..traction import traction_from_params
from . import _kernel as K
from .model import EmpactModel

__all__ = ["TrimError", "TrimResult", "TrimGrid", "trim", "trim_grid", "traction_peak"]

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
    r_g, nu : float
        Ratio and slip [-].
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

    def as_dict(self) -> dict[str, float]:
        """The scalar fields by name (SI)."""
        return {k: getattr(self, k) for k in ("r_g", "nu", "F_s", "F_p", "omega_p", "omega_s",
                                              "T_b", "T_d", "T_l", "T_mp", "T_ms", "mu")}


def traction_peak(model: EmpactModel, r_g: float) -> tuple[float, float]:
    """Slip at the peak of the traction curve and the peak value ``(nu_peak, mu_peak)``."""
    res = minimize_scalar(lambda nu: -K.traction_mu(nu, r_g, model.p), bounds=(0.0, 0.99),
                          method="bounded", options={"xatol": 1e-12})
    return float(res.x), float(-res.fun)


def _belt_radii(model: EmpactModel, r_g: float, F_s: float, request: str) -> tuple[float, ...]:
    """Radii of the stretched belt carrying clamping force F_s at ratio r_g."""
    v, k = model.params.variator, model.p[K.P_KBELT]
    tb = np.tan(v.beta)

    def f(R_s: float) -> float:
        phi = float(wrap_angle(r_g * R_s, R_s, v.a))
        return float(belt_length(r_g * R_s, R_s, v.a)) - v.L_belt \
            - F_s * tb / (k * (np.pi - 2 * phi))

    _, R_s0 = radii(r_g, v.L_belt, v.a)
    R_s0 = float(R_s0)
    try:
        R_s = brentq(f, 0.98 * R_s0, 1.02 * R_s0, xtol=1e-15, rtol=1e-15)
    except ValueError:
        raise TrimError(f"{request}: no belt geometry carries F_s = {F_s:g} N at r_g = "
                        f"{r_g:g} (belt stretch too large for k_belt = {k:g} N/m)") from None
    R_p = r_g * R_s
    phi = float(np.arcsin((R_p - R_s) / v.a))
    e = F_s * tb / (k * (np.pi - 2 * phi))
    return R_p, R_s, phi, e


def trim(model: EmpactModel, r_g: float, omega_p: float, *, nu: float | None = None,
         F_s: float | None = None, T_l: float | None = None) -> TrimResult:
    """Steady operating point of `model`.

    Parameters
    ----------
    model : EmpactModel
    r_g : float
        Geometric ratio [-], inside the variator's range.
    omega_p : float
        Primary pulley speed [rad/s], > 0.
    nu, F_s, T_l : float, optional
        Exactly two of: slip [-] in (-1, 1), secondary clamping force [N] > 0, load torque
        [N m].  With ``belt="locked"`` give `F_s` (and optionally `T_l`, default 0); `nu` must
        then be 0 or omitted.

    Returns
    -------
    TrimResult

    Raises
    ------
    TrimError
        Naming the request, when no steady point exists (load beyond the traction capacity,
        slip that cannot carry the load, slack belt) or the residual check fails.
    """
    r_g = float(check_ratio(check_number("r_g", r_g), model.params.variator))
    omega_p = check_number("omega_p", omega_p, 0.0, lo_open=True, unit="rad/s")
    if nu is not None:
        lo, hi = traction_from_params(model.params).nu_range
        nu = check_number("nu", nu, lo, hi, note="the valid slip range of the traction curve")
    if F_s is not None:
        F_s = check_number("F_s", F_s, 0.0, lo_open=True, unit="N")
    if T_l is not None:
        T_l = check_number("T_l", T_l, unit="N m")
    request = (f"trim request (r_g = {r_g:g}, omega_p = {omega_p:g} rad/s, nu = {nu}, "
               f"F_s = {F_s}, T_l = {T_l})")
    locked = model.options.belt == "locked"
    cosb = np.cos(model.params.variator.beta)
    if locked:
        if F_s is None or (nu not in (None, 0, 0.0)):
            raise TrimError(f"{request}: with belt = 'locked' give F_s (and T_l); the slip is 0")
        nu, T_l = 0.0, 0.0 if T_l is None else float(T_l)
    elif sum(v is not None for v in (nu, F_s, T_l)) != 2:
        raise TrimError(f"{request}: give exactly two of nu, F_s, T_l")

    mu_max = _mu_max(model, r_g)
    if locked:
        R_p, R_s, phi, e = _contact_radii(
            model, r_g, F_s, lambda R_s, F_el: T_l * cosb / (2 * mu_max * F_el * R_s), request)
    elif nu is not None and F_s is not None:
        mu = K.traction_mu(nu, r_g, model.p)
        R_p, R_s, phi, e = _contact_radii(model, r_g, F_s, lambda R_s, F_el: mu / mu_max,
                                          request)
        T_l = 2 * mu * F_s * R_s / cosb
    elif nu is not None:  # nu and T_l: find F_s (R_s depends weakly on F_s: fixed point)
        mu = K.traction_mu(nu, r_g, model.p)
        if mu * T_l <= 0:
            raise TrimError(f"{request}: mu(nu) = {mu:.4g} cannot carry T_l = {T_l:g} N m "
                            f"with a positive clamping force")
        R_s = float(radii(r_g, model.params.variator.L_belt, model.params.variator.a)[1])
        for _ in range(30):
            F_s = T_l * cosb / (2 * mu * R_s)
            R_p, R_s_new, phi, e = _contact_radii(model, r_g, F_s,
                                                  lambda R_s, F_el: mu / mu_max, request)
            done = abs(R_s_new - R_s) < 1e-15
            R_s = R_s_new
            if done:
                break
        F_s = T_l * cosb / (2 * mu * R_s)
        R_p, R_s, phi, e = _contact_radii(model, r_g, F_s, lambda R_s, F_el: mu / mu_max,
                                          request)
    else:  # F_s and T_l: find nu on the rising branch of the traction curve
        R_p, R_s, phi, e = _contact_radii(
            model, r_g, F_s, lambda R_s, F_el: T_l * cosb / (2 * F_s * R_s) / mu_max, request)
        need = T_l * cosb / (2 * F_s * R_s)
        nu_pk, mu_pk = traction_peak(model, r_g)
        if abs(need) > mu_pk:
            raise TrimError(f"{request}: T_l = {T_l:g} N m needs mu = {abs(need):.4g}, above "
                            f"the traction peak {mu_pk:.4g} at F_s = {F_s:g} N (slip would "
                            f"run away)")
        if need == 0:
            nu = 0.0
        else:
            sgn = np.sign(need)
            nu = sgn * brentq(lambda n: K.traction_mu(n, r_g, model.p) - abs(need), 0.0,
                              nu_pk, xtol=1e-15, rtol=1e-14)
    x, u, named = _assemble(model, r_g, omega_p, float(nu), float(F_s), float(T_l),
                            R_p, R_s, phi, e)
    residual = _residual(model, x, u, named)
    if not residual < RESIDUAL_TOL:
        raise TrimError(f"{request}: steady-state residual {residual:.3g} above "
                        f"{RESIDUAL_TOL:g} (no equilibrium found)")
    y = model.output_dict(x, u)
    return TrimResult(model=model, x=x, u=u, r_g=y["r_g"], nu=y["nu"], F_s=y["F_s"],
                      F_p=y["F_p"], omega_p=omega_p, omega_s=y["omega_s"], T_b=y["T_b"],
                      T_d=y["T_d_act"], T_l=y["T_l_act"], T_mp=y["T_mp_act"],
                      T_ms=named["T_ms"], mu=y["mu"], residual=residual)


def _mu_max(model: EmpactModel, r_g: float) -> float:
    """Peak traction coefficient D(r_g) of the magic formula (the kernel's interpolation)."""
    p = model.p
    return float(K._interp3(np.log(r_g), p[K.P_LLOW], p[K.P_LMED], p[K.P_LOD], p[K.P_D0],
                            p[K.P_D1], p[K.P_D2]))


def _static_creep(model: EmpactModel, r_g, R_p, R_s, phi, F_el, tau) -> tuple[float, float]:
    """``(Lambda, kappa*)`` of the creep law at rest for the belt element's secondary force
    `F_el` (``Lambda = 0`` and the geometric thrust ratio for Shafai's law)."""
    p = model.p
    kgeo = (np.pi + 2 * phi) / (np.pi - 2 * phi)
    if p[K.P_LAW] == K.LAW_SHAFAI:
        return 0.0, kgeo
    lam, _, keq = K.creep_force(r_g, R_p, R_s, phi, F_el, tau, 0.0, 1.0, p)
    return float(lam), float(keq)


def _contact_radii(model: EmpactModel, r_g: float, F_s: float, tau_of, request: str):
    """Radii of the stretched belt whose secondary *clamping* force (belt element minus the
    static creep force) is `F_s`; `tau_of(R_s, F_el)` gives the torque ratio.  Fixed point
    on the belt element's force ``F_el = F_s (a + kappa* b) / (a + kappa_geo b)``."""
    tb = model.p[K.P_TB]
    F_el = F_s
    for _ in range(50):
        R_p, R_s, phi, e = _belt_radii(model, r_g, F_el, request)
        if model.p[K.P_LAW] == K.LAW_SHAFAI:
            return R_p, R_s, phi, e
        kgeo = (np.pi + 2 * phi) / (np.pi - 2 * phi)
        _, keq = _static_creep(model, r_g, R_p, R_s, phi, F_el, tau_of(R_s, F_el))
        a, b = r_g / (tb * R_p), r_g / (tb * R_s)
        new = F_s * (a + keq * b) / (a + kgeo * b)
        if abs(new - F_el) <= 1e-13 * F_s:
            return _belt_radii(model, r_g, new, request)
        F_el = new
    raise TrimError(f"{request}: the belt force does not converge with the creep law's "
                    "static force")


def _servo_statics(model: EmpactModel, F_p_act, F_s_act, q5, q6):
    """Servo-side coordinates q1..q4 [rad] and holding torques T_mp, T_ms [N m] that carry the
    actuator forces `F_p_act`, `F_s_act` [N] with the sheaves at `q5`, `q6` [m] (scalars or
    arrays: `_assemble` and `trim_grid` share it)."""
    a, p = model.params.actuation, model.p
    sig = p[K.P_SIG]
    q3 = (-F_p_act / p[K.P_KTP] - q5) / a.s
    q4 = q3 + (sig * F_s_act / p[K.P_KTS] - q6) / a.s
    T_c = a.i_e * a.s * sig * F_s_act
    q2 = a.i_c * (T_c / p[K.P_KC] + q4 / a.i_e)
    T_w = -a.i_e * a.s * (F_p_act + sig * F_s_act)
    q1 = a.i_w * (T_w / p[K.P_KW] + q3 / a.i_e)
    return q1, q2, q3, q4, T_w / a.i_w, T_c / a.i_c


def _assemble(model: EmpactModel, r_g, omega_p, nu, F_s, T_l, R_p, R_s, phi, e):
    v, d = model.params.variator, model.params.driveline
    p = model.p
    k_belt = p[K.P_KBELT]
    tb = np.tan(v.beta)
    N = k_belt * e
    F_p = N * (np.pi + 2 * phi) / tb
    q5 = (R_p - v.R_min) * tb
    sig = p[K.P_SIG]  # sense of q6 (ModelOptions.kinematics)
    q6 = sig * (p[K.P_RS0] - R_s) * tb
    # the actuator forces carry the clamping forces: the belt element's and the static creep
    # force of the law at rest (torque ratio as the kernel computes it)
    F_el = N * (np.pi - 2 * phi) / tb
    tau = (T_l * np.cos(v.beta) / (2 * _mu_max(model, r_g) * F_el * R_s) if model.ix[0] >= 0
           else K.traction_mu(nu, r_g, p) / _mu_max(model, r_g))
    lam, _ = _static_creep(model, r_g, R_p, R_s, phi, F_el, tau)
    F_p_act = F_p + lam * r_g / (tb * R_p)
    F_s_act = F_el - lam * r_g / (tb * R_s)
    q1, q2, q3, q4, T_mp, T_ms = _servo_statics(model, F_p_act, F_s_act, q5, q6)
    omega_s = (1 - nu) * r_g * omega_p
    T_d = r_g * T_l
    x = np.zeros(model.n)
    x[:6] = q1, q2, q3, q4, q5, q6
    x[12], x[13] = T_d / d.k_tc, T_l / d.k_ds
    x[14:18] = omega_p, omega_p, omega_s, omega_s
    ix = model.ix
    if ix[0] >= 0:
        x[ix[0]] = T_l / (R_s * d.k_belt)
    u = np.array([T_mp, T_ms, T_d, T_l])
    if ix[1] >= 0:
        x[ix[1]], u[2] = T_d, omega_p
    if ix[2] >= 0:
        x[ix[2]], u[3] = T_l, omega_s
    if ix[3] >= 0:
        x[ix[3]], u[0] = T_mp, r_g  # the integral carries the holding torque
    return x, u, {"T_ms": T_ms, "F_p": F_p_act, "T_d": T_d}


def _residual(model: EmpactModel, x, u, named) -> float:
    """Largest ``|dx_i/dt|`` normalised by the size of the forces on each body."""
    a, d = model.params.actuation, model.params.driveline
    dx = model.rhs(0.0, x, u)
    F = abs(named["F_p"]) + abs(model.output_dict(x, u)["F_s"]) + 1.0
    torque_act = a.s * F
    torque_dl = abs(named["T_d"]) + abs(u[3]) + 1.0
    scale = np.ones(model.n)
    scale[:6] = 1.0  # velocities: exactly zero at trim
    scale[6:12] = [torque_act / a.J_mp, torque_act / a.J_ms, torque_act / a.J_sp,
                   torque_act / a.J_ss, F / a.m_p, F / a.m_s]
    scale[12:14] = 1.0  # speed differences [rad/s]
    scale[14:18] = [torque_dl / d.J_d, torque_dl / d.J_p, torque_dl / d.J_s, torque_dl / d.J_l]
    return float(np.max(np.abs(dx) / scale))


# -- many points at once (plant families) ----------------------------------------------------
@dataclass(frozen=True, eq=False)
class TrimGrid:
    """Trimmed operating points of one model, many at once (`trim_grid`).

    Attributes
    ----------
    model : EmpactModel
    x : array, shape (N, n)
        States (NaN where ``ok`` is False).
    u : array, shape (N, 4)
        Inputs.
    r_g, omega_p, nu, F_s, T_l : arrays, shape (N,)
        The operating variables (requested and solved).
    ok : bool array, shape (N,)
        Trimmed with a normalised residual below `RESIDUAL_TOL`.
    reason : tuple of str, length N
        Why a point failed ('' where ok).
    """

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


def _radii_many(model, r, F_el, tol=1e-15):
    """Vectorised `_belt_radii`: Newton on R_s for the stretched belt carrying `F_el`."""
    v, k, tb = model.params.variator, model.p[K.P_KBELT], model.p[K.P_TB]
    _, R_s = radii(r, v.L_belt, v.a)
    R_s = np.array(R_s, float)
    active = np.ones(R_s.shape, dtype=bool)  # each point stops on its own convergence, so
    for _ in range(30):                      # its result does not depend on the others
        phi = np.arcsin((r - 1) * R_s / v.a)
        L = 2 * v.a * np.cos(phi) + (np.pi + 2 * phi) * r * R_s + (np.pi - 2 * phi) * R_s
        g = np.pi - 2 * phi
        f = L - v.L_belt - F_el * tb / (k * g)
        dphi = (r - 1) / (v.a * np.cos(phi))
        df = r * (np.pi + 2 * phi) + g - F_el * tb / k * 2 * dphi / g**2
        step = np.where(active, f / df, 0.0)
        R_s = R_s - step
        active &= np.abs(step) > tol * R_s
        if not active.any():
            break
    phi = np.arcsin((r - 1) * R_s / v.a)
    return r * R_s, R_s, phi, F_el * tb / (k * (np.pi - 2 * phi))


def trim_grid(model: EmpactModel, r_g, omega_p, *, nu=None, F_s=None, T_l=None) -> TrimGrid:
    """`trim` at many points at once (1-D arrays, broadcast): the same equations, solved
    vectorised (Newton on the belt radii, bisection on the rising branch of the traction
    curve, the creep law's fixed point), then checked by the same residual.  Traction belt
    only.  Points that cannot be trimmed are marked (``ok``, ``reason``), never dropped.

    Parameters as `trim`: exactly two of `nu`, `F_s`, `T_l`.
    """
    if model.options.belt != "traction":
        raise TrimError("trim_grid: only the traction belt (belt = 'traction')")
    if sum(v is not None for v in (nu, F_s, T_l)) != 2:
        raise TrimError("trim_grid: give exactly two of nu, F_s, T_l")
    arrays = [np.atleast_1d(np.asarray(v, float)) for v in (r_g, omega_p, nu if nu is not None
              else np.nan, F_s if F_s is not None else np.nan, T_l if T_l is not None
              else np.nan)]
    r, w, nu_, Fs, Tl = (np.array(a, float) for a in np.broadcast_arrays(*arrays))
    N = r.size
    p, tb = model.p, model.p[K.P_TB]
    cosb = np.cos(model.params.variator.beta)
    lo, hi = ratio_range(model.params.variator)
    reason = np.full(N, "", dtype=object)
    reason[(r < lo) | (r > hi)] = "r_g outside the variator's range"
    reason[~(w > 0)] = "omega_p must be > 0"
    good = reason == ""
    r = np.where(good, r, 1.0)
    mu_max = np.empty(N)
    K.mu_max_many(r, p, mu_max)
    mu = np.full(N, np.nan)
    if nu is not None:
        K.traction_many(np.nan_to_num(nu_), r, p, mu)

    def contact(F_contact, tau_of):
        """Radii for the clamping force (fixed point on the belt element's force)."""
        F_el = F_contact.copy()
        active = np.ones(N, dtype=bool)  # per-point convergence (chunk-independent results)
        for _ in range(60):
            R_p, R_s, phi, e = _radii_many(model, r, F_el)
            if p[K.P_LAW] == K.LAW_SHAFAI:
                return R_p, R_s, phi, e
            kgeo = (np.pi + 2 * phi) / (np.pi - 2 * phi)
            lam, keq = np.empty(N), np.empty(N)
            K.creep_many(r, R_p, R_s, phi, F_el, tau_of(R_s, F_el), p, lam, keq)
            a, b = r / (tb * R_p), r / (tb * R_s)
            new = np.where(active, F_contact * (a + keq * b) / (a + kgeo * b), F_el)
            active &= np.abs(new - F_el) > 1e-13 * np.abs(F_contact)
            F_el = new
            if not active.any():
                break
        return _radii_many(model, r, F_el)

    if nu is not None and F_s is not None:
        R_p, R_s, phi, e = contact(Fs, lambda R_s, F_el: mu / mu_max)
        Tl = 2 * mu * Fs * R_s / cosb
    elif nu is not None:  # nu and T_l
        reason[good & ~(mu * Tl > 0)] = "mu(nu) cannot carry T_l with a positive clamping force"
        good = reason == ""
        R_s = radii(r, model.params.variator.L_belt, model.params.variator.a)[1]
        active = np.ones(N, dtype=bool)
        for _ in range(40):
            Fs = np.where(good, Tl * cosb / (2 * mu * R_s), 1e4)
            R_p, R_s_new, phi, e = contact(Fs, lambda R_s, F_el: mu / mu_max)
            R_s_new = np.where(active, R_s_new, R_s)
            active &= np.abs(R_s_new - R_s) >= 1e-15
            R_s = R_s_new
            if not active.any():
                break
        Fs = np.where(good, Tl * cosb / (2 * mu * R_s), 1e4)
        R_p, R_s, phi, e = contact(Fs, lambda R_s, F_el: mu / mu_max)
    else:  # F_s and T_l: the slip on the rising branch
        R_p, R_s, phi, e = contact(Fs, lambda R_s, F_el: Tl * cosb / (2 * Fs * R_s) / mu_max)
        need = Tl * cosb / (2 * Fs * R_s)
        nu_pk = np.empty(N)
        mu_pk = np.empty(N)
        for rr in np.unique(r):
            sel = r == rr
            nu_pk[sel], mu_pk[sel] = traction_peak(model, float(rr))
        reason[good & (np.abs(need) > mu_pk)] = "the load needs mu above the traction peak"
        good = reason == ""
        a_, b_ = np.zeros(N), np.where(good, nu_pk, 0.0)
        target = np.abs(need)
        m_ = np.empty(N)
        for _ in range(64):
            mid = 0.5 * (a_ + b_)
            K.traction_many(mid, r, p, m_)
            below = m_ < target
            a_, b_ = np.where(below, mid, a_), np.where(below, b_, mid)
        nu_ = np.sign(need) * 0.5 * (a_ + b_)
        K.traction_many(nu_, r, p, mu)
    reason[good & ~(Fs > 0)] = "clamping force must be > 0"
    good = reason == ""
    # assemble (vectorised `_assemble`)
    a = model.params.actuation
    N_b = p[K.P_KBELT] * e
    F_p = N_b * (np.pi + 2 * phi) / tb
    F_el = N_b * (np.pi - 2 * phi) / tb
    q5 = (R_p - model.params.variator.R_min) * tb
    sig = p[K.P_SIG]
    q6 = sig * (p[K.P_RS0] - R_s) * tb
    lam, keq = np.zeros(N), np.zeros(N)
    if p[K.P_LAW] != K.LAW_SHAFAI:
        K.creep_many(r, R_p, R_s, phi, F_el, mu / mu_max, p, lam, keq)
    F_p_act = F_p + lam * r / (tb * R_p)
    F_s_act = F_el - lam * r / (tb * R_s)
    q1, q2, q3, q4, T_mp, T_ms = _servo_statics(model, F_p_act, F_s_act, q5, q6)
    omega_s = (1 - nu_) * r * w
    d = model.params.driveline
    T_d = r * Tl
    x = np.zeros((N, model.n))
    x[:, :6] = np.column_stack([q1, q2, q3, q4, q5, q6])
    x[:, 12], x[:, 13] = T_d / d.k_tc, Tl / d.k_ds
    x[:, 14:18] = np.column_stack([w, w, omega_s, omega_s])
    u = np.column_stack([T_mp, T_ms, T_d, Tl])
    ix = model.ix
    if ix[1] >= 0:
        x[:, ix[1]], u[:, 2] = T_d, w
    if ix[2] >= 0:
        x[:, ix[2]], u[:, 3] = Tl, omega_s
    if ix[3] >= 0:
        x[:, ix[3]], u[:, 0] = T_mp, r
    # the same check as `trim`: every derivative zero, normalised by the forces on each body
    residual = np.full(N, np.inf)
    g = np.flatnonzero(good)
    xg, ug = np.ascontiguousarray(x[g]), np.ascontiguousarray(u[g])
    dx, y = np.empty_like(xg), np.empty((len(g), K.NY))
    K.eval_batch(xg, ug, p, ix, dx, y)
    F = np.abs(F_p_act[g]) + np.abs(y[:, K.Y_FS]) + 1.0
    torque_act = a.s * F
    torque_dl = np.abs(T_d[g]) + np.abs(ug[:, 3]) + 1.0
    scale = np.ones_like(xg)
    scale[:, 6:12] = np.column_stack([torque_act / a.J_mp, torque_act / a.J_ms,
                                      torque_act / a.J_sp, torque_act / a.J_ss, F / a.m_p,
                                      F / a.m_s])
    scale[:, 14:18] = np.column_stack([torque_dl / d.J_d, torque_dl / d.J_p,
                                       torque_dl / d.J_s, torque_dl / d.J_l])
    residual[g] = np.max(np.abs(dx) / scale, axis=1)
    reason[good & ~(residual < RESIDUAL_TOL)] = "steady-state residual above the tolerance"
    good = reason == ""
    x[~good] = np.nan
    u[~good] = np.nan
    return TrimGrid(model=model, x=x, u=u, r_g=r, omega_p=w, nu=nu_, F_s=Fs, T_l=Tl, ok=good,
                    reason=tuple(reason.tolist()))
