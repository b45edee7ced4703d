"""The pushbelt variator's losses beside the slip: clamping, load and drag (the ``[losses]``
block).

The kernel (`empact.nonlinear._kernel._losses`) applies them as torques on the pulley shafts,
each opposing its shaft's rotation (smooth sign ``tanh(omega / coulomb_omega)``, as the
model's Coulomb terms)::

    primary:    T_var_p = r_g T_b + T_clamp + T_load + T_drag(omega_p)
    secondary:  T_var_s = T_b - T_drag(omega_s)

    T_clamp = lambda_F F_s R_p                    (power lambda_F F_s v_b, v_b = R_p omega_p)
    T_load  = k_T |r_g T_b|                       (|T| ~ T tanh(T / T_smooth))
    T_drag(omega) = c_v omega + c_q omega^2 sg(omega)     (on each shaft at its own speed)

so that ``P_var_in - P_var_out = P_slip + P_clamp + P_load + P_drag`` with the shaft powers
``P_var_in = T_var_p omega_p`` and ``P_var_out = T_var_s omega_s`` (outputs ``P_loss_*``,
``P_var_in``, ``P_var_out`` of `empact.nonlinear`; `empact.nonlinear.VARIATOR_LOSSES`).

Forms and sources.  The loss mechanisms are those of Akehurst, Vaughan, Parker & Simner,
Proc. IMechE D 218 (2004), Parts 1-3: band-set and segment friction and band-band sliding
(Part 1), pulley deflection and misalignment, i.e. the belt's radial motion in the wrap
(Part 2), and belt-pulley slip (Part 3; the kernel's slip power).  Micklem et al., Proc.
IMechE D 210 (1996): the belt's torque loss, the pump and the slip lead the losses, and
"much lower pulley clamping pressures" are the remedy, i.e. a torque loss growing with the
clamping force.  Narita & Priest, Proc. IMechE J 221 (2007) (a production unit at secondary
clamping 10.5-34.6 kN): efficiency falls at low load (a load-independent torque: clamping
and drag) and towards overdrive.  van der Meulen et al. (extremum seeking of the variator's
efficiency): efficiency over clamping force has an interior maximum, where the falling slip
power meets the rising clamping loss.  The clamping term is written as a sliding power at the
belt speed: at given input torque and torque ratio ``F_s R_p = T_in cos(beta) / (2 tau
mu_max)``, so its share of the input torque does not depend on the radii but grows with the
clamping reserve and where mu_max is low (overdrive, Fig. 10).

The coefficients are estimates (no published coefficient of these forms could be read): the
bands of ``data/parameter_sources.toml`` state their basis.
"""
from __future__ import annotations

from dataclasses import dataclass

from .._section import Section, param

__all__ = ["LossParams"]


@dataclass(frozen=True)
class LossParams(Section):
    """The variator's losses beside the slip (``[losses]``; every key has a default).

    Attributes
    ----------
    lambda_F : float
        Clamping loss [-]: ``T_clamp = lambda_F F_s R_p`` on the primary, the sliding power
        ``lambda_F F_s v_b`` at the belt speed (default 3e-3: 0.17 N m per kN of clamping at
        r_g 1; estimate).
    k_T : float
        Load loss [-]: ``T_load = k_T |r_g T_b|`` on the primary, a fraction of the input
        torque (default 0.01; estimate).
    c_v : float
        Viscous drag of each pulley shaft [N m s/rad] (default 5e-4: 0.15 N m at 300 rad/s;
        estimate).
    c_q : float
        Quadratic (churning) drag of each pulley shaft [N m s^2/rad^2] (default 1e-6: 0.09 N m
        at 300 rad/s; estimate).
    T_smooth : float
        Torque scale of the smooth ``|T| ~ T tanh(T / T_smooth)`` of the load loss [N m]
        (default 1; a regularisation: the Jacobian exists at zero torque).
    """

    _name = "losses"

    lambda_F: float = param("-", "clamping loss: T_clamp = lambda_F F_s R_p on the primary "
                            "(band and segment friction, sheave deflection; sliding power "
                            "lambda_F F_s v_b)", 0.0, 0.1, lo_open=False, default=3e-3)
    k_T: float = param("-", "load loss: T_load = k_T |r_g T_b| on the primary (torque-"
                       "dependent belt loss)", 0.0, 0.2, lo_open=False, default=0.01)
    c_v: float = param("N m s/rad", "viscous drag of each pulley shaft (spin loss: bearings, "
                       "seals)", 0.0, 0.1, lo_open=False, default=5e-4)
    c_q: float = param("N m s^2/rad^2", "quadratic drag of each pulley shaft (spin loss: oil "
                       "churning)", 0.0, 1e-3, lo_open=False, default=1e-6)
    T_smooth: float = param("N m", "torque scale of the load loss's smooth |T| (a "
                            "regularisation)", 0.0, 100.0, default=1.0)
