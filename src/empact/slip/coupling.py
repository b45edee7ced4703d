r"""The belt coupling of the variator: eqs. 1-3 of the paper (Sec. 2.2 "Slip dynamics").

* Belt torque on the secondary pulley (eq. 1): ``T_b = 2 mu(nu, r_g) F_s R_s / cos(beta)``.
  The same belt force acts at ``R_p`` on the primary, which is loaded by ``-r_g T_b``
  (``r_g = R_p / R_s``).
* Slip (eq. 2): ``nu = 1 - omega_s R_s / (omega_p R_p) = 1 - omega_s / (r_g omega_p)``;
  undefined at ``omega_p = 0`` (an error, never a division by zero).  At the operating point
  ``omega_s0 = rho omega_p0`` with the kinematic ratio ``rho = r_g (1 - nu0)``.
* Linearisation at ``(r_g, nu0, F_s0, omega_p0)`` (eq. 3), exact derivative of eqs. 1-2::

      nu~  = (rho omega~_p - omega~_s) / (r_g omega_p0)
      T_b~ = c_s (rho omega~_p - omega~_s) + g_F F_s~
      c_s  = 2 mu'(nu0, r_g) F_s0 R_s / (cos(beta) r_g omega_p0)     [N m s/rad]
      g_F  = 2 mu(nu0, r_g) R_s / cos(beta)                           [m]

  so the belt is a damper between q2 and q3 with the (non-symmetric, rank-one) damping matrix
  ``C_b = c_s [0, r_g, -1, 0]^T [0, rho, -1, 0]``.  The paper's eq. 3 writes
  ``c_b = 2 mu' F_s0 R_p / (omega_p0 cos(beta) r_g) = r_g c_s``: with ``R_p`` in place of
  ``R_s`` it is the damping constant of the *primary-side* torque ``r_g T_b``.  Both agree at
  ``r_g = 1`` (Figs. 9, 11, 12a).  `BeltLinearisation.c_b` is ``c_b`` as the paper defines it;
  the models use the exact derivative (``c_s`` on the secondary, ``r_g c_s`` on the primary).

Operating points are `empact.params.OperatingPoint` (default: the ``[operating]`` table of
the parameter set).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._deprecate import warn_renamed
from .._results import Result
from .._validate import check_values
from ..params import OPERATING_VARIABLES, OperatingPoint, Params, ResolvedPoint
from ..variator.geometry import variator_state
from ..variator.traction import TractionModel, traction_from_params

__all__ = ["VARIABLES", "BeltLinearisation", "slip", "belt_torque", "linearize_belt",
           "linearisation_terms", "check_speed", "check_clamp", "check_slip"]

#: Operating-point variables, their units and descriptions (names as in the paper).
VARIABLES = OPERATING_VARIABLES

_STANDSTILL = "the slip nu = 1 - omega_s / (r_g omega_p) of eq. 2 is undefined at standstill"


def check_speed(omega_p: ArrayLike) -> NDArray[np.float64]:
    """Primary speeds [rad/s] as an array, all > 0 (one-line error naming the first bad).

    Parameters
    ----------
    omega_p : array_like
        Primary pulley speed(s) [rad/s], any shape.

    Returns
    -------
    ndarray
        `omega_p` as a float array, its shape.

    Raises
    ------
    ParameterError
        If any speed is not finite or not positive (the slip is undefined at standstill).
    """
    return check_values("omega_p", omega_p, 0.0, lo_open=True, unit="rad/s", note=_STANDSTILL)


def check_clamp(F_s: ArrayLike) -> NDArray[np.float64]:
    """Clamping forces [N] as an array, all >= 0.

    Parameters
    ----------
    F_s : array_like
        Secondary clamping force(s) [N], any shape.

    Returns
    -------
    ndarray
        `F_s` as a float array, its shape.

    Raises
    ------
    ParameterError
        If any force is not finite or negative.
    """
    return check_values("F_s", F_s, 0.0, unit="N")


def check_slip(nu: ArrayLike) -> NDArray[np.float64]:
    """Slips [-] as an array, all in (-1, 1).

    Parameters
    ----------
    nu : array_like
        Slip(s) [-] (fractions: 0.01 is 1 %), any shape.

    Returns
    -------
    ndarray
        `nu` as a float array, its shape.

    Raises
    ------
    ParameterError
        If any slip is not finite or outside (-1, 1).
    """
    return check_values("nu", nu, -1.0, 1.0, lo_open=True, hi_open=True,
                        note="a fraction: 0.01 is 1 %")


def slip(omega_p: ArrayLike, omega_s: ArrayLike, r_g: ArrayLike) -> NDArray[np.float64]:
    """Slip ``nu = 1 - omega_s / (r_g omega_p)`` [-] (eq. 2), arrays broadcast.

    Parameters
    ----------
    omega_p, omega_s : array_like
        Primary and secondary pulley speeds [rad/s]; ``omega_p`` > 0.
    r_g : array_like
        Geometric ratio ``R_p / R_s`` [-].

    Returns
    -------
    ndarray
        The slip ``nu`` [-], the broadcast shape of the inputs.

    Raises
    ------
    ParameterError
        If any ``omega_p`` is 0 (slip undefined) or negative.
    """
    w_p = check_speed(omega_p)
    return 1.0 - np.asarray(omega_s, float) / (np.asarray(r_g, float) * w_p)


def belt_torque(params: Params, nu: ArrayLike, r_g: ArrayLike, F_s: ArrayLike,
                traction: TractionModel | None = None) -> NDArray[np.float64]:
    """Belt torque on the secondary pulley ``T_b = 2 mu(nu, r_g) F_s R_s / cos(beta)`` [N m].

    Eq. 1; the primary pulley is loaded by ``r_g T_b``.  Arrays broadcast.

    Parameters
    ----------
    params : Params
        Parameter set (variator geometry; traction model if `traction` is None).
    nu : array_like
        Slip [-].
    r_g : array_like
        Geometric ratio [-].
    F_s : array_like
        Secondary clamping force [N], >= 0.
    traction : TractionModel, optional
        Traction model (default `traction_from_params(params)`).

    Returns
    -------
    ndarray
        The belt torque ``T_b`` on the secondary pulley [N m], the broadcast shape of `nu`,
        `r_g` and `F_s`.
    """
    tr = traction_from_params(params) if traction is None else traction
    nu_a, r_a, f_a = np.broadcast_arrays(np.asarray(nu, float), np.asarray(r_g, float),
                                         check_clamp(F_s))
    R_s = variator_state(r_a, params.variator).R_s
    return 2 * tr.mu(nu_a, r_a) * f_a * R_s / math.cos(params.variator.beta)


# --------------------------------------------------------------------------------------------
# Linearisation (eq. 3) and the state-space model
@dataclass(frozen=True)
class BeltLinearisation(Result):
    """The belt torque linearised at an operating point (eq. 3).

    Attributes
    ----------
    op : the operating point
    R_p, R_s : running radii [m]
    mu, dmu : traction coefficient and its slope ``d mu / d nu`` at the point [-]
    c_b : the paper's damping constant ``2 mu' F_s0 R_p / (omega_p0 cos(beta) r_g)``
        [N m s/rad] (eq. 3; damping of the primary-side torque ``r_g T_b``)
    c_s : damping of the secondary torque, ``d T_b / d(-omega_s) = c_b / r_g`` [N m s/rad]
    g_F : clamping-force gain ``d T_b / d F_s = 2 mu R_s / cos(beta)`` [m]
    rho : kinematic ratio ``omega_s0 / omega_p0 = r_g (1 - nu0)`` [-]
    """

    op: ResolvedPoint
    R_p: float
    R_s: float
    mu: float
    dmu: float
    c_b: float
    c_s: float
    g_F: float
    rho: float


def linearisation_terms(params: Params, r_g: ArrayLike, nu: ArrayLike, F_s: ArrayLike,
                        omega_p: ArrayLike, traction: TractionModel | None = None) \
        -> dict[str, NDArray[np.float64]]:
    """The terms of eq. 3 at many operating points at once (arrays broadcast).

    Parameters
    ----------
    params : parameter set (variator geometry, traction curve)
    r_g, nu, F_s, omega_p : operating-point arrays [-, -, N, rad/s]
    traction : traction model (default `traction_from_params(params)`)

    Returns
    -------
    dict
        Broadcast arrays ``r_g, nu, F_s, omega_p, R_p, R_s, mu, dmu, c_s, c_b, g_F, rho``
        (see `BeltLinearisation`).
    """
    tr = traction_from_params(params) if traction is None else traction
    w = check_speed(omega_p)
    f = check_clamp(F_s)
    n = check_slip(nu)
    r, n, f, w = np.broadcast_arrays(np.asarray(r_g, float), n, f, w)
    geo = variator_state(r, params.variator)
    mu = tr.mu(n, r)
    dmu = tr.dmu(n, r)
    cb = math.cos(params.variator.beta)
    c_s = 2 * dmu * f * geo.R_s / (cb * r * w)
    return dict(r_g=r, nu=n, F_s=f, omega_p=w, R_p=geo.R_p, R_s=geo.R_s, mu=mu, dmu=dmu,
                c_s=c_s, c_b=r * c_s, g_F=2 * mu * geo.R_s / cb, rho=r * (1 - n))


def linearize_belt(params: Params, op: OperatingPoint | None = None,
                   traction: TractionModel | None = None) -> BeltLinearisation:
    """Eq. 3 at `op` (default: the ``[operating]`` point of `params`; a point given by a torque
    ratio or a load is resolved first).

    Parameters
    ----------
    params : Params
        Parameter set (variator geometry; traction curve if `traction` is None).
    op : OperatingPoint, optional
        The operating point (default ``params.operating``).
    traction : TractionModel, optional
        Traction model (default `traction_from_params(params)`).

    Returns
    -------
    BeltLinearisation
        The resolved point with the radii [m], ``mu`` and ``dmu`` [-], the damping constants
        ``c_b`` and ``c_s`` [N m s/rad], the clamping-force gain ``g_F`` [m] and the
        kinematic ratio ``rho`` [-].
    """
    op = (params.operating if op is None else op).resolve(params, traction)
    t = linearisation_terms(params, op.r_g, op.nu, op.F_s, op.omega_p, traction)
    return BeltLinearisation(op=op, **{k: float(t[k]) for k in
                                       ("R_p", "R_s", "mu", "dmu", "c_b", "c_s", "g_F", "rho")})



def linearise_belt(params: Params, op: OperatingPoint | None = None,
                   traction: TractionModel | None = None) -> BeltLinearisation:
    """Deprecated: `linearize_belt`.

    Parameters
    ----------
    params : Params
        Parameter set.
    op : OperatingPoint, optional
        The operating point (default ``params.operating``).
    traction : TractionModel, optional
        Traction model (default `traction_from_params(params)`).

    Returns
    -------
    BeltLinearisation
        As `linearize_belt` (with a `DeprecationWarning`).
    """
    warn_renamed("linearise_belt", "linearize_belt")
    return linearize_belt(params, op, traction)
