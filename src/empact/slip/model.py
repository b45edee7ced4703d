r"""The slip model: the driveline of Fig. 7 with the linearised belt damper (eq. 3).

::

    drive motor    torque converter    primary              secondary    driveshaft   load motor
     J_d (q1) ---/\/\/\ k_tc ---- J_p (q2)  ==[ slip ]==  J_s (q3) ---/\/\/\ k_ds --- J_l (q4)
       ^ T_d                        ^ -r_g T_b         T_b ^                            ^ T_l

* State ``x = [theta_d, theta_p, theta_s, theta_l, theta_d_dot, ..., theta_l_dot]``
  (deviations [rad, rad/s]); inputs ``F_s`` [N], ``T_d``, ``T_l`` [N m]; outputs ``nu``
  (linearised slip [-]), ``omega_p``, ``omega_s`` [rad/s] and ``T_b`` (belt torque on the
  secondary [N m]).  The belt terms are those of `empact.slip.coupling`.
* Structural poles: with no spring across the slipping belt the model always has three
  eigenvalues at 0 - the free rotation of the whole driveline (a double zero: angle and speed)
  and the relative angle of the two sides.  They carry no information about the coupling.
  `reduced_matrices` removes them exactly: on the invariant subspace of zero referred momentum
  ``J_d omega_d + J_p omega_p + r_g (J_s omega_s + J_l omega_l) = 0`` (its rate is
  ``T_d + r_g T_l``: the spring and belt torques cancel in it, so it is invariant) the states
  ``[theta_d - theta_p, theta_s - theta_l, omega_p, omega_s, omega_l]`` carry the other five
  eigenvalues.  A fourth real pole, near ``-c_s (r_g rho / (J_d + J_p) + 1 / (J_s + J_l))``,
  is the relative speed of the sides: it is positive (unstable) whenever ``mu' < 0``.
* Zeros of ``F_s -> nu``: the clamping force enters along the same direction as the belt
  damper and the slip is the damper's own velocity, so this channel is ``G(s) = g H(s) /
  (1 + c_s H(s))`` with the belt-free ``H``: its zeros do not depend on ``c_b`` (hence not on
  ``mu'``, ``F_s0`` or ``omega_p0``), only on ``r_g`` and (through ``rho``) very slightly on
  ``nu0``; they are the poles of the kinematically coupled driveline
  (`empact.slip.loci.coupled_limit`), the end points of the Fig. 9 root locus.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._validate import check_values
from ..linear.driveline import COORDINATES, driveline_model
from ..lti import FrequencyResponse, frequency_response, statespace, transmission_zeros
from ..params import OperatingPoint, Params
from ..variator.traction import TractionModel
from .coupling import BeltLinearisation, linearisation_terms, linearize_belt

__all__ = ["STATES", "INPUTS", "OUTPUTS", "N_STRUCTURAL_ZEROS", "REDUCED_STATES", "SlipModel",
           "slip_model", "slip_state_space", "state_matrices", "reduced_matrices",
           "mass_stiffness", "assemble_A", "assemble_reduced"]

STATES = tuple(COORDINATES) + tuple(f"{c}_dot" for c in COORDINATES)
INPUTS = ("F_s", "T_d", "T_l")
OUTPUTS = ("nu", "omega_p", "omega_s", "T_b")
#: Eigenvalues at 0 of every slip model (free rotation: double; relative angle: single).
N_STRUCTURAL_ZEROS = 3
#: States of the reduced model (`reduced_matrices`): torque-converter and driveshaft
#: deflections ``theta_d - theta_p``, ``theta_s - theta_l`` [rad] and three speeds [rad/s].
REDUCED_STATES = ("e_tc", "e_ds", "omega_p", "omega_s", "omega_l")


def mass_stiffness(params: Params) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Diagonal inertias (4,) and stiffness matrix (4, 4) of the driveline without the belt.

    Taken from ``driveline_model(params, r_g, belt=False)``; without the belt spring neither
    depends on the ratio.

    Parameters
    ----------
    params : Params
        Its ``[driveline]`` block is read.

    Returns
    -------
    J : ndarray, shape (4,)
        Inertias of the coordinates ``theta_d, theta_p, theta_s, theta_l`` [kg m^2].
    K : ndarray, shape (4, 4)
        Stiffness matrix of the torque converter and driveshaft springs [N m/rad].
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


def assemble_A(J: NDArray[np.float64], K: NDArray[np.float64], r_g: NDArray[np.float64],
                rho: NDArray[np.float64], c_s: NDArray[np.float64]) -> NDArray[np.float64]:
    """Stacked system matrices ``A``, shape (N, 8, 8), from 1-d arrays of length N.

    ``A = [[0, I], [-M^-1 K, -M^-1 C_b]]`` with ``C_b = c_s force vel^T``.

    Parameters
    ----------
    J : ndarray, shape (4,)
        Driveline inertias [kg m^2] (`mass_stiffness`).
    K : ndarray, shape (4, 4)
        Driveline stiffness matrix [N m/rad] (`mass_stiffness`).
    r_g : ndarray, shape (N,)
        Geometric ratios [-].
    rho : ndarray, shape (N,)
        Kinematic ratios ``r_g (1 - nu0)`` [-].
    c_s : ndarray, shape (N,)
        Belt damping of the secondary torque [N m s/rad].

    Returns
    -------
    ndarray, shape (N, 8, 8)
        The system matrices (``x' = A x``) on the states `STATES`.
    """
    N = r_g.shape[0]
    Jinv = 1.0 / J
    force, vel = _directions(r_g, rho)
    A = np.zeros((N, 8, 8))
    A[:, :4, 4:] = np.eye(4)
    A[:, 4:, :4] = -(Jinv[:, None] * K)
    A[:, 4:, 4:] = -(c_s[:, None, None] * (Jinv * force)[:, :, None] * vel[:, None, :])
    return A


def assemble_reduced(J: NDArray[np.float64], K: NDArray[np.float64], r_g: NDArray[np.float64],
                      rho: NDArray[np.float64], c_s: NDArray[np.float64]) -> NDArray[np.float64]:
    """Stacked reduced system matrices, shape (N, 5, 5), states `REDUCED_STATES`.

    Exact restriction of ``A`` to the invariant subspace of zero referred momentum
    ``J_d w_d + J_p w_p + r_g (J_s w_s + J_l w_l) = 0`` in the coordinates (spring deflections,
    speeds); ``w_d`` follows from the momentum.  Its five eigenvalues are the eigenvalues of
    ``A`` other than the three structural zeros.

    Parameters
    ----------
    J : ndarray, shape (4,)
        Driveline inertias [kg m^2] (`mass_stiffness`).
    K : ndarray, shape (4, 4)
        Driveline stiffness matrix [N m/rad] (`mass_stiffness`).
    r_g : ndarray, shape (N,)
        Geometric ratios [-].
    rho : ndarray, shape (N,)
        Kinematic ratios ``r_g (1 - nu0)`` [-].
    c_s : ndarray, shape (N,)
        Belt damping of the secondary torque [N m s/rad].

    Returns
    -------
    ndarray, shape (N, 5, 5)
        The reduced system matrices on the states `REDUCED_STATES`.
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


def _assemble(J: NDArray[np.float64], K: NDArray[np.float64], r_g: NDArray[np.float64],
              rho: NDArray[np.float64], c_s: NDArray[np.float64], g_F: NDArray[np.float64],
              omega_p: NDArray[np.float64]) -> tuple[NDArray[np.float64], ...]:
    """Stacked ``A (N, 8, 8)``, ``B (N, 8, 3)``, ``C (N, 4, 8)``, ``D (N, 4, 3)`` (1-d inputs)."""
    N = r_g.shape[0]
    Jinv = 1.0 / J
    A = assemble_A(J, K, r_g, rho, c_s)
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

    Parameters
    ----------
    params : Params
        Parameter set (variator, driveline; traction curve if `traction` is None).
    r_g, nu, F_s, omega_p : array_like
        Operating points: ratio [-], slip [-], clamping force [N] and primary speed [rad/s],
        broadcast together to shape S.
    traction : TractionModel, optional
        Traction model (default `traction_from_params(params)`).

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
    t = linearisation_terms(params, r_g, nu, F_s, omega_p, traction)
    shape = t["r_g"].shape
    J, K = mass_stiffness(params)
    flat = {k: np.ravel(v) for k, v in t.items()}
    mats = _assemble(J, K, flat["r_g"], flat["rho"], flat["c_s"], flat["g_F"], flat["omega_p"])
    return tuple(m.reshape(shape + m.shape[1:]) for m in mats)


def reduced_matrices(params: Params, r_g: ArrayLike, nu: ArrayLike, F_s: ArrayLike,
                     omega_p: ArrayLike, traction: TractionModel | None = None) \
        -> NDArray[np.float64]:
    """Reduced system matrices without the structural zeros, shape S + (5, 5).

    The slip model restricted (exactly) to zero referred momentum ``J_d omega_d + J_p omega_p
    + r_g (J_s omega_s + J_l omega_l) = 0``, states `REDUCED_STATES`.  Its eigenvalues are the
    five eigenvalues of `state_matrices`' ``A`` that are not structural zeros, so stability
    needs no rule for telling the structural zeros apart.  Arguments as `state_matrices`.

    Parameters
    ----------
    params : Params
        Parameter set (variator, driveline; traction curve if `traction` is None).
    r_g, nu, F_s, omega_p : array_like
        Operating points: ratio [-], slip [-], clamping force [N] and primary speed [rad/s],
        broadcast together to shape S.
    traction : TractionModel, optional
        Traction model (default `traction_from_params(params)`).

    Returns
    -------
    ndarray, shape S + (5, 5)
        The reduced system matrices, states `REDUCED_STATES`.
    """
    t = linearisation_terms(params, r_g, nu, F_s, omega_p, traction)
    shape = t["r_g"].shape
    J, K = mass_stiffness(params)
    A = assemble_reduced(J, K, np.ravel(t["r_g"]), np.ravel(t["rho"]), np.ravel(t["c_s"]))
    return A.reshape(shape + (5, 5))


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
    def op(self) -> OperatingPoint:
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
        """Named `control.StateSpace` (states `STATES`; default all inputs and outputs).

        Parameters
        ----------
        inputs : sequence of str, optional
            Input names (default all of `INPUTS`).
        outputs : sequence of str, optional
            Output names (default all of `OUTPUTS`).
        """
        ii, oo, ins, outs = self._select(inputs, outputs)
        return statespace(self.A, self.B[:, ii], self.C[oo], self.D[np.ix_(oo, ii)],
                          inputs=ins, outputs=outs, states=self.states, name=self.name)

    def poles(self) -> NDArray[np.complex128]:
        """All eight eigenvalues of A [rad/s] (three structural zeros included), shape (8,)."""
        return np.sort_complex(np.linalg.eigvals(self.A).astype(np.complex128))

    def frequency_response(self, omega: ArrayLike, inputs: Sequence[str] | None = None,
                           outputs: Sequence[str] | None = None, label: str = "") \
            -> FrequencyResponse:
        """``H(j w) = C (j w I - A)^{-1} B + D`` at `omega` [rad/s] (> 0), vectorised.

        Returns a `~empact.lti.FrequencyResponse` with ``H`` of shape (n_out, n_in, n_f).

        Parameters
        ----------
        omega : array_like, shape (n_f,)
            Angular frequencies [rad/s], > 0.
        inputs : sequence of str, optional
            Input names (default all of `INPUTS`).
        outputs : sequence of str, optional
            Output names (default all of `OUTPUTS`).
        label : str, optional
            The response's label (legends).
        """
        w = check_values("omega", omega, 0.0, lo_open=True, unit="rad/s",
                         note="the model has poles at 0")
        ii, oo, ins, outs = self._select(inputs, outputs)
        return frequency_response(self.A, self.B[:, ii], self.C[oo], self.D[np.ix_(oo, ii)],
                                  np.atleast_1d(w), ins, outs, label=label)

    def zeros(self, input: str = "F_s", output: str = "nu") -> NDArray[np.complex128]:
        """Finite invariant zeros of one input -> output channel [rad/s], by magnitude.

        Parameters
        ----------
        input : str, optional
            One of `INPUTS` (default ``"F_s"``).
        output : str, optional
            One of `OUTPUTS` (default ``"nu"``).
        """
        ii, oo, _, _ = self._select([input], [output])
        return transmission_zeros(self.A, self.B[:, ii], self.C[oo], self.D[np.ix_(oo, ii)])


def slip_model(params: Params, op: OperatingPoint | None = None,
               traction: TractionModel | None = None) -> SlipModel:
    """The slip model at `op` (default: the ``[operating]`` point of `params`).

    Parameters
    ----------
    params : parameter set (variator, driveline, traction)
    op : operating point (r_g, nu, F_s, omega_p; one given by a torque ratio or a load is
        resolved, `OperatingPoint.resolve`)
    traction : traction model (default `traction_from_params(params)`)

    Returns
    -------
    SlipModel
        States ``theta_d, theta_p, theta_s, theta_l`` [rad] and their speeds [rad/s];
        inputs ``F_s`` [N], ``T_d, T_l`` [N m]; outputs ``nu`` [-], ``omega_p, omega_s``
        [rad/s], ``T_b`` [N m]: ``poles()``, ``zeros()``, ``frequency_response`` and
        ``state_space()``.

    Examples
    --------
    On the falling side of the traction curve (4 % slip at r_g = 1) the driveline's two
    oscillatory pairs are unstable (Fig. 11):

    >>> import empact
    >>> op = empact.OperatingPoint(r_g=1.0, nu=0.04, F_s=10e3, omega_p=300.0)
    >>> p = empact.slip_model(empact.load_params(), op).poles()
    >>> int(((p.real > 0) & (p.imag > 1.0)).sum())     # pairs with a growing oscillation
    2
    """
    op = (params.operating if op is None else op).resolve(params, traction)
    belt = linearize_belt(params, op, traction)
    A, B, C, D = (m[0] for m in state_matrices(params, [op.r_g], [op.nu], [op.F_s],
                                               [op.omega_p], traction))
    return SlipModel(belt=belt, A=A, B=B, C=C, D=D, name="slip")


def slip_state_space(params: Params, op: OperatingPoint | None = None,
                     traction: TractionModel | None = None, inputs: Sequence[str] | None = None,
                     outputs: Sequence[str] | None = None):
    """Named `control.StateSpace` of the slip model at `op` (see `slip_model`).

    Parameters
    ----------
    params : Params
        Parameter set (variator, driveline, traction).
    op : OperatingPoint, optional
        The operating point (default ``params.operating``; resolved first).
    traction : TractionModel, optional
        Traction model (default `traction_from_params(params)`).
    inputs : sequence of str, optional
        Inputs to keep, from `INPUTS` (default all).
    outputs : sequence of str, optional
        Outputs to keep, from `OUTPUTS` (default all).

    Returns
    -------
    control.StateSpace
        Continuous, states `STATES` (deviations [rad, rad/s]), inputs ``F_s`` [N], ``T_d,
        T_l`` [N m], outputs ``nu`` [-], ``omega_p, omega_s`` [rad/s], ``T_b`` [N m].
    """
    return slip_model(params, op, traction).state_space(inputs, outputs)


# --------------------------------------------------------------------------------------------
# Stability measures
# --------------------------------------------------------------------------------------------
