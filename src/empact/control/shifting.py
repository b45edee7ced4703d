"""How fast the machine can shift: the ratio-rate envelope the servo limits allow, and a ratio
reference that follows it.

On the test bench (drive speed-controlled, load torque-controlled) a ratio rate ``dr_g/dt``
accelerates the secondary side (``J_s + J_l``) at ``omega_p dr_g/dt``: the belt must carry
``T_l + (J_s + J_l) omega_p dr_g/dt``, which at the set-point's torque ratio ``tau`` needs the
clamping force ``F_s = T_b cos(beta) / (2 tau mu_max R_s)``.  The primary servo must hold the
thrust ratio the creep law needs for that rate (``kappa* exp(xi)``, ``xi = xi_sat tanh(rate /
(omega K_c) / xi_sat)``; `empact.variator.shift_law`): its torque is the holding torque at
that clamping plus ``(i_e s / i_w) kappa* (exp(xi) - 1) F_s``.  The largest rate at each
ratio is where the first of these reaches its limit (`empact.hardware.ServoLimits`):

* ``"clamping"``: ``F_s`` at the secondary servo's torque limit (``T_ms = i_e s F_s /
  i_c``);
* ``"primary"``: the primary servo's torque limit;
* ``"speed"``: the primary servo's speed limit (``omega_mp = (i_w / i_e) tan(beta)
  (dR_p/dr_g) rate / s``);
* ``"creep"``: the creep mode itself: beyond ``xi = CREEP_SHARE xi_sat`` the belt's shift
  resistance saturates (slip-mode shifting, Sorge, FISITA CVT2007), the ratio then answers
  the primary servo like a free sheave mass and the loop loses its handle on the rate.

These are quasi-static (no actuation dynamics, no slip-loop error): an upper bound for a
shift without macro slip.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._results import TableResult
from ..errors import ParameterError
from ..hardware import ServoLimits
from ..nonlinear.equilibrium import trim_grid
from ..nonlinear.model import EmpactModel
from ..variator.geometry import primary_radius_per_ratio, variator_state
from ..variator.shift_law import creep_coefficient

__all__ = ["ShiftEnvelope", "shift_envelope", "shift_reference", "LIMITS", "CREEP_SHARE"]

#: the limits that can bind
LIMITS = ("clamping", "primary", "speed", "creep")
#: the share of the creep law's saturation a controlled shift may use (``xi / xi_sat``)
CREEP_SHARE = 0.5


@dataclass(frozen=True, eq=False)
class ShiftEnvelope(TableResult):
    """The largest upshift rate at each ratio and what stops it.

    Attributes
    ----------
    r_g : array (n,)
    rate : array (n,)
        Largest ratio rate [1/s].
    binding : array of str (n,)
        The limit reached there (`LIMITS`).
    F_s : array (n,)
        Clamping force at that rate [N].
    T_mp : array (n,)
        Primary servo torque at that rate [N m] (magnitude).
    omega_p, T_l, tau : float
        The conditions.
    """

    r_g: NDArray[np.float64]
    rate: NDArray[np.float64]
    binding: NDArray[np.object_]
    F_s: NDArray[np.float64]
    T_mp: NDArray[np.float64]
    omega_p: float
    T_l: float
    tau: float

    def _columns(self) -> dict[str, NDArray]:
        return {"r_g": self.r_g, "rate": self.rate, "binding": self.binding, "F_s": self.F_s,
                "T_mp": self.T_mp}

    def rate_at(self, r_g: ArrayLike) -> NDArray[np.float64]:
        """The envelope at ratio(s) `r_g` (linear in ``ln r_g``).

        Parameters
        ----------
        r_g : array_like
            Geometric ratio(s) [-] (any shape).
        """
        return np.interp(np.log(r_g), np.log(self.r_g), self.rate)


def shift_envelope(model: EmpactModel, r_g: ArrayLike, omega_p: float, T_l: float,
                   tau: float, limits: ServoLimits) -> ShiftEnvelope:
    """The upshift-rate envelope of the module notes at ratios `r_g` on the test bench
    (`model`: drive speed-controlled, load torque-controlled), primary speed `omega_p`
    [rad/s], load torque `T_l` [N m] and set-point torque ratio `tau`.

    Parameters
    ----------
    model : EmpactModel
        The test bench: ``drive = "speed"``, ``load = "torque"``.
    r_g : array_like, shape (n,)
        Geometric ratios [-] (a scalar is one ratio).
    omega_p : float
        Primary speed [rad/s].
    T_l : float
        Load torque [N m] (its magnitude counts).
    tau : float
        Torque ratio of the set-point ``mu / mu_max`` [-], in (0, 1).
    limits : ServoLimits
        The servo torque and speed limits.

    Returns
    -------
    ShiftEnvelope
        At each ratio the largest ratio rate [1/s], the limit that binds (`LIMITS`) and the
        clamping force [N] and primary servo torque [N m] at that rate.

    Raises
    ------
    ParameterError
        For a model that is not the test bench, `tau` outside (0, 1), or a ratio that does
        not trim.
    """
    o = model.options
    if o.drive != "speed" or o.load != "torque":
        raise ParameterError("shift_envelope: the test bench (drive speed-controlled, load "
                             "torque-controlled)")
    if not 0 < tau < 1:
        raise ParameterError(f"tau = {tau!r}: a torque ratio lies in (0, 1)")
    p = model.params
    a, v, sh, dl = p.actuation, p.variator, p.shift, p.driveline
    r = np.atleast_1d(np.asarray(r_g, float))
    st = variator_state(r, v)
    cosb = np.cos(v.beta)
    cap_per_N = 2 * model.mu_max(r) * st.R_s / cosb          # torque capacity per N
    F_max = limits.T_ms_max * a.i_c / (a.i_e * a.s)
    c = a.i_e * a.s / a.i_w
    J = dl.J_s + dl.J_l
    F_ref = 10e3
    g = trim_grid(model, r, omega_p, tau=np.full(r.shape, tau), F_s=F_ref)
    if not np.all(g.ok):
        raise ParameterError(f"shift_envelope: no trim at r_g = {r[~g.ok][0]:g} "
                             f"({g.reason[~g.ok][0]})")
    hold_per_N = np.abs(g.u[:, 0]) / F_ref
    _, keq = model.static_creep(r, st.R_p, st.R_s, st.phi, F_ref, tau)
    w_eff = np.hypot(omega_p, sh.omega_0)
    speed_per_rate = (a.i_w / a.i_e) * np.tan(v.beta) * primary_radius_per_ratio(r, v) / a.s

    def demand(rate):
        F = (abs(T_l) + J * omega_p * rate) / (tau * cap_per_N)
        K_c = creep_coefficient(p, r, F, R_p=st.R_p)
        xi = sh.xi_sat * np.tanh(rate / (w_eff * K_c) / sh.xi_sat)
        T = hold_per_N * F + c * keq * np.expm1(xi) * F
        return F, T, speed_per_rate * rate, xi / sh.xi_sat

    def ok(rate):
        F, T, w, x = demand(rate)
        return (F <= F_max) & (T <= limits.T_mp_max) & (w <= limits.omega_mp_max) & \
            (x <= CREEP_SHARE)

    lo, hi = np.zeros(r.shape), np.full(r.shape, 50.0)
    base = ok(lo)
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        good = ok(mid)
        lo, hi = np.where(good, mid, lo), np.where(good, hi, mid)
    rate = np.where(base, lo, 0.0)
    F, T, w, x = demand(hi)
    binding = np.where(F > F_max, "clamping", np.where(
        T > limits.T_mp_max, "primary", np.where(x > CREEP_SHARE, "creep",
                                                 "speed"))).astype(object)
    F0, T0, _, _ = demand(rate)
    return ShiftEnvelope(r_g=r, rate=rate, binding=binding, F_s=F0, T_mp=T0,
                         omega_p=float(omega_p), T_l=float(T_l), tau=float(tau))


def shift_reference(envelope: ShiftEnvelope, r_start: float, r_end: float, t_start: float,
                    share: float = 0.8, acceleration: float = 2.0,
                    n: int = 48) -> NDArray[np.float64]:
    """A ratio reference ``[[t, r_g], ...]`` from `r_start` to `r_end` (upshift) starting at
    `t_start` [s] whose rate is `share` of the envelope at every ratio, reached and left at
    `acceleration` [1/s^2] (the rate ``min(share envelope, sqrt(2 a (r - r_start)),
    sqrt(2 a (r_end - r)))``; `n` straight pieces, equal in ``ln r_g``).

    Parameters
    ----------
    envelope : ShiftEnvelope
        The rate envelope (`shift_envelope`), covering ``[r_start, r_end]``.
    r_start, r_end : float
        First and last ratio [-], ``r_end > r_start``.
    t_start : float
        Start of the shift [s].
    share : float
        Share of the envelope's rate used [-], in (0, 1].
    acceleration : float
        Ratio acceleration ``a`` at the start and end of the shift [1/s^2].
    n : int
        Number of straight pieces.

    Returns
    -------
    ndarray, shape (n + 1, 2)
        Rows ``[t, r_g]``: times [s] from `t_start`, ratios [-] geometric from `r_start` to
        `r_end` (a scenario's ``r_g`` reference).

    Raises
    ------
    ParameterError
        For ``r_end <= r_start``, `share` or `acceleration` out of range, or an envelope
        that allows no shift at some ratio.
    """
    if not r_end > r_start:
        raise ParameterError(f"shift_reference: an upshift needs r_end > r_start, got "
                             f"{r_start:g} -> {r_end:g}")
    if not 0 < share <= 1:
        raise ParameterError(f"share = {share!r}: in (0, 1]")
    if not acceleration > 0:
        raise ParameterError(f"acceleration = {acceleration!r}: must be > 0 [1/s^2]")
    rr = np.geomspace(r_start, r_end, n + 1)
    mid = np.sqrt(rr[:-1] * rr[1:])
    rate = share * envelope.rate_at(mid)
    if np.any(rate <= 0):
        raise ParameterError("shift_reference: the limits allow no shift at some ratio "
                             "(the clamping the load alone needs exceeds the servo's)")
    ramp = np.sqrt(2 * acceleration * np.minimum(mid - r_start, r_end - mid))
    rate = np.minimum(rate, ramp)
    t = t_start + np.concatenate([[0.0], np.cumsum(np.diff(rr) / rate)])
    return np.column_stack([t, rr])
