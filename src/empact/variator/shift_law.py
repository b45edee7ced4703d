"""Creep-mode shifting of the pushbelt: the belt's resistance to a change of ratio.

Carbone, Mangialardi, Bonsen, Tursi, Veenhuizen, "CVT dynamics: theory and experiments",
Mechanism and Machine Theory 42 (2007) 409-428 (measured on a TU Eindhoven pushbelt rig): in
creep mode the ratio changes at a rate proportional to the primary speed and linear in the
log of the ratio of the actual to the equilibrium thrust ratio::

    dr_g/dt = omega_p K_c(r_g, F_s) ln(kappa / kappa*(tau, r_g)),   kappa = F_p / F_s
    K_c = gain D(F_s) (1 + cos^2 beta) / sin(2 beta) r_g (R_p / a) (a1 + a2 ln^2 r_g)
    D(F_s) = D_ref (1 + k_D (F_s - F_ref))

Ide et al. (VSD 24, 1995) take the rate linear in the thrust difference instead,
``dr_g/dt = omega_p k_I (F_p - kappa* F_s)``; with ``k_I = K_c / (kappa* F_s)`` the two agree
to first order at equilibrium, and empact uses that coefficient (no published k_I could be
read), so the laws differ only away from equilibrium: ``ln(kappa / kappa*)`` against
``kappa / kappa* - 1``.

In the models the law is inverted: the thrust ratio it implies for a ratio rate,
``kappa = kappa* exp(xi)`` (Ide: ``kappa* (1 + xi)``), ``xi = rdot / (omega_eff K_c)``
saturated at ``xi_sat`` (beyond it the belt slides radially: slip-mode shifting, no published
threshold), ``omega_eff = sqrt(omega_p^2 + omega_0^2)`` (no shifting at standstill).  The belt
resists the ratio change with a generalised force ``Lambda`` conjugate to the ratio, acting on
the sheaves by virtual work as ``-Lambda dr_g/dq5`` and ``-Lambda dr_g/dq6``, sized so that the
clamping forces stand in the ratio ``kappa``.  Its static part (``kappa*`` away from the
geometric ``kappa_geo``) is the path by which the torque moves the ratio.  Linearised at rest it
is a damper on the ratio, ``C_Lambda = F_s kappa* / ((a + kappa* b) omega_eff K_c)`` [N m s]
(``a = dr_g/dx_p``, ``b = |dr_g/dx_s|``): on the sheave translations the symmetric rank-one
matrix ``C_Lambda grad(r_g) grad(r_g)^T`` (`creep_damping`), dissipative by construction.  In
the limit of infinite resistance (``K_c -> 0``) it is the ideal constraint of constant ratio.

The law is the physical content of Shafai's pulley damping ``c / |omega|`` (a sheave
resistance that falls with speed): in the nonlinear model it *replaces* it (shift law
``"carbone"`` or ``"ide"``); Shafai's term remains as shift law ``"shafai"`` and as the
paper's illustrative levels of Fig. 6 in the linear model.
"""
from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._section import Section, param
from .._validate import check_choice, check_number
from ..errors import ParameterError
from . import _laws
from ._tables import check_curve, encode_curves, interpolate_curves, read_curves
from .geometry import VariatorParams, check_ratio, variator_state

__all__ = ["ShiftParams", "SHIFT_LAWS", "creep_coefficient", "shift_rate", "CreepDamping",
           "creep_damping", "g_beta", "CreepMap", "load_creep_map"]


@dataclass(frozen=True)
class ShiftParams(Section):
    """Creep-mode shifting of the pushbelt: the belt's resistance to a ratio change.

    Carbone, Mangialardi, Bonsen, Tursi, Veenhuizen, "CVT dynamics: theory and experiments",
    Mechanism and Machine Theory 42 (2007) 409-428: in creep mode the ratio rate is
    proportional to the primary speed and linear in the log of the ratio of the actual to the
    equilibrium thrust ratio::

        dr_g/dt = |omega_p| K_c [ln(F_p / F_s) - ln kappa*(tau, r_g)]
        K_c = gain D(F_s) (1 + cos^2 beta) / sin(2 beta) r_g (R_p / a) (a1 + a2 ln^2 r_g)
        D(F_s) = D_ref (1 + k_D (F_s - F_ref))

    D is the amplitude of the pulley deformation that lets the belt creep radially (rigid
    pulleys: no creep).  The coefficients are a third party's reconstruction of the paper's
    fits (eng-tools.dev, "How does a CVT actually change ratio?", its Eqs. 23 and 49 and the
    calculator's a1, a2 fitted to the paper's Fig. 13); the paper's own tables could not be
    read.  The magnitude is calibrated by `gain` against the creep anchors (15, band 10-20:
    0.1-0.2 mm of primary radius per revolution at a 20 % thrust imbalance, about 1e6 N s/m of
    equivalent axial damping at 300 rad/s, the creep-to-slip transition at ordinary shift
    rates, Fig. 14's -1 slope; issue 20).  The test rig of the paper covered r_g = 0.6-1.8,
    F_s = 20-30 kN, 1000-2000 rpm.  A measured shift-speed map (`CreepMap`) replaces the
    analytic coefficient.

    Attributes
    ----------
    D_ref : float
        Pulley deformation amplitude ``D`` at `F_ref` [rad] (Carbone 2007, reconstructed:
        1e-3).
    F_ref : float
        Clamping force at which ``D = D_ref`` [N] (Carbone 2007: 20 kN).
    k_D : float
        Growth of ``D`` with the clamping force [1/N] (reconstructed: 2e-5, i.e. 2 % per kN).
    a1, a2 : float
        Constant and quadratic terms of the ratio dependence ``g(r) = r q (a1 + a2 ln^2 r)``
        [-] (reconstructed fit: 0.21 and 0.08).
    gain : float
        Overall factor on the creep rate [-]: 1 is the reconstruction's magnitude, which the
        creep anchors put 10-20 times too slow.
    omega_0 : float
        Speed below which creep fades [rad/s] (``omega_eff = sqrt(omega_p^2 + omega_0^2)``:
        no shifting without rotation).
    xi_sat : float
        Saturation of the log thrust-ratio error ``xi`` [-] (slip-mode shifting beyond it; no
        published threshold).
    """

    _name = "shift"
    D_ref: float = param("rad", "pulley deformation amplitude at F_ref (Carbone 2007, "
                             "reconstructed: 1e-3)", 0.0, 5e-3)
    F_ref: float = param("N", "clamping force of D_ref (Carbone 2007: 20 kN)", 1e3, 1e6)
    k_D: float = param("1/N", "growth of D with the clamping force (Carbone 2007, "
                           "reconstructed: 2e-5, i.e. 2 % per kN)", 0.0, 1e-4, lo_open=False)
    a1: float = param("-", "ratio dependence g(r) = r q (a1 + a2 ln^2 r), constant term "
                        "(reconstructed fit: 0.21)", 0.0, 5.0)
    a2: float = param("-", "ratio dependence, quadratic term (reconstructed fit: 0.08)", 0.0, 5.0,
                   lo_open=False)
    gain: float = param("-", "overall factor on the creep rate: 1 is the reconstruction's "
                          "magnitude, which the creep anchors put 10-20 times too slow", 0.1,
                     50.0,
                     lo_open=False)
    omega_0: float = param("rad/s", "speed below which creep fades (regularisation at "
                                 "standstill: no shifting without rotation)", 0.01, 10.0)
    xi_sat: float = param("-", "saturation of the log thrust-ratio error (slip mode beyond "
                            "it; no published threshold)", 0.3, 3.0, lo_open=False)


class _HasShift(Protocol):
    """A parameter set (`empact.params.Params`): what the creep law reads of it."""

    @property
    def variator(self) -> VariatorParams: ...
    @property
    def shift(self) -> ShiftParams: ...

#: shift laws of the nonlinear model
SHIFT_LAWS = ("carbone", "ide", "shafai")


def g_beta(beta: float) -> float:
    """``(1 + cos^2 beta) / sin(2 beta)`` [-] (Carbone's wedge factor).

    Parameters
    ----------
    beta : float
        Pulley wedge angle [rad].

    Returns
    -------
    float
        The wedge factor ``G_beta`` [-].
    """
    return (1 + np.cos(beta) ** 2) / np.sin(2 * beta)


@dataclass(frozen=True)
class CreepMap:
    """A measured shift-speed map: the creep coefficient ``K_c`` [-] (ratio change per radian
    of primary rotation per unit log thrust-ratio error, ``dr_g/dtheta_p = K_c ln(kappa /
    kappa*)``) as one curve ``K_c(F_s)`` per ratio, replacing the analytic law's ``D(F_s)
    G_beta r_g (R_p / a) (a1 + a2 ln^2 r_g)`` (``[shift] gain`` still multiplies it).

    Interpolated linearly in ``F_s`` along each curve and in ``ln r_g`` between curves, held
    constant outside: what the compiled model does (`empact.variator._tables.encode_curves`).
    Read with `load_creep_map` (CSV columns ``r_g, F_s, K_c``, or TOML ``[[curve]]`` tables).

    Parameters
    ----------
    ratios : tuple of float
        Ratios [-], strictly increasing.
    F_s_data, K_c_data : tuple of arrays
        Per curve: clamping forces [N] strictly increasing (at least 2), > 0, and creep
        coefficients [-] > 0.
    source : str
        Where the table came from (used in messages).
    """

    ratios: tuple[float, ...]
    F_s_data: tuple[NDArray[np.float64], ...]
    K_c_data: tuple[NDArray[np.float64], ...]
    source: str = "shift-speed map"

    def __post_init__(self) -> None:
        ratios = tuple(float(r) for r in self.ratios)
        if not ratios or len(ratios) != len(self.F_s_data) or len(ratios) != len(self.K_c_data):
            raise ParameterError(f"{self.source}: need one (F_s, K_c) curve per ratio, got "
                                 f"{len(ratios)} ratios")
        if any(not (np.isfinite(r) and r > 0) for r in ratios):
            raise ParameterError(f"{self.source}: ratios must be positive finite numbers")
        if any(b <= a for a, b in zip(ratios, ratios[1:])):
            raise ParameterError(f"{self.source}: ratios {ratios!r} must be distinct and "
                                 "increasing")
        xs, ys = [], []
        for r, F, Kc in zip(ratios, self.F_s_data, self.K_c_data):
            where = f"{self.source}, curve r_g = {r:g}"
            F, Kc = check_curve(where, F, Kc, ("F_s", "K_c"), 2)
            for name, arr, unit in (("F_s", F, "N"), ("K_c", Kc, "-")):
                bad = np.flatnonzero(~(arr > 0))
                if bad.size:
                    raise ParameterError(f"{where}: {name}[{bad[0]}] = {arr[bad[0]]:g}: allowed "
                                         f"range is (0, inf) [{unit}]")
            xs.append(F)
            ys.append(Kc)
        object.__setattr__(self, "ratios", ratios)
        object.__setattr__(self, "F_s_data", tuple(xs))
        object.__setattr__(self, "K_c_data", tuple(ys))

    def __hash__(self) -> int:  # arrays are not hashable: hash the contents
        return hash((self.ratios, tuple(a.tobytes() for a in self.F_s_data),
                     tuple(a.tobytes() for a in self.K_c_data)))

    def __eq__(self, other: object) -> bool:
        return isinstance(other, CreepMap) and hash(self) == hash(other)

    def K_c(self, r_g: ArrayLike, F_s: ArrayLike) -> NDArray[np.float64]:
        """The map's creep coefficient [-] at ratios `r_g` and clamping forces `F_s` [N].

        Parameters
        ----------
        r_g : array_like
            Geometric ratios [-].
        F_s : array_like
            Clamping forces [N] (broadcast against `r_g`).
        """
        return interpolate_curves(self.ratios, self.F_s_data, self.K_c_data, F_s, r_g)

    def encode(self) -> NDArray[np.float64]:
        """Flat encoding for the compiled model (`empact.variator._tables.encode_curves`)."""
        return encode_curves(self.ratios, self.F_s_data, self.K_c_data)


def load_creep_map(path: str | os.PathLike[str]) -> CreepMap:
    """Read a measured shift-speed map from ``.csv`` (header ``r_g,F_s,K_c``; rows with the
    same ``r_g`` form one curve) or ``.toml`` (``[[curve]]`` tables with ``r_g``, ``F_s``,
    ``K_c``).  Raises `ParameterError` naming the file, row and value.

    Parameters
    ----------
    path : str or path-like
        The ``.csv`` or ``.toml`` file: ratios ``r_g`` [-], clamping forces ``F_s`` [N] and
        creep coefficients ``K_c`` [-].

    Returns
    -------
    CreepMap
        One curve per ratio, the ratios increasing; its ``source`` is `path`.
    """
    curves = read_curves(path, "shift-speed map", "F_s", "K_c")
    items = sorted(curves.items())
    return CreepMap(ratios=tuple(r for r, _ in items),
                    F_s_data=tuple(np.asarray(c[0], float) for _, c in items),
                    K_c_data=tuple(np.asarray(c[1], float) for _, c in items),
                    source=str(Path(path)))


def creep_coefficient(params: _HasShift, r_g: ArrayLike, F_s: ArrayLike,
                      R_p: ArrayLike | None = None,
                      creep_map: CreepMap | None = None) -> NDArray[np.float64]:
    """``K_c`` [-]: ratio change per radian of primary rotation per unit log thrust-ratio
    error, at ratio `r_g` and clamping force `F_s` [N] (broadcast); `R_p` [m] defaults to the
    unstretched belt's primary radius.  With a measured `creep_map` its ``K_c(r_g, F_s)``
    times ``[shift] gain``.

    Parameters
    ----------
    params : Params
        Its ``[variator]`` and ``[shift]`` blocks are read.
    r_g : array_like
        Geometric ratio [-], broadcast with `F_s` (and `R_p`).
    F_s : array_like
        Secondary clamping force [N].
    R_p : array_like, optional
        Primary running radius [m] (default: the unstretched belt's, from `r_g`).
    creep_map : CreepMap, optional
        A measured shift-speed map in place of the analytic coefficient.

    Returns
    -------
    ndarray
        The creep coefficient ``K_c`` [-], the broadcast shape of the inputs.
    """
    sh, v = params.shift, params.variator
    r = np.asarray(r_g, float)
    if creep_map is not None:
        return sh.gain * creep_map.K_c(r, F_s)
    if R_p is None:
        R_p = variator_state(r, v).R_p
    # the one law, as the kernel and the loop law's compiled sample evaluate it
    return _laws.creep_coefficient(r, np.asarray(R_p, float), np.asarray(F_s, float), np.log(r),
                                   v.a, sh.gain, g_beta(v.beta), sh.D_ref, sh.k_D, sh.F_ref,
                                   sh.a1, sh.a2)


def shift_rate(params: _HasShift, r_g: ArrayLike, omega_p: ArrayLike, kappa: ArrayLike,
               kappa_eq: ArrayLike, F_s: ArrayLike, law: str = "carbone") -> NDArray[np.float64]:
    """Ratio rate ``dr_g/dt`` [1/s] of the creep law (unsaturated) for the thrust ratio
    `kappa` against the equilibrium `kappa_eq`, at primary speed `omega_p` [rad/s].

    Parameters
    ----------
    params : Params
        Its ``[variator]`` and ``[shift]`` blocks are read.
    r_g, omega_p, kappa, kappa_eq, F_s : array_like
        Ratio [-], primary speed [rad/s], thrust ratio and its equilibrium [-], clamping force
        [N]; broadcast together.
    law : {"carbone", "ide"}
        The creep law.

    Returns
    -------
    ndarray
        ``dr_g/dt`` [1/s], the broadcast shape of the inputs.
    """
    check_choice("law", law, SHIFT_LAWS[:2])
    w_eff = np.sqrt(np.asarray(omega_p, float) ** 2 + params.shift.omega_0 ** 2)
    ratio = np.asarray(kappa, float) / np.asarray(kappa_eq, float)
    err = np.log(ratio) if law == "carbone" else ratio - 1
    return w_eff * creep_coefficient(params, r_g, F_s) * err


@dataclass(frozen=True)
class CreepDamping:
    """The creep law linearised at rest (``dr_g/dt = 0``) at one operating point.

    Attributes
    ----------
    C_lambda : float
        Damping on the ratio coordinate [N m s] (generalised force per unit ratio rate).
    grad_r : array, shape (2,)
        ``(dr_g/dx_p, dr_g/dx_s)`` [1/m] for the chosen kinematics.
    matrix : array, shape (2, 2)
        ``C_lambda grad_r grad_r^T`` [N s/m] on the sheave translations (q5, q6).
    c_shift : float
        Equivalent damping on x_p along the shift at constant belt length [N s/m].
    c_shafai_equivalent : float
        ``c_shift |omega_p|`` [N/m], the Shafai coefficient with the same shift damping.
    """

    C_lambda: float
    grad_r: NDArray[np.float64]
    matrix: NDArray[np.float64]
    c_shift: float
    c_shafai_equivalent: float


def creep_damping(params: _HasShift, r_g: float, omega_p: float, F_s: float,
                  kinematics: str = "equal-translation", kappa_eq: float | None = None,
                  creep_map: CreepMap | None = None) -> CreepDamping:
    """Linearised creep resistance at ratio `r_g`, primary speed `omega_p` [rad/s] and
    clamping force `F_s` [N], at rest and at the equilibrium thrust ratio `kappa_eq`
    (default: the geometric one, i.e. zero torque with ``p0 = 1``), on the unstretched
    belt's radii.

    Both laws (Carbone, Ide) have the same linearisation: ``d kappa / d rdot =
    kappa* / (omega_eff K_c)``; `creep_map` replaces the analytic ``K_c`` by a measured one.

    Parameters
    ----------
    params : Params
        Its ``[variator]`` and ``[shift]`` blocks are read.
    r_g : float
        Geometric ratio [-].
    omega_p : float
        Primary speed [rad/s].
    F_s : float
        Clamping force [N].
    kinematics : {"equal-translation", "paper-sec2.1"}
        The sheave kinematics the damping acts through.
    kappa_eq : float, optional
        Equilibrium thrust ratio [-].
    creep_map : CreepMap, optional
        A measured shift-speed map in place of the analytic ``K_c``.

    Returns
    -------
    CreepDamping
        ``C_lambda`` [N m s] on the ratio rate, ``grad_r`` (``dr_g/dx_p, dr_g/dx_s`` [1/m]), the
        2 x 2 sheave damping ``matrix`` [N s/m], ``c_shift`` [N s/m] and
        ``c_shafai_equivalent`` [N/m].
    """
    check_choice("kinematics", kinematics, ("equal-translation", "paper-sec2.1"))
    r = float(check_ratio(check_number("r_g", r_g), params.variator))
    omega_p = check_number("omega_p", omega_p, 0.0, lo_open=True, unit="rad/s")
    F_s = check_number("F_s", F_s, 0.0, lo_open=True, unit="N")
    v = params.variator
    geo = variator_state(r, v)
    R_p, R_s, phi = float(geo.R_p), float(geo.R_s), float(geo.phi)
    tb = np.tan(v.beta)
    kgeo = _laws.kappa_geo(phi)
    k = kgeo if kappa_eq is None else check_number("kappa_eq", kappa_eq, 0.0, lo_open=True)
    w_eff = np.hypot(omega_p, params.shift.omega_0)
    a, b = r / (tb * R_p), r / (tb * R_s)
    # at rest the clamping force equals the belt element's only when kappa* = kappa_geo;
    # F_s here is the belt element's force (the law's)
    K_c = float(creep_coefficient(params, r, F_s, R_p, creep_map))
    C = F_s * k / ((a + k * b) * w_eff * K_c)
    sig = -1.0 if kinematics == "equal-translation" else 1.0
    grad = np.array([a, sig * b])
    G_p = (1 + kgeo * r) / (R_s * tb)  # dr_g/dx_p along the shift at constant belt length
    c_shift = C * G_p**2
    return CreepDamping(C_lambda=float(C), grad_r=grad, matrix=C * np.outer(grad, grad),
                        c_shift=float(c_shift), c_shafai_equivalent=float(c_shift * omega_p))
