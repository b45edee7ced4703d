r"""Linear driveline (test-bench) model of the Empact CVT (paper Sec. 2.2, Fig. 7).

::

    drive motor      torque converter     primary        pushbelt       secondary    driveshaft    load motor
      J_d (q1) ----/\/\/\ k_tc ----- J_p (q2) ==[R_p  k_belt  R_s]== J_s (q3) ---/\/\/\ k_ds--- J_l (q4)

Coordinates (rotations [rad]), in this order: ``theta_d`` (q1, drive motor), ``theta_p``
(q2, primary pulley with the torque-converter inertia), ``theta_s`` (q3, secondary pulley),
``theta_l`` (q4, load motor).

Springs: ``tc`` torque-converter lock-up clutch, elongation ``q1 - q2`` [rad]; ``belt`` the
pushbelt as a chain element, elongation ``R_p q2 - R_s q3`` [m] (the ratio enters here);
``ds`` driveshaft, elongation ``q3 - q4`` [rad].  Inputs: drive torque ``T_d`` on q1, load torque
``T_l`` on q4 [N m].

Normalised shapes refer the secondary side to the primary through the ratio: divisors
``[1, 1, r_g, r_g]`` (in the rigid-body mode ``q3 = r_g q2``).

With the belt removed the two sides are uncoupled: the primary side (J_d, k_tc, J_p) and the
secondary side (J_s, k_ds, J_l) each have one rigid-body and one flexible mode
(`uncoupled_frequencies`).  The paper's text labels these 15.5 Hz primary and 24.6 Hz
secondary; only the swapped reading (24.6 Hz primary, 15.5 Hz secondary) is consistent with
Table 2 and with the paper's own root-locus story (see the README, "Paper inconsistencies").
"""
from __future__ import annotations

import numpy as np

from ..params import Params
from ..variator.geometry import variator_state
from .lumped import LumpedModel

__all__ = ["COORDINATES", "SPRINGS", "INPUTS", "driveline_model", "uncoupled_frequencies"]

COORDINATES = ("theta_d", "theta_p", "theta_s", "theta_l")
SPRINGS = ("tc", "belt", "ds")
INPUTS = ("T_d", "T_l")


def driveline_model(params: Params, r_g: float, *, belt: bool = True) -> LumpedModel:
    """The test-bench driveline (Fig. 7) at geometric ratio `r_g`.

    Parameters
    ----------
    params : Params
    r_g : float
        Geometric ratio [-], inside the variator's range.
    belt : bool
        With the belt as a chain element (default); `False`: the belt spring removed (the
        two uncoupled sides).

    Returns
    -------
    LumpedModel
        Coordinates ``theta_d, theta_p, theta_s, theta_l`` [rad], inputs ``T_d, T_l``
        [N m]: its ``modes()``, ``frequency_response`` and ``state_space()``.

    Examples
    --------
    >>> import empact
    >>> dl = empact.driveline_model(empact.load_params(), r_g=0.5)
    >>> dl.modes().frequencies_hz.round(1)             # Table 2 at r_g = 0.5 [Hz]
    array([  0. ,   3.5,  24. , 235.6])
    """
    d = params.driveline
    geo = variator_state(r_g, params.variator)
    R_p, R_s = float(geo.R_p), float(geo.R_s)
    rows = np.array([[1, -1, 0, 0], [0, R_p, -R_s, 0], [0, 0, 1, -1]], float)
    eye = np.eye(4)
    return LumpedModel(
        name=f"driveline(r_g={float(r_g):g})",
        coordinates=COORDINATES,
        mass=np.array([d.J_d, d.J_p, d.J_s, d.J_l]),
        springs=SPRINGS, spring_rows=rows,
        stiffness=np.array([d.k_tc, d.k_belt if belt else 0.0, d.k_ds]),
        inputs={"T_d": eye[0], "T_l": eye[3]},
        scale=np.array([1, 1, float(r_g), float(r_g)]),
        spring_parameters=("driveline.k_tc", "driveline.k_belt" if belt else "",
                           "driveline.k_ds"),
    )


def uncoupled_frequencies(params: Params) -> dict[str, float]:
    """Flexible-mode frequencies of the two sides without the belt [Hz].

    Closed form of a two-inertia, one-spring system: ``sqrt(k (1/J_a + 1/J_b)) / (2 pi)``.
    Returns ``{"primary": ..., "secondary": ...}``.

    Parameters
    ----------
    params : Params
        Reads ``[driveline]``: the primary side is the drive motor ``J_d`` and the primary
        ``J_p`` on the torque converter ``k_tc``, the secondary side the secondary ``J_s``
        and the load motor ``J_l`` on the driveshaft ``k_ds``.

    Returns
    -------
    dict str -> float
        ``{"primary": f_p, "secondary": f_s}``, the flexible-mode frequency of each side
        [Hz].
    """
    d = params.driveline
    f = lambda k, Ja, Jb: float(np.sqrt(k * (1 / Ja + 1 / Jb)) / (2 * np.pi))  # noqa: E731
    return {"primary": f(d.k_tc, d.J_d, d.J_p), "secondary": f(d.k_ds, d.J_s, d.J_l)}
