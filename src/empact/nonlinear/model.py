r"""Nonlinear model of the Empact CVT: actuation, elastic belt on the full geometry, traction
with slip, and the test-bench driveline (model notes Sec. 6; the paper's ref. [4]).

::

      servo P  T_mp                                          servo S  T_ms
      J_mp (q1) --worm k_w--> ring P ==i_e== sun P (q3) ==ring coupling== sun S (q4) <--chain k_c-- J_ms (q2)
                                              |  screw s, thrust k_tp               |  screw s, thrust k_ts
                                              v  q7 = s q3 + q5                     v  q8 = s (q4 - q3) + q6
                                    sheave P (q5, m_p)                     sheave S (q6, m_s)
                                     R_p = R_min + q5/tan(beta)             R_s = R_min + q6/tan(beta)
                                              \___ pushbelt: N = k_belt (L(R_p, R_s) - L_0) ___/
                                               |  creep resistance Lambda on r_g (shift law)
                                               |  traction T_b = 2 mu(nu, r_g) F_s R_s / cos(beta)
      drive motor         lock-up clutch      primary pulley        secondary pulley    driveshaft     load motor
      J_d (omega_d) --/\/\ k_tc /\/\-- J_p (omega_p)  -r_g T_b  |  +T_b  J_s (omega_s) --/\/\ k_ds --- J_l (omega_l)
        T_d ->                                                                                          <- T_l

State ordering (SI), ``x``:

=====  =================  ================================================================
0-5    q1..q6             ``theta_mp, theta_ms, theta_sp, theta_ss`` [rad], ``x_p, x_s`` [m]
6-11   velocities         ``omega_mp, omega_ms, omega_sp, omega_ss`` [rad/s], ``v_p, v_s`` [m/s]
12     ``twist_tc``       ``theta_d - theta_p``, lock-up clutch twist [rad]
13     ``twist_ds``       ``theta_s - theta_l``, driveshaft twist [rad]
14-17  shaft speeds       ``omega_d, omega_p, omega_s, omega_l`` [rad/s]
(opt)  ``s_b``            belt stretch of the locked belt, ``d/dt s_b = R_p omega_p - R_s omega_s``
                          [m] (only with ``belt="locked"``)
(opt)  ``z_d``, ``z_l``   integral torques of the drive / load speed loops [N m]
(opt)  ``z_r``            integral torque of the ratio controller [N m]
=====  =================  ================================================================

The driveline is written in the rotating frame (twists and speeds): the shaft angles grow
without bound at speed and only their differences store energy, so a steady operating point
is a true equilibrium of this state.

Inputs ``u`` (4): ``T_mp`` (or ``r_g_ref`` with the ratio controller), ``T_ms`` [N m],
``T_d`` drive torque on the drive motor (or ``omega_d_ref`` with a speed-controlled drive),
``T_l`` load torque *opposing* the rotation of the load motor (or ``omega_l_ref``).

Construction choices (documented, not hidden):

* **Sheave kinematics** (`ModelOptions.kinematics`).  The machine (``"equal-translation"``,
  default): ``R_p = R_min + q5 / tan(beta)``, ``R_s = R_min + q6 / tan(beta)``; both sheaves
  close for positive q, so an equal translation ``q5 = -q6`` (both in the same absolute
  direction) is a ratio change at nearly constant belt length: the primary servo shifts, the
  secondary clamps (paper Secs. 1 and 2.3; model notes Sec. 5).  The element is the exact,
  nonlinear version of spring 3 of `empact.linear.actuation`, ``[(pi + 2 phi) q5 + (pi - 2
  phi) q6] / tan(beta)``.  The paper's Sec. 2.1 rows (``"paper-sec2.1"``): ``R_s = R_max -
  q6 / tan(beta)``, spring 3 ``[(pi + 2 phi) q5 - (pi - 2 phi) q6] / tan(beta)``, with the
  ``[paper_sec21]`` stiffnesses; a primary-servo rotation then squeezes both sheaves.
* **Belt.** An elastic element with force ``N = k_belt (e + alpha de/dt)`` (``k_belt`` is
  ``actuation.k_belt``, ``paper_sec21.k_belt`` with the Sec. 2.1 kinematics; never
  ``driveline.k_belt``, which only ``belt="locked"`` uses), ``e = L(R_p, R_s) -
  L_0`` (eq. 6 on the current radii), ``L_0 = L_belt`` (the belt's unstretched length): the
  clamping force comes from stretching it, e.g. ``e = 0.35 mm`` for ``F_s = 10 kN``.  Axial
  sheave forces by virtual work (``dL/dR_p = pi + 2 phi``, ``dL/dR_s = pi - 2 phi``):
  ``F_p = N (pi + 2 phi) / tan(beta)``, ``F_s = N (pi - 2 phi) / tan(beta)``.  A slack belt
  (``e < 0``) would give negative forces; the simulator stops there rather than clip.
* **Thrust bearings, worm, chain, screws** exactly as the rows of `empact.linear.actuation`, with zero
  free length at ``q7 = q8 = 0`` and zero worm/chain twist.  Proportional damping ``alpha k``
  on every spring (belt included), viscous friction ``c_mp, c_ms`` (servos), ``c_sp`` (q3),
  ``c_ss`` (q4 - q3).  Optional smooth Coulomb friction ``T_c tanh(omega / omega_c)`` in the
  spindles (on q3 and on q4 - q3).
* **Shift law** (`ModelOptions.shift_law`, `empact.shift_law`).  The belt resists a ratio change
  by creep (Carbone et al. 2007, or Ide et al.): a generalised force ``Lambda`` on the ratio,
  acting on the sheaves as ``-Lambda dr_g/dq5`` and ``-Lambda dr_g/dq6`` (virtual work), sized
  so that the actuator forces stand in the thrust ratio the law gives for the current ratio
  rate, ``kappa = kappa*(tau, r_g) exp(xi)``.  Its static part ``F_s (kappa* - kappa_geo)``
  is how the transmitted torque (through ``tau = mu / mu_max``) pushes the ratio; its rate
  part is a damper ``~ F_s / (omega_p K_c)`` on the ratio: this couples the actuation to the
  driveline.  Its power ``Lambda dr_g/dt`` is part of ``P_diss``.  Shift law ``"shafai"``
  instead puts ``c_shafai / |omega|`` on each sheave with the *current* pulley speed
  (primary ``omega_p``, secondary ``omega_s``) and no torque path.
* **Traction** (eqs. 1-2): ``nu = 1 - omega_s / (r_g omega_p)``, ``T_b = 2 mu(nu, r_g) F_s R_s /
  cos(beta)`` on the secondary and ``-r_g T_b`` on the primary; ``mu`` is the magic formula of
  `empact.params.TractionParams`.  The slip power ``T_b (r_g omega_p - omega_s)`` is dissipated.
  With ``belt="locked"`` the traction is replaced by the elastic chain element of
  `empact.linear.driveline` (stiffness ``driveline.k_belt``), the limit in which the belt does not slip.
* **Variator losses** (`empact.variator.losses`, the ``[losses]`` block): beside the slip, a
  clamping loss ``lambda_F F_s R_p`` and a load loss ``k_T |r_g T_b|`` on the primary shaft
  and a spin drag ``c_v omega + c_q omega^2`` on each pulley shaft, each opposing its
  shaft's rotation (Akehurst et al. 2004; Micklem et al. 1996; Narita & Priest 2007); or a
  measured loss map (`ModelOptions.loss_map`, ``[losses] table``,
  `empact.variator.losses.LossMap`): its torque loss ``T_loss(r_g, omega_p, T_in, F_s)`` on
  the primary at the input torque it carries, in place of those three.  The outputs
  ``P_loss_slip``, ``P_loss_clamp``, ``P_loss_load``, ``P_loss_drag``, ``P_loss_map``
  (`VARIATOR_LOSSES`) sum to ``P_var_in - P_var_out``, the powers at the variator's shafts.
* **Driveline** (`ModelOptions.driveline`).  The test bench of the diagram above, or the car
  (``"vehicle"``): the drive is the engine's inertia (``[engine] J_e``, torque ``T_d``), the
  load the car reflected to the secondary's speed (``m (1 + e_rot) r_w^2 / i_fd^2``, the
  driveshaft ``[vehicle] k_driveline / i_fd^2``) with the road load and the final drive's
  loss as a load torque of the state (`empact.nonlinear._kernel._vehicle_load`), ``T_l`` the
  brakes' torque beyond it; outputs ``v``, ``F_road``, ``P_road``, ``P_loss_fd`` (zero on the
  bench).
* **Energy.** ``E`` is the stored (kinetic and elastic) energy, ``P_in`` the power of the
  servos, the drive and the load, ``P_diss`` the dissipated power, the sum of
  `DISSIPATION_TERMS` (the variator's losses, ``P_creep``, ``P_diss_servo``,
  ``P_diss_spindle``, ``P_diss_material``, ``P_diss_sheave``): ``dE/dt = P_in - P_diss``.
* **Controllers** (optional, for a test bench): PI speed loops on the drive and load motors,
  and a ratio controller (``r_g_ref`` input): ``T_mp = z_r + K_p e - K_d omega_mp``,
  ``dz_r/dt = K_i e``, with ``e = (r_g_ref - r_g) / G``.  With a creep law the shift is a
  damper, not an inertia: ``G = -omega_eff K_c i_w / (i_e s F_p)`` is the ratio rate per N m of
  primary servo torque at rest (the creep law ``dr_g/dt = omega_eff K_c ln(kappa / kappa*)``
  with ``dF_p = -(i_w / (i_e s)) dT_mp`` through the worm and the screw), evaluated at the
  current state, so that the loop ``K_p G / s`` crosses over at ``K_p = 2 pi
  ratio_bandwidth_hz`` at every ratio, speed and clamping force (``K_i = K_p^2 / 4``;
  ``K_d`` damps the servo as below).  With Shafai's law ``G = d r_g / d q1`` along the shift
  (rigid-body) motion and a PID on its inertia.  (A feedforward of
  the static holding torque ``-(i_e s / i_w)(F_p + F_s)`` from the current belt forces was
  tried and dropped: it feeds the clamping-force transients of a fast shift back into the
  shift and destabilised the loop.)  Keep the ratio bandwidth below about 3 Hz: the P path
  is non-collocated across the worm mode (10.7 Hz).

What the linear models of Sec. 2 leave out, and this one contains: the geometric stiffness of
the belt preload (``N d^2 L / dq^2``, ``d^2 L/dR_p^2 = 2 / (a cos phi)``), which with Shafai's
law turns the actuation's rigid-body (shift) mode into a slow oscillation of a few Hz at
10 kN and moves the other actuation modes by well under 1 %; the dependence of the radii on
the belt stretch; the shift law's static force (the torque's push on the ratio); and the
coupling of actuation and driveline through the shift law and the traction torque.  With the
creep law linearised as its pulley damping (`empact.linear.actuation`, ``pulley_damping=
"creep"``) the linear actuation model has the nonlinear model's actuation eigenvalues to
within about 1 %.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from functools import cached_property, lru_cache

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._lazy import lazy_module
from ..errors import ParameterError
from ..linear.actuation import actuation_model
from ..params import Params
from ..variator import _laws
from ..variator.geometry import radii
from ..variator.shift_law import g_beta
from ..variator.traction import (
    AnalyticTraction,
    TabulatedTraction,
    traction_from_params,
    traction_parameters,
)
from ..vehicle import G
from . import _batch as KB
from . import _kernel as K
from . import _tangent as KT
from .options import KINEMATICS, ModelOptions

control = lazy_module("control")


__all__ = ["KINEMATICS", "ModelOptions", "EmpactModel", "nonlinear_model", "rhs", "BASE_STATES",
           "OUTPUTS",
           "OUTPUT_UNITS", "STATE_UNITS", "VARIATOR_LOSSES", "DISSIPATION_TERMS"]

BASE_STATES = K.BASE_STATES
OUTPUTS = K.OUTPUTS
VARIATOR_LOSSES = K.VARIATOR_LOSSES
DISSIPATION_TERMS = K.DISSIPATION_TERMS
STATE_UNITS = {"theta_mp": "rad", "theta_ms": "rad", "theta_sp": "rad", "theta_ss": "rad",
               "x_p": "m", "x_s": "m", "omega_mp": "rad/s", "omega_ms": "rad/s",
               "omega_sp": "rad/s", "omega_ss": "rad/s", "v_p": "m/s", "v_s": "m/s",
               "twist_tc": "rad", "twist_ds": "rad", "omega_d": "rad/s", "omega_p": "rad/s",
               "omega_s": "rad/s", "omega_l": "rad/s", "s_b": "m", "z_d": "N m", "z_l": "N m",
               "z_r": "N m"}
OUTPUT_UNITS = {"r_g": "-", "nu": "-", "nu_r": "-", "theta_mp": "rad", "theta_ms": "rad",
                "F_p": "N", "F_s": "N", "F_p_act": "N", "F_s_act": "N", "omega_p": "rad/s",
                "omega_s": "rad/s", "omega_d": "rad/s", "omega_l": "rad/s",
                "omega_mp": "rad/s", "omega_ms": "rad/s", "T_b": "N m", "mu": "-", "tau": "-",
                "kappa": "-", "kappa_eq": "-", "r_g_dot": "1/s", "F_creep": "N", "R_p": "m",
                "R_s": "m", "phi": "rad", "x_p": "m", "x_s": "m", "belt_elongation": "m",
                "T_mp_act": "N m", "T_d_act": "N m", "T_l_act": "N m", "E": "J", "P_in": "W",
                "P_diss": "W", "P_creep": "W", "T_ms_act": "N m", "T_ds": "N m", "mu_max": "-",
                **{name: "W" for name in K.OUTPUTS[K.Y_LSLIP:]}, "v": "m/s", "F_road": "N",
                "T_d_sec": "N m"}
#: what each output is (`empact.nonlinear.model` docs, JSON exports)
OUTPUT_DESCRIPTIONS = {
    "nu": "slip of eq. 2 on the current radii, 1 - omega_s / (r_g omega_p)",
    "nu_r": "slip at the reference ratio, 1 - omega_s / (r_ref omega_p) (eq. 3, Fig. 12)",
    "F_p": "primary axial force of the belt element", "F_s": "secondary clamping force of "
    "the belt element (eq. 1)", "F_p_act": "primary thrust-bearing force (actuator)",
    "F_s_act": "secondary thrust-bearing force (actuator)",
    "tau": "torque ratio T_b cos(beta) / (2 mu_max F_s R_s)",
    "kappa": "thrust ratio the shift law implies for the current ratio rate",
    "kappa_eq": "equilibrium thrust ratio kappa*(tau, r_g)", "r_g_dot": "ratio rate",
    "F_creep": "creep force on the primary sheave (opening)",
    "P_creep": "power absorbed by the creep resistance (part of P_diss)",
    "T_ms_act": "secondary servo torque", "T_ds": "driveshaft torque k_ds twist_ds (what a "
    "test bench measures)", "mu_max": "peak traction coefficient at the current ratio",
    "P_loss_slip": "the variator's slip power T_b (r_g omega_p - omega_s)",
    "P_loss_clamp": "the variator's clamping loss lambda_F F_s R_p omega_p (band and segment "
    "friction, sheave deflection)", "P_loss_load": "the variator's load loss k_T |r_g T_b| "
    "omega_p", "P_loss_drag": "the variator's spin loss on both pulley shafts",
    "P_loss_map": "the measured loss map's torque loss T_loss omega_p (zero without a map, "
    "which replaces the clamping, load and drag losses)",
    "P_var_in": "power into the variator at the primary pulley shaft",
    "P_var_out": "power out of the variator at the secondary pulley shaft",
    "P_diss_servo": "viscous friction of the servos (part of P_diss)",
    "P_diss_spindle": "viscous and Coulomb friction of the spindles (part of P_diss)",
    "P_diss_material": "proportional (material) damping of the springs and the belt (part "
    "of P_diss)", "P_diss_sheave": "Shafai's sheave damping (part of P_diss)",
    "v": "the car's speed (vehicle driveline; 0 on the bench)",
    "F_road": "the road load f0 + f1 v + f2 v^2 + m g sin(grade) (vehicle driveline)",
    "P_road": "the road load's power F_road v (vehicle driveline; part of the load's work)",
    "P_loss_fd": "the final drive's loss (1 - eta_fd) |T_ds| omega_l (vehicle driveline; "
                 "part of the load's work)",
    "T_d_sec": "the engine's torque referred to the secondary, T_d omega_d / omega_s "
               "(vehicle driveline: as the engine's controller reports it)"}
INPUT_UNITS = {"T_mp": "N m", "r_g_ref": "-", "T_ms": "N m", "T_d": "N m",
               "omega_d_ref": "rad/s", "T_l": "N m", "omega_l_ref": "rad/s"}


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
        states, ix = K.state_layout(o.belt == "locked", o.drive == "speed", o.load == "speed",
                                    o.ratio_control)
        inputs = ("r_g_ref" if o.ratio_control else "T_mp", "T_ms",
                  "omega_d_ref" if o.drive == "speed" else "T_d",
                  "omega_l_ref" if o.load == "speed" else "T_l")
        object.__setattr__(self, "states", states)
        object.__setattr__(self, "inputs", inputs)
        object.__setattr__(self, "outputs", tuple(OUTPUTS))
        object.__setattr__(self, "p", _parameter_vector(self.params, o))
        object.__setattr__(self, "ix", ix)

    # -- layout by name ---------------------------------------------------------------------
    @property
    def n(self) -> int:
        """Number of states."""
        return len(self.states)

    def state_index(self, name: str) -> int:
        """Position of the state `name` in ``x`` (e.g. ``"twist_ds"``).

        Parameters
        ----------
        name : str
            One of `states`.
        """
        return _index(self.states, name, "state")

    def output_index(self, name: str) -> int:
        """Position of the output `name` in ``y`` (e.g. ``"nu_r"``).

        Parameters
        ----------
        name : str
            An output's name (`outputs`; `OUTPUT_UNITS` gives its unit).
        """
        return _index(self.outputs, name, "output")

    def input_index(self, name: str) -> int:
        """Position of the input `name` in ``u`` (e.g. ``"T_l"``).

        Parameters
        ----------
        name : str
            An input's name (`inputs`: torques, or references where a loop is closed).
        """
        return _index(self.inputs, name, "input")

    @cached_property
    def constants(self) -> K.KernelConstants:
        """The compiled kernel's parameters by name (a named tuple: ``k_belt``, ``tan_beta``,
        ``sheave_sense``, ``R_s0``, ...; `empact.nonlinear._kernel.PARAMETER_NAMES`)."""
        return K.constants(self.p)

    @property
    def vehicle(self) -> bool:
        """True on the car's driveline (`ModelOptions.driveline` ``"vehicle"``): the engine
        drives, the road loads (`empact.nonlinear._kernel._vehicle_load`)."""
        return self.options.driveline == "vehicle"

    @property
    def creep(self) -> bool:
        """True when a creep law (Carbone or Ide) resists the shift; False for Shafai."""
        return self.options.shift_law != "shafai"

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
        c = self.constants
        if x[self.state_index("omega_p")] == 0.0:
            raise ValueError("omega_p = 0: the slip nu (eq. 2) is undefined at a standing "
                             "primary pulley")
        if x[self.state_index("omega_s")] == 0.0 and c.c_shafai != 0.0 and not self.creep:
            raise ValueError("omega_s = 0: Shafai damping c_shafai / |omega_s| is undefined")
        v = self.params.variator
        x_p, x_s = x[self.state_index("x_p")], x[self.state_index("x_s")]
        R_p = v.R_min + x_p / c.tan_beta
        R_s = c.R_s0 - c.sheave_sense * x_s / c.tan_beta
        if not (abs(R_p - R_s) < v.a and R_p > 0 and R_s > 0):
            raise ValueError(f"x_p = {x_p:g} m, x_s = {x_s:g} m: radii R_p = {R_p:g} m, "
                             f"R_s = {R_s:g} m have no belt geometry (need |R_p - R_s| < a = "
                             f"{v.a:g} m)")
        return x, u

    def evaluate(self, x: ArrayLike, u: ArrayLike) -> tuple[NDArray, NDArray]:
        """State derivative, shape (n,), and outputs, shape (len(OUTPUTS),), at (x, u).

        Parameters
        ----------
        x : array_like, shape (n,)
            State, in the order of `states` (SI).
        u : array_like, shape (4,)
            Inputs, in the order of `inputs` (SI).
        """
        x, u = self._check(x, u)
        dx = np.empty(self.n)
        y = np.empty(len(self.outputs))
        K._eval(x, u, self.p, self.ix, dx, y)
        return dx, y

    def rhs(self, t: float, x: ArrayLike, u: ArrayLike) -> NDArray[np.float64]:
        """``dx/dt`` at time `t` [s] (unused: the model is autonomous), shape (n,).

        Parameters
        ----------
        t : float
            Time [s] (unused).
        x, u : array_like, shapes (n,) and (4,)
            As `evaluate`'s.
        """
        return self.evaluate(x, u)[0]

    def output(self, t: float, x: ArrayLike, u: ArrayLike) -> NDArray[np.float64]:
        """Outputs (`outputs`, SI units in `OUTPUT_UNITS`), shape (len(OUTPUTS),).

        Parameters
        ----------
        t : float
            Time [s] (unused: the model is autonomous).
        x, u : array_like, shapes (n,) and (4,)
            The state (`states`) and the inputs (`inputs`), SI.
        """
        return self.evaluate(x, u)[1]

    def output_dict(self, x: ArrayLike, u: ArrayLike) -> dict[str, float]:
        """Outputs by name.

        Parameters
        ----------
        x, u : array_like, shapes (n,) and (4,)
            As `evaluate`'s.
        """
        return dict(zip(self.outputs, map(float, self.output(0.0, x, u))))

    def jacobian(self, x: ArrayLike, u: ArrayLike) -> tuple[NDArray, NDArray, NDArray, NDArray]:
        """Exact ``A = df/dx`` (n, n), ``B = df/du`` (n, 4), ``C = dy/dx`` (ny, n),
        ``D = dy/du`` (ny, 4), exact: forward-mode derivatives of the compiled kernel (no
        truncation error; equal to the complex step to rounding).

        Parameters
        ----------
        x, u : array_like, shapes (n,) and (4,)
            The point to linearise at, as `evaluate` takes it.
        """
        x, u = self._check(x, u)
        A = np.empty((self.n, self.n))
        B = np.empty((self.n, 4))
        C = np.empty((len(self.outputs), self.n))
        D = np.empty((len(self.outputs), 4))
        KT._jacobian(x, u, self.p, self.ix, A, B, C, D)
        return A, B, C, D

    def traction(self, nu: ArrayLike, r_g: ArrayLike) -> NDArray[np.float64]:
        """Traction coefficient ``mu(nu, r_g)`` of the compiled kernel [-] (broadcasts).

        Parameters
        ----------
        nu : array_like
            Slip [-].
        r_g : array_like
            Geometric ratio [-] (broadcast against `nu`).
        """
        nu, r = np.broadcast_arrays(np.asarray(nu, float), np.asarray(r_g, float))
        if np.any(r <= 0):
            raise ValueError(f"r_g = {r[r <= 0].flat[0]:g}: must be positive")
        out = np.empty(nu.size)
        KB.traction_many(np.ascontiguousarray(nu.ravel()), np.ascontiguousarray(r.ravel()),
                        self.p, out)
        return out.reshape(nu.shape)

    @property
    def traction_law(self) -> AnalyticTraction | TabulatedTraction:
        """The traction law the kernel evaluates: the option ``traction`` (measured curves) or
        the analytic law ``options.traction_law`` (default the magic formula) of
        ``params.traction``."""
        if self.options.traction is not None:
            return self.options.traction
        return traction_from_params(self.params, self.options.traction_law)

    def mu_max(self, r_g: ArrayLike) -> NDArray[np.float64]:
        """Peak traction coefficient ``mu_max(r_g)`` of the kernel's curve [-] (the torque
        ratio is ``tau = mu / mu_max``).

        Parameters
        ----------
        r_g : array_like
            Geometric ratio(s) [-].
        """
        r = np.asarray(r_g, float)
        out = np.empty(r.size)
        KB.mu_max_many(np.ascontiguousarray(r.ravel()), self.p, out)
        return out.reshape(r.shape)

    def torque_loss(self, r_g: ArrayLike, omega_p: ArrayLike, T_in: ArrayLike,
                    F_s: ArrayLike, nu: ArrayLike = 0.0) -> NDArray[np.float64]:
        """The variator's torque loss beside the slip [N m], referred to the primary: the
        loss power of the kernel's law (the clamping, load and drag terms of ``[losses]``,
        or the measured loss map) over ``omega_p``, at the input torque `T_in` the primary
        carries, i.e. what a `~empact.variator.losses.LossMap` tabulates (a map sampled
        from it replaces the analytic law).

        The secondary's drag, at ``omega_s = (1 - nu) r_g omega_p``, is referred to the
        primary by the speed ratio; the radii are the unstretched belt's.  The input torque
        is reached by the secant method on the belt's torque (to 1e-12 N m).

        Parameters
        ----------
        r_g : array_like
            Ratios [-].
        omega_p : array_like
            Primary speeds [rad/s], > 0.
        T_in : array_like
            Input torques at the primary [N m].
        F_s : array_like
            Secondary clamping forces [N].
        nu : array_like, optional
            Slips [-] (default 0: the geometric speed ratio); all five broadcast.

        Returns
        -------
        ndarray
            ``T_loss`` [N m], the broadcast shape.

        Raises
        ------
        ParameterError
            When the input torque is not met (a loss law whose input torque does not rise
            with the belt's).
        """
        r, w, T, F, n = (np.ascontiguousarray(a.ravel()) for a in np.broadcast_arrays(
            *(np.asarray(v, float) for v in (r_g, omega_p, T_in, F_s, nu))))
        shape = np.broadcast_shapes(*(np.shape(v) for v in (r_g, omega_p, T_in, F_s, nu)))
        v = self.params.variator
        R_p = np.ascontiguousarray(radii(r, v.L_belt, v.a)[0])
        w_s = (1.0 - n) * r * w
        T_lp, T_ls = np.empty(r.size), np.empty(r.size)

        def miss(T_pb):  # the input torque's miss at the belt torque T_pb
            KB.losses_many(T_pb, r, R_p, w, w_s, F, self.p, T_lp, T_ls)
            return T_pb + T_lp - T

        a, fa = T.copy(), miss(T.copy())
        b = T - fa
        fb = miss(b)
        for _ in range(60):
            done = np.abs(fb) <= 1e-12 * np.maximum(1.0, np.abs(T))
            if done.all():
                break
            step = np.where(done | (fb == fa), 0.0, fb * (b - a) / np.where(fb == fa, 1.0,
                                                                             fb - fa))
            a, fa = b, fb
            b = b - step
            fb = miss(b)
        else:
            k = int(np.argmax(np.abs(fb)))
            raise ParameterError(f"torque_loss: the input torque T_in = {T[k]:g} N m is not "
                                 f"met (miss {fb[k]:.3g} N m at r_g = {r[k]:g}, omega_p = "
                                 f"{w[k]:g} rad/s, F_s = {F[k]:g} N)")
        return (T_lp + T_ls * w_s / w).reshape(shape)

    def static_creep(self, r_g, R_p, R_s, phi, F_el, tau) -> tuple[NDArray, NDArray]:
        """The shift law at rest for arrays (broadcast): the generalised force ``Lambda``
        [N m] on the ratio and the equilibrium thrust ratio ``kappa*`` [-], at the belt
        element's secondary force `F_el` [N] and the torque ratio `tau` (zero force and the
        geometric thrust ratio for Shafai's law).

        Parameters
        ----------
        r_g : array_like
            Geometric ratio [-].
        R_p, R_s : array_like
            Primary and secondary running radii [m].
        phi : array_like
            Wrap angle on the primary pulley [rad].
        F_el : array_like
            The belt element's secondary force [N].
        tau : array_like
            Torque ratio ``mu / mu_max`` [-].
        """
        args = [np.ascontiguousarray(a, dtype=float).ravel()
                for a in np.broadcast_arrays(r_g, R_p, R_s, phi, F_el, tau)]
        shape = np.broadcast(r_g, R_p, R_s, phi, F_el, tau).shape
        if not self.creep:
            phi_ = args[3]
            return np.zeros(shape), _laws.kappa_geo(phi_).reshape(shape)
        lam, keq = np.empty(args[0].size), np.empty(args[0].size)
        r, R_p_, R_s_, phi_, F_el_, tau_ = args
        KB.creep_many(r, R_p_, R_s_, phi_, F_el_, tau_, self.p, lam, keq)
        return lam.reshape(shape), keq.reshape(shape)

    def static_creep_point(self, r_g: float, R_p: float, R_s: float, phi: float,
                           F_el: float, tau: float,
                           work: list[NDArray] | None = None) -> tuple[float, float]:
        """`static_creep` at one point, as floats (what a sampled law calls at every
        sample): the same compiled loop on one-element arrays, `work` (eight of them) if
        given.

        Parameters
        ----------
        r_g, R_p, R_s, phi, F_el, tau : float
            One point of `static_creep`'s arrays, in its units.
        work : list of ndarray, optional
            Eight one-element work arrays, reused between calls (default: new ones).
        """
        if not self.creep:
            return 0.0, float(_laws.kappa_geo(phi))
        a = work if work is not None else [np.empty(1) for _ in range(8)]
        for j, v in enumerate((r_g, R_p, R_s, phi, F_el, tau)):
            a[j][0] = v
        KB.creep_many(a[0], a[1], a[2], a[3], a[4], a[5], self.p, a[6], a[7])
        return float(a[6][0]), float(a[7][0])

    def evaluate_many(self, X: ArrayLike, U: ArrayLike) -> tuple[NDArray, NDArray]:
        """`evaluate` at many points in one compiled loop: `X` (N, n), `U` (N, 4) ->
        derivatives (N, n) and outputs (N, len(outputs)).

        Parameters
        ----------
        X : array_like, shape (N, n)
            States, one per row.
        U : array_like, shape (N, 4)
            Inputs, one per row.
        """
        X, U = np.ascontiguousarray(X, float), np.ascontiguousarray(U, float)
        DX, Y = np.empty_like(X), np.empty((X.shape[0], len(self.outputs)))
        KB.eval_batch(X, U, self.p, self.ix, DX, Y)
        return DX, Y

    def jacobian_many(self, X: ArrayLike, U: ArrayLike) -> tuple[NDArray, ...]:
        """`jacobian` at many points in one compiled loop: ``A`` (N, n, n), ``B`` (N, n, 4),
        ``C`` (N, ny, n), ``D`` (N, ny, 4).

        Parameters
        ----------
        X, U : array_like, shapes (N, n) and (N, 4)
            The points, one per row, as `evaluate_many` takes them.
        """
        X, U = np.ascontiguousarray(X, float), np.ascontiguousarray(U, float)
        N, n, ny = X.shape[0], self.n, len(self.outputs)
        A, B = np.empty((N, n, n)), np.empty((N, n, 4))
        C, D = np.empty((N, ny, n)), np.empty((N, ny, 4))
        KB.linearize_batch(X, U, self.p, self.ix, np.empty((N, n)), A, B, C, D)
        return A, B, C, D

    def stop_status(self, y: NDArray[np.float64], omega_min: float = 1.0) -> int:
        """Why a simulation would stop at outputs `y` (0: it need not; codes of
        `empact.nonlinear.simulation.STATUS`).

        Parameters
        ----------
        y : ndarray, shape (len(OUTPUTS),)
            Outputs, in the order of `outputs` (SI).
        omega_min : float, optional
            Primary speed [rad/s] at or below which the run stops (slip undefined; default 1).
        """
        return int(K.stop_status(np.ascontiguousarray(y, float), self.p, omega_min))

    def iosystem(self, name: str = "empact"):
        """The model as a `control.NonlinearIOSystem` (updfcn signature ``(t, x, u, params)``).

        Parameters
        ----------
        name : str, optional
            The system's name (default ``"empact"``).
        """
        return control.nlsys(lambda t, x, u, params: self.rhs(t, x, u),
                             lambda t, x, u, params: self.output(t, x, u),
                             inputs=list(self.inputs), outputs=list(self.outputs),
                             states=list(self.states), name=name)


def stiffnesses(params: Params, kinematics: str) -> tuple[float, float, float, float, float]:
    """``(k_w, k_c, k_belt, k_tp, k_ts)`` of the actuation for `kinematics`: the machine's
    (``[actuation]``) or the Sec. 2.1 overlay (``[paper_sec21]``)."""
    s = params.actuation if kinematics == "equal-translation" else params.paper_sec21
    return s.k_w, s.k_c, s.k_belt, s.k_tp, s.k_ts


def _parameter_vector(params: Params, o: ModelOptions) -> NDArray[np.float64]:
    """The kernel's parameter vector for `params` under the options `o`, packed by name."""
    v, a, d = params.variator, params.actuation, params.driveline
    lvl = params.damping.level(o.damping)
    t, sh, kr = params.traction, params.shift, params.thrust_ratio
    thrust_table = o.thrust_ratio.encode() if o.thrust_ratio is not None else np.zeros(0)
    creep_table = o.creep_map.encode() if o.creep_map is not None else np.zeros(0)
    traction_table = o.traction.encode() if o.traction is not None else np.zeros(0)
    loss_table = o.loss_map.encode() if o.loss_map is not None else np.zeros(0)
    sig = sheave_sense(o.kinematics)
    k_w, k_c, k_belt, k_tp, k_ts = stiffnesses(params, o.kinematics)
    values = dict(
        a=v.a, tan_beta=np.tan(v.beta), cos_beta=np.cos(v.beta), R_min=v.R_min, R_max=v.R_max,
        L_belt=v.L_belt, J_mp=a.J_mp, J_ms=a.J_ms, J_sp=a.J_sp, J_ss=a.J_ss, m_p=a.m_p,
        m_s=a.m_s, i_w=a.i_w, i_c=a.i_c, i_e=a.i_e, s=a.s, k_w=k_w, k_c=k_c, k_belt=k_belt,
        k_tp=k_tp, k_ts=k_ts, alpha=lvl.alpha, c_mp=lvl.c_mp, c_ms=lvl.c_ms, c_sp=lvl.c_sp,
        c_ss=lvl.c_ss, c_shafai=lvl.c_shafai, coulomb_sp=o.coulomb_sp,
        coulomb_ss=o.coulomb_ss, coulomb_omega=o.coulomb_omega, J_d=d.J_d, J_p=d.J_p,
        J_s=d.J_s, J_l=d.J_l, k_tc=d.k_tc, k_ds=d.k_ds, k_belt_driveline=d.k_belt,
        **traction_parameters(t, o.traction_law), sheave_sense=sig,
        R_s0=(v.R_max if sig > 0 else v.R_min),
        shift_law={"shafai": K.LAW_SHAFAI, "carbone": K.LAW_CARBONE,
                   "ide": K.LAW_IDE}[o.shift_law],
        D_ref=sh.D_ref, F_ref=sh.F_ref, k_D=sh.k_D, a1=sh.a1, a2=sh.a2, gain=sh.gain,
        omega_0=sh.omega_0, xi_sat=sh.xi_sat, g_beta=g_beta(v.beta), kappa_p0=kr.p0,
        kappa_b0=kr.b0, kappa_b1=kr.b1,
        r_ref=params.operating.r_g if o.reference_ratio is None else o.reference_ratio,
        loss_lambda_F=params.losses.lambda_F, loss_k_T=params.losses.k_T,
        loss_c_v=params.losses.c_v, loss_c_q=params.losses.c_q,
        loss_T_smooth=params.losses.T_smooth)
    values.update(_vehicle_values(params, o))
    for loop, J, f in (("drive", d.J_d, o.drive_bandwidth_hz),
                       ("load", d.J_l, o.load_bandwidth_hz)):
        w = 2 * np.pi * f
        values[f"{loop}_kp"], values[f"{loop}_ki"] = J * w, J * w * w / 4
    w = 2 * np.pi * o.ratio_bandwidth_hz
    J = shift_inertia(params, o.kinematics)
    if o.shift_law == "shafai":  # PID on the shift inertia: natural frequency w
        values.update(ratio_kp=J * w * w, ratio_kd=2 * 0.7 * w * J, ratio_ki=J * w**3 / 4)
    else:  # PI on the creep law's ratio rate per N m: crossover w (servo damping kept)
        values.update(ratio_kp=w, ratio_kd=2 * 0.7 * w * J, ratio_ki=w * w / 4)
    return K.pack_parameters(values, thrust_table, creep_table, traction_table, loss_table)


def _vehicle_values(params: Params, o: ModelOptions) -> dict[str, float]:
    """The kernel's driveline values of the car (`ModelOptions.driveline` ``"vehicle"``):
    the engine's inertia as the drive's, the car reflected to the load shaft (which turns at
    the secondary's speed: ``omega_l = v i_fd / r_w``) as the load's inertia ``m (1 + e_rot)
    r_w^2 / i_fd^2`` and the driveline's stiffness ``k_driveline / i_fd^2``, and the road
    load's and final drive's values (`empact.nonlinear._kernel.VEHICLE_PARAMETER_NAMES`);
    on the bench the flag and those values are zero (the bench's inertias stand)."""
    if o.driveline != "vehicle":
        return dict.fromkeys(K.VEHICLE_PARAMETER_NAMES, 0.0)
    veh = params.vehicle
    gear = veh.r_wheel / veh.i_fd
    return dict(J_d=params.engine.J_e, J_l=veh.mass * (1 + veh.e_rot) * gear ** 2,
                k_ds=veh.k_driveline / veh.i_fd ** 2, vehicle=1.0, vehicle_gear=gear,
                road_f0=veh.f0, road_f1=veh.f1, road_f2=veh.f2,
                road_grade_force=veh.mass * G * np.sin(veh.grade), eta_fd=veh.eta_fd)


def _index(names: tuple[str, ...], name: str, what: str) -> int:
    try:
        return names.index(name)
    except ValueError:
        raise ParameterError(f"unknown {what} {name!r}: choose from "
                             f"{', '.join(names)}") from None


def sheave_sense(kinematics: str) -> float:
    """Sense of the secondary sheave coordinate q6: -1 for ``"equal-translation"`` (q6 > 0
    closes the secondary, ``R_s = R_min + q6 / tan(beta)``), +1 for ``"paper-sec2.1"`` (q6 > 0
    opens it, ``R_s = R_max - q6 / tan(beta)``)."""
    return -1.0 if kinematics == "equal-translation" else 1.0


def shift_inertia(params: Params, kinematics: str = "equal-translation",
                  r_g: float = 1.0) -> float:
    """Inertia of the actuation's shift (rigid-body) motion referred to the primary servo
    [kg m^2]: ``v^T M v`` with the rigid-body mode ``v`` scaled to ``q1 = 1``.

    Parameters
    ----------
    params : Params
        Its ``[actuation]`` and ``[variator]`` blocks are read.
    kinematics : {"equal-translation", "paper-sec2.1"}
        The sheave kinematics of the actuation model.
    r_g : float
        Geometric ratio [-] at which the actuation model is built.

    Returns
    -------
    float
        The shift inertia referred to the primary servo [kg m^2].
    """
    lm = actuation_model(params, r_g, kinematics=kinematics)
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
        ...; see `ModelOptions`).  Unknown keywords are an error.  Without a ``traction``
        option the measured curves the parameter file names (`Params.traction_table`) are
        the traction law, else the magic formula of ``[traction]``; an explicit option (the
        CLI's ``--traction``, a scenario's ``[model] traction``) wins.  Likewise the
        measured loss map (``loss_map``; `Params.loss_map`, ``[losses] table``) replaces
        the analytic losses of ``[losses]``.
    **kwargs
        The `ModelOptions` fields as keywords (instead of `options`).

    Returns
    -------
    EmpactModel
        The compiled right-hand side with its names: 18 base states (the module notes'
        ordering; more with options), inputs ``T_mp, T_ms`` [N m] and the drive and load
        inputs of the chosen bench, outputs by name (``r_g``, ``nu``, ``F_s``, ...).

    Examples
    --------
    >>> from empact.params import default_params
    >>> m = nonlinear_model(default_params(), damping="none", drive="speed")
    >>> m.inputs
    ('T_mp', 'T_ms', 'omega_d_ref', 'T_l')
    """
    if options is not None and kwargs:
        raise ValueError("give either options or keyword options, not both")
    opts = options if options is not None else ModelOptions.from_mapping(kwargs)
    if opts.traction is None and params.traction_table is not None:
        opts = replace(opts, traction=params.traction_table)
    if opts.loss_map is None and params.loss_map is not None:
        opts = replace(opts, loss_map=params.loss_map)
    return EmpactModel(params, opts)


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

    Returns
    -------
    ndarray, shape (n,)
        The state derivative ``dx/dt`` (SI units of the states per second).
    """
    model = params if isinstance(params, EmpactModel) else _default_model(params)
    return model.rhs(t, x, u)
