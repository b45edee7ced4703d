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

Spring elongations:

1. worm ``q1 / i_w - q3 / i_e`` (the epicyclic set is a gear of ratio ``i_e = 2``);
2. chain ``q2 / i_c - q4 / i_e``;
3. pushbelt, the linearised belt-length change; the ratio enters only here, through
   ``phi(r_g)``:

   * ``kinematics="equal-translation"`` (default; the Empact as built, paper Secs. 1 and 2.3):
     ``[(pi + 2 phi) q5 + (pi - 2 phi) q6] / tan(beta)``, q5 > 0 closes the primary, q6 > 0
     closes the secondary; with the secondary servo held, the primary servo translates both
     sheaves equally (``q5 = -q6``, a ratio change) and the secondary servo clamps.
     Stiffnesses from ``[actuation]``, calibrated to 10.7 / 17.3 / 47.9 Hz at r_g = 1 for these
     rows.  At r_g = 1 the worm decouples from the belt and bearings (mode 3 is the worm mode)
     and the rigid-body mode has ``q~2 = q~4 = 0`` (the secondary side stands still).
   * ``kinematics="paper-sec2.1"``: the rows as the paper's Sec. 2.1 publishes them,
     ``[(pi + 2 phi) q5 - (pi - 2 phi) q6] / tan(beta)`` (q6 > 0 opens the secondary), with the
     stiffness overlay ``[paper_sec21]`` calibrated to Table 1 on them; its rigid-body mode has
     all ``q~1..q~6`` equal and mode 2 is the worm with belt and bearings, as Sec. 2.1 says.  A
     named variant for reproducing Table 1 and Figs. 4-5; not the machine (a primary-servo
     rotation squeezes both sheaves).
4. primary thrust bearing ``q7``;
5. secondary thrust bearing ``q8``.

Inputs: servo torques ``T_mp`` on q1 and ``T_ms`` on q2 [N m].

Damping (`damping` level, Fig. 6): proportional spring damping ``alpha K``, viscous friction in
the servos (on q1, q2) and screws (on the screw rotations q3 and q4 - q3), and a pulley damping
on the sheave translations: ``pulley_damping="shafai"`` (default) is Shafai's ``c_shafai /
|omega|`` on each sheave at the level's ``c_shafai``, with ``omega`` the pulley speed
(primary ``omega_pulley``, secondary ``r_g omega_pulley``): the paper's illustrative levels;
``pulley_damping="creep"`` is the linearisation of the belt's creep law at the operating point
(``omega_pulley``, clamping force ``F_s``; `empact.shift_law.creep_damping`), the damping the
nonlinear model has, so that the Sec. 2 cut and the machine agree.

Normalised shapes (Fig. 4) refer every coordinate to the primary sun through the rigid-body
kinematics at ``r_g = 1``: divisors ``[i_w / i_e, 2 i_c / i_e, 1, 2, -s, -+s, s, s]`` (``-s``
for q6 under the Sec. 2.1 rows, ``+s`` for the machine), so that the rigid-body mode has
``q~1 = q~3 = q~5 = q~6`` and ``q~7 = q~8 = 0``.
"""
from __future__ import annotations

import numpy as np

from .._validate import check_choice, check_number
from ..params import Params
from ..variator.geometry import variator_state
from ..variator.shift_law import creep_damping
from .lumped import LumpedModel, element_matrix

__all__ = ["COORDINATES", "SPRINGS", "INPUTS", "KINEMATICS", "actuation_model"]

#: the machine's belt row, and the paper's Sec. 2.1 rows as published
KINEMATICS = ("equal-translation", "paper-sec2.1")

COORDINATES = ("theta_mp", "theta_ms", "theta_sp", "theta_ss", "x_p", "x_s")
DERIVED = ("x_np", "x_ns")
SPRINGS = ("worm", "chain", "belt", "thrust_p", "thrust_s")
INPUTS = ("T_mp", "T_ms")


def actuation_model(params: Params, r_g: float, damping: str = "none",
                    omega_pulley: float | None = None, *,
                    kinematics: str = "equal-translation", pulley_damping: str = "shafai",
                    F_s: float | None = None) -> LumpedModel:
    """The actuation model at geometric ratio `r_g`.

    Parameters
    ----------
    params : Params
    r_g : float
        Geometric ratio, inside the variator's range.
    damping : {"none", "moderate", "large"}
        Damping level from ``params.damping``.
    omega_pulley : float, optional
        Primary pulley speed for the pulley damping [rad/s]; default
        ``params.damping.omega_pulley``.
    kinematics : {"equal-translation", "paper-sec2.1"}
        The machine's belt row (default) or the paper's Sec. 2.1 rows with the
        ``[paper_sec21]`` stiffnesses (see the module notes).
    pulley_damping : {"shafai", "creep"}
        Shafai's ``c_shafai / |omega|`` at the damping level, or the creep law linearised at
        (`r_g`, `omega_pulley`, `F_s`).
    F_s : float, optional
        Clamping force for the creep damping [N]; default ``params.operating.F_s``.

    Returns
    -------
    LumpedModel
        Coordinates ``theta_mp, theta_ms, theta_sp, theta_ss`` [rad], ``x_p, x_s`` [m] (and
        the derived ``x_np, x_ns``), inputs ``T_mp, T_ms`` [N m]: its ``modes()``,
        ``frequency_response(omega, inputs, outputs)`` and ``state_space()``.

    Examples
    --------
    >>> import empact
    >>> act = empact.actuation_model(empact.load_params(), r_g=1.0)
    >>> act.modes().frequencies_hz[:4].round(1)        # Table 1 at r_g = 1 [Hz]
    array([ 0. , 10.7, 17.3, 47.9])
    """
    check_choice("kinematics", kinematics, KINEMATICS)
    check_choice("pulley_damping", pulley_damping, ("shafai", "creep"))
    p = params.actuation
    k_src = p if kinematics == "equal-translation" else params.paper_sec21
    sig = -1.0 if kinematics == "equal-translation" else 1.0
    geo = variator_state(r_g, params.variator)
    phi, tb = float(geo.phi), np.tan(params.variator.beta)
    s = p.s
    rows = np.array([
        [1 / p.i_w, 0, -1 / p.i_e, 0, 0, 0],
        [0, 1 / p.i_c, 0, -1 / p.i_e, 0, 0],
        [0, 0, 0, 0, (np.pi + 2 * phi) / tb, -sig * (np.pi - 2 * phi) / tb],
        [0, 0, s, 0, 1, 0],
        [0, 0, -s, s, 0, 1],
    ])
    k = np.array([k_src.k_w, k_src.k_c, k_src.k_belt, k_src.k_tp, k_src.k_ts])
    section = "actuation" if kinematics == "equal-translation" else "paper_sec21"
    level = params.damping.level(damping)
    w_p = params.damping.omega_pulley if omega_pulley is None else check_number(
        "omega_pulley", omega_pulley, 0.0, lo_open=True, unit="rad/s",
        note="the pulley damping needs a turning pulley")
    viscous_rows = np.array([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, -1, 1]], float)
    viscous_rows = np.hstack([viscous_rows, np.zeros((4, 2))])
    C = level.alpha * element_matrix(rows, k) + element_matrix(
        viscous_rows, [level.c_mp, level.c_ms, level.c_sp, level.c_ss])
    if pulley_damping == "shafai":
        C[4, 4] += level.c_shafai / w_p
        C[5, 5] += level.c_shafai / (float(r_g) * w_p)
    else:
        F = params.operating.F_s if F_s is None else F_s
        if F is None:  # a point given by its slip and load: its clamping force solved
            F = params.operating.resolve(params).F_s
        C[4:, 4:] += creep_damping(params, r_g, w_p, F, kinematics).matrix
    eye = np.eye(6)
    label = "" if kinematics == "equal-translation" else ", paper-sec2.1"
    return LumpedModel(
        name=f"actuation(r_g={float(r_g):g}, damping={damping}{label})",
        coordinates=COORDINATES,
        mass=np.array([p.J_mp, p.J_ms, p.J_sp, p.J_ss, p.m_p, p.m_s]),
        springs=SPRINGS, spring_rows=rows, stiffness=k, damping=C,
        inputs={"T_mp": eye[0], "T_ms": eye[1]},
        derived={"x_np": rows[3], "x_ns": rows[4]},
        scale=np.array([p.i_w / p.i_e, 2 * p.i_c / p.i_e, 1, 2, -s, -sig * s, s, s]),
        spring_parameters=tuple(f"{section}.{k}" for k in ("k_w", "k_c", "k_belt", "k_tp",
                                                            "k_ts")),
    )
