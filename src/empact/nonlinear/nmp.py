"""Non-minimum-phase behaviour of the actuation (paper Sec. 2.3; model notes Sec. 5).

Two parts:

* **Geometry.**  ``Delta_x = x_p - x_s = a sin(phi) tan(beta)`` (eq. 5) and the belt-length
  change for an equal translation ``delta`` of both sheaves (primary closing, secondary
  opening), exact from eq. 6 and to first order ``4 phi delta / tan(beta)``: negative below
  r_g = 1 (the belt slackens, F_s falls, the slip rises), positive above.
* **Zeros.**  The finite zeros of the T_mp -> slip channel of the exactly linearised model
  (`empact.nonlinear.linearization`) over the ratio, for either slip signal (model notes
  Sec. 6): ``slip="nu"``, the slip of eq. 2 on the current radii, or ``slip="nu_r"``, the slip
  at the operating ratio, ``1 - omega_s / (r_g0 omega_p)``, whose linearisation is ``nu~ -
  (1 - nu0) r_g~ / r_g0`` (eq. 2 without its direct dependence on the ratio: eq. 3 and the
  paper's Fig. 12 slip).  The paper states a right-half-plane zero at r_g = 0.5 and none at
  r_g = 2; `nmp_analysis` reports what the model gives, for either sheave kinematics
  (`empact.nonlinear.model.ModelOptions.kinematics`).

A zero counts as right-half-plane when its real part exceeds 1e-3 of its magnitude (damping
ratio below -0.001): lightly damped zeros on the imaginary axis stay out of the count.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._deprecate import warn_renamed
from .._results import Result
from .._validate import check_choice, check_number
from ..lti import channel_zeros
from ..params import OperatingPoint, Params
from ..variator.geometry import belt_length, check_ratio, radii, wrap_angle
from .linearization import plant
from .model import nonlinear_model

__all__ = ["BeltLengthChange", "belt_length_change", "NmpResult", "nmp_analysis", "SLIPS"]

#: the two slip signals (plant outputs)
SLIPS = ("nu", "nu_r")


@dataclass(frozen=True)
class BeltLengthChange(Result):
    """Sec. 2.3 geometry over ratios (arrays of shape (n_r,)).

    Attributes
    ----------
    r_g : ratios [-]
    phi : wrapped-angle term [rad] (eq. 4)
    delta_x : ``x_p - x_s = a sin(phi) tan(beta)`` [m] (eq. 5)
    delta : the equal sheave translation used [m]
    dL_exact : ``L(R_p + delta/tan(beta), R_s - delta/tan(beta)) - L(R_p, R_s)`` [m] (eq. 6)
    dL_first_order : ``4 phi delta / tan(beta)`` [m]
    """

    r_g: NDArray[np.float64]
    phi: NDArray[np.float64]
    delta_x: NDArray[np.float64]
    delta: float
    dL_exact: NDArray[np.float64]
    dL_first_order: NDArray[np.float64]


def belt_length_change(params: Params, r_g: ArrayLike, delta: float = 1e-5) -> BeltLengthChange:
    """Delta_x (eq. 5) and the belt-length change for an equal translation `delta` [m].

    Parameters
    ----------
    params : Params
        Its ``[variator]`` block is read.
    r_g : array_like
        Geometric ratio(s) [-], a scalar or shape (n_r,), inside the variator's range.
    delta : float
        Equal translation of both moving sheaves [m], in (0, 1e-3).

    Returns
    -------
    BeltLengthChange
        ``phi`` [rad], ``delta_x`` [m] and the exact and first-order belt-length changes
        ``dL_exact``, ``dL_first_order`` [m], each of shape (n_r,).
    """
    v = params.variator
    check_number("delta", delta, 0.0, 1e-3, lo_open=True, hi_open=True, unit="m")
    r = np.atleast_1d(check_ratio(r_g, v))
    R_p, R_s = radii(r, v.L_belt, v.a)
    tb = np.tan(v.beta)
    phi = wrap_angle(R_p, R_s, v.a)
    dL = belt_length(R_p + delta / tb, R_s - delta / tb, v.a) - belt_length(R_p, R_s, v.a)
    return BeltLengthChange(r_g=r, phi=phi, delta_x=v.a * np.sin(phi) * tb, delta=float(delta),
                            dL_exact=dL, dL_first_order=4 * phi * delta / tb)


@dataclass(frozen=True)
class NmpResult(Result):
    """Zeros of T_mp -> nu over the ratio, and the Sec. 2.3 geometry.

    Attributes
    ----------
    r_g : ratios [-], shape (n_r,)
    zeros : tuple of arrays
        Finite zeros [rad/s] (complex) of T_mp -> nu at each ratio, below `f_max_hz`.
    rhp_zeros : tuple of arrays
        Those with a real part above 1e-3 of their magnitude (zeros at the origin, below
        1e-3 rad/s, are not counted).
    n_rhp : array of int, shape (n_r,)
    n_rhp_real : array of int, shape (n_r,)
        Real right-half-plane zeros (imaginary part below 1e-6 of the magnitude).
    slip : "nu" or "nu_r" (see the module docstring)
    geometry : BeltLengthChange
    operating : dict
        nu, F_s [N], omega_p [rad/s], model options.
    f_max_hz : float
        Zeros above this frequency [Hz] are left out.
    """

    r_g: NDArray[np.float64]
    zeros: tuple[NDArray[np.complex128], ...]
    rhp_zeros: tuple[NDArray[np.complex128], ...]
    n_rhp: NDArray[np.int64]
    n_rhp_real: NDArray[np.int64]
    slip: str
    geometry: BeltLengthChange
    operating: dict
    f_max_hz: float

    @property
    def f_max(self) -> float:
        """Deprecated: `f_max_hz`."""
        warn_renamed("NmpResult.f_max", "f_max_hz [Hz]")
        return self.f_max_hz

    def summary(self) -> list[dict]:
        """One row per ratio: RHP zeros [Hz] as (real, imag) pairs."""
        return [{"r_g": float(r), "n_rhp": int(n), "n_rhp_real": int(nr),
                 "rhp_zeros_hz": [(float(z.real / 2 / np.pi), float(z.imag / 2 / np.pi))
                                  for z in rz]}
                for r, n, nr, rz in zip(self.r_g, self.n_rhp, self.n_rhp_real, self.rhp_zeros)]


def nmp_analysis(params: Params, ratios: ArrayLike = (0.5, 1.0, 2.0), *,
                 base: OperatingPoint | None = None, f_max_hz: float = 200.0,
                 slip: str = "nu", f_max: float | None = None, **options) -> NmpResult:
    """Zeros of the exactly linearised T_mp -> nu transfer over `ratios`.

    Parameters
    ----------
    params : Params
    ratios : array, shape (n_r,)
        Geometric ratios [-].
    base : OperatingPoint, optional
        Slip (on the rising branch of the traction curve, so the plant is stable), clamping
        force and primary speed of the points (default: ``params.operating``); its ratio is
        replaced by each of `ratios`.
    f_max_hz : float
        Keep zeros below this frequency [Hz], > 0.  (``f_max``: deprecated name.)
    slip : {"nu", "nu_r"}
        The slip signal (see the module docstring).
    f_max : float, optional
        Deprecated name of `f_max_hz`.
    **options
        `empact.nonlinear.model.ModelOptions` (default: moderate damping, torque-controlled
        drive and load, the machine's kinematics and shift law).

    Returns
    -------
    NmpResult
        ``zeros`` and ``rhp_zeros`` [rad/s] per ratio, ``n_rhp`` and ``n_rhp_real`` (shape
        (n_r,)), the Sec. 2.3 ``geometry`` and the ``operating`` point.
    """
    check_choice("slip", slip, SLIPS)
    if f_max is not None:
        warn_renamed("nmp_analysis(f_max=)", "f_max_hz [Hz]")
        f_max_hz = f_max
    f_max_hz = check_number("f_max_hz", f_max_hz, 0.0, lo_open=True, unit="Hz")
    base = params.operating if base is None else base
    r = np.atleast_1d(np.asarray(ratios, float))
    model = nonlinear_model(params, **options)
    zs, rhp = [], []
    for rg in r:
        pl = plant(params, base.replace(r_g=float(rg)), model=model, disturbance=False)
        z = channel_zeros(pl, "T_mp", slip, max_abs=1e7)  # (no python-control object)
        z = z[np.abs(z) < 2 * np.pi * f_max_hz]
        zs.append(z)
        rhp.append(z[(z.real > 1e-3 * np.abs(z)) & (np.abs(z) > 1e-3)])
    real = [int(np.sum(np.abs(z.imag) < 1e-6 * np.abs(z))) for z in rhp]
    return NmpResult(r_g=r, zeros=tuple(zs), rhp_zeros=tuple(rhp),
                     n_rhp=np.array([len(z) for z in rhp]), n_rhp_real=np.array(real), slip=slip,
                     geometry=belt_length_change(params, r), f_max_hz=f_max_hz,
                     operating={"nu": base.nu, "F_s": base.F_s, "omega_p": base.omega_p,
                                "options": {k: getattr(model.options, k)
                                            for k in model.options.__dataclass_fields__}})
