r"""Slip dynamics of the variator coupling (paper Sec. 2.2 "Slip dynamics", eqs. 1-3, Figs. 9-13).

The driveline of Fig. 7 with the belt *spring* removed and the belt *traction torque* in its
place::

    drive motor    torque converter    primary              secondary    driveshaft   load motor
     J_d (q1) ---/\/\/\ k_tc ---- J_p (q2)  ==[ slip ]==  J_s (q3) ---/\/\/\ k_ds --- J_l (q4)
       ^ T_d                        ^ -r_g T_b         T_b ^                            ^ T_l

Physics (decided here, used by every function of the module)
------------------------------------------------------------
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
  ``r_g = 1`` (Figs. 9, 11, 12a).  This module exposes ``c_b`` as the paper defines it
  (`BeltLinearisation.c_b`) and builds the model from the exact derivative (``c_s`` on the
  secondary, ``r_g c_s`` on the primary); root loci "over c_b" use ``c_s = c_b / r_g``.
* State ``x = [theta_d, theta_p, theta_s, theta_l, theta_d_dot, ..., theta_l_dot]``
  (deviations [rad, rad/s]); inputs ``F_s`` [N], ``T_d``, ``T_l`` [N m]; outputs ``nu``
  (linearised slip [-]), ``omega_p``, ``omega_s`` [rad/s] and ``T_b`` (belt torque on the
  secondary [N m]).
* Structural poles: with no spring across the slipping belt the model always has three
  eigenvalues at 0 - the free rotation of the whole driveline (a double zero: angle and speed)
  and the relative angle of the two sides.  They carry no information about the coupling.
  `reduced_matrices` removes them exactly: on the invariant subspace of zero referred momentum
  ``J_d omega_d + J_p omega_p + r_g (J_s omega_s + J_l omega_l) = 0`` (its rate is
  ``T_d + r_g T_l``: the spring and belt torques cancel in it, so it is invariant) the states
  ``[theta_d - theta_p, theta_s - theta_l, omega_p, omega_s, omega_l]`` carry the other five
  eigenvalues; `PoleSweep` and `stability_map` use it.  On the full eigenvalues,
  `stability_measures` drops the three of smallest magnitude instead.  A fourth real pole,
  near ``-c_s (r_g rho / (J_d + J_p) + 1 / (J_s + J_l))``, is the relative speed of the sides:
  it is positive (unstable) whenever ``mu' < 0``.
  The characteristic polynomial makes this explicit: it is ``s^3 Q(s)`` with
  ``Q(s) = s P(s) S(s) + c_s [r_g rho (J_d s^2 + k_tc) S(s) + (J_l s^2 + k_ds) P(s)]``,
  ``P = J_d J_p s^2 + k_tc (J_d + J_p)``, ``S = J_s J_l s^2 + k_ds (J_s + J_l)``.
* Zeros of ``F_s -> nu``: the clamping force enters along the same direction as the belt
  damper and the slip is the damper's own velocity, so this channel is ``G(s) = g H(s) /
  (1 + c_s H(s))`` with the belt-free ``H``: its zeros do not depend on ``c_b`` (hence not on
  ``mu'``, ``F_s0`` or ``omega_p0``), only on ``r_g`` and (through ``rho``) very slightly on
  ``nu0``, and they are exactly the poles of the kinematically coupled driveline
  (`coupled_limit`, Table 2 with a rigid belt) - the end points of the Fig. 9 root locus.

Public API: `SlipOperatingPoint`, `slip`, `belt_torque`, `linearise_belt`, `slip_model`
(`SlipModel`, with ``state_space()``, ``poles()``, ``frequency_response()``, ``zeros()``),
`slip_state_space`, `state_matrices` and `reduced_matrices` (batched), `coupled_limit`,
`belt_root_locus` (Fig. 9), `pole_sweep` (Fig. 11), `slip_frequency_responses` (Fig. 12),
`zero_locus` (Fig. 13), `stability_map`; helpers `oscillatory`, `stability_measures`,
`dynamic_poles`, `transmission_zeros`.  The general parameter root locus is
`empact.rootlocus.root_locus`.
Compute only; figures are drawn by `empact.plotting_slip`.
"""
from __future__ import annotations

import os

import math
from dataclasses import dataclass
from typing import Literal, Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.linalg import eigvals as generalized_eigvals, null_space

from .driveline import COORDINATES, driveline_model
from .geometry import variator_state
from .lumped import FrequencyResponse
from .params import ParameterError, Params
from .rootlocus import RootLocus, root_locus, track_branches
from .traction import TractionModel, traction_from_params

__all__ = [
    "STATES", "INPUTS", "OUTPUTS", "VARIABLES", "N_STRUCTURAL_ZEROS", "REDUCED_STATES",
    "SlipOperatingPoint", "BeltLinearisation", "SlipModel", "BeltRootLocus", "PoleSweep",
    "ZeroLocus", "StabilityMap",
    "slip", "belt_torque", "linearise_belt", "slip_model", "slip_state_space", "state_matrices",
    "reduced_matrices", "dynamic_poles",
    "transmission_zeros", "stability_measures", "oscillatory", "belt_root_locus",
    "coupled_limit",
    "pole_sweep", "slip_frequency_responses", "zero_locus", "stability_map",
]

STATES = tuple(COORDINATES) + tuple(f"{c}_dot" for c in COORDINATES)
INPUTS = ("F_s", "T_d", "T_l")
OUTPUTS = ("nu", "omega_p", "omega_s", "T_b")
#: Operating-point variables, their units and descriptions (names as in the paper).
VARIABLES = {"r_g": ("-", "geometric ratio R_p / R_s"),
             "nu": ("-", "slip (fraction, 0.01 is 1 %)"),
             "F_s": ("N", "secondary clamping force"),
             "omega_p": ("rad/s", "primary pulley speed")}
#: Eigenvalues at 0 of every slip model (free rotation: double; relative angle: single).
N_STRUCTURAL_ZEROS = 3
#: States of the reduced model (`reduced_matrices`): torque-converter and driveshaft
#: deflections ``theta_d - theta_p``, ``theta_s - theta_l`` [rad] and three speeds [rad/s].
REDUCED_STATES = ("e_tc", "e_ds", "omega_p", "omega_s", "omega_l")

Variable = Literal["r_g", "nu", "F_s", "omega_p"]
MapMethod = Literal["roots", "reduced", "full"]


# --------------------------------------------------------------------------------------------
# Operating point and eqs. 1-2
# --------------------------------------------------------------------------------------------
def _check(name: str, value: ArrayLike, bad_fn, allowed: str) -> NDArray[np.float64]:
    """`value` as an array, or a `ParameterError` naming the first bad entry and `allowed`."""
    a = np.asarray(value, float)
    bad = ~np.isfinite(a) | bad_fn(a)
    if np.any(bad):
        raise ParameterError(f"{name} = {float(a[bad].flat[0]):g}: allowed range is {allowed}")
    return a


def _check_speed(omega_p: ArrayLike) -> NDArray[np.float64]:
    if np.any(np.asarray(omega_p, float) == 0):
        raise ParameterError("omega_p = 0: the slip nu = 1 - omega_s / (r_g omega_p) (eq. 2) is "
                             "undefined at standstill; allowed range is (0, inf) [rad/s]")
    return _check("omega_p", omega_p, lambda w: w < 0, "(0, inf) [rad/s]")


def _check_clamp(F_s: ArrayLike) -> NDArray[np.float64]:
    return _check("F_s", F_s, lambda f: f < 0, "[0, inf) [N]")


def _check_slip_value(nu: ArrayLike) -> NDArray[np.float64]:
    return _check("nu", nu, lambda n: np.abs(n) >= 1, "(-1, 1) (a fraction: 0.01 is 1 %)")


@dataclass(frozen=True)
class SlipOperatingPoint:
    """Operating point of the slip model (names as in the paper).

    Attributes
    ----------
    r_g : geometric ratio ``R_p / R_s`` [-] (checked against the variator where it is used)
    nu : slip [-] (a fraction: 0.01 is 1 %), in (-1, 1)
    F_s : secondary clamping force [N], >= 0
    omega_p : primary pulley speed [rad/s], > 0 (eq. 2 is undefined at 0)
    """

    r_g: float
    nu: float
    F_s: float
    omega_p: float

    def __post_init__(self) -> None:
        r = float(self.r_g)
        if not (math.isfinite(r) and r > 0):
            raise ParameterError(f"r_g = {self.r_g!r}: must be a positive finite ratio")
        object.__setattr__(self, "r_g", r)
        object.__setattr__(self, "nu", float(_check_slip_value(self.nu)))
        object.__setattr__(self, "F_s", float(_check_clamp(self.F_s)))
        object.__setattr__(self, "omega_p", float(_check_speed(self.omega_p)))

    @property
    def omega_s(self) -> float:
        """Secondary speed ``r_g (1 - nu) omega_p`` [rad/s] (eq. 2 solved for omega_s)."""
        return self.r_g * (1 - self.nu) * self.omega_p

    @classmethod
    def from_params(cls, params: Params, **changes: float) -> "SlipOperatingPoint":
        """The ``[operating]`` point of a parameter set, with keyword `changes`."""
        unknown = set(changes) - set(VARIABLES)
        if unknown:
            raise ParameterError(f"unknown operating-point variable {sorted(unknown)[0]!r}: "
                                 f"choose from {', '.join(VARIABLES)}")
        o = params.operating
        values = dict(r_g=o.r_g, nu=o.nu, F_s=o.F_s, omega_p=o.omega_p)
        values.update({k: float(v) for k, v in changes.items()})
        return cls(**values)

    def replace(self, **changes: float) -> "SlipOperatingPoint":
        """A copy with some variables changed."""
        unknown = set(changes) - set(VARIABLES)
        if unknown:
            raise ParameterError(f"unknown operating-point variable {sorted(unknown)[0]!r}: "
                                 f"choose from {', '.join(VARIABLES)}")
        values = dict(r_g=self.r_g, nu=self.nu, F_s=self.F_s, omega_p=self.omega_p)
        values.update(changes)
        return SlipOperatingPoint(**values)

    def as_dict(self) -> dict[str, float]:
        """``{"r_g": ..., "nu": ..., "F_s": ..., "omega_p": ...}`` (SI)."""
        return dict(r_g=self.r_g, nu=self.nu, F_s=self.F_s, omega_p=self.omega_p)


def slip(omega_p: ArrayLike, omega_s: ArrayLike, r_g: ArrayLike) -> NDArray[np.float64]:
    """Slip ``nu = 1 - omega_s / (r_g omega_p)`` [-] (eq. 2), arrays broadcast.

    Parameters
    ----------
    omega_p, omega_s : primary and secondary pulley speeds [rad/s]; ``omega_p`` > 0
    r_g : geometric ratio ``R_p / R_s`` [-]

    Raises
    ------
    ParameterError
        If any ``omega_p`` is 0 (slip undefined) or negative.
    """
    w_p = _check_speed(omega_p)
    return 1.0 - np.asarray(omega_s, float) / (np.asarray(r_g, float) * w_p)


def belt_torque(params: Params, nu: ArrayLike, r_g: ArrayLike, F_s: ArrayLike,
                traction: TractionModel | None = None) -> NDArray[np.float64]:
    """Belt torque on the secondary pulley ``T_b = 2 mu(nu, r_g) F_s R_s / cos(beta)`` [N m].

    Eq. 1; the primary pulley is loaded by ``r_g T_b``.  Arrays broadcast.

    Parameters
    ----------
    params : parameter set (variator geometry; traction model if `traction` is None)
    nu : slip [-];  r_g : geometric ratio [-];  F_s : clamping force [N]
    traction : traction model (default `traction_from_params(params)`)
    """
    tr = traction_from_params(params) if traction is None else traction
    nu_a, r_a, f_a = np.broadcast_arrays(np.asarray(nu, float), np.asarray(r_g, float),
                                         _check_clamp(F_s))
    R_s = variator_state(r_a, params.variator).R_s
    return 2 * tr.mu(nu_a, r_a) * f_a * R_s / math.cos(params.variator.beta)


# --------------------------------------------------------------------------------------------
# Linearisation (eq. 3) and the state-space model
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class BeltLinearisation:
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

    op: SlipOperatingPoint
    R_p: float
    R_s: float
    mu: float
    dmu: float
    c_b: float
    c_s: float
    g_F: float
    rho: float


def _terms(params: Params, r_g: ArrayLike, nu: ArrayLike, F_s: ArrayLike, omega_p: ArrayLike,
           traction: TractionModel | None) -> dict[str, NDArray[np.float64]]:
    """Linearisation terms, broadcast over the four operating-point arrays."""
    tr = traction_from_params(params) if traction is None else traction
    w = _check_speed(omega_p)
    f = _check_clamp(F_s)
    n = _check_slip_value(nu)
    r, n, f, w = np.broadcast_arrays(np.asarray(r_g, float), n, f, w)
    geo = variator_state(r, params.variator)
    mu = tr.mu(n, r)
    dmu = tr.dmu(n, r)
    cb = math.cos(params.variator.beta)
    c_s = 2 * dmu * f * geo.R_s / (cb * r * w)
    return dict(r_g=r, nu=n, F_s=f, omega_p=w, R_p=geo.R_p, R_s=geo.R_s, mu=mu, dmu=dmu,
                c_s=c_s, c_b=r * c_s, g_F=2 * mu * geo.R_s / cb, rho=r * (1 - n))


def linearise_belt(params: Params, op: SlipOperatingPoint | None = None,
                   traction: TractionModel | None = None) -> BeltLinearisation:
    """Eq. 3 at `op` (default: the ``[operating]`` point of `params`)."""
    op = SlipOperatingPoint.from_params(params) if op is None else op
    t = _terms(params, op.r_g, op.nu, op.F_s, op.omega_p, traction)
    return BeltLinearisation(op=op, **{k: float(t[k]) for k in
                                       ("R_p", "R_s", "mu", "dmu", "c_b", "c_s", "g_F", "rho")})


def _mass_stiffness(params: Params) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Diagonal inertias (4,) and stiffness matrix (4, 4) of the driveline without the belt.

    Taken from ``driveline_model(params, r_g, belt=False)``; without the belt spring neither
    depends on the ratio.
    """
    lm = driveline_model(params, 1.0, belt=False)
    return np.diag(lm.M).copy(), lm.K


def _directions(r_g: NDArray[np.float64], rho: NDArray[np.float64]) \
        -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Belt-torque direction ``[0, r_g, -1, 0]`` (generalised force of ``-T_b``) and slip-velocity
    row ``[0, rho, -1, 0]``, each shape (N, 4)."""
    zeros = np.zeros(r_g.shape[0])
    ones = np.ones(r_g.shape[0])
    return (np.stack([zeros, r_g, -ones, zeros], axis=-1),
            np.stack([zeros, rho, -ones, zeros], axis=-1))


def _assemble_A(J: NDArray[np.float64], K: NDArray[np.float64], r_g: NDArray[np.float64],
                rho: NDArray[np.float64], c_s: NDArray[np.float64]) -> NDArray[np.float64]:
    """Stacked system matrices ``A``, shape (N, 8, 8), from 1-d arrays of length N.

    ``A = [[0, I], [-M^-1 K, -M^-1 C_b]]`` with ``C_b = c_s force vel^T``.
    """
    N = r_g.shape[0]
    Jinv = 1.0 / J
    force, vel = _directions(r_g, rho)
    A = np.zeros((N, 8, 8))
    A[:, :4, 4:] = np.eye(4)
    A[:, 4:, :4] = -(Jinv[:, None] * K)
    A[:, 4:, 4:] = -(c_s[:, None, None] * (Jinv * force)[:, :, None] * vel[:, None, :])
    return A


def _assemble_reduced(J: NDArray[np.float64], K: NDArray[np.float64], r_g: NDArray[np.float64],
                      rho: NDArray[np.float64], c_s: NDArray[np.float64]) -> NDArray[np.float64]:
    """Stacked reduced system matrices, shape (N, 5, 5), states `REDUCED_STATES`.

    Exact restriction of ``A`` to the invariant subspace of zero referred momentum
    ``J_d w_d + J_p w_p + r_g (J_s w_s + J_l w_l) = 0`` in the coordinates (spring deflections,
    speeds); ``w_d`` follows from the momentum.  Its five eigenvalues are the eigenvalues of
    ``A`` other than the three structural zeros.
    """
    N = r_g.shape[0]
    J_d, J_p, J_s, J_l = J
    k_tc, k_ds = K[0, 0], K[2, 2]
    A = np.zeros((N, 5, 5))
    A[:, 0, 2] = -(J_p / J_d) - 1.0           # e_tc' = w_d - w_p
    A[:, 0, 3] = -r_g * J_s / J_d
    A[:, 0, 4] = -r_g * J_l / J_d
    A[:, 1, 3] = 1.0                          # e_ds' = w_s - w_l
    A[:, 1, 4] = -1.0
    A[:, 2, 0] = k_tc / J_p                   # J_p w_p' = k_tc e_tc - r_g T_b~
    A[:, 2, 2] = -r_g * c_s * rho / J_p
    A[:, 2, 3] = r_g * c_s / J_p
    A[:, 3, 1] = -k_ds / J_s                  # J_s w_s' = -k_ds e_ds + T_b~
    A[:, 3, 2] = c_s * rho / J_s
    A[:, 3, 3] = -c_s / J_s
    A[:, 4, 1] = k_ds / J_l                   # J_l w_l' = k_ds e_ds
    return A


def _reduced_charpoly(J: NDArray[np.float64], K: NDArray[np.float64],
                      r_g: NDArray[np.float64], rho: NDArray[np.float64],
                      c_s: NDArray[np.float64]) -> NDArray[np.float64]:
    """Characteristic polynomials of `_assemble_reduced`'s matrices, shape (N, 6), highest
    power first, monic.

    Closed form ``Q(s) / (J_d J_p J_s J_l)`` (module docstring) with ``P = p2 s^2 + p0``,
    ``S = s2 s^2 + s0``: ``s P S`` gives the odd powers, the belt term ``c_s [r_g rho (J_d s^2 +
    k_tc) S + (J_l s^2 + k_ds) P]`` the even ones.  Every coefficient is a sum of positive
    products (times ``c_s``), so each is exact to a few ulps - no cancellation.
    """
    J_d, J_p, J_s, J_l = J
    k_tc, k_ds = K[0, 0], K[2, 2]
    p2, p0 = J_d * J_p, k_tc * (J_d + J_p)
    s2, s0 = J_s * J_l, k_ds * (J_s + J_l)
    lead = p2 * s2
    g = r_g * rho
    co = np.empty((r_g.shape[0], 6))
    co[:, 0] = 1.0
    co[:, 1] = c_s * (g * (J_d * s2) + J_l * p2) / lead
    co[:, 2] = (p2 * s0 + p0 * s2) / lead
    co[:, 3] = c_s * (g * (J_d * s0 + k_tc * s2) + (J_l * p0 + k_ds * p2)) / lead
    co[:, 4] = p0 * s0 / lead
    co[:, 5] = c_s * (g * (k_tc * s0) + k_ds * p0) / lead
    return co


def _assemble(J: NDArray[np.float64], K: NDArray[np.float64], r_g: NDArray[np.float64],
              rho: NDArray[np.float64], c_s: NDArray[np.float64], g_F: NDArray[np.float64],
              omega_p: NDArray[np.float64]) -> tuple[NDArray[np.float64], ...]:
    """Stacked ``A (N, 8, 8)``, ``B (N, 8, 3)``, ``C (N, 4, 8)``, ``D (N, 4, 3)`` (1-d inputs)."""
    N = r_g.shape[0]
    Jinv = 1.0 / J
    A = _assemble_A(J, K, r_g, rho, c_s)
    force, vel = _directions(r_g, rho)
    B = np.zeros((N, 8, 3))
    B[:, 4:, 0] = -(g_F[:, None] * force) * Jinv
    B[:, 4, 1] = Jinv[0]
    B[:, 7, 2] = Jinv[3]
    C = np.zeros((N, 4, 8))
    C[:, 0, 4:] = vel / (r_g * omega_p)[:, None]
    C[:, 1, 5] = 1.0
    C[:, 2, 6] = 1.0
    C[:, 3, 4:] = c_s[:, None] * vel
    D = np.zeros((N, 4, 3))
    D[:, 3, 0] = g_F
    return A, B, C, D


def state_matrices(params: Params, r_g: ArrayLike, nu: ArrayLike, F_s: ArrayLike,
                   omega_p: ArrayLike, traction: TractionModel | None = None) \
        -> tuple[NDArray[np.float64], ...]:
    """Slip-model matrices at many operating points at once (arrays broadcast to shape S).

    Returns
    -------
    A : shape S + (8, 8);  B : shape S + (8, 3);  C : shape S + (4, 8);  D : shape S + (4, 3)
        States `STATES`, inputs `INPUTS`, outputs `OUTPUTS` (module docstring).

    Raises
    ------
    ParameterError
        For ``omega_p <= 0``, ``F_s < 0``, a ratio outside the variator's range or a slip
        outside the traction curve's range (the message names the value).
    """
    t = _terms(params, r_g, nu, F_s, omega_p, traction)
    shape = t["r_g"].shape
    J, K = _mass_stiffness(params)
    flat = {k: np.ravel(v) for k, v in t.items()}
    mats = _assemble(J, K, flat["r_g"], flat["rho"], flat["c_s"], flat["g_F"], flat["omega_p"])
    return tuple(m.reshape(shape + m.shape[1:]) for m in mats)  # type: ignore[return-value]


def reduced_matrices(params: Params, r_g: ArrayLike, nu: ArrayLike, F_s: ArrayLike,
                     omega_p: ArrayLike, traction: TractionModel | None = None) \
        -> NDArray[np.float64]:
    """Reduced system matrices without the structural zeros, shape S + (5, 5).

    The slip model restricted (exactly) to zero referred momentum ``J_d omega_d + J_p omega_p
    + r_g (J_s omega_s + J_l omega_l) = 0``, states `REDUCED_STATES`.  Its eigenvalues are the
    five eigenvalues of `state_matrices`' ``A`` that are not structural zeros, so stability
    needs no rule for telling the structural zeros apart.  Arguments as `state_matrices`.
    """
    t = _terms(params, r_g, nu, F_s, omega_p, traction)
    shape = t["r_g"].shape
    J, K = _mass_stiffness(params)
    A = _assemble_reduced(J, K, np.ravel(t["r_g"]), np.ravel(t["rho"]), np.ravel(t["c_s"]))
    return A.reshape(shape + (5, 5))


def transmission_zeros(A: ArrayLike, B: ArrayLike, C: ArrayLike, D: ArrayLike) \
        -> NDArray[np.complex128]:
    """Finite invariant zeros of a square system (generalised eigenvalues of the Rosenbrock
    pencil ``[[A, B], [C, D]] - s [[I, 0], [0, 0]]``) [rad/s], sorted by magnitude."""
    A, B, C, D = (np.atleast_2d(np.asarray(x, float)) for x in (A, B, C, D))
    n, m, p = A.shape[0], B.shape[1], C.shape[0]
    if m != p:
        raise ValueError(f"transmission_zeros: {p} outputs and {m} inputs; need a square system")
    L = np.block([[A, B], [C, D]])
    Mp = np.zeros((n + m, n + m))
    Mp[:n, :n] = np.eye(n)
    z = generalized_eigvals(L, Mp)
    z = z[np.isfinite(z) & (np.abs(z) < 1e12)]
    return z[np.argsort(np.abs(z))]


@dataclass(frozen=True)
class SlipModel:
    """The driveline with the linearised slip damper at one operating point.

    Attributes
    ----------
    belt : the linearisation (operating point, c_b, c_s, g_F, ...)
    A : shape (8, 8);  B : shape (8, 3);  C : shape (4, 8);  D : shape (4, 3)
    states, inputs, outputs : signal names (`STATES`, `INPUTS`, `OUTPUTS`)
    name : model name (python-control allows no dots; the operating point is in ``belt.op``)
    """

    belt: BeltLinearisation
    A: NDArray[np.float64]
    B: NDArray[np.float64]
    C: NDArray[np.float64]
    D: NDArray[np.float64]
    states: tuple[str, ...] = STATES
    inputs: tuple[str, ...] = INPUTS
    outputs: tuple[str, ...] = OUTPUTS
    name: str = "slip"

    @property
    def op(self) -> SlipOperatingPoint:
        """The operating point."""
        return self.belt.op

    def _select(self, inputs: Sequence[str] | None, outputs: Sequence[str] | None) \
            -> tuple[list[int], list[int], list[str], list[str]]:
        ins = list(self.inputs) if inputs is None else list(inputs)
        outs = list(self.outputs) if outputs is None else list(outputs)
        for name in ins:
            if name not in self.inputs:
                raise ValueError(f"unknown input {name!r}: choose from {', '.join(self.inputs)}")
        for name in outs:
            if name not in self.outputs:
                raise ValueError(f"unknown output {name!r}: choose from {', '.join(self.outputs)}")
        return ([self.inputs.index(i) for i in ins], [self.outputs.index(o) for o in outs],
                ins, outs)

    def state_space(self, inputs: Sequence[str] | None = None,
                    outputs: Sequence[str] | None = None):
        """Named `control.StateSpace` (states `STATES`; default all inputs and outputs)."""
        import control

        ii, oo, ins, outs = self._select(inputs, outputs)
        return control.ss(self.A, self.B[:, ii], self.C[oo], self.D[np.ix_(oo, ii)],
                          inputs=ins, outputs=outs, states=list(self.states), name=self.name)

    def poles(self) -> NDArray[np.complex128]:
        """All eight eigenvalues of A [rad/s] (three structural zeros included), shape (8,)."""
        return np.sort_complex(np.linalg.eigvals(self.A))

    def frequency_response(self, omega: ArrayLike, inputs: Sequence[str] | None = None,
                           outputs: Sequence[str] | None = None, label: str = "") \
            -> FrequencyResponse:
        """``H(j w) = C (j w I - A)^{-1} B + D`` at `omega` [rad/s] (> 0), vectorised.

        Returns a `~empact.lumped.FrequencyResponse` with ``H`` of shape (n_out, n_in, n_f).
        """
        w = np.atleast_1d(np.asarray(omega, float))
        if np.any(~np.isfinite(w) | (w <= 0)):
            raise ValueError(f"omega = {float(w[~np.isfinite(w) | (w <= 0)][0]):g}: frequencies "
                             "must be > 0 [rad/s] (the model has poles at 0)")
        ii, oo, ins, outs = self._select(inputs, outputs)
        Z = 1j * w[:, None, None] * np.eye(8)[None] - self.A[None]
        X = np.linalg.solve(Z, np.broadcast_to(self.B[:, ii], (len(w), 8, len(ii))))
        H = np.einsum("on,fni->oif", self.C[oo], X) + self.D[np.ix_(oo, ii)][:, :, None]
        return FrequencyResponse(omega=w, H=H, inputs=tuple(ins), outputs=tuple(outs),
                                 label=label)

    def zeros(self, input: str = "F_s", output: str = "nu") -> NDArray[np.complex128]:
        """Finite invariant zeros of one input -> output channel [rad/s], by magnitude."""
        ii, oo, _, _ = self._select([input], [output])
        return transmission_zeros(self.A, self.B[:, ii], self.C[oo], self.D[np.ix_(oo, ii)])


def slip_model(params: Params, op: SlipOperatingPoint | None = None,
               traction: TractionModel | None = None) -> SlipModel:
    """The slip model at `op` (default: the ``[operating]`` point of `params`).

    Parameters
    ----------
    params : parameter set (variator, driveline, traction)
    op : operating point (r_g, nu, F_s, omega_p)
    traction : traction model (default `traction_from_params(params)`)
    """
    op = SlipOperatingPoint.from_params(params) if op is None else op
    belt = linearise_belt(params, op, traction)
    A, B, C, D = (m[0] for m in state_matrices(params, [op.r_g], [op.nu], [op.F_s],
                                               [op.omega_p], traction))
    return SlipModel(belt=belt, A=A, B=B, C=C, D=D, name="slip")


def slip_state_space(params: Params, op: SlipOperatingPoint | None = None,
                     traction: TractionModel | None = None, inputs: Sequence[str] | None = None,
                     outputs: Sequence[str] | None = None):
    """Named `control.StateSpace` of the slip model at `op` (see `slip_model`)."""
    return slip_model(params, op, traction).state_space(inputs, outputs)


# --------------------------------------------------------------------------------------------
# Stability measures
# --------------------------------------------------------------------------------------------
def dynamic_poles(eigs: ArrayLike) -> NDArray[np.complex128]:
    """Drop the `N_STRUCTURAL_ZEROS` eigenvalues of smallest magnitude (last axis)."""
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
    mag = np.abs(p)
    zeta = np.where(mag > 0, -p.real / np.where(mag > 0, mag, 1.0), 1.0)
    return p.real.max(axis=-1), zeta.min(axis=-1)


def oscillatory(poles: ArrayLike, tol: float = 1e-3) \
        -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Natural frequencies ``|p| / (2 pi)`` [Hz] and damping ratios ``-Re(p) / |p|`` [-] of the
    poles (or zeros) with ``Im(p) > tol`` [rad/s], ascending in frequency.

    The default `tol` (1e-3 rad/s) is far above the rounding of the structural zeros (below
    1e-4 rad/s) and far below any oscillatory mode of the driveline.
    """
    p = np.asarray(poles, complex).ravel()
    p = p[p.imag > tol]
    order = np.argsort(np.abs(p))
    p = p[order]
    return np.abs(p) / (2 * np.pi), -p.real / np.abs(p)


# --------------------------------------------------------------------------------------------
# Fig. 9: root locus over c_b
# --------------------------------------------------------------------------------------------
def coupled_limit(params: Params, r_g: float, nu0: float = 0.0) -> NDArray[np.complex128]:
    """Finite poles of the slip model as ``c_b -> inf`` [rad/s], shape (7,), by magnitude.

    The slip velocity is then held at zero (``omega_s = rho omega_p``): the constrained system
    ``M q'' + K q = b lambda``, ``a^T q' = 0``, reduced with ``q = N y`` (``a^T N = 0``) and
    projected with ``W`` (``b^T W = 0``).  Its eigenvalues ``+-sqrt(-w^2)`` are the coupled
    driveline's (Table 2 with a rigid belt), plus the three structural zeros; the eighth pole
    goes to ``-inf``.
    """
    if not (math.isfinite(r_g) and r_g > 0):
        raise ParameterError(f"r_g = {r_g!r}: must be a positive finite ratio")
    variator_state(r_g, params.variator)  # range check
    J, K = _mass_stiffness(params)
    rho = r_g * (1 - float(_check_slip_value(nu0)))
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
class BeltRootLocus:
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

    The locus itself runs over `c_b_range` [N m s/rad] (log spacing, `empact.rootlocus.
    root_locus`); the end points ``c_b = 0`` (uncoupled sides) and ``c_b -> inf``
    (`coupled_limit`) are computed exactly.  The model damping is ``c_s = c_b / r_g`` (module
    docstring).  The clamping-force gain does not enter the poles.
    """
    lo, hi = c_b_range
    if not (0 < lo < hi and math.isfinite(hi)):
        raise ParameterError(f"c_b_range = {c_b_range!r}: need 0 < c_b_min < c_b_max < inf "
                             "[N m s/rad]")
    variator_state(r_g, params.variator)
    nu0 = float(_check_slip_value(nu0))
    J, K = _mass_stiffness(params)
    r = np.array([float(r_g)])
    rho = r * (1 - nu0)

    def A_of(c_b: float) -> NDArray[np.float64]:
        return _assemble_A(J, K, r, rho, np.array([c_b / r_g]))[0]

    loc = root_locus(A_of, lo, hi, spacing="log", max_move=max_move, name="c_b [N m s/rad]")
    start = np.sort_complex(np.linalg.eigvals(A_of(0.0)))
    stop = coupled_limit(params, r_g, nu0)
    return BeltRootLocus(r_g=float(r_g), nu0=nu0, locus=loc, start=start, stop=stop,
                         uncoupled_hz=_oscillatory_hz(start), coupled_hz=_oscillatory_hz(stop))


# --------------------------------------------------------------------------------------------
# Fig. 11: poles over an operating-point variable
# --------------------------------------------------------------------------------------------
def _grid_terms(name: str, values: ArrayLike) -> NDArray[np.float64]:
    if name not in VARIABLES:
        raise ParameterError(f"unknown operating-point variable {name!r}: choose from "
                             f"{', '.join(VARIABLES)}")
    v = np.atleast_1d(np.asarray(values, float))
    if v.ndim != 1 or v.size == 0:
        raise ParameterError(f"{name}: need a non-empty 1-d array of values")
    return v


@dataclass(frozen=True)
class PoleSweep:
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
    base: SlipOperatingPoint
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
        mag = np.abs(self.poles)
        return np.where(mag > 0, -self.poles.real / np.where(mag > 0, mag, 1.0), 1.0)

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
        ascending in frequency (upper-half-plane poles only)."""
        return oscillatory(self.poles[k])


def pole_sweep(params: Params, name: Variable, values: ArrayLike,
               base: SlipOperatingPoint | None = None,
               traction: TractionModel | None = None) -> PoleSweep:
    """Poles of the slip model over one variable of the operating point (batched).

    Parameters
    ----------
    params : the parameter set
    name : "nu", "F_s", "omega_p" or "r_g"
    values : values of that variable, shape (n,)
    base : the other variables (default: the ``[operating]`` point of `params`)
    traction : traction model (default `traction_from_params(params)`)
    """
    v = _grid_terms(name, values)
    base = SlipOperatingPoint.from_params(params) if base is None else base
    op = base.as_dict()
    op[name] = v
    t = {k: np.broadcast_to(a, v.shape) for k, a in
         _terms(params, op["r_g"], op["nu"], op["F_s"], op["omega_p"], traction).items()}
    J, K = _mass_stiffness(params)
    A = _assemble_reduced(J, K, t["r_g"], t["rho"], t["c_s"])
    poles = track_branches(np.linalg.eigvals(A))
    return PoleSweep(name=name, values=v, base=base, poles=poles,
                     c_b=np.broadcast_to(t["c_b"], v.shape).copy(),
                     dmu=np.broadcast_to(t["dmu"], v.shape).copy())


# --------------------------------------------------------------------------------------------
# Fig. 12: F_s -> nu transfer functions
# --------------------------------------------------------------------------------------------
def slip_frequency_responses(params: Params, ops: Sequence[SlipOperatingPoint],
                             omega: ArrayLike, labels: Sequence[str] | None = None,
                             traction: TractionModel | None = None, input: str = "F_s",
                             output: str = "nu") -> list[FrequencyResponse]:
    """``input -> output`` responses at several operating points (Fig. 12: ``F_s -> nu``).

    Returns one `~empact.lumped.FrequencyResponse` per point, ``H`` shape (1, 1, n_f) in
    output units per input unit (``nu`` per N for ``F_s -> nu``); `omega` [rad/s].
    """
    if labels is not None and len(labels) != len(ops):
        raise ValueError(f"{len(labels)} labels for {len(ops)} operating points")
    out = []
    for k, op in enumerate(ops):
        label = labels[k] if labels is not None else \
            f"r_g = {op.r_g:g}, nu = {100 * op.nu:g} %"
        out.append(slip_model(params, op, traction).frequency_response(omega, [input], [output],
                                                                       label=label))
    return out


# --------------------------------------------------------------------------------------------
# Fig. 13: zeros of F_s -> nu over the ratio
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class ZeroLocus:
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
    base: SlipOperatingPoint
    zeros: NDArray[np.complex128]
    n_origin: NDArray[np.int64]
    coupled: NDArray[np.complex128]

    @property
    def zero_hz(self) -> NDArray[np.float64]:
        """``|z| / (2 pi)`` of the upper-half-plane zeros [Hz], shape (n, m // 2), ascending."""
        z = np.where(self.zeros.imag > 0, np.abs(self.zeros), np.nan)
        return np.sort(z, axis=1)[:, : self.zeros.shape[1] // 2] / (2 * np.pi)


def zero_locus(params: Params, r_g: ArrayLike, base: SlipOperatingPoint | None = None,
               traction: TractionModel | None = None, origin_tol: float = 1e-5) -> ZeroLocus:
    """Invariant zeros of ``F_s -> nu`` at each ratio of `r_g` (shape (n,)).

    Zeros with ``|z| < origin_tol * max |z|`` count as zeros at the origin.
    """
    r = _grid_terms("r_g", r_g)
    base = SlipOperatingPoint.from_params(params) if base is None else base
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


# --------------------------------------------------------------------------------------------
# Stability map
# --------------------------------------------------------------------------------------------
#: Certified relative accuracy of every pole of ``stability_map(method="roots")``
#: (`empact._polyroots`); points that miss it are recomputed with `numpy.linalg.eigvals`.
_ROOTS_RTOL = 1e-11

@dataclass(frozen=True)
class StabilityMap:
    """Largest pole real part and smallest damping ratio over a grid of two variables.

    Attributes
    ----------
    x_name, y_name : the two variables (from `VARIABLES`)
    x : shape (nx,);  y : shape (ny,)   [units of the variables]
    base : operating point of the other two variables
    max_real : largest real part of the non-structural poles [1/s], shape (ny, nx)
    min_damping : smallest damping ratio [-], shape (ny, nx)
    tol : real parts above ``tol`` [1/s] count as unstable
    method : the method that computed the map ("roots", "reduced" or "full")
    n_fallback : ``method="roots"`` only: number of points whose polynomial roots were not
        certified and were recomputed with `numpy.linalg.eigvals` (0 for the other methods)
    """

    x_name: str
    y_name: str
    x: NDArray[np.float64]
    y: NDArray[np.float64]
    base: SlipOperatingPoint
    max_real: NDArray[np.float64]
    min_damping: NDArray[np.float64]
    tol: float
    method: str = "reduced"
    n_fallback: int = 0

    @property
    def unstable(self) -> NDArray[np.bool_]:
        """Points with a pole in the right half-plane, shape (ny, nx)."""
        return self.max_real > self.tol

    @property
    def unstable_fraction(self) -> float:
        """Fraction of grid points that are unstable [-]."""
        return float(self.unstable.mean())


def stability_map(params: Params, x_name: Variable, x: ArrayLike, y_name: Variable,
                  y: ArrayLike, *, base: SlipOperatingPoint | None = None,
                  traction: TractionModel | None = None, method: MapMethod = "roots",
                  chunk_size: int = 4096, workers: int | None = None, tol: float = 1e-6) -> StabilityMap:
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
    method : {"roots", "reduced", "full"}
        ``"full"``: the stacked ``A`` of `state_matrices`, shape (chunk, 8, 8), and the three
        eigenvalues of smallest magnitude dropped as the structural zeros.  ``"reduced"``:
        the stacked matrices of `reduced_matrices`, shape (chunk, 5, 5), whose eigenvalues
        are exactly the five non-structural ones - no magnitude rule, and about twice as
        fast.  ``"roots"`` (default): per point the closed-form characteristic polynomial of
        the reduced matrix (`_reduced_charpoly`) and its roots by a compiled Aberth-Ehrlich
        iteration (`empact._polyroots`), each root certified to ``1e-11`` relative by
        inclusion disks; points that are not certified (repeated or clustered poles) are
        recomputed with `numpy.linalg.eigvals` on the reduced matrices and counted in
        ``StabilityMap.n_fallback``.  About 1.5x faster than ``"reduced"``; the first call
        in a process compiles the numba kernels (seconds) or loads them from numba's
        on-disk cache (~0.3 s).  All three give the same map to rounding.
    chunk_size : points per eigenvalue call (>= 1)
    workers : threads working on chunks in parallel (>= 1; default: one per CPU core; the
        compiled root finder and numpy's eigenvalue routine release the GIL)
    tol : real parts above this [1/s] count as unstable (absorbs rounding only)

    Returns
    -------
    StabilityMap
        ``max_real`` and ``min_damping`` of shape (ny, nx).
    """
    xv, yv = _grid_terms(x_name, x), _grid_terms(y_name, y)
    if x_name == y_name:
        raise ParameterError(f"stability map over {x_name!r} twice: choose two different "
                             f"variables of {', '.join(VARIABLES)}")
    if method not in ("roots", "reduced", "full"):
        raise ParameterError(f"method = {method!r}: choose 'roots', 'reduced' or 'full'")
    workers = (os.cpu_count() or 1) if workers is None else workers
    chunk_size, workers = int(chunk_size), int(workers)
    if chunk_size < 1:
        raise ParameterError(f"chunk_size = {chunk_size!r}: must be >= 1")
    if workers < 1:
        raise ParameterError(f"workers = {workers!r}: must be >= 1")
    base = SlipOperatingPoint.from_params(params) if base is None else base
    fixed = base.as_dict()
    # Every variable is valid or not on its own: checking the two axes checks the whole grid,
    # so a bad value is reported at once, before any chunk is computed.
    for name, values in ((x_name, xv), (y_name, yv)):
        _terms(params, **{**fixed, name: values}, traction=traction)
    tr = traction_from_params(params) if traction is None else traction
    J, K = _mass_stiffness(params)
    nx = xv.size
    n = nx * yv.size
    max_real = np.empty(n)
    min_damp = np.empty(n)
    fallbacks: list[int] = []  # one entry per chunk (list.append is thread-safe)
    if method == "roots":
        from ._polyroots import polyroots

    def work(start: int) -> None:
        idx = np.arange(start, min(start + chunk_size, n))
        op = dict(fixed)
        op[x_name], op[y_name] = xv[idx % nx], yv[idx // nx]
        t = _terms(params, op["r_g"], op["nu"], op["F_s"], op["omega_p"], tr)
        r, rho, c_s = (np.broadcast_to(t[k], idx.shape) for k in ("r_g", "rho", "c_s"))
        if method == "full":
            eig = np.linalg.eigvals(_assemble_A(J, K, r, rho, c_s))
            max_real[idx], min_damp[idx] = stability_measures(eig)
        elif method == "roots":
            z, ok = polyroots(_reduced_charpoly(J, K, r, rho, c_s), rtol=_ROOTS_RTOL)
            mr, mz = _measures(z)
            bad = np.flatnonzero(~ok)
            if bad.size:  # not certified: exactly these points by LAPACK, counted
                mr[bad], mz[bad] = _measures(np.linalg.eigvals(
                    _assemble_reduced(J, K, r[bad], rho[bad], c_s[bad])))
            fallbacks.append(int(bad.size))
            max_real[idx], min_damp[idx] = mr, mz
        else:
            eig = np.linalg.eigvals(_assemble_reduced(J, K, r, rho, c_s))
            max_real[idx], min_damp[idx] = _measures(eig)

    starts = range(0, n, chunk_size)
    if workers == 1:
        for s0 in starts:
            work(s0)
    else:
        from concurrent.futures import ThreadPoolExecutor

        with ThreadPoolExecutor(workers) as pool:
            list(pool.map(work, starts))
    shape = (yv.size, nx)
    return StabilityMap(x_name=x_name, y_name=y_name, x=xv, y=yv, base=base,
                        max_real=max_real.reshape(shape), min_damping=min_damp.reshape(shape),
                        tol=float(tol), method=method, n_fallback=int(sum(fallbacks)))
