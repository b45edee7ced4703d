"""H-infinity mixed-sensitivity design of the 2x2 ratio and slip controller, with the checks
python-control does not make.

``control.mixsyn`` (python-control 0.10) builds ``P = augw(G, W1, W2)`` and calls slycot's
``sb10ad`` with job 3 from gamma = 1e100, without checking the standard assumptions; on an
ill-posed problem (``D12`` rank deficient, a weight or plant zero on the imaginary axis) it
can hang (python-control issues #152 and #973) or return a useless controller.  Here:

1. the nominal plant's modes faster than ``f_keep`` (the creep law's poles near -1e6 1/s, the
   bearing modes) are residualised (Schur form, fast block last, DC gain kept), so that the
   Riccati equations are not asked to span 12 decades;
2. the generalized plant is checked (`check_wellposed`): ``D12`` full column rank and ``D21``
   full row rank (relative tolerance sqrt(eps), as sb10ad), ``(A, B2)`` stabilisable and
   ``(C2, A)`` detectable (PBH), and no invariant zeros of ``[A - sI, B2; C1, D12]`` or of
   ``[A - sI, B1; C2, D21]`` on or near the imaginary axis; a failure is one `ParameterError`
   line naming the assumption;
3. sb10ad is called with a finite starting gamma (job 1, bisection), then again at 1.1 times
   the optimum (job 4), which gives a far better conditioned controller than the optimal one.

Weights (outputs scaled by `Y_SCALE`: ratio 0.01, slip 0.001, so that 1 is a "unit error"; the
one source of the scaling, used to build the plant and to undo it on the controller)::

    W1_i = (s / M + w_b,i) / (s + w_b,i A)          performance on S: bandwidth w_b, peak M
    W2   = (s + w_bc / M_u) / (eps_u s + w_bc) / u_scale   control effort, biproper
"""
from __future__ import annotations

import warnings

import numpy as np
from numpy.typing import NDArray

from .._deprecate import warn_renamed
from .._lazy import lazy_module
from .._validate import check_number
from ..errors import ParameterError
from .controller import Controller
from .family import PlantFamily
from .robustness import disk_gain_phase, measured_rows, robustness_map

control = lazy_module("control")
slycot = lazy_module("slycot")
sla = lazy_module("scipy.linalg")

__all__ = ["check_wellposed", "residualize", "design_hinf", "mixed_sensitivity_plant",
           "Y_SCALE"]

#: the size of a "unit error" of each measured output (ratio, slip) in the weights [-]
Y_SCALE = (0.01, 0.001)


def residualize(A, B, C, D, f_keep_hz: float | None = None, *,
                f_keep: float | None = None) -> tuple[NDArray, NDArray, NDArray, NDArray]:
    """Remove the modes faster than `f_keep_hz` [Hz] by residualisation (DC gain kept): real
    Schur form with the slow eigenvalues first; the fast block's states are set to their
    quasi-static values (they must be stable).  (``f_keep``: deprecated name.)

    Parameters
    ----------
    A, B, C, D : array_like
        State-space matrices, shapes (n, n), (n, m), (p, n), (p, m).
    f_keep_hz : float
        Modes with ``|lambda| >= 2 pi f_keep_hz`` [rad/s] are residualised.
    f_keep : float, optional
        Deprecated name of `f_keep_hz`.

    Returns
    -------
    A_r, B_r, C_r, D_r : ndarray
        The reduced model in the slow Schur coordinates, shapes (k, k), (k, m), (p, k),
        (p, m), with k the number of slow modes; its DC gain equals the full model's.

    Raises
    ------
    ParameterError
        When a fast mode is not stable.
    """
    if f_keep is not None:
        warn_renamed("residualize(f_keep=)", "f_keep_hz [Hz]")
        f_keep_hz = f_keep
    if f_keep_hz is None:
        raise ParameterError("residualize: give f_keep_hz [Hz], the fastest mode kept")
    A, B, C, D = (np.asarray(M, float) for M in (A, B, C, D))
    w = 2 * np.pi * f_keep_hz
    # balanced first (a diagonal similarity by powers of 2, exact): the machine's rows span
    # ten decades, and the unbalanced Schur form puts rounding of eps |A| on the slow modes
    # (a rigid-body mode at the origin came out at +-1e-4 1/s, on either side of the axis)
    A, (sc, _) = sla.matrix_balance(A, permute=False, separate=True)
    B, C = B / sc[:, None], C * sc[None, :]
    T, Z, k = sla.schur(A, output="real", sort=lambda re, im: np.hypot(re, im) < w)
    Bt, Ct = Z.T @ B, C @ Z
    A11, A12, A22 = T[:k, :k], T[:k, k:], T[k:, k:]
    if k < A.shape[0] and np.linalg.eigvals(A22).real.max() >= 0:
        raise ParameterError("residualize: a fast mode is not stable")
    # x2 = -A22^-1 B2 u (A21 = 0 in Schur form): x1' = A11 x1 + (B1 - A12 A22^-1 B2) u
    X = np.linalg.solve(A22, Bt[k:]) if k < A.shape[0] else np.zeros((0, B.shape[1]))
    return A11, Bt[:k] - A12 @ X, Ct[:, :k], D - Ct[:, k:] @ X


def _rank(M: NDArray, rtol: float) -> int:
    if M.size == 0:
        return 0
    s = np.linalg.svd(M, compute_uv=False)
    return int(np.sum(s > rtol * max(s[0], 1.0)))


def _zeros_tall(A, B, C, D) -> NDArray[np.complex128]:
    """Finite invariant zeros of ``[A - sI, B; C, D]`` with ``D`` of full column rank: the
    unobservable modes of ``(A - B R^-1 U1' C, U2' C)`` after ``D = U [R; 0]``."""
    m = D.shape[1]
    Q, R = np.linalg.qr(D, mode="complete")
    U1, U2 = Q[:, :m], Q[:, m:]
    At = A - B @ np.linalg.solve(R[:m], U1.T @ C)
    Ct = U2.T @ C
    n = A.shape[0]
    if Ct.shape[0] == 0:
        return np.linalg.eigvals(At)
    tol = 1e-10 * max(float(np.linalg.norm(At, 2)), float(np.linalg.norm(Ct, 2)), 1.0)
    N = sla.null_space(Ct, rcond=tol / max(float(np.linalg.norm(Ct, 2)), 1e-300))
    for _ in range(n + 1):  # largest At-invariant subspace inside ker Ct
        if N.shape[1] == 0:
            return np.zeros(0, complex)
        AN = At @ N
        Rm = AN - N @ (N.T @ AN)
        Zs = sla.null_space(Rm, rcond=1e-10) if Rm.size else np.eye(N.shape[1])
        if Zs.shape[1] == N.shape[1]:
            break
        N = N @ Zs
    return np.linalg.eigvals(N.T @ At @ N) if N.shape[1] else np.zeros(0, complex)


def check_wellposed(P, nmeas: int, ncon: int, axis_tol: float = 1e-6) -> None:
    """Raise `ParameterError` (one line) when the H-infinity assumptions A1-A4 fail for the
    generalized plant `P` (last `ncon` inputs are controls, last `nmeas` outputs
    measurements).

    Parameters
    ----------
    P : control.StateSpace
        The generalized plant (e.g. of `mixed_sensitivity_plant`): exogenous inputs, then
        controls; performance outputs, then measurements.
    nmeas : int
        Number of measurements (the last outputs of `P`).
    ncon : int
        Number of controls (the last inputs of `P`).
    axis_tol : float
        An invariant zero ``z`` counts as on the imaginary axis when ``|Re z| <= axis_tol
        max(1, |z|)`` [-].

    Raises
    ------
    ParameterError
        Naming the assumption that fails: A1 (stabilisable, detectable), A2 (rank of D12,
        D21), A3 or A4 (no invariant zero on the imaginary axis).
    """
    A, B, C, D = (np.asarray(M, float) for M in (P.A, P.B, P.C, P.D))
    n, m, p = A.shape[0], B.shape[1], C.shape[0]
    m1, p1 = m - ncon, p - nmeas
    if p1 < ncon or m1 < nmeas:
        raise ParameterError(f"H-infinity: {p1} performance outputs and {m1} exogenous inputs "
                             f"cannot carry {ncon} controls and {nmeas} measurements")
    B1, B2, C1, C2 = B[:, :m1], B[:, m1:], C[:p1], C[p1:]
    D12, D21 = D[:p1, m1:], D[p1:, :m1]
    rtol = np.sqrt(np.finfo(float).eps)
    if _rank(D12, rtol) < ncon:
        raise ParameterError("H-infinity ill-posed (A2): D12 is rank deficient, the control "
                             "effort is not penalised directly; give W2 a non-zero "
                             "feedthrough (biproper)")
    if _rank(D21, rtol) < nmeas:
        raise ParameterError("H-infinity ill-posed (A2): D21 is rank deficient, the "
                             "measurements are not all reached by the exogenous inputs")
    for lam in np.linalg.eigvals(A):
        if lam.real >= -1e-9 * max(1.0, abs(lam)):
            for X, side in ((B2, "right"), (C2, "left")):
                M = np.hstack([A - lam * np.eye(n), X]) if side == "right" \
                    else np.vstack([A - lam * np.eye(n), X])
                s = np.linalg.svd(M, compute_uv=False)[-1]
                if s <= 1e-9 * max(1.0, float(np.linalg.norm(A, 2))):
                    what = "stabilisable from the controls" if side == "right" \
                        else "detectable from the measurements"
                    raise ParameterError(f"H-infinity ill-posed (A1): the mode at "
                                         f"{lam:.4g} 1/s is not {what} (a weight with an "
                                         f"integrator or an unstable pole?)")
    for label, zeros in (("A3: [A - jwI, B2; C1, D12]", _zeros_tall(A, B2, C1, D12)),
                         ("A4: [A - jwI, B1; C2, D21]", _zeros_tall(A.T, C2.T, B1.T,
                                                                   D21.T))):
        near = [z for z in zeros if abs(z.real) <= axis_tol * max(1.0, abs(z))]
        if near:
            raise ParameterError(f"H-infinity ill-posed ({label} loses rank on the "
                                 f"imaginary axis at s = {near[0]:.4g}); a pole or zero of "
                                 "the plant or a weight lies on the axis: shift it")


def _tf_weight(num, den):
    return control.tf(num, den)


def mixed_sensitivity_plant(G, bandwidth_hz, *, M: float = 2.0, A_low: float = 1e-3,
                            u_bandwidth_hz: float = 20.0, u_scale: float = 1.0,
                            y_scale=Y_SCALE):
    """``(P, W1, W2, Gs)``: the S / KS generalized plant of the output-scaled plant ``Gs``
    (python-control ``augw``) and its weights.

    Parameters
    ----------
    G : control.StateSpace
        The plant, controls (servo torques [N m]) to measured outputs (ratio, slip [-]).
    bandwidth_hz : sequence of float
        Performance bandwidth ``w_b / (2 pi)`` of W1 for each output [Hz].
    M : float
        High-frequency gain bound of the sensitivity in W1 (its peak allowed) [-].
    A_low : float
        Low-frequency gain of the sensitivity in W1 (the steady error allowed) [-].
    u_bandwidth_hz : float
        Corner ``w_bc / (2 pi)`` of the control-effort weight W2 [Hz].
    u_scale : float
        Servo torque regarded as large [N m] (W2 is divided by it).
    y_scale : sequence of float
        Size of a unit error of each output [-] (default `Y_SCALE`); ``Gs`` has its
        outputs divided by these.

    Returns
    -------
    P : control.StateSpace
        The generalized plant ``augw(Gs, W1, W2)``: inputs the exogenous signals ``w`` (one
        per output), then the controls ``u``; outputs the weighted error ``W1 (w - Gs u)``,
        the weighted effort ``W2 u``, then the error ``w - Gs u`` (closing ``u = K (w - Gs
        u)`` gives ``W1 S`` and ``W2 K S``).
    W1 : control.TransferFunction
        Diagonal performance weight ``(s / M + w_b) / (s + A_low w_b)``, one per output.
    W2 : control.TransferFunction
        Diagonal effort weight ``(s + w_bc / 1e3) / (1e-3 s + w_bc) / u_scale``, one per
        control.
    Gs : control.StateSpace
        The output-scaled plant.
    """
    Sy = np.diag(1.0 / np.asarray(y_scale, float))
    Gs = control.ss(G.A, G.B, Sy @ G.C, Sy @ G.D)
    wb = 2 * np.pi * np.asarray(bandwidth_hz, float)
    W1 = control.append(*[_tf_weight([1 / M, w], [1, w * A_low]) for w in wb])
    wbc = 2 * np.pi * u_bandwidth_hz
    w2 = _tf_weight([1, wbc / 1e3], [1e-3, wbc])
    W2 = control.append(*[w2 * (1.0 / u_scale) for _ in range(G.ninputs)])
    with warnings.catch_warnings():  # augw uses the deprecated connect()
        warnings.simplefilter("ignore")
        P = control.augw(Gs, control.ss(W1), control.ss(W2))
    return P, W1, W2, Gs


def design_hinf(family: PlantFamily, bandwidth_hz=(0.1, 0.05), *, slip: str = "nu",
                nominal: tuple[int, ...] | None = None, f_keep_hz: float = 100.0,
                u_scale: float = 1.0, f_keep: float | None = None) -> Controller:
    """H-infinity S / KS mixed-sensitivity controller on the family's nominal plant, checked
    against the whole family (`robustness_map`).

    Parameters
    ----------
    family : PlantFamily
    bandwidth_hz : (ratio, slip)
        Performance bandwidths of W1 [Hz] (default: the shipped design's).
    slip : measured slip signal (see `empact.control.pi.design_pi`)
    nominal : grid index of the nominal plant (default: the well-posed point nearest the
        grid's middle; a given point that is ill-posed is an error)
    f_keep_hz : float
        Modes faster than this [Hz] are residualised before the synthesis.
    u_scale : float
        Servo torque regarded as large [N m] (scales W2).
    f_keep : float, optional
        Deprecated name of `f_keep_hz`.

    Returns
    -------
    Controller
        Continuous, measured ``(r_g, slip)`` errors -> ``(T_mp, T_ms)`` [N m]; ``design``
        holds ``gamma`` (the achieved S/KS norm) and the robustness over the family.

    Examples
    --------
    >>> import empact
    >>> family = empact.plant_family(empact.load_params(), r_g=[0.5, 1.0, 2.0],
    ...                              tau=[0.85, 0.95])
    >>> k = empact.design_hinf(family, bandwidth_hz=(0.1, 0.05))
    >>> bool((empact.robustness_map(family, k).max_real_pole < 0).all())
    True
    """
    if f_keep is not None:
        warn_renamed("design_hinf(f_keep=)", "f_keep_hz [Hz]")
        f_keep_hz = f_keep
    if not np.all(family.ok):
        raise ParameterError("the family has points that did not trim")
    f_keep_hz = check_number("f_keep_hz", f_keep_hz, 1.0, 1e4, unit="Hz")
    if nominal is None:  # the well-posed point nearest the grid's middle
        middle = np.array([s // 2 for s in family.shape])
        order = sorted(np.ndindex(family.shape),
                       key=lambda i: (np.abs(np.array(i) - middle).sum(), i))
        for idx in order:
            try:
                return design_hinf(family, bandwidth_hz, slip=slip, nominal=idx,
                                   f_keep_hz=f_keep_hz, u_scale=u_scale)
            except ParameterError as exc:
                if "ill-posed" not in str(exc):
                    raise
        raise ParameterError("H-infinity: no grid point of the family gives a well-posed "
                             "problem with these weights")
    nominal = tuple(nominal)
    measured, outputs = ("r_g", slip), ("T_mp", "T_ms")
    ii = [family.inputs.index(n) for n in outputs]
    A0, B0 = family.A[nominal], family.B[nominal][:, ii]
    C0 = measured_rows(family, measured)[nominal]
    Ar, Br, Cr, Dr = residualize(A0, B0, C0, np.zeros((2, 2)), f_keep_hz)
    G = control.ss(Ar, Br, Cr, Dr)
    P, W1, W2, Gs = mixed_sensitivity_plant(G, bandwidth_hz, u_scale=u_scale)
    try:
        check_wellposed(P, 2, 2)
    except ParameterError as exc:
        at = ", ".join(f"{k} = {family.operating[k][nominal]:.4g}" for k in family.axes)
        raise ParameterError(f"nominal point {nominal} ({at}): {exc}") from None
    n, m, p = P.A.shape[0], P.B.shape[1], P.C.shape[0]
    try:
        gam = slycot.sb10ad(n, m, p, 2, 2, 1e3, P.A, P.B, P.C, P.D, job=1)[0]
        out = slycot.sb10ad(n, m, p, 2, 2, 1.1 * gam, P.A, P.B, P.C, P.D, job=4)
    except Exception as exc:  # noqa: BLE001 - slycot raises its own error types
        raise ParameterError(f"H-infinity synthesis failed: {str(exc).splitlines()[0]}") \
            from None
    _, Ak, Bk, Ck, Dk = out[:5]
    # the controller works on the scaled errors: undo the output scaling
    Sy = np.diag(1.0 / np.asarray(Y_SCALE, float))
    ctrl = Controller(Ak, Bk @ Sy, Ck, Dk @ Sy, measured, outputs, 0.0, "hinf")
    rm = robustness_map(family, ctrl)
    worst = rm.worst()
    gm, pm = disk_gain_phase(worst["disk_margin"])
    design = {"gamma_opt": float(gam), "gamma": float(1.1 * gam), "n_states": int(Ak.shape[0]),
              "bandwidth_hz": list(map(float, bandwidth_hz)), "f_keep_hz": f_keep_hz,
              "reduced_order": int(Ar.shape[0]), "plant_order": int(A0.shape[0]),
              "weights": {"W1": "(s/2 + w_b) / (s + 1e-3 w_b)", "W2": "(s + w_bc/1e3) / "
                          "(1e-3 s + w_bc) / u_scale", "w_bc_hz": 20.0, "u_scale": u_scale,
                          "y_scale": list(Y_SCALE)},
              "worst": worst, "nominal": {k: float(v[nominal])
                                          for k, v in family.operating.items()},
              "family_axes": {k: v.tolist() for k, v in family.axes.items()},
              "family_fixed": dict(family.fixed), "slip": slip}
    return Controller(ctrl.A, ctrl.B, ctrl.C, ctrl.D, measured, outputs, 0.0, "hinf", design)
