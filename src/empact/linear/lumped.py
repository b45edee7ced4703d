"""A small, general lumped-parameter engine: M, K, C from kinematic rows; modes; FRFs.

A model has ``n`` generalised coordinates ``q`` with a (diagonal or full) mass matrix ``M``,
``m`` springs whose elongations are ``B q`` (one kinematic row per spring) with stiffnesses
``k``, so ``K = B^T diag(k) B``, and a damping matrix ``C`` built the same way from damper rows.
Inputs are generalised forces ``F u`` (one column of ``F`` per named input); derived
coordinates (such as the screw-input translations q7, q8 of the actuation model) are further
rows ``D q``.

Equations of motion: ``M q'' + C q' + K q = F u``.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.linalg import eigh

from .._results import Result
from ..lti import FrequencyResponse, index, statespace

__all__ = ["LumpedModel", "Modes", "element_matrix"]

#: eigenvalues below this fraction of the largest are rigid-body modes
RIGID_TOL = 1e-9


def element_matrix(rows: ArrayLike, values: ArrayLike) -> NDArray[np.float64]:
    """``R^T diag(values) R`` for element rows ``R`` (shape (m, n)) and values (shape (m,)).

    Parameters
    ----------
    rows : array_like, shape (m, n)
        Kinematic rows: the elongation of element i is ``rows[i] @ q`` (a single row may be
        given as shape (n,)).
    values : array_like, shape (m,)
        The element constants, e.g. stiffnesses or damping constants (in the units of force
        per unit elongation, or per unit elongation rate, of each element).

    Returns
    -------
    ndarray, shape (n, n)
        The symmetric matrix on the coordinates (e.g. ``K = B^T diag(k) B``).
    """
    R = np.atleast_2d(np.asarray(rows, float))
    return R.T @ (np.asarray(values, float)[:, None] * R)


@dataclass(frozen=True)
class Modes(Result):
    """Undamped modes of a `LumpedModel` (mode index last in the shape arrays).

    Attributes
    ----------
    model : model name
    coordinates : names of the coordinates, then the derived coordinates
    springs : spring names
    omega : natural frequencies [rad/s], shape (n,), ascending; rigid-body modes exactly 0
    shapes : mass-normalised mode shapes, shape (n, n) (column j is mode j)
    derived_shapes : derived coordinates of each mode, shape (n_derived, n)
    normalised_shapes : shapes of coordinates and derived coordinates divided by the gear /
        screw ratios (``scale``) and scaled to a largest magnitude of 1, sign chosen so the
        largest entry is positive; shape (n + n_derived, n) (Fig. 4 of the paper)
    energy_fraction : signed modal potential energy per spring, shape (n, m): entry (j, i) is
        ``sign(e_ij) * k_i e_ij^2 / sum_i k_i e_ij^2`` with ``e = B shape_j``; zero for
        rigid-body modes (Fig. 5)
    n_rigid : number of rigid-body modes
    mass_matrix, stiffness_matrix : M and K
    spring_parameters : the parameter each spring's stiffness is, by its dotted name
        (``actuation.k_belt``, ``driveline.k_belt``), in the order of `springs`; ``""`` for a
        spring removed (stiffness 0); empty when the model names none
    """

    model: str
    coordinates: tuple[str, ...]
    springs: tuple[str, ...]
    omega: NDArray[np.float64]
    shapes: NDArray[np.float64]
    derived_shapes: NDArray[np.float64]
    normalised_shapes: NDArray[np.float64]
    energy_fraction: NDArray[np.float64]
    n_rigid: int
    mass_matrix: NDArray[np.float64]
    stiffness_matrix: NDArray[np.float64]
    spring_parameters: tuple[str, ...] = ()

    @property
    def frequencies_hz(self) -> NDArray[np.float64]:
        """Natural frequencies [Hz], shape (n,)."""
        return self.omega / (2 * np.pi)


@dataclass(frozen=True)
class LumpedModel:
    """Linear lumped-parameter model ``M q'' + C q' + K q = F u``.

    Parameters
    ----------
    name : str
        Model name.
    coordinates : sequence of str, length n
        Names of the generalised coordinates.
    mass : array, shape (n,) or (n, n)
        Diagonal masses/inertias [kg or kg m^2], or the full mass matrix.
    springs : sequence of str, length m
        Spring names.
    spring_rows : array, shape (m, n)
        Kinematic rows: elongation of spring i is ``spring_rows[i] @ q``.
    stiffness : array, shape (m,)
        Spring stiffnesses (units to match the rows).
    damping : array, shape (n, n), optional
        Damping matrix ``C`` (zero if omitted); need not be symmetric.
    inputs : dict name -> array (n,)
        Generalised-force distribution of each named input.
    derived : dict name -> array (n,), optional
        Derived coordinates ``row @ q``.
    scale : array, shape (n + n_derived,), optional
        Divisors that refer every coordinate to a common side (gear and screw ratios), used for
        `Modes.normalised_shapes`.
    spring_parameters : sequence of str, length m, optional
        The parameter each stiffness is, by its dotted name (``actuation.k_belt``; ``""``
        for a spring removed); `Modes` carries it, so that a model's output says which of
        the parameter set's stiffnesses it used.
    """

    name: str
    coordinates: tuple[str, ...]
    mass: NDArray[np.float64]
    springs: tuple[str, ...]
    spring_rows: NDArray[np.float64]
    stiffness: NDArray[np.float64]
    inputs: dict[str, NDArray[np.float64]]
    damping: NDArray[np.float64] | None = None
    derived: dict[str, NDArray[np.float64]] = field(default_factory=dict)
    scale: NDArray[np.float64] | None = None
    spring_parameters: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        n = len(self.coordinates)
        rows = np.atleast_2d(np.asarray(self.spring_rows, float))
        if rows.shape != (len(self.springs), n):
            raise ValueError(f"spring_rows has shape {rows.shape}, expected "
                             f"({len(self.springs)}, {n})")
        if self.spring_parameters and len(self.spring_parameters) != len(self.springs):
            raise ValueError(f"{len(self.spring_parameters)} spring_parameters for "
                             f"{len(self.springs)} springs")
        object.__setattr__(self, "spring_rows", rows)
        object.__setattr__(self, "stiffness", np.asarray(self.stiffness, float))
        object.__setattr__(self, "mass", np.asarray(self.mass, float))

    # -- matrices ------------------------------------------------------------------------
    @property
    def n(self) -> int:
        """Number of coordinates."""
        return len(self.coordinates)

    @property
    def M(self) -> NDArray[np.float64]:
        """Mass matrix, shape (n, n)."""
        return np.diag(self.mass) if self.mass.ndim == 1 else self.mass

    @property
    def K(self) -> NDArray[np.float64]:
        """Stiffness matrix ``B^T diag(k) B``, shape (n, n)."""
        return element_matrix(self.spring_rows, self.stiffness)

    @property
    def C(self) -> NDArray[np.float64]:
        """Damping matrix, shape (n, n)."""
        return np.zeros((self.n, self.n)) if self.damping is None else np.asarray(self.damping)

    def force_matrix(self, inputs: Sequence[str] | None = None) -> NDArray[np.float64]:
        """Input distribution ``F``, shape (n, n_in), for the named inputs (default all).

        Parameters
        ----------
        inputs : sequence of str, optional
            Input names (default all, in the model's order).
        """
        names = list(self.inputs) if inputs is None else list(inputs)
        for name in names:
            index(list(self.inputs), name, "input")
        return np.column_stack([self.inputs[name] for name in names])

    def output_matrix(self, outputs: Sequence[str]
                      ) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
        """Rows ``(n_out, 2n)`` on ``[q, q']`` for named outputs.

        A coordinate or derived-coordinate name gives a displacement; the same name with
        ``_dot`` appended gives its velocity.  Also returns a mask of the velocity outputs.

        Parameters
        ----------
        outputs : sequence of str
            Coordinate or derived-coordinate names, each optionally with ``_dot``.
        """
        known = {**{c: np.eye(self.n)[i] for i, c in enumerate(self.coordinates)}, **self.derived}
        rows, is_velocity = [], []
        for name in outputs:
            base = name[:-4] if name.endswith("_dot") else name
            if base not in known:
                choices = list(known) + [f"{c}_dot" for c in known]
                raise ValueError(f"unknown output {name!r}: choose from {', '.join(choices)}")
            vel = name.endswith("_dot")
            row = np.zeros(2 * self.n)
            row[self.n * vel:self.n * (vel + 1)] = known[base]
            rows.append(row)
            is_velocity.append(vel)
        return np.array(rows), np.array(is_velocity)

    # -- analysis ------------------------------------------------------------------------
    def modes(self) -> Modes:
        """Undamped modes (generalised symmetric eigenproblem ``K v = w^2 M v``)."""
        M, K = self.M, self.K
        lam, V = eigh(K, M)
        lam_max = max(abs(lam).max(), 1e-300)
        rigid = lam < RIGID_TOL * lam_max
        omega = np.where(rigid, 0.0, np.sqrt(np.clip(lam, 0, None)))
        D = np.array(list(self.derived.values())).reshape(len(self.derived), self.n)
        full = np.vstack([V, D @ V])
        scale = np.ones(len(full)) if self.scale is None else np.asarray(self.scale, float)
        norm = full / scale[:, None]
        peak = norm[np.argmax(np.abs(norm), axis=0), np.arange(self.n)]
        norm = norm / peak  # largest entry +1
        V = V * np.sign(peak)
        elong = self.spring_rows @ V  # (m, n)
        energy = self.stiffness[:, None] * elong**2
        total = energy.sum(axis=0)
        frac = np.where(rigid, 0.0, np.sign(elong) * energy / np.where(rigid, 1.0, total))
        return Modes(model=self.name, coordinates=tuple(self.coordinates) + tuple(self.derived),
                     springs=tuple(self.springs), omega=omega, shapes=V,
                     derived_shapes=D @ V, normalised_shapes=norm, energy_fraction=frac.T,
                     n_rigid=int(rigid.sum()), mass_matrix=M, stiffness_matrix=K,
                     spring_parameters=tuple(self.spring_parameters))

    def frequency_response(self, omega: ArrayLike, inputs: Sequence[str] | None = None,
                           outputs: Sequence[str] | None = None, label: str = "") \
            -> FrequencyResponse:
        """Frequency response computed directly from M, C, K, vectorised over frequency.

        ``H(w) = C_out (K + s^2 M + s C)^{-1} F`` at ``s = j w``, velocity outputs times ``s``.
        A model without any damping (``C = 0``) is evaluated in the limit of vanishing damping,
        at ``s = j w + 1e-9 w``: its response is real on the axis and its phase at every sign
        change an arbitrary +-180 deg; the limit makes it the continuation of the damped
        curves (-180 deg below the first mode for a rigid-body mode), at a relative change of
        the magnitude of 1e-9 away from the resonances.

        Parameters
        ----------
        omega : array, shape (n_f,)
            Frequencies [rad/s], all > 0 when the model has a rigid-body mode.
        inputs, outputs : names (default: all inputs; all coordinates)
        label : free text for the result
        """
        w = np.atleast_1d(np.asarray(omega, float))
        inputs = list(self.inputs) if inputs is None else list(inputs)
        outputs = list(self.coordinates) if outputs is None else list(outputs)
        F = self.force_matrix(inputs)
        rows, vel = self.output_matrix(outputs)
        rows = rows[:, :self.n] + rows[:, self.n:]  # velocity rows are multiplied by s below
        s = 1j * w + (1e-9 * w if not np.any(self.C) else 0.0)
        Z = self.K[None] + (s**2)[:, None, None] * self.M[None] + s[:, None, None] * self.C[None]
        X = np.linalg.solve(Z, np.broadcast_to(F, (len(w),) + F.shape))  # (n_f, n, n_in)
        H = np.einsum("on,fni->oif", rows, X)
        H[vel] *= s
        return FrequencyResponse(omega=w, H=H, inputs=tuple(inputs), outputs=tuple(outputs),
                                 label=label)

    def state_space(self, inputs: Sequence[str] | None = None,
                    outputs: Sequence[str] | None = None):
        """Named `control.StateSpace` with states ``[q, q']``.

        State names are the coordinates and ``<coordinate>_dot``; outputs as in
        `output_matrix` (default: all coordinates).

        Parameters
        ----------
        inputs : sequence of str, optional
            Input names (default all).
        outputs : sequence of str, optional
            Output names as `output_matrix` takes them (default all coordinates).
        """
        inputs = list(self.inputs) if inputs is None else list(inputs)
        outputs = list(self.coordinates) if outputs is None else list(outputs)
        n = self.n
        Minv = np.linalg.inv(self.M)
        A = np.block([[np.zeros((n, n)), np.eye(n)], [-Minv @ self.K, -Minv @ self.C]])
        B = np.vstack([np.zeros((n, len(inputs))), Minv @ self.force_matrix(inputs)])
        C, _ = self.output_matrix(outputs)
        states = list(self.coordinates) + [f"{c}_dot" for c in self.coordinates]
        return statespace(A, B, C, np.zeros((len(outputs), len(inputs))), inputs=inputs,
                          outputs=outputs, states=states, name=self.name)
