"""Robustness of a controller across a plant family: closed-loop poles, disk margins and the
structured singular value.

Disk margins after Seiler, Packard & Gahinet, "An introduction to disk margins", IEEE Control
Systems Magazine 40(5), 2020 (balanced disks, skew 0): for a loop ``L`` the multiloop disk margin
``alpha = 1 / sup_w mu(S - I/2)``, ``S = (I + L)^-1``, with ``mu`` for independent complex scalar
perturbations in each loop; for two loops the D-scaled upper bound ``inf_d sbar(D M D^-1)`` is
exact (two complex scalar blocks) and is computed for every frequency and grid point at once
(golden section on ``ln d``: ``ln sbar`` is convex in it).  ``alpha`` gives the simultaneous
gain range ``[(2 - alpha)/(2 + alpha), (2 + alpha)/(2 - alpha)]`` and phase ``+-2 atan(alpha/2)``
in every loop.  ``control.disk_margins`` computes the same (checked in the tests), one system at
a time.

The closed loop is ``u = K (r - y)`` with the plant's control inputs ``u`` (T_mp, T_ms) and
measured outputs ``y`` (ratio, slip); margins are taken at the plant input (``L = K G``) and at
the output (``L = G K``); the smaller is reported.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._lazy import lazy_module
from .._results import Result
from .family import PlantFamily

slycot = lazy_module("slycot")

#: frequencies of the margin computations [rad/s]: 0.01-1000 Hz, 300 points
OMEGA = 2 * np.pi * np.logspace(-2, 3, 300)

__all__ = ["OMEGA", "frequency_responses", "plant_responses", "disk_margin", "disk_gain_phase",
           "closed_loop_matrix", "RobustnessMap", "robustness_map", "mu_upper_bound"]


def frequency_responses(A, B, C, D, omega) -> NDArray[np.complex128]:
    """``C (j w I - A)^-1 B + D`` for stacks of systems: A (..., n, n) -> (..., n_w, p, m).

    Parameters
    ----------
    A, B, C, D : array_like
        Continuous state-space matrices, shapes (..., n, n), (..., n, m), (..., p, n),
        (..., p, m), with common (broadcastable) leading dimensions.
    omega : array_like, shape (n_w,)
        Frequencies [rad/s].

    Returns
    -------
    ndarray of complex, shape (..., n_w, p, m)
        The responses, output units per input unit.
    """
    A, B, C, D = (np.asarray(M) for M in (A, B, C, D))
    w = np.asarray(omega, float)
    n = A.shape[-1]
    M = 1j * w[:, None, None] * np.eye(n) - A[..., None, :, :]
    X = np.linalg.solve(M, np.broadcast_to(B[..., None, :, :], M.shape[:-1] + B.shape[-1:]))
    return C[..., None, :, :] @ X + D[..., None, :, :]


def _mu_2x2(M: NDArray[np.complexfloating[Any, Any]], iters: int = 60) -> NDArray[np.float64]:
    """``inf_d sbar(diag(d, 1) M diag(1/d, 1))`` for a stack (..., 2, 2)."""
    M = np.asarray(M)

    a11, a12, a21, a22 = M[..., 0, 0], M[..., 0, 1], M[..., 1, 0], M[..., 1, 1]
    p0 = np.abs(a11) ** 2 + np.abs(a22) ** 2
    det2 = np.abs(a11 * a22 - a12 * a21) ** 2  # |det| does not change with d

    def sbar(t):
        """Largest singular value of the scaled 2x2 in closed form."""
        d2 = np.exp(2 * t)
        f = p0 + np.abs(a12) ** 2 * d2 + np.abs(a21) ** 2 / d2  # squared Frobenius norm
        return np.sqrt(0.5 * (f + np.sqrt(np.maximum(f * f - 4 * det2, 0.0))))

    g = (np.sqrt(5) - 1) / 2
    a, b = np.full(M.shape[:-2], -30.0), np.full(M.shape[:-2], 30.0)
    c, d = b - g * (b - a), a + g * (b - a)
    fc, fd = sbar(c), sbar(d)
    for _ in range(iters):
        left = fc < fd
        b, a = np.where(left, d, b), np.where(left, a, c)
        c, d = np.where(left, b - g * (b - a), d), np.where(left, c, a + g * (b - a))
        # recompute both: cheap, and keeps the bracket consistent under np.where
        fc, fd = sbar(c), sbar(d)
    return np.minimum(fc, fd)


def disk_margin(L: NDArray[np.complex128]) -> NDArray[np.float64]:
    """Multiloop balanced disk margin ``alpha`` of loops ``L`` (..., n_w, m, m) over the
    frequency axis: shape (...).

    Parameters
    ----------
    L : array_like of complex, shape (..., n_w, m, m)
        Loop responses (``K G`` or ``G K``) at n_w frequencies, one or two loops (m = 1 or
        2).

    Returns
    -------
    ndarray, shape (...)
        ``alpha = 1 / max_w mu(S - I/2)`` [-], ``S = (I + L)^-1``; it says nothing of
        closed-loop stability (check the poles).

    Raises
    ------
    ValueError
        For more than two loops.
    """
    L = np.asarray(L)
    m = L.shape[-1]
    S = np.linalg.inv(np.eye(m) + L)
    M = S - 0.5 * np.eye(m)
    if m == 1:
        mu = np.abs(M[..., 0, 0])
    elif m == 2:
        mu = _mu_2x2(M)
    else:
        raise ValueError("disk margins for one or two loops")
    return 1.0 / mu.max(axis=-1)


def disk_gain_phase(alpha) -> tuple[NDArray, NDArray]:
    """``(gain margin [dB], phase margin [deg])`` of a balanced disk margin ``alpha``.

    Parameters
    ----------
    alpha : array_like
        Balanced disk margins [-], any shape.

    Returns
    -------
    gain_margin_db : ndarray
        ``20 log10((2 + alpha) / (2 - alpha))`` [dB] (inf for ``alpha >= 2``), the shape of
        `alpha`.
    phase_margin_deg : ndarray
        ``2 atan(alpha / 2)`` [deg], the shape of `alpha`.
    """
    a = np.asarray(alpha, float)
    with np.errstate(divide="ignore"):
        gm = np.where(a < 2, 20 * np.log10((2 + a) / np.where(a < 2, 2 - a, 1.0)), np.inf)
    return gm, np.degrees(2 * np.arctan(a / 2))


def closed_loop_matrix(A, B, C, Ac, Bc, Cc, Dc) -> NDArray[np.float64]:
    """State matrix of ``u = K (r - y)`` around plants (stacked A (..., n, n), B (..., n, m)
    control inputs, C (..., p, n) measured outputs, no feedthrough) with the controller.

    Parameters
    ----------
    A, B, C : array_like
        The plants, shapes (..., n, n), (..., n, m), (..., p, n).
    Ac, Bc, Cc, Dc : ndarray
        The continuous controller from the p errors to the m controls, shapes (n_c, n_c),
        (n_c, p), (m, n_c), (m, p).

    Returns
    -------
    ndarray, shape (..., n + n_c, n + n_c)
        The closed loop's state matrix [1/s], state ``[x; x_c]``.
    """
    A, B, C = (np.asarray(M) for M in (A, B, C))
    nc = Ac.shape[0]
    top = np.concatenate([A - B @ Dc @ C, np.broadcast_to(B @ Cc, A.shape[:-2] + (A.shape[-1],
                                                                                  nc))], -1)
    bot = np.concatenate([-np.broadcast_to(Bc, C.shape[:-2] + Bc.shape) @ C,
                          np.broadcast_to(Ac, A.shape[:-2] + (nc, nc))], -1)
    return np.concatenate([top, bot], -2)


@dataclass(frozen=True)
class RobustnessMap(Result):
    """A controller against every plant of a family.

    Attributes
    ----------
    max_real_pole : array, shape ``family.shape``
        Largest real part of the closed-loop poles [1/s] (< 0: stable).
    disk_margin : array, shape ``family.shape``
        Multiloop balanced disk margin alpha, the smaller of plant input and output [-]
        (0 where the loop is unstable).
    gain_margin_db, phase_margin_deg : arrays, shape ``family.shape``
        Its simultaneous gain [dB] and phase [deg] margins.
    omega : array
        Frequencies of the margin computation [rad/s].
    """

    max_real_pole: NDArray[np.float64]
    disk_margin: NDArray[np.float64]
    gain_margin_db: NDArray[np.float64]
    phase_margin_deg: NDArray[np.float64]
    omega: NDArray[np.float64]

    @property
    def stable(self) -> NDArray[np.bool_]:
        """Closed loop stable at each grid point."""
        return self.max_real_pole < 0

    def worst(self) -> dict[str, float]:
        """The worst case over the family."""
        a = float(self.disk_margin.min())
        gm, pm = disk_gain_phase(a)
        return {"max_real_pole": float(self.max_real_pole.max()), "disk_margin": a,
                "gain_margin_db": float(gm), "phase_margin_deg": float(pm),
                "all_stable": bool(self.stable.all())}


def measured_rows(family: PlantFamily, names) -> NDArray[np.float64]:
    """Output rows (``family.shape + (len(names), n)``) of measured signals: the family's
    outputs, or ``ln_<slip>`` (the logarithm of a slip signal, linearised at each point:
    the row divided by the point's slip)."""
    rows = []
    for name in names:
        if name.startswith("ln_"):
            base = name[3:]
            rows.append(family.C[..., family.outputs.index(base), :]
                        / family.operating["nu"][..., None])
        else:
            rows.append(family.C[..., family.outputs.index(name), :])
    return np.stack(rows, axis=-2)


def plant_responses(family: PlantFamily, inputs, outputs, omega) -> NDArray[np.complex128]:
    """The family's responses from `inputs` to `outputs` (`measured_rows` names) at `omega`
    [rad/s]: shape ``family.shape + (n_w, n_out, n_in)`` (reusable across controllers).

    Parameters
    ----------
    family : PlantFamily
        The plants.
    inputs : sequence of str
        Family inputs (e.g. ``("T_mp", "T_ms")``), n_in of them.
    outputs : sequence of str
        Family outputs or ``ln_<slip>`` (`measured_rows`), n_out of them.
    omega : array_like, shape (n_w,)
        Frequencies [rad/s].

    Returns
    -------
    ndarray of complex, shape ``family.shape + (n_w, n_out, n_in)``
        The responses without feedthrough (e.g. [1/(N m)] from a servo torque to ratio or
        slip).
    """
    ii = [family.inputs.index(n) for n in inputs]
    B, C = family.B[..., ii], measured_rows(family, outputs)
    return frequency_responses(family.A, B, C, np.zeros(C.shape[:-1] + (B.shape[-1],)), omega)


def robustness_map(family: PlantFamily, controller, channels=None,
                   omega: NDArray | None = None, G: NDArray | None = None) -> RobustnessMap:
    """Closed-loop poles and disk margins of `controller` against every plant of `family`.

    `controller` is a continuous `empact.control.controller.Controller`; `G` are the family's
    responses at `omega` (`plant_responses`) when already computed.

    Parameters
    ----------
    family : PlantFamily
    controller : Controller
        Continuous.
    channels : optional
        Not used: the measured channels are ``controller.measured``.
    omega : ndarray, optional
        Frequencies [rad/s] of the margin computation, shape (n_f,) (default `OMEGA`).
    G : ndarray, optional
        The family's responses at `omega` (`plant_responses`).

    Returns
    -------
    RobustnessMap
        ``max_real_pole`` [1/s], ``disk_margin`` [-], ``gain_margin_db`` [dB] and
        ``phase_margin_deg`` [deg], each of shape ``family.shape``.
    """
    if controller.dt:
        raise ValueError("robustness_map needs the continuous controller (dt = 0)")
    ii = [family.inputs.index(n) for n in controller.outputs]
    A, B, C = family.A, family.B[..., ii], measured_rows(family, controller.measured)
    Acl = closed_loop_matrix(A, B, C, controller.A, controller.B, controller.C, controller.D)
    ev = np.linalg.eigvals(Acl)
    max_re = ev.real.max(axis=-1)
    w = OMEGA if omega is None else np.asarray(omega, float)
    if G is None:
        G = plant_responses(family, controller.outputs, controller.measured, w)
    Kjw = frequency_responses(controller.A, controller.B, controller.C, controller.D, w)
    a_in = disk_margin(Kjw @ G)
    a_out = disk_margin(G @ Kjw)
    alpha = np.where(max_re < 0, np.minimum(a_in, a_out), 0.0)
    gm, pm = disk_gain_phase(alpha)
    return RobustnessMap(max_real_pole=max_re, disk_margin=alpha, gain_margin_db=gm,
                         phase_margin_deg=pm, omega=w)


def mu_upper_bound(family: PlantFamily, controller, nominal: tuple[int, ...],
                   n_directions: int = 3, omega: NDArray | None = None) -> dict[str, float]:
    """Upper bound of the structured singular value of the closed loop over a real parametric
    spread that covers the family (slycot ``ab13md``).

    The family's state matrices are written ``A(delta) = A0 + sum_i delta_i E_i`` around the
    nominal point: the ``E_i`` are the first `n_directions` principal directions of the
    deviations ``A_k - A0`` over the grid, scaled so that every grid point has ``|delta_i| <=
    1``.  Each ``E_i`` is factored into rank-one terms (``svd``, kept to 1e-6 of the largest),
    and each term enters as an independent real 1x1 block (ab13md supports no repeated real
    block): a conservative bound.  The loop is robustly stable for the whole box if the
    returned ``mu_peak < 1``.  B and C are taken at the nominal point (their spread is not in
    the bound).

    Returns ``{"mu_peak", "n_blocks", "captured"}`` (``captured``: the share of the
    deviations' energy the kept directions carry).

    Parameters
    ----------
    family : PlantFamily
        The plants.
    controller : Controller
        Continuous, from ``controller.measured`` errors to ``controller.outputs``.
    nominal : tuple of int
        Grid index of the nominal point ``A0``.
    n_directions : int
        Most principal directions ``E_i`` kept.
    omega : ndarray, optional
        Frequencies [rad/s] (default 200 points, log-spaced from 0.01 to 1000 Hz).

    Returns
    -------
    dict str -> float
        ``mu_peak`` [-] (< 1: robustly stable over the box), ``n_blocks`` (the number of
        real 1x1 blocks, an int), ``captured`` [-] and ``omega_peak`` [rad/s], the
        frequency of the peak.
    """
    ii = [family.inputs.index(n) for n in controller.outputs]
    A0, B0 = family.A[nominal], family.B[nominal][:, ii]
    C0 = measured_rows(family, controller.measured)[nominal]
    dev = (family.A - A0).reshape(-1, A0.size)
    U, s, Vt = np.linalg.svd(dev, full_matrices=False)
    q = min(n_directions, int(np.sum(s > 1e-12 * s[0])))
    captured = float(np.sum(s[:q] ** 2) / np.sum(s ** 2))
    coef = U[:, :q] * s[:q]
    scale = np.abs(coef).max(axis=0)
    cols_b, rows_c = [], []
    for i in range(q):
        E = (Vt[i] * scale[i]).reshape(A0.shape)
        u, sv, vt = np.linalg.svd(E)
        keep = sv > 1e-6 * sv[0]
        for j in np.flatnonzero(keep):
            cols_b.append(u[:, j] * np.sqrt(sv[j]))
            rows_c.append(vt[j] * np.sqrt(sv[j]))
    Bd, Cd = np.array(cols_b).T, np.array(rows_c)
    nc = controller.A.shape[0]
    Acl = closed_loop_matrix(A0, B0, C0, controller.A, controller.B, controller.C,
                             controller.D)
    Bdc = np.vstack([Bd, np.zeros((nc, Bd.shape[1]))])
    Cdc = np.hstack([Cd, np.zeros((Cd.shape[0], nc))])
    w = np.logspace(-2, 3, 200) * 2 * np.pi if omega is None else np.asarray(omega, float)
    M = frequency_responses(Acl, Bdc, Cdc, np.zeros((Cdc.shape[0], Bdc.shape[1])), w)
    nb = len(cols_b)
    nblock = np.ones(nb, dtype=np.int64)
    itype = np.ones(nb, dtype=np.int64)  # real blocks
    mu = [float(slycot.ab13md(Mk, nblock, itype)[0]) for Mk in M]
    return {"mu_peak": float(max(mu)), "n_blocks": nb, "captured": captured,
            "omega_peak": float(w[int(np.argmax(mu))])}
