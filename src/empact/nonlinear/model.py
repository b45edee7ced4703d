r"""Nonlinear model of the Empact CVT: actuation, elastic belt on the full geometry, traction
with slip, and the test-bench driveline (model notes Sec. 6; the paper's ref. [4]).

::

      servo P  T_mp                                          servo S  T_ms
      J_mp (q1) --worm k_w--> ring P ==i_e== sun P (q3) ==ring coupling== sun S (q4) <--chain k_c-- J_ms (q2)
                                              |  screw s, thrust k_tp               |  screw s, thrust k_ts
                                              v  q7 = s q3 + q5                     v  q8 = s (q4 - q3) + q6
                                    sheave P (q5, m_p)                     sheave S (q6, m_s)
                                     R_p = R_min + q5/tan(beta)             R_s = R_max - q6/tan(beta)
                                              \___ pushbelt: N = k_belt (L(R_p, R_s) - L_0) ___/
                                               |  traction T_b = 2 mu(nu, r_g) F_s R_s / cos(beta)
      drive motor         lock-up clutch      primary pulley        secondary pulley    driveshaft     load motor
      J_d (omega_d) --/\/\ k_tc /\/\-- J_p (omega_p)  -r_g T_b  |  +T_b  J_s (omega_s) --/\/\ k_ds --- J_l (omega_l)
        T_d ->                                                                                          <- T_l

State ordering (SI), ``x``:

=====  ===============  ================================================================
0-5    q1..q6           ``theta_mp, theta_ms, theta_sp, theta_ss`` [rad], ``x_p, x_s`` [m]
6-11   velocities       ``omega_mp, omega_ms, omega_sp, omega_ss`` [rad/s], ``v_p, v_s`` [m/s]
12     ``twist_tc``     ``theta_d - theta_p``, lock-up clutch twist [rad]
13     ``twist_ds``     ``theta_s - theta_l``, driveshaft twist [rad]
14-17  shaft speeds     ``omega_d, omega_p, omega_s, omega_l`` [rad/s]
(opt)  ``s_b``          belt stretch of the locked belt, ``d/dt s_b = R_p omega_p - R_s omega_s``
                        [m] (only with ``belt="locked"``)
(opt)  ``z_d``, ``z_l`` integral torques of the drive / load speed loops [N m]
(opt)  ``z_r``          integral torque of the ratio controller [N m]
=====  ===============  ================================================================

The driveline is written in the rotating frame (twists and speeds): the shaft angles grow
without bound at speed and only their differences store energy, so a steady operating point
is a true equilibrium of this state.

Inputs ``u`` (4): ``T_mp`` (or ``r_g_ref`` with the ratio controller), ``T_ms`` [N m],
``T_d`` drive torque on the drive motor (or ``omega_d_ref`` with a speed-controlled drive),
``T_l`` load torque *opposing* the rotation of the load motor (or ``omega_l_ref``).

Construction choices (documented, not hidden):

* **Sheave kinematics.** ``R_p = R_min + q5 / tan(beta)`` and ``R_s = R_max - q6 / tan(beta)``:
  both moving sheaves translate in the same absolute direction; ``q5 > 0`` closes the primary
  (R_p grows), ``q6 > 0`` opens the secondary (R_s shrinks).  ``q5 = 0`` is the primary at its
  smallest radius, ``q6 = 0`` the secondary at its largest.  These are the directions of spring 3
  of `empact.linear.actuation` (elongation ``[(pi + 2 phi) q5 - (pi - 2 phi) q6] / tan(beta)``), of
  which this element is the exact, nonlinear version.
* **Belt.** An elastic element with force ``N = k_belt (e + alpha de/dt)``, ``e = L(R_p, R_s) -
  L_0`` (eq. 6 on the current radii), ``L_0 = L_belt`` (the belt's unstretched length): the
  clamping force comes from stretching it, e.g. ``e = 0.35 mm`` for ``F_s = 10 kN``.  Axial
  sheave forces by virtual work (``dL/dR_p = pi + 2 phi``, ``dL/dR_s = pi - 2 phi``):
  ``F_p = N (pi + 2 phi) / tan(beta)``, ``F_s = N (pi - 2 phi) / tan(beta)``.  A slack belt
  (``e < 0``) would give negative forces; the simulator stops there rather than clip.
* **Thrust bearings, worm, chain, screws** exactly as the rows of `empact.linear.actuation`, with zero
  free length at ``q7 = q8 = 0`` and zero worm/chain twist.  Proportional damping ``alpha k``
  on every spring (belt included), viscous friction ``c_mp, c_ms`` (servos), ``c_sp`` (q3),
  ``c_ss`` (q4 - q3), Shafai damping ``c_shafai / |omega|`` on each sheave with the *current*
  pulley speed (primary ``omega_p``, secondary ``omega_s``): this couples the actuation to the
  driveline.  Optional smooth Coulomb friction ``T_c tanh(omega / omega_c)`` in the spindles
  (on q3 and on q4 - q3).
* **Traction** (eqs. 1-2): ``nu = 1 - omega_s / (r_g omega_p)``, ``T_b = 2 mu(nu, r_g) F_s R_s /
  cos(beta)`` on the secondary and ``-r_g T_b`` on the primary; ``mu`` is the magic formula of
  `empact.params.TractionParams`.  The slip power ``T_b (r_g omega_p - omega_s)`` is dissipated.
  With ``belt="locked"`` the traction is replaced by the elastic chain element of
  `empact.linear.driveline` (stiffness ``driveline.k_belt``), the limit in which the belt does not slip.
* **Controllers** (optional, for a test bench): PI speed loops on the drive and load motors,
  and a ratio controller (``r_g_ref`` input): ``T_mp = z_r + K_p e - K_d omega_mp``,
  ``dz_r/dt = K_i e``, with ``e = (r_g_ref - r_g) / G`` and ``G = d r_g / d q1`` along the
  shift (rigid-body) motion, so that the gains hold over the ratio range.  (A feedforward of
  the static holding torque ``-(i_e s / i_w)(F_p + F_s)`` from the current belt forces was
  tried and dropped: it feeds the clamping-force transients of a fast shift back into the
  shift and destabilised the loop.)  Keep the ratio bandwidth below about 3 Hz: the P path
  is non-collocated across the worm mode (10.7 Hz).

What the linear models of Sec. 2 leave out, and this one contains: the geometric stiffness of
the belt preload (``N d^2 L / dq^2``, ``d^2 L/dR_p^2 = 2 / (a cos phi)``), which turns the
actuation's rigid-body (shift) mode into a slow oscillation of a few Hz at 10 kN, and moves the
other actuation modes by well under 1 %; the dependence of the radii on the belt stretch; and
the coupling of actuation and driveline through Shafai damping and through the traction torque.
"""
from __future__ import annotations

from dataclasses import dataclass, field, fields, replace
from functools import lru_cache
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._lazy import lazy_module
from .._validate import check_bool, check_choice, check_number
from ..errors import ParameterError
from ..linear.actuation import actuation_model
from ..params import DAMPING_LEVELS, Params
from . import _kernel as K

control = lazy_module("control")

__all__ = ["ModelOptions", "EmpactModel", "nonlinear_model", "rhs", "BASE_STATES", "OUTPUTS",
           "OUTPUT_UNITS", "STATE_UNITS"]

BASE_STATES = ("theta_mp", "theta_ms", "theta_sp", "theta_ss", "x_p", "x_s",
               "omega_mp", "omega_ms", "omega_sp", "omega_ss", "v_p", "v_s",
               "twist_tc", "twist_ds", "omega_d", "omega_p", "omega_s", "omega_l")
OUTPUTS = K.OUTPUTS
STATE_UNITS = {"theta_mp": "rad", "theta_ms": "rad", "theta_sp": "rad", "theta_ss": "rad",
               "x_p": "m", "x_s": "m", "omega_mp": "rad/s", "omega_ms": "rad/s",
               "omega_sp": "rad/s", "omega_ss": "rad/s", "v_p": "m/s", "v_s": "m/s",
               "twist_tc": "rad", "twist_ds": "rad", "omega_d": "rad/s", "omega_p": "rad/s",
               "omega_s": "rad/s", "omega_l": "rad/s", "s_b": "m", "z_d": "N m", "z_l": "N m",
               "z_r": "N m"}
OUTPUT_UNITS = {"r_g": "-", "nu": "-", "theta_mp": "rad", "theta_ms": "rad", "F_p": "N",
                "F_s": "N", "omega_p": "rad/s", "omega_s": "rad/s", "omega_d": "rad/s",
                "omega_l": "rad/s", "omega_mp": "rad/s", "omega_ms": "rad/s", "T_b": "N m",
                "mu": "-", "R_p": "m", "R_s": "m", "phi": "rad", "x_p": "m", "x_s": "m",
                "belt_elongation": "m", "T_mp_act": "N m", "T_d_act": "N m", "T_l_act": "N m",
                "E": "J", "P_in": "W", "P_diss": "W"}
INPUT_UNITS = {"T_mp": "N m", "r_g_ref": "-", "T_ms": "N m", "T_d": "N m",
               "omega_d_ref": "rad/s", "T_l": "N m", "omega_l_ref": "rad/s"}


@dataclass(frozen=True)
class ModelOptions:
    """Choices of the nonlinear model (all validated on construction).

    Parameters
    ----------
    damping : {"none", "moderate", "large"}
        Damping level of the actuation (``params.damping``).
    belt : {"traction", "locked"}
        Traction with slip (eqs. 1-2), or the belt as the elastic chain element of the
        driveline model (no slip; the linear model's limit).
    drive, load : {"torque", "speed"}
        Drive / load motor torque-controlled (input ``T_d`` / ``T_l``) or speed-controlled by a
        PI loop (input ``omega_d_ref`` / ``omega_l_ref`` [rad/s]).
    ratio_control : bool
        Replace the input ``T_mp`` by ``r_g_ref`` and a ratio controller (see module notes).
    coulomb_sp, coulomb_ss : float
        Coulomb friction torque of the primary (q3) and secondary (q4 - q3) spindle [N m], >= 0.
    coulomb_omega : float
        Velocity scale of the smooth Coulomb friction ``tanh(omega / coulomb_omega)`` [rad/s].
    drive_bandwidth, load_bandwidth : float
        Speed-loop bandwidths [Hz]: ``K_p = 2 pi f J``, ``K_i = K_p 2 pi f / 4``.
    ratio_bandwidth : float
        Ratio-loop natural frequency [Hz] (damping ratio 0.7, integral at a quarter of it),
        gains from the shift-mode inertia at r_g = 1 referred to the primary servo.
    kinematics : {"actuation", "equal-translation"}
        Sense of the secondary sheave coordinate q6.  ``"actuation"`` (default): ``R_s = R_max
        - q6 / tan(beta)``, the convention of `empact.linear.actuation` whose stiffnesses are
        calibrated to Table 1.  ``"equal-translation"``: ``R_s = R_min + q6 / tan(beta)``, so
        that with the secondary servo held a primary-servo rotation translates both sheaves
        equally (the premise of Sec. 2.3); with the calibrated stiffnesses its two lowest
        actuation modes are lower than Table 1 (about 5.7 and 15.9 Hz at r_g = 1).
    """

    damping: Literal["none", "moderate", "large"] = "moderate"
    belt: Literal["traction", "locked"] = "traction"
    drive: Literal["torque", "speed"] = "torque"
    load: Literal["torque", "speed"] = "torque"
    ratio_control: bool = False
    coulomb_sp: float = 0.0
    coulomb_ss: float = 0.0
    coulomb_omega: float = 0.5
    drive_bandwidth: float = 5.0
    load_bandwidth: float = 5.0
    ratio_bandwidth: float = 2.0
    kinematics: Literal["actuation", "equal-translation"] = "actuation"

    def __post_init__(self) -> None:
        check_choice("damping", self.damping, DAMPING_LEVELS)
        check_choice("kinematics", self.kinematics, ("actuation", "equal-translation"))
        check_choice("belt", self.belt, ("traction", "locked"))
        check_choice("drive", self.drive, ("torque", "speed"))
        check_choice("load", self.load, ("torque", "speed"))
        check_bool("ratio_control", self.ratio_control)
        for name, unit in (("coulomb_sp", "N m"), ("coulomb_ss", "N m")):
            object.__setattr__(self, name, check_number(name, getattr(self, name), 0.0,
                                                        unit=unit))
        for name, unit in (("coulomb_omega", "rad/s"), ("drive_bandwidth", "Hz"),
                           ("load_bandwidth", "Hz"), ("ratio_bandwidth", "Hz")):
            object.__setattr__(self, name, check_number(name, getattr(self, name), 0.0,
                                                        lo_open=True, unit=unit))

    @classmethod
    def from_mapping(cls, values: dict) -> "ModelOptions":
        """Options from keyword values; an unknown key is an error naming the allowed ones."""
        allowed = [f.name for f in fields(cls)]
        for key in values:
            if key not in allowed:
                raise ParameterError(f"unknown model option {key!r} (allowed: "
                                     f"{', '.join(allowed)})")
        return cls(**values)


@dataclass(frozen=True, eq=False)
class EmpactModel:
    """The nonlinear Empact model for one parameter set and one choice of options.

    Build with `nonlinear_model`.  Immutable; the compiled kernel works on the flat vectors
    ``p`` and ``ix`` built once here.

    Attributes
    ----------
    params : Params
    options : ModelOptions
    states : tuple of str, length n
        State names (see the module docstring for the ordering and units).
    inputs : tuple of str, length 4
    outputs : tuple of str, length `len(OUTPUTS)`
    """

    params: Params
    options: ModelOptions
    states: tuple[str, ...] = field(init=False)
    inputs: tuple[str, ...] = field(init=False)
    outputs: tuple[str, ...] = field(init=False)
    p: NDArray[np.float64] = field(init=False, repr=False)
    ix: NDArray[np.int64] = field(init=False, repr=False)

    def __post_init__(self) -> None:
        o = self.options
        states = list(BASE_STATES)
        ix = np.full(4, -1, dtype=np.int64)
        for k, (name, on) in enumerate((("s_b", o.belt == "locked"), ("z_d", o.drive == "speed"),
                                        ("z_l", o.load == "speed"), ("z_r", o.ratio_control))):
            if on:
                ix[k] = len(states)
                states.append(name)
        inputs = ("r_g_ref" if o.ratio_control else "T_mp", "T_ms",
                  "omega_d_ref" if o.drive == "speed" else "T_d",
                  "omega_l_ref" if o.load == "speed" else "T_l")
        object.__setattr__(self, "states", tuple(states))
        object.__setattr__(self, "inputs", inputs)
        object.__setattr__(self, "outputs", tuple(OUTPUTS))
        object.__setattr__(self, "p", _parameter_vector(self.params, o))
        object.__setattr__(self, "ix", ix)

    # -- evaluation ---------------------------------------------------------------------
    @property
    def n(self) -> int:
        """Number of states."""
        return len(self.states)

    def _check(self, x: ArrayLike, u: ArrayLike) -> tuple[NDArray, NDArray]:
        x = np.ascontiguousarray(x, dtype=float)
        u = np.ascontiguousarray(u, dtype=float)
        if x.shape != (self.n,):
            raise ValueError(f"state has shape {x.shape}: expected ({self.n},) for states "
                             f"{', '.join(self.states)}")
        if u.shape != (4,):
            raise ValueError(f"input has shape {u.shape}: expected (4,) for inputs "
                             f"{', '.join(self.inputs)}")
        if not np.all(np.isfinite(x)) or not np.all(np.isfinite(u)):
            raise ValueError("state or input is not finite")
        if x[15] == 0.0:
            raise ValueError("omega_p = 0: the slip nu (eq. 2) is undefined at a standing "
                             "primary pulley")
        if x[16] == 0.0 and self.p[K.P_CSH] != 0.0:
            raise ValueError("omega_s = 0: Shafai damping c_shafai / |omega_s| is undefined")
        v = self.params.variator
        R_p = v.R_min + x[4] / self.p[K.P_TB]
        R_s = v.R_max - x[5] / self.p[K.P_TB]
        if not (abs(R_p - R_s) < v.a and R_p > 0 and R_s > 0):
            raise ValueError(f"x_p = {x[4]:g} m, x_s = {x[5]:g} m: radii R_p = {R_p:g} m, "
                             f"R_s = {R_s:g} m have no belt geometry (need |R_p - R_s| < a = "
                             f"{v.a:g} m)")
        return x, u

    def evaluate(self, x: ArrayLike, u: ArrayLike) -> tuple[NDArray, NDArray]:
        """State derivative, shape (n,), and outputs, shape (len(OUTPUTS),), at (x, u)."""
        x, u = self._check(x, u)
        dx = np.empty(self.n)
        y = np.empty(K.NY)
        K._eval(x, u, self.p, self.ix, dx, y)
        return dx, y

    def rhs(self, t: float, x: ArrayLike, u: ArrayLike) -> NDArray[np.float64]:
        """``dx/dt`` at time `t` [s] (unused: the model is autonomous), shape (n,)."""
        return self.evaluate(x, u)[0]

    def output(self, t: float, x: ArrayLike, u: ArrayLike) -> NDArray[np.float64]:
        """Outputs (`outputs`, SI units in `OUTPUT_UNITS`), shape (len(OUTPUTS),)."""
        return self.evaluate(x, u)[1]

    def output_dict(self, x: ArrayLike, u: ArrayLike) -> dict[str, float]:
        """Outputs by name."""
        return dict(zip(self.outputs, map(float, self.output(0.0, x, u))))

    def jacobian(self, x: ArrayLike, u: ArrayLike) -> tuple[NDArray, NDArray, NDArray, NDArray]:
        """Exact ``A = df/dx`` (n, n), ``B = df/du`` (n, 4), ``C = dy/dx`` (ny, n),
        ``D = dy/du`` (ny, 4), by the complex step (no truncation error)."""
        x, u = self._check(x, u)
        A = np.empty((self.n, self.n))
        B = np.empty((self.n, 4))
        C = np.empty((K.NY, self.n))
        D = np.empty((K.NY, 4))
        K._jacobian(x, u, self.p, self.ix, A, B, C, D)
        return A, B, C, D

    def traction(self, nu: ArrayLike, r_g: ArrayLike) -> NDArray[np.float64]:
        """Traction coefficient ``mu(nu, r_g)`` of the compiled kernel [-] (broadcasts)."""
        nu, r = np.broadcast_arrays(np.asarray(nu, float), np.asarray(r_g, float))
        if np.any(r <= 0):
            raise ValueError(f"r_g = {r[r <= 0].flat[0]:g}: must be positive")
        out = np.empty(nu.shape)
        for k in np.ndindex(nu.shape):
            out[k] = K.traction_mu(float(nu[k]), float(r[k]), self.p)
        return out

    def iosystem(self, name: str = "empact"):
        """The model as a `control.NonlinearIOSystem` (updfcn signature ``(t, x, u, params)``)."""
        return control.nlsys(lambda t, x, u, params: self.rhs(t, x, u),
                             lambda t, x, u, params: self.output(t, x, u),
                             inputs=list(self.inputs), outputs=list(self.outputs),
                             states=list(self.states), name=name)


def _parameter_vector(params: Params, o: ModelOptions) -> NDArray[np.float64]:
    v, a, d = params.variator, params.actuation, params.driveline
    lvl = params.damping.level(o.damping)
    t = params.traction
    p = np.zeros(K.NP)
    p[K.P_A], p[K.P_TB], p[K.P_COSB] = v.a, np.tan(v.beta), np.cos(v.beta)
    p[K.P_RMIN], p[K.P_RMAX], p[K.P_L0] = v.R_min, v.R_max, v.L_belt
    sig = 1.0 if o.kinematics == "actuation" else -1.0
    p[K.P_SIG], p[K.P_RS0] = sig, (v.R_max if sig > 0 else v.R_min)
    p[K.P_JMP], p[K.P_JMS], p[K.P_JSP], p[K.P_JSS] = a.J_mp, a.J_ms, a.J_sp, a.J_ss
    p[K.P_MP], p[K.P_MS] = a.m_p, a.m_s
    p[K.P_IW], p[K.P_IC], p[K.P_IE], p[K.P_S] = a.i_w, a.i_c, a.i_e, a.s
    p[K.P_KW], p[K.P_KC], p[K.P_KBELT], p[K.P_KTP], p[K.P_KTS] = \
        a.k_w, a.k_c, a.k_belt, a.k_tp, a.k_ts
    p[K.P_ALPHA], p[K.P_CMP], p[K.P_CMS] = lvl.alpha, lvl.c_mp, lvl.c_ms
    p[K.P_CSP], p[K.P_CSS], p[K.P_CSH] = lvl.c_sp, lvl.c_ss, lvl.c_shafai
    p[K.P_TCSP], p[K.P_TCSS], p[K.P_WC] = o.coulomb_sp, o.coulomb_ss, o.coulomb_omega
    p[K.P_JD], p[K.P_JP], p[K.P_JS], p[K.P_JL] = d.J_d, d.J_p, d.J_s, d.J_l
    p[K.P_KTC], p[K.P_KDS], p[K.P_KBD] = d.k_tc, d.k_ds, d.k_belt
    p[K.P_LLOW], p[K.P_LMED], p[K.P_LOD] = np.log([t.r_low, t.r_med, t.r_od])
    p[K.P_B0:K.P_B2 + 1] = t.B_low, t.B_med, t.B_od
    p[K.P_C0:K.P_C2 + 1] = t.C_low, t.C_med, t.C_od
    p[K.P_D0:K.P_D2 + 1] = t.D_low, t.D_med, t.D_od
    p[K.P_E0:K.P_E2 + 1] = t.E_low, t.E_med, t.E_od
    for kp, ki, J, f in ((K.P_DKP, K.P_DKI, d.J_d, o.drive_bandwidth),
                         (K.P_LKP, K.P_LKI, d.J_l, o.load_bandwidth)):
        w = 2 * np.pi * f
        p[kp], p[ki] = J * w, J * w * w / 4
    w = 2 * np.pi * o.ratio_bandwidth
    J = shift_inertia(params, sig)
    p[K.P_RKP], p[K.P_RKD], p[K.P_RKI] = J * w * w, 2 * 0.7 * w * J, J * w**3 / 4
    return p


def shift_inertia(params: Params, sense: float = 1.0, r_g: float = 1.0) -> float:
    """Inertia of the actuation's shift (rigid-body) motion referred to the primary servo
    [kg m^2]: ``v^T M v`` with the rigid-body mode ``v`` scaled to ``q1 = 1``; `sense` is
    +1 for the ``"actuation"`` kinematics and -1 for ``"equal-translation"``."""
    lm = actuation_model(params, r_g)
    rows = lm.spring_rows.copy()
    rows[2, 5] *= sense
    lm = replace(lm, spring_rows=rows)
    v = lm.modes().shapes[:, 0]
    v = v / v[0]
    return float(v @ lm.M @ v)


def nonlinear_model(params: Params, options: ModelOptions | None = None, **kwargs) -> EmpactModel:
    """The nonlinear model for `params`.

    Parameters
    ----------
    params : Params
    options : ModelOptions, optional
        All choices at once; or give them as keywords (``damping="none"``, ``belt="locked"``,
        ...; see `ModelOptions`).  Unknown keywords are an error.
    **kwargs
        The `ModelOptions` fields as keywords (instead of `options`).

    Examples
    --------
    >>> from empact.params import default_params
    >>> m = nonlinear_model(default_params(), damping="none", drive="speed")
    >>> m.inputs
    ('T_mp', 'T_ms', 'omega_d_ref', 'T_l')
    """
    if options is not None and kwargs:
        raise ValueError("give either options or keyword options, not both")
    return EmpactModel(params, options if options is not None
                       else ModelOptions.from_mapping(kwargs))


@lru_cache(maxsize=8)
def _default_model(params: Params) -> EmpactModel:
    return nonlinear_model(params)


def rhs(t: float, x: ArrayLike, u: ArrayLike, params: Params | EmpactModel) -> NDArray[np.float64]:
    """``dx/dt`` of the nonlinear model, argument order ``(t, x, u, params)``.

    Parameters
    ----------
    t : float
        Time [s] (the model is autonomous).
    x : array, shape (n,)
        State (ordering in the module docstring).
    u : array, shape (4,)
        Inputs ``T_mp, T_ms, T_d, T_l`` [N m] (other names with the controllers).
    params : Params or EmpactModel
        A parameter set (default options) or a built model.
    """
    model = params if isinstance(params, EmpactModel) else _default_model(params)
    return model.rhs(t, x, u)
