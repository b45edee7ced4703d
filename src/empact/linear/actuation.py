"""Linear actuation model of the Empact CVT (paper Sec. 2.1, Fig. 3).

::

      servo P (q1)                                      servo S (q2)
        |  worm, k_w (1)                                   |  chain, k_c (2)
        v                                                  v
     ring P ==(i_e)== sun P (q3) ----- ring coupling ---- ring S ==(i_e)== sun S (q4)
                        |  screw, pitch s                                  |  screw, pitch s
                   nut P (q7 = s q3 + q5)                     nut S (q8 = s (q4 - q3) + q6)
                        |  thrust bearing k_tp (4)                         |  thrust bearing k_ts (5)
                   sheave P (q5) ======== pushbelt, k_belt (3) ======== sheave S (q6)

Coordinates (SI), in this order:

====  ============  ==========================================================
q1    ``theta_mp``  primary servo rotation [rad]
q2    ``theta_ms``  secondary servo rotation [rad]
q3    ``theta_sp``  primary sun gear (output side of the primary screw) [rad]
q4    ``theta_ss``  secondary sun gear (input side of the secondary screw) [rad]
q5    ``x_p``       primary moving-sheave translation [m]
q6    ``x_s``       secondary moving-sheave translation [m]
q7    ``x_np``      derived: primary screw input translation ``s q3 + q5`` [m]
q8    ``x_ns``      derived: secondary screw input translation ``s (q4 - q3) + q6`` [m]
====  ============  ==========================================================

Spring elongations (the sign convention of this module):

1. worm ``q1 / i_w - q3 / i_e`` (the epicyclic set is a gear of ratio ``i_e = 2``);
2. chain ``q2 / i_c - q4 / i_e``;
3. pushbelt ``[(pi + 2 phi) q5 - (pi - 2 phi) q6] / tan(beta)``, the linearised belt-length
   change (both sheaves translate in the same absolute direction: q5 > 0 opens ``R_p``,
   q6 > 0 closes ``R_s``); the ratio enters only here, through ``phi(r_g)``;
4. primary thrust bearing ``q7``;
5. secondary thrust bearing ``q8``.

Inputs: servo torques ``T_mp`` on q1 and ``T_ms`` on q2 [N m].

Damping (`damping` level, Fig. 6): proportional spring damping ``alpha K``, viscous friction in
the servos (on q1, q2) and screws (on the screw rotations q3 and q4 - q3), and Shafai pulley
damping ``c_shafai / |omega|`` on each sheave translation, with ``omega`` the pulley speed
(primary ``omega_pulley``, secondary ``r_g omega_pulley``).

Normalised shapes (Fig. 4) refer every coordinate to the primary sun through the rigid-body
kinematics at ``r_g = 1``: divisors ``[i_w / i_e, 2 i_c / i_e, 1, 2, -s, -s, s, s]``, so that
the rigid-body mode has ``q~1 = ... = q~6`` and ``q~7 = q~8 = 0``.
"""
from __future__ import annotations

import numpy as np

from ..geometry import variator_state
from .lumped import LumpedModel, element_matrix
from .._validate import check_number
from ..params import Params

__all__ = ["COORDINATES", "SPRINGS", "INPUTS", "actuation_model"]

COORDINATES = ("theta_mp", "theta_ms", "theta_sp", "theta_ss", "x_p", "x_s")
DERIVED = ("x_np", "x_ns")
SPRINGS = ("worm", "chain", "belt", "thrust_p", "thrust_s")
INPUTS = ("T_mp", "T_ms")


def actuation_model(params: Params, r_g: float, damping: str = "none",
                    omega_pulley: float | None = None) -> LumpedModel:
    """The actuation model at geometric ratio `r_g`.

    Parameters
    ----------
    params : Params
    r_g : float
        Geometric ratio, inside the variator's range.
    damping : {"none", "moderate", "large"}
        Damping level from ``params.damping``.
    omega_pulley : float, optional
        Primary pulley speed for Shafai's damping [rad/s]; default
        ``params.damping.omega_pulley``.
    """
    p = params.actuation
    geo = variator_state(r_g, params.variator)
    phi, tb = float(geo.phi), np.tan(params.variator.beta)
    s = p.s
    rows = np.array([
        [1 / p.i_w, 0, -1 / p.i_e, 0, 0, 0],
        [0, 1 / p.i_c, 0, -1 / p.i_e, 0, 0],
        [0, 0, 0, 0, (np.pi + 2 * phi) / tb, -(np.pi - 2 * phi) / tb],
        [0, 0, s, 0, 1, 0],
        [0, 0, -s, s, 0, 1],
    ])
    k = np.array([p.k_w, p.k_c, p.k_belt, p.k_tp, p.k_ts])
    level = params.damping.level(damping)
    w_p = params.damping.omega_pulley if omega_pulley is None else check_number(
        "omega_pulley", omega_pulley, 0.0, lo_open=True, unit="rad/s",
        note="Shafai damping c_shafai / |omega| needs a turning pulley")
    viscous_rows = np.array([[1, 0, 0, 0, 0, 0], [0, 1, 0, 0, 0, 0], [0, 0, 1, 0, 0, 0],
                             [0, 0, -1, 1, 0, 0], [0, 0, 0, 0, 1, 0], [0, 0, 0, 0, 0, 1]], float)
    c = [level.c_mp, level.c_ms, level.c_sp, level.c_ss,
         level.c_shafai / w_p, level.c_shafai / (float(r_g) * w_p)]
    C = level.alpha * element_matrix(rows, k) + element_matrix(viscous_rows, c)
    eye = np.eye(6)
    return LumpedModel(
        name=f"actuation(r_g={float(r_g):g}, damping={damping})",
        coordinates=COORDINATES,
        mass=np.array([p.J_mp, p.J_ms, p.J_sp, p.J_ss, p.m_p, p.m_s]),
        springs=SPRINGS, spring_rows=rows, stiffness=k, damping=C,
        inputs={"T_mp": eye[0], "T_ms": eye[1]},
        derived={"x_np": rows[3], "x_ns": rows[4]},
        scale=np.array([p.i_w / p.i_e, 2 * p.i_c / p.i_e, 1, 2, -s, -s, s, s]),
    )
