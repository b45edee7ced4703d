"""The variator's laws, each written once (private).

Every function here is the one source of its law for the NumPy API (`empact.variator`), the
compiled nonlinear kernel (`empact.nonlinear._kernel`) and the sampled loop law's core
(`empact.control._law_core`).  They are plain Python in the subset numba compiles, so that:

* `empact.variator._compiled` compiles each of them as it stands (``njit(cache=True)``),
  scalar, real or complex arguments (the kernel's complex step differentiates through them;
  comparisons use the real part);
* the branch-free ones (arithmetic and numpy ufuncs only: `wrap_angle`, `belt_geometry`,
  `belt_newton_step`, `radius_at_zero_wrap`, `kappa_geo`, `magic_angle`, `magic_formula`,
  `magic_formula_d`, `lerp`, `log_kappa_eq`, `creep_factors`, `creep_coefficient`) also
  evaluate elementwise on numpy arrays, which is how the NumPy API calls them (without
  loading numba: ``empact params`` and the linear analyses stay numba-free);
* the branching ones (`secondary_radius`, `knots_at`, `table_at`) are scalar; the NumPy API
  holds the same rule with `lerp` on a vectorised search
  (`empact.variator._tables.interp_knots`), tested equal to the compiled law.

The analytic traction laws are a registry (`TRACTION_LAWS`, `register_traction`): a law is
its three functions here and one `register_traction` call; everything else is generated from
the registry (the compiled twins and the kernel's dispatch, `empact.variator._compiled`; the
law's part of the kernel's parameter vector, `traction_parameter_names`; the NumPy model,
`empact.variator.traction.AnalyticTraction`; the choices of
`empact.nonlinear.ModelOptions` ``traction_law`` and of the command line's
``--traction-law``).  Its coefficients are the fields ``<c>_low``, ``<c>_med``, ``<c>_od`` of
``[traction]`` (`empact.variator.traction.TractionParams`), interpolated linearly in
``ln r_g`` between the section's three ratios (`knots_at`), as the magic formula's are.

Equation numbers are the paper's (`empact.variator.geometry`).  SI units.
"""
from __future__ import annotations

import os
from typing import Any, Callable, NamedTuple

import numpy as np

#: the laws, each compiled by `empact.variator._compiled` (with the helpers they call)
LAWS = ("wrap_angle", "belt_geometry", "belt_newton_step", "radius_at_zero_wrap",
        "secondary_radius", "kappa_geo", "magic_angle", "magic_formula", "magic_formula_d",
        "magic_peak_d", "lerp", "knots_at", "_curve_at", "table_at", "log_kappa_eq",
        "creep_factors", "creep_coefficient", "creep_coefficient_d")
#: those compiled as calls rather than inlined into their callers (the loops and the tables'
#: rare path: inlined, they would crowd the kernel's common path)
NOT_INLINED = ("secondary_radius", "_curve_at", "table_at")

__all__ = [name for name in LAWS if not name.startswith("_")] + [
    "LAWS", "NOT_INLINED", "TractionLaw", "TRACTION_LAWS", "TRACTION_KNOTS",
    "register_traction", "traction_parameter_names"]


# -- eqs. 4 and 6: wrap angle, belt length, the running radii ---------------------------------
def wrap_angle(R_p, R_s, a):
    """``phi = arcsin((R_p - R_s) / a)`` [rad] (eq. 4)."""
    return np.arcsin((R_p - R_s) / a)


def belt_geometry(R_p, R_s, a):
    """``(phi, L)``: wrap angle (eq. 4) and belt length
    ``L = 2 a cos(phi) + (pi + 2 phi) R_p + (pi - 2 phi) R_s`` [m] (eq. 6)."""
    phi = wrap_angle(R_p, R_s, a)
    return phi, 2.0 * a * np.cos(phi) + (np.pi + 2.0 * phi) * R_p + (np.pi - 2.0 * phi) * R_s


def belt_newton_step(R_s, r_g, L_belt, a):
    """Newton step on ``R_s`` of ``L(r_g R_s, R_s) = L_belt`` [m], with the exact derivative
    ``dL/dR_s = r_g (pi + 2 phi) + (pi - 2 phi)`` (NaN outside the arcsin's domain)."""
    phi, L = belt_geometry(r_g * R_s, R_s, a)
    return (L - L_belt) / (r_g * (np.pi + 2.0 * phi) + (np.pi - 2.0 * phi))


def radius_at_zero_wrap(r_g, L_belt, a):
    """``R_s`` [m] of eq. 6 with ``phi = 0``: the Newton iteration's start."""
    return (L_belt - 2.0 * a) / (np.pi * (1.0 + r_g))


def secondary_radius(r_g, L_belt, a, guess, tol):
    """Secondary running radius ``R_s`` [m] at ratio `r_g` (scalar): Newton steps
    (`belt_newton_step`) from `guess` (NaN: `radius_at_zero_wrap`) until a step is at most
    ``tol L_belt``; NaN when there is no belt geometry at that ratio (50 steps)."""
    R_s = radius_at_zero_wrap(r_g, L_belt, a) if guess != guess else guess
    for _ in range(50):
        step = belt_newton_step(R_s, r_g, L_belt, a)
        if step != step:
            return np.nan
        R_s -= step
        if abs(step) <= tol * L_belt:
            return R_s
    return np.nan


def kappa_geo(phi):
    """Geometric thrust ratio ``(pi + 2 phi) / (pi - 2 phi)`` [-] (``dL/dR_p / dL/dR_s``)."""
    return (np.pi + 2.0 * phi) / (np.pi - 2.0 * phi)


# -- traction: the magic formula ---------------------------------------------------------------
def magic_angle(nu, B, E):
    """``(B nu, arctan(B nu), inner, arctan(inner))`` with the magic formula's ``inner = B nu
    - E (B nu - arctan(B nu))``."""
    Bn = B * nu
    t = np.arctan(Bn)
    inner = Bn - E * (Bn - t)
    return Bn, t, inner, np.arctan(inner)


def magic_formula(nu, B, C, D, E):
    """``mu = D sin(C arctan(B nu - E (B nu - arctan(B nu))))`` [-] (`magic_angle`)."""
    return D * np.sin(C * magic_angle(nu, B, E)[3])


def magic_formula_d(nu, B, C, D, E, B_l, C_l, D_l, E_l):
    """``(mu, dmu/dnu, dmu/dl)``: `magic_formula` and its partials in the slip and in a
    variable ``l`` the coefficients move with at slopes ``B_l, C_l, D_l, E_l`` (the
    kernel's ``ln r_g``; zeros for the slope in nu alone)."""
    Bn, t, inner, at = magic_angle(nu, B, E)
    sn = np.sin(C * at)
    mu_ca = D * np.cos(C * at)                      # d mu / d(C at)
    in_bn = 1.0 - E * (1.0 - 1.0 / (1.0 + Bn * Bn))  # d inner / d Bn
    at_in = 1.0 / (1.0 + inner * inner)             # d at / d inner
    mu_nu = mu_ca * C * at_in * in_bn * B
    mu_l = D_l * sn + mu_ca * (C_l * at + C * at_in * (in_bn * B_l * nu - E_l * (Bn - t)))
    return D * sn, mu_nu, mu_l


def magic_peak_d(B, C, D, E, B_l, C_l, D_l, E_l):
    """``(mu_max, d mu_max / dl)``: the magic formula's peak, its coefficient ``D`` (reached
    where ``C arctan(phi) = pi / 2``, for ``C >= 1``), and its slope."""
    return D, D_l


# -- interpolation of coefficients and tabulated maps -----------------------------------------
def lerp(x, x0, x1, y0, y1):
    """``y0 + (x - x0) / (x1 - x0) (y1 - y0)``: the straight line through two samples."""
    return y0 + (x - x0) / (x1 - x0) * (y1 - y0)


def knots_at(x, p, k0, v0, n):
    """``(value, rise, run)`` of the piecewise-linear function through the `n` samples
    ``(p[k0 + j], p[v0 + j])`` at `x` (scalar, real or complex), held constant outside the
    knots; a knot counts to the segment on its left (the complex step's branch).  The slope
    is ``rise / run`` (``0 / 1`` outside), divided only by a caller that needs it."""
    if x.real <= p[k0]:
        return p[v0] + 0.0 * x, 0.0, 1.0
    for j in range(n - 1):
        if x.real <= p[k0 + j + 1]:
            return (lerp(x, p[k0 + j], p[k0 + j + 1], p[v0 + j], p[v0 + j + 1]),
                    p[v0 + j + 1] - p[v0 + j], p[k0 + j + 1] - p[k0 + j])
    return p[v0 + n - 1] + 0.0 * x, 0.0, 1.0


def _curve_at(xv, p, s):
    """``(value, slope)`` of the table's curve starting at ``p[s]`` (`knots_at`)."""
    v, rise, run = knots_at(xv, p, s + 1, s + 1 + int(p[s]), int(p[s]))
    return v, rise / run


def table_at(xv, lr, p, base):
    """``(value, d/d xv, d/d lr)`` of a tabulated map at `xv` and log-ratio `lr` (scalar, real
    or complex), the table encoded at ``p[base:]`` (`empact.variator._tables.encode_curves`):
    linear in x along each curve, linear in ln r_g between the curves, held constant
    outside (`knots_at` along both)."""
    n_r = int(p[base])
    if n_r == 1 or lr.real <= p[base + 1]:
        v, d = _curve_at(xv, p, base + int(p[base + 1 + n_r]))
        return v, d, 0.0
    for i in range(n_r - 1):
        if lr.real <= p[base + 2 + i]:
            c0, d0 = _curve_at(xv, p, base + int(p[base + 1 + n_r + i]))
            c1, d1 = _curve_at(xv, p, base + int(p[base + 2 + n_r + i]))
            l0, l1 = p[base + 1 + i], p[base + 2 + i]
            return (lerp(lr, l0, l1, c0, c1), lerp(lr, l0, l1, d0, d1),
                    (c1 - c0) / (l1 - l0))
    v, d = _curve_at(xv, p, base + int(p[base + 2 * n_r]))
    return v, d, 0.0


# -- thrust ratio and creep ----------------------------------------------------------------------
def log_kappa_eq(tau, lr, kgeo, p0, b0, b1):
    """``ln kappa* = p0 ln kappa_geo + (b0 - b1 ln r_g) tau``: the analytic equilibrium
    thrust ratio at torque ratio `tau` and log-ratio `lr`."""
    return p0 * np.log(kgeo) + (b0 - b1 * lr) * tau


def creep_factors(F_s, lr, D_ref, k_D, F_ref, a1, a2):
    """``(D(F_s), a1 + a2 lr^2)``: the creep coefficient's force and ratio factors, ``D(F_s)
    = D_ref (1 + k_D (F_s - F_ref))`` (Carbone et al. 2007); `lr` is ``ln r_g``."""
    return D_ref * (1.0 + k_D * (F_s - F_ref)), a1 + a2 * lr * lr


def creep_coefficient(r_g, R_p, F_s, lr, a, gain, G_beta, D_ref, k_D, F_ref, a1, a2):
    """``K_c = gain D(F_s) G_beta r_g (R_p / a) (a1 + a2 ln^2 r_g)`` [-] (`creep_factors`):
    ratio change per radian of primary rotation per unit log thrust-ratio error."""
    D, Q = creep_factors(F_s, lr, D_ref, k_D, F_ref, a1, a2)
    return gain * D * G_beta * r_g * (R_p / a) * Q


def creep_coefficient_d(r_g, R_p, F_s, lr, a, gain, G_beta, D_ref, k_D, F_ref, a1, a2):
    """``(K_c, dK_c/dF_s, dK_c/dr_g, dK_c/dR_p, dK_c/d lr)``: `creep_coefficient` and its
    partials (real)."""
    D, Q = creep_factors(F_s, lr, D_ref, k_D, F_ref, a1, a2)
    cg = gain * G_beta / a
    return (creep_coefficient(r_g, R_p, F_s, lr, a, gain, G_beta, D_ref, k_D, F_ref, a1, a2),
            cg * D_ref * k_D * r_g * R_p * Q, cg * D * R_p * Q, cg * D * r_g * Q,
            cg * D * r_g * R_p * 2.0 * a2 * lr)


# -- the registry of analytic traction laws ------------------------------------------------------
#: the ratios at which a law's coefficients are given: the fields ``<c>_low``, ``<c>_med``,
#: ``<c>_od`` of ``[traction]``, at its ``r_low``, ``r_med``, ``r_od``
TRACTION_KNOTS = ("low", "med", "od")


class TractionLaw(NamedTuple):
    """An analytic traction law ``mu(nu, c_1(r_g), .., c_m(r_g))`` of the registry.

    Every function is plain Python in the subset numba compiles, without branches
    (arithmetic and numpy ufuncs), so that the same code runs compiled on scalars (real or
    complex: the kernel's complex step) and on numpy arrays (the NumPy model).

    Attributes
    ----------
    name : str
        The law's name: the choice of ``ModelOptions(traction_law=...)`` and
        ``--traction-law``.
    coefficients : tuple of str
        The coefficients' names ``c``; each is given at the knots (`TRACTION_KNOTS`) by the
        ``[traction]`` fields ``<c>_low``, ``<c>_med``, ``<c>_od`` (a name two laws share is
        one set of fields).
    mu : callable
        ``mu(nu, *c)`` [-]: the traction coefficient at slip `nu` [-].
    mu_d : callable
        ``mu_d(nu, *c, *c_l) -> (mu, dmu/dnu, dmu/dl)``: the value and its partials in the
        slip and in a variable ``l`` the coefficients move with at slopes ``c_l`` (the
        kernel's ``ln r_g``; zeros for the slope in nu alone).
    peak_d : callable
        ``peak_d(*c, *c_l) -> (mu_max, d mu_max / dl)``: the curve's peak [-] (the torque
        ratio is ``tau = mu / mu_max``) and its slope.
    """

    name: str
    coefficients: tuple[str, ...]
    mu: Callable[..., Any]
    mu_d: Callable[..., Any]
    peak_d: Callable[..., Any]


#: the analytic traction laws by name, in registration order (the kernel's law index)
TRACTION_LAWS: dict[str, TractionLaw] = {}
_FROZEN: list[str] = []  # set when the compiled dispatch is generated (`_compiled`)


def register_traction(name: str, coefficients: tuple[str, ...], mu: Callable[..., Any],
                      mu_d: Callable[..., Any], peak_d: Callable[..., Any]) -> TractionLaw:
    """Add an analytic traction law to the registry (see `TractionLaw`).

    Call it in this module, below the law's functions: the compiled kernel's dispatch is
    generated from the registry when `empact.variator._compiled` is first imported, and numba
    caches the kernel by its source files (a law registered elsewhere is refused once the
    dispatch exists, and needs its own numba cache, ``NUMBA_CACHE_DIR``).

    Parameters
    ----------
    name : str
        The law's name (lower case, digits and ``-``), new.
    coefficients : tuple of str
        The coefficients' names (identifiers), as the law's functions take them.
    mu, mu_d, peak_d : callable
        The law's value, its partials and its peak (`TractionLaw`).

    Returns
    -------
    TractionLaw
        The registered law.
    """
    if _FROZEN:
        raise RuntimeError(f"traction law {name!r}: registered after the compiled dispatch "
                           f"was generated (by {_FROZEN[0]}); register it in "
                           "empact.variator._laws")
    if any(getattr(f, "__module__", __name__) != __name__ for f in (mu, mu_d, peak_d)) \
            and not os.environ.get("NUMBA_CACHE_DIR"):
        raise RuntimeError(f"traction law {name!r}: a law registered outside "
                           "empact.variator._laws needs its own numba cache (set "
                           "NUMBA_CACHE_DIR): the package's cache holds the kernel compiled "
                           "with the laws of _laws.py")
    if not (isinstance(name, str) and name and name.replace("-", "").isalnum()
            and name == name.lower()):
        raise ValueError(f"traction law name {name!r}: lower-case letters, digits and '-'")
    if name in TRACTION_LAWS:
        raise ValueError(f"traction law {name!r}: already registered")
    coefficients = tuple(coefficients)
    if not coefficients or not all(isinstance(c, str) and c.isidentifier()
                                   for c in coefficients) \
            or len(set(coefficients)) != len(coefficients):
        raise ValueError(f"traction law {name!r}: coefficients {coefficients!r} must be "
                         "distinct identifiers, at least one")
    for f in (mu, mu_d, peak_d):
        if not callable(f):
            raise ValueError(f"traction law {name!r}: {f!r} is not a function")
    law = TractionLaw(name, coefficients, mu, mu_d, peak_d)
    TRACTION_LAWS[name] = law
    return law


def traction_parameter_names() -> tuple[str, ...]:
    """The traction laws' part of the kernel's parameter vector, from the registry:
    ``traction_law`` (the law's index in `TRACTION_LAWS`), ``ln_r_low``, ``ln_r_med``,
    ``ln_r_od`` (the knots' log-ratios), then every coefficient at every knot
    (``<c>_low``, ``<c>_med``, ``<c>_od``), each name once, in registration order."""
    names = ["traction_law"] + [f"ln_r_{k}" for k in TRACTION_KNOTS]
    for law in TRACTION_LAWS.values():
        for c in law.coefficients:
            for k in TRACTION_KNOTS:
                if f"{c}_{k}" not in names:
                    names.append(f"{c}_{k}")
    return tuple(names)


register_traction("magic-formula", ("B", "C", "D", "E"), magic_formula, magic_formula_d,
                  magic_peak_d)
