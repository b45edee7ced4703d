"""H-infinity design of the 2x2 ratio and slip controller: on the loop that runs (the
shipped ``hinf.json``), and on the continuous plant with the checks python-control does not
make.

**On the loop that runs** (``design_hinf(..., loop=, params=)``; ``empact control design
--method hinf``; issue 33).  A multi-model, fixed-structure design in the spirit of MATLAB's
``hinfstruct`` / ``systune``: a structured controller of fixed order is tuned to minimise the
worst weighted H-infinity norm over *every* plant of a family, each plant being the augmented
sampled loop `empact.control.loop.family_loops` builds (the machine held and sampled at the
loop's rate, with the law's sample delay, counting window, clamping feedforward and its
scheduled gain, decoupler and its filter, holding torques), the norm evaluated in the z-domain
on a frequency grid up to the Nyquist frequency.

*Why multi-model and not a full-order design at a nominal point with an uncertainty weight:*
on the loop that runs the ratio loop's gain at its crossover varies 37-fold and the slip
loop's 85-fold over the design family (`DESIGN_GRID`); a multiplicative uncertainty weight
covering that spread exceeds 1 at the crossover, where no controller can meet it, and a
full-order controller of the 43-state augmented loop would be as large as the loop.  The
structure below keeps the controller at 8 states, each plant of the family is in the
objective as it is, and the design's figures are the loop's own.

Structure (`STRUCTURE`: 16 parameters ``theta``, 14 of them free)::

    u = K(s) diag(g(sigma)) e,   K(s) = diag(R_j(s) Lambda_j(s)) (K_p + K_i / s)
    R_j(s) = w_f,j^2 / (s^2 + 2 zeta_j w_f,j s + w_f,j^2)       second-order roll-off
    Lambda_j(s) = (s / w_z,j + 1) / (s / w_p,j + 1)              lead-lag

``e`` the ratio and slip errors, ``K_p``, ``K_i`` 2x2 matrices (the multivariable part: the
ratio servo acts on both errors; the clamping servo on the slip error alone, ``K_21 = 0``,
`FIXED`: in a servo-limited shift the ratio error leaves the small-signal range, and a
clamping servo acting on it unclamps the belt), ``g(sigma)`` the gain schedule over the
family's axes
(`empact.control.controller.Schedule`): at each grid point the inverse of the loop's own
diagonal gain at the bandwidth, ``g_j = sign_j / |G_jj(e^(j w_b,j dt))|``, ``G`` the augmented
plant of the loop that runs (not the bare plant's); the law discretises ``K`` by Tustin at
its rate, so its response on the loop is ``K`` at the warped frequency ``(2 / dt) j tan(w dt /
2)``, exactly.

Objective (minimised over ``theta``)::

    gamma = max_plants max_w  sbar([W1 Sy S Sy^-1; W2 K S Sy^-1; W3 Sy T Sy^-1])

with ``S = (I + G K)^-1`` and ``T = I - S`` at the errors of the sampled loop (``z = e^(j w
dt)``, ``G`` the augmented plant with the schedule), ``Sy = diag(1 / Y_SCALE)`` (a unit error is
0.01 of ratio, 0.001 of slip) and the weights (`LOOP_WEIGHTS`)::

    W1_j = (s / 2 + w_b,j) / (s + 1e-3 w_b,j)            bandwidth w_b,j, |S| <= 2 gamma above
    W2_j = (s + w_u / 1e3) / (1e-3 s + w_u) / U_j        effort against the servo's limit U_j,
                                                          rising above w_u (5 Hz)
    W3   = (s + w_t / 2) / (0.01 s + w_t)                roll-off: |T| falls 20 dB/decade
                                                          above w_t (2 Hz)

subject to closed-loop stability of every plant (the loop model's eigenvalues, ``|z| < 1``)
and a multiloop disk margin of at least ``alpha_min`` at every plant at both places the
loop breaks (``mu(S - I/2) <= 1 / alpha_min`` at the errors and at the servo torques, what
``empact control check`` reports).  The search is BFGS with a weak Wolfe line search for
nonsmooth functions (Lewis & Overton, *Nonsmooth optimization via quasi-Newton methods*, Math.
Programming 141, 2013; the method of HIFOO, Burke, Henrion, Lewis & Overton, 2006) on ``gamma +
10 max(0, alpha_min mu_max - 1)`` with the exact (sub)gradient of the peak; an unstable plant
or a parameter outside its box is an infinite value the line search backs away from.  It
starts from the scheduled unit PI (``K_p = I``, ``K_i = w_b / 4``, roll-off at ``5 w_b``) and
is deterministic.  The grid is `empact.control.loop.default_omega` refined 4 times (1197
points from 0.01 Hz to 0.98 of the Nyquist frequency; it holds ``control check``'s 300), and
the design record states the figures on a grid 16 times as fine.

**On the continuous plant** (``design_hinf(family)`` without a loop): the S / KS
mixed-sensitivity controller of the family's nominal plant (full order, slycot), checked
against the whole family by `robustness_map`.  ``control.mixsyn`` (python-control 0.10) builds
``P = augw(G, W1, W2)`` and calls slycot's ``sb10ad`` with job 3 from gamma = 1e100, without
checking the standard assumptions; on an ill-posed problem (``D12`` rank deficient, a weight
or plant zero on the imaginary axis) it can hang (python-control issues #152 and #973) or
return a useless controller.  Here:

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

Its weights (outputs scaled by `Y_SCALE`: ratio 0.01, slip 0.001, so that 1 is a "unit error";
the one source of the scaling, used to build the plant and to undo it on the controller)::

    W1_i = (s / M + w_b,i) / (s + w_b,i A)          performance on S: bandwidth w_b, peak M
    W2   = (s + w_bc / M_u) / (eps_u s + w_bc) / u_scale   control effort, biproper
"""
from __future__ import annotations

import time
import warnings
from dataclasses import replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._deprecate import warn_renamed
from .._lazy import lazy_module
from .._validate import check_number
from ..errors import ParameterError
from ..nonlinear.model import nonlinear_model
from ..params import Params
from .controller import SCHEDULE_VARIABLES, Controller, Schedule
from .family import PlantFamily
from .law import LoopConfig, LoopLaw
from .loop import LoopModel, default_omega, family_loops, loop_specification
from .pi import check_loop_design
from .robustness import disk_gain_phase, measured_rows, robustness_map
from .tune import loop_summary

control = lazy_module("control")
slycot = lazy_module("slycot")
sla = lazy_module("scipy.linalg")

__all__ = ["check_wellposed", "residualize", "design_hinf", "mixed_sensitivity_plant",
           "Y_SCALE", "STRUCTURE", "LOOP_WEIGHTS", "structure_response",
           "structure_state_space", "loop_weights", "loop_mixed_sensitivity", "design_grid",
           "applied_gains"]

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


def design_hinf(family: PlantFamily, bandwidth_hz=(0.1, 0.2), *, slip: str = "nu",
                nominal: tuple[int, ...] | None = None, f_keep_hz: float = 100.0,
                u_scale: float = 1.0, f_keep: float | None = None,
                loop: LoopConfig | None = None, params: Params | None = None,
                alpha_min: float = 0.5, schedule: bool | None = None,
                max_iterations: int = 150) -> Controller:
    """H-infinity controller for a plant family: with `loop`, the multi-model design on the
    loop that runs (the shipped ``hinf.json``); without it, the S / KS mixed-sensitivity
    controller of the family's nominal continuous plant, checked against the whole family
    (`robustness_map`).  The module notes give both.

    Parameters
    ----------
    family : PlantFamily
        All points trimmed (with `loop`: with `LOOP_FAMILY_OUTPUTS`).
    bandwidth_hz : (ratio, slip)
        Performance bandwidths of W1 [Hz] (default: the shipped design's; with `loop` also
        where the schedule normalises each loop's gain).
    slip : str
        The measured slip signal (see `empact.control.pi.design_pi`).
    nominal : tuple of int, optional
        Grid index of the nominal plant (default: without `loop` the well-posed point nearest
        the grid's middle, a given point that is ill-posed is an error; with `loop` the
        middle, whose gain signs the schedule keeps).
    f_keep_hz : float
        Without `loop`: modes faster than this [Hz] are residualised before the synthesis.
    u_scale : float
        Without `loop`: servo torque regarded as large [N m] (scales W2).
    f_keep : float, optional
        Deprecated name of `f_keep_hz`.
    loop : LoopConfig, optional
        Design on this loop (`empact.control.loop.family_loops`: sampled, with its sensors,
        feedforwards and decoupler); needs `params`.
    params : Params, optional
        With `loop`: the parameter set (its ``[servo]`` limits scale W2).
    alpha_min : float
        With `loop`: the smallest multiloop disk margin allowed at every plant [-].
    schedule : bool, optional
        With `loop`: schedule the error gains over the family's axes (default True); False
        keeps the nominal point's gains everywhere.
    max_iterations : int
        With `loop`: the most BFGS iterations.

    Returns
    -------
    Controller
        Continuous (the loop law discretises it by Tustin), measured ``(r_g, slip)`` errors
        -> ``(T_mp, T_ms)`` [N m]; ``design`` holds ``gamma`` (the achieved norm) and the
        robustness over the family (with `loop`: every figure on the loop that runs, its
        weights, structure, optimiser and frequency grid).

    Examples
    --------
    >>> import empact
    >>> family = empact.plant_family(empact.load_params(), r_g=[0.5, 1.0, 2.0],
    ...                              tau=[0.85, 0.95])
    >>> k = empact.design_hinf(family, bandwidth_hz=(0.1, 0.05))
    >>> bool((empact.robustness_map(family, k).max_real_pole < 0).all())
    True
    """
    if loop is not None:
        return _design_hinf_loop(family, bandwidth_hz, slip, nominal, loop, params, alpha_min,
                                 schedule, max_iterations)
    if schedule:
        raise ParameterError("schedule = True needs the loop it runs in (loop=, params=)")
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


# ---------------------------------------------------------------------------------------------
# The multi-model design on the loop that runs (module notes)

#: the structured controller's parameters ``theta`` in order, and what each is (``ln_``: the
#: logarithm of a positive quantity; gains per unit of scheduled error)
STRUCTURE = {
    "kp_11": "proportional gain, ratio error -> T_mp",
    "kp_12": "proportional gain, slip error -> T_mp",
    "kp_21": "proportional gain, ratio error -> T_ms",
    "kp_22": "proportional gain, slip error -> T_ms",
    "ln_ki_11": "ln of the integral gain ratio error -> T_mp [ln(1/s)]",
    "ki_12": "integral gain, slip error -> T_mp [1/s]",
    "ki_21": "integral gain, ratio error -> T_ms [1/s]",
    "ln_ki_22": "ln of the integral gain slip error -> T_ms [ln(1/s)]",
    "ln_wf_1": "ln of the T_mp roll-off's corner w_f [ln(rad/s)]",
    "ln_wf_2": "ln of the T_ms roll-off's corner w_f [ln(rad/s)]",
    "ln_zeta_1": "ln of the T_mp roll-off's damping ratio",
    "ln_zeta_2": "ln of the T_ms roll-off's damping ratio",
    "ln_wz_1": "ln of the T_mp lead-lag's zero w_z [ln(rad/s)]",
    "ln_wz_2": "ln of the T_ms lead-lag's zero w_z [ln(rad/s)]",
    "ln_wp_1": "ln of the T_mp lead-lag's pole w_p [ln(rad/s)]",
    "ln_wp_2": "ln of the T_ms lead-lag's pole w_p [ln(rad/s)]"}
#: parameters held at these values: the clamping servo does not act on the ratio error
#: (``K_21 = 0``): in a shift the servo limits hold the ratio back and its error grows far
#: beyond the small-signal range; a clamping servo acting on it unclamps the belt (a first
#: design with ``K_21`` free: macro slip, peak slip error 9.4 pp, in ``shift-low-od``)
FIXED = {"kp_21": 0.0, "ki_21": 0.0}
_FREE = np.array([k not in FIXED for k in STRUCTURE])
_TWO_PI = 2 * np.pi
#: the box the parameters stay in (a point outside is an infinite objective)
_LO = np.array([-1e3] * 4 + [np.log(_TWO_PI * 1e-4), -1e3, -1e3, np.log(_TWO_PI * 1e-4)]
               + [np.log(_TWO_PI * 0.05)] * 2 + [np.log(0.1)] * 2
               + [np.log(_TWO_PI * 1e-3)] * 4)
_HI = np.array([1e3] * 4 + [np.log(_TWO_PI * 50), 1e3, 1e3, np.log(_TWO_PI * 50)]
               + [np.log(_TWO_PI * 100)] * 2 + [np.log(5.0)] * 2
               + [np.log(_TWO_PI * 100)] * 4)
#: the weights of the objective on the loop (module notes), besides the bandwidths:
#: ``W1``'s peak and low-frequency gain, ``W2``'s corner [Hz] (the servo torque limits of
#: ``[servo]`` scale it), ``W3``'s corner [Hz], peak and high-frequency gain
LOOP_WEIGHTS = {"s_peak": 2.0, "s_low": 1e-3, "effort_hz": 5.0, "effort_low": 1e-3,
                "rolloff_hz": 2.0, "t_peak": 2.0, "t_high": 1e-2}
#: the exact-penalty weight on the disk-margin constraint, the margin the search requires
#: above ``alpha_min`` (so that the check's own rounding cannot take it below), the grid's
#: refinement of `default_omega` and the verification grid's
PENALTY, ALPHA_RESERVE, GRID_REFINE, CHECK_REFINE = 10.0, 1e-4, 4, 16
#: the most rounds of the search: the first on the design's grid, each further one with the
#: fine grid's peaks added (where the fine grid's margin is below ``alpha_min`` or its norm
#: above the design grid's by more than `FINE_TOLERANCE`), a quarter of the iterations
REFINE_ROUNDS, FINE_TOLERANCE = 4, 1e-3
#: the start: the integral corner and the roll-off corner as multiples of the bandwidth
START_INTEGRAL, START_ROLLOFF = 0.25, 5.0
_I2 = np.eye(2)


def _unpack(theta: NDArray) -> tuple[NDArray, ...]:
    """``K_p``, ``K_i``, ``w_f``, ``zeta``, ``w_z``, ``w_p`` of ``theta`` (`STRUCTURE`)."""
    th = np.asarray(theta, float)
    Kp = th[:4].reshape(2, 2)
    Ki = np.array([[np.exp(th[4]), th[5]], [th[6], np.exp(th[7])]])
    return (Kp, Ki, np.exp(th[8:10]), np.exp(th[10:12]), np.exp(th[12:14]),
            np.exp(th[14:16]))


def structure_response(theta: NDArray, s: NDArray, gradient: bool = False):
    """The structured controller ``K(s)`` (module notes, without the schedule) at complex
    frequencies `s`, and its derivatives by the parameters.

    Parameters
    ----------
    theta : array_like, shape (16,)
        The parameters (`STRUCTURE`).
    s : array_like of complex, shape (n_w,)
        Laplace variables [rad/s] (on the loop: the Tustin-warped ``(2 / dt) j tan(w dt /
        2)``).
    gradient : bool
        Also return the derivatives.

    Returns
    -------
    K : ndarray of complex, shape (n_w, 2, 2)
        Servo torques (``T_mp``, ``T_ms``) per unit of scheduled error (ratio, slip).
    dK : ndarray of complex, shape (16, n_w, 2, 2)
        ``dK / dtheta_i`` (with `gradient`).
    """
    Kp, Ki, wf, zf, wz, wp = _unpack(theta)
    s = np.asarray(s, complex)
    s1 = s[:, None]
    den = s1 ** 2 + 2 * zf * wf * s1 + wf ** 2
    R = wf ** 2 / den
    lam = (s1 / wz + 1) / (s1 / wp + 1)
    f = R * lam  # (n_w, 2): each servo's filter
    P = Kp[None] + Ki[None] / s[:, None, None]
    K = f[:, :, None] * P
    if not gradient:
        return K
    dK = np.zeros((16,) + K.shape, complex)
    for j in range(2):
        for k in range(2):
            dK[2 * j + k, :, j, k] = f[:, j]
    dK[4, :, 0, 0] = f[:, 0] / s * Ki[0, 0]
    dK[5, :, 0, 1] = f[:, 0] / s
    dK[6, :, 1, 0] = f[:, 1] / s
    dK[7, :, 1, 1] = f[:, 1] / s * Ki[1, 1]
    for j in range(2):
        # dR/dln w_f = R 2 s (s + zeta w_f) / den, dR/dln zeta = -R 2 zeta w_f s / den
        dR_w = R[:, j] * 2 * s * (s + zf[j] * wf[j]) / den[:, j]
        dR_z = -R[:, j] * 2 * zf[j] * wf[j] * s / den[:, j]
        dL_z = -(s / wz[j]) / (s / wp[j] + 1)
        dL_p = lam[:, j] * (s / wp[j]) / (s / wp[j] + 1)
        for i, df in ((8 + j, dR_w * lam[:, j]), (10 + j, dR_z * lam[:, j]),
                      (12 + j, R[:, j] * dL_z), (14 + j, R[:, j] * dL_p)):
            dK[i, :, j, :] = df[:, None] * P[:, j, :]
    return K, dK


def structure_state_space(theta: NDArray) -> tuple[NDArray, NDArray, NDArray, NDArray]:
    """The structured controller (module notes) as a continuous state space: the two
    integrators of the errors, then per servo the lead-lag's state and the roll-off's two.

    Parameters
    ----------
    theta : array_like, shape (16,)
        The parameters (`STRUCTURE`).

    Returns
    -------
    A, B, C, D : ndarray
        Shapes (8, 8), (8, 2), (2, 8), (2, 2): scheduled errors (ratio, slip) to servo
        torques (``T_mp``, ``T_ms``) [N m]; ``D = 0`` (the roll-off makes it strictly
        proper).
    """
    Kp, Ki, wf, zf, wz, wp = _unpack(theta)
    A, B = np.zeros((8, 8)), np.zeros((8, 2))
    C, D = np.zeros((2, 8)), np.zeros((2, 2))
    B[:2] = np.eye(2)  # x_I' = e; v = K_p e + K_i x_I
    for j in range(2):
        il, r1, r2 = 2 + 3 * j, 3 + 3 * j, 4 + 3 * j
        # lead-lag: x_l' = w_p (v_j - x_l), its output (w_p / w_z) v_j + (1 - w_p / w_z) x_l
        A[il, :2], B[il], A[il, il] = wp[j] * Ki[j], wp[j] * Kp[j], -wp[j]
        c = wp[j] / wz[j]
        # roll-off: x_r1' = x_r2, x_r2' = w_f^2 (out - x_r1) - 2 zeta w_f x_r2; u_j = x_r1
        A[r1, r2] = 1.0
        A[r2, r1], A[r2, r2] = -wf[j] ** 2, -2 * zf[j] * wf[j]
        A[r2, :2] += wf[j] ** 2 * c * Ki[j]
        B[r2] += wf[j] ** 2 * c * Kp[j]
        A[r2, il] += wf[j] ** 2 * (1 - c)
        C[j, r1] = 1.0
    return A, B, C, D


def _parts(M: NDArray) -> tuple[NDArray, NDArray, NDArray, NDArray]:
    """The entries ``(m11, m12, m21, m22)`` of a stack of 2 x 2 matrices (..., 2, 2)."""
    return M[..., 0, 0], M[..., 0, 1], M[..., 1, 0], M[..., 1, 1]


def _mul(X, Y):
    """The product of two stacks of 2 x 2 matrices given by their entries (`_parts`): entry by
    entry, far faster than ``@`` on millions of 2 x 2 matrices."""
    a, b, c, d = X
    e, f, g, h = Y
    return a * e + b * g, a * f + b * h, c * e + d * g, c * f + d * h


def _inv_one_plus(X):
    """``(I + X)^-1`` of a stack of 2 x 2 matrices given by their entries."""
    a, b, c, d = X
    a, d = a + 1, d + 1
    det = a * d - b * c
    return d / det, -b / det, -c / det, a / det


def _peaks(Gp, Kp, E: NDArray, W, terms: bool = False) -> dict[str, Any]:
    """The mixed-sensitivity peaks of the design on the loop (module notes) from the entries
    (`_parts`) of the plants' responses ``G`` (n_plants, n_w) and the controller's ``K``
    (n_w,), the unit-error scaling ``E`` (n_plants, 2) and the weights' magnitudes ``W1``,
    ``W2``, ``W3`` (n_w, 2): ``gamma``, ``mu`` at the errors and at the servo torques, the
    sensitivities' entries and (`terms`) each term's largest singular value (n_plants,
    n_w)."""
    S = _inv_one_plus(_mul(Gp, Kp))
    Si = _inv_one_plus(_mul(Kp, Gp))
    e0, e1 = E[:, :1], E[:, 1:]
    Su = (S[0], S[1] * e0 / e1, S[2] * e1 / e0, S[3])  # E S E^-1
    KS = _mul(Kp, S)
    X = (KS[0] / e0, KS[1] / e1, KS[2] / e0, KS[3] / e1)  # K S E^-1
    T = (1 - Su[0], -Su[1], -Su[2], 1 - Su[3])
    out: dict[str, Any] = {}
    h00 = h11 = h01 = 0.0
    for name, (w, M) in zip(("W1 S", "W2 K S", "W3 T"), zip(W, (Su, X, T))):
        w0, w1 = w[:, 0] ** 2, w[:, 1] ** 2  # row weights, squared
        a00 = w0 * np.abs(M[0]) ** 2 + w1 * np.abs(M[2]) ** 2
        a11 = w0 * np.abs(M[1]) ** 2 + w1 * np.abs(M[3]) ** 2
        a01 = w0 * np.conj(M[0]) * M[1] + w1 * np.conj(M[2]) * M[3]
        if terms:
            out[name] = np.sqrt(0.5 * (a00 + a11 + np.sqrt((a00 - a11) ** 2
                                                           + 4 * np.abs(a01) ** 2)))
        h00, h11, h01 = h00 + a00, h11 + a11, h01 + a01
    gam = np.sqrt(0.5 * (h00 + h11 + np.sqrt((h00 - h11) ** 2 + 4 * np.abs(h01) ** 2)))
    return {"gamma": gam, "mu_output": _mu_parts(S[0] - 0.5, S[1], S[2], S[3] - 0.5),
            "mu_input": _mu_parts(Si[0] - 0.5, Si[1], Si[2], Si[3] - 0.5),
            "S": S, "Si": Si, "terms": out}


def _mu_parts(a11, a12, a21, a22) -> NDArray[np.float64]:
    """`_mu` of 2 x 2 matrices given by their entries."""
    f = np.abs(a11) ** 2 + np.abs(a22) ** 2 + 2 * np.abs(a12) * np.abs(a21)
    q = np.abs(a11 * a22 - a12 * a21) ** 2
    return np.sqrt(0.5 * (f + np.sqrt(np.maximum(f * f - 4 * q, 0.0))))


def _at(X, p: int, k: int) -> NDArray:
    """The 2 x 2 matrix at plant `p`, frequency `k` of a stack given by its entries."""
    return np.array([[X[0][p, k], X[1][p, k]], [X[2][p, k], X[3][p, k]]])


def _sbar_vectors(M: NDArray) -> tuple[NDArray, NDArray, NDArray]:
    """Largest singular values of a stack (..., m, 2) and their left and right vectors."""
    U, s, Vh = np.linalg.svd(M, full_matrices=False)
    return s[..., 0], U[..., :, 0], np.conj(Vh[..., 0, :])


def _mu(M: NDArray, gradient: bool = False):
    """``mu`` of 2 x 2 matrices for two complex scalar blocks, ``inf_d sbar(D M D^-1)``, in
    closed form: the largest singular value grows with the Frobenius norm at a fixed
    determinant, and ``|m12|^2 d^2 + |m21|^2 / d^2`` is least at ``d^2 = |m21| / |m12|``, so
    ``mu^2 = (f + sqrt(f^2 - 4 |det|^2)) / 2`` with ``f = |m11|^2 + |m22|^2 + 2 |m12| |m21|``
    (the golden section of `empact.control.robustness` converges to it).  With `gradient`,
    also ``C`` with ``d mu = Re(sum C_ij dM_ij)``."""
    a11, a12, a21, a22 = _parts(M)
    A12, A21 = np.abs(a12), np.abs(a21)
    f = np.abs(a11) ** 2 + np.abs(a22) ** 2 + 2 * A12 * A21
    det = a11 * a22 - a12 * a21
    root = np.sqrt(np.maximum(f * f - 4 * np.abs(det) ** 2, 0.0))
    mu = np.sqrt(0.5 * (f + root))
    if not gradient:
        return mu
    tiny = np.finfo(float).tiny
    Cf = np.zeros(M.shape, complex)
    Cf[..., 0, 0], Cf[..., 1, 1] = 2 * np.conj(a11), 2 * np.conj(a22)
    Cf[..., 0, 1] = 2 * A21 * np.conj(a12) / np.maximum(A12, tiny)
    Cf[..., 1, 0] = 2 * A12 * np.conj(a21) / np.maximum(A21, tiny)
    Cq = 2 * np.conj(det)[..., None, None] * np.stack([np.stack([a22, -a21], -1),
                                                       np.stack([-a12, a11], -1)], -2)
    r = np.maximum(root, tiny)[..., None, None]
    dmu2 = 0.5 * (Cf + (f[..., None, None] * Cf - 2 * Cq) / r)
    return mu, dmu2 / (2 * mu[..., None, None])


def loop_weights(omega: NDArray, bandwidth_hz, servo_limits) -> tuple[NDArray, ...]:
    """The magnitudes of the weights ``W1``, ``W2``, ``W3`` of the design on the loop (module
    notes, `LOOP_WEIGHTS`) at `omega`, each per loop (ratio, slip).

    Parameters
    ----------
    omega : array_like, shape (n_w,)
        Frequencies [rad/s] (the weights are taken at ``s = j omega``).
    bandwidth_hz : (ratio, slip)
        ``W1``'s bandwidths [Hz].
    servo_limits : (T_mp_max, T_ms_max)
        The servo torques ``W2`` divides by [N m].

    Returns
    -------
    W1, W2, W3 : ndarray, shape (n_w, 2)
        ``|W1|`` [-], ``|W2|`` [1/(N m)], ``|W3|`` [-].
    """
    s = 1j * np.asarray(omega, float)[:, None]
    lw = LOOP_WEIGHTS
    wb = _TWO_PI * np.asarray(bandwidth_hz, float)
    wu, wt = _TWO_PI * lw["effort_hz"], _TWO_PI * lw["rolloff_hz"]
    W1 = (s / lw["s_peak"] + wb) / (s + lw["s_low"] * wb)
    W2 = (s + lw["effort_low"] * wu) / (lw["effort_low"] * s + wu) / np.asarray(servo_limits,
                                                                                 float)
    W3 = (s + wt / lw["t_peak"]) / (lw["t_high"] * s + wt) * np.ones(2)
    return np.abs(W1), np.abs(W2), np.abs(W3)


class _LoopProblem:
    """The objective of the design on the loop (module notes) over a family's loop models:
    the scheduled augmented plants' responses, the weights, the stability test."""

    def __init__(self, lm: LoopModel, gains: NDArray, omega: NDArray, bandwidth_hz,
                 servo_limits, alpha_min: float):
        self.shape = lm.shape
        g = gains.reshape(-1, 2)
        # the schedule acts on the errors: the loop model without it, its errors times the
        # gains the law applies (`applied_gains`), is `family_loops` of the scheduled
        # controller (tested)
        self.lm = replace(lm, Ce=lm.Ce * gains[..., :, None], Dew=lm.Dew * gains[..., :, None],
                          Der=lm.Der * gains[..., :, None], _cache={})
        self.dt = lm.dt
        self.bandwidth_hz, self.servo_limits = bandwidth_hz, servo_limits
        self.omega = np.zeros(0)
        self.s = np.zeros(0, complex)
        self.G = np.zeros((g.shape[0], 0, 2, 2), complex)
        self.W = tuple(np.zeros((0, 2)) for _ in range(3))
        self.extend(omega)
        # unit errors (Y_SCALE) per scheduled error: e_unit = E e_scheduled
        self.E = 1.0 / (np.asarray(Y_SCALE) * np.abs(g))
        self.alpha = alpha_min + ALPHA_RESERVE
        self.evaluations = 0

    def extend(self, omega: NDArray) -> None:
        """Add frequencies [rad/s] to the grid (the peaks' order does not matter)."""
        w = np.asarray(omega, float)
        G = self.lm.plant_response(w).reshape((-1, len(w), 2, 2))
        self.omega = np.concatenate([self.omega, w])
        self.s = np.concatenate([self.s, 2j / self.dt * np.tan(w * self.dt / 2)])  # Tustin
        self.G = np.concatenate([self.G, G], axis=1)
        self.Gp = _parts(self.G)
        self.W = tuple(np.concatenate([a, b]) for a, b in zip(
            self.W, loop_weights(w, self.bandwidth_hz, self.servo_limits)))

    def controller(self, theta: NDArray, measured, outputs) -> Controller:
        A, B, C, D = structure_state_space(theta)
        return Controller(A, B, C, D, measured, outputs, 0.0, "hinf")

    def spectral_radius(self, theta: NDArray) -> NDArray[np.float64]:
        return self.lm.with_controller(self.controller(theta, ("r_g", "nu"),
                                                       ("T_mp", "T_ms"))).spectral_radius()

    def peaks(self, theta: NDArray, K: NDArray | None = None) -> dict[str, NDArray]:
        """``gamma`` at every plant and frequency, its three terms, ``mu`` at the errors and
        at the servo torques (shapes (n_plants, n_w))."""
        K = structure_response(theta, self.s) if K is None else K
        return _peaks(self.Gp, _parts(K), self.E, self.W)

    def __call__(self, theta: NDArray) -> tuple[float, NDArray | None, dict[str, Any]]:
        """The penalised objective, its (sub)gradient and what it is made of; an unstable
        plant or a parameter outside the box: ``inf``."""
        self.evaluations += 1
        if np.any(theta < _LO) or np.any(theta > _HI):
            return np.inf, None, {}
        rho = self.spectral_radius(theta)
        if np.any(rho >= 1):
            return np.inf, None, {}
        K, dK = structure_response(theta, self.s, gradient=True)
        pk = self.peaks(theta, K)
        gam, mu = pk["gamma"], np.maximum(pk["mu_output"], pk["mu_input"])
        p, k = (int(i) for i in np.unravel_index(int(np.argmax(gam)), gam.shape))
        q, m = (int(i) for i in np.unravel_index(int(np.argmax(mu)), mu.shape))
        excess = self.alpha * mu[q, m] - 1.0
        value = float(gam[p, k] + PENALTY * max(0.0, excess))
        info = {"gamma": float(gam[p, k]), "disk_margin": float(1 / mu[q, m]),
                "spectral_radius": float(rho.max())}
        # d sbar = Re(u^H dM v), dS = -S G dK S, d(K S) = S_i dK S, dT = -dS
        W1, W2, W3 = (w[k] for w in self.W)
        E, S, Si, G = self.E[p], _at(pk["S"], p, k), _at(pk["Si"], p, k), self.G[p, k]
        M = np.concatenate([W1[:, None] * E[:, None] * S / E[None, :],
                            W2[:, None] * (K[k] @ S) / E[None, :],
                            W3[:, None] * (_I2 - E[:, None] * S / E[None, :])])
        _, u, v = _sbar_vectors(M)
        b = S @ (v / E)
        a = ((-np.conj(u[:2]) * W1 * E + np.conj(u[4:]) * W3 * E) @ S @ G
             + (np.conj(u[2:4]) * W2) @ Si)
        grad = np.real(np.einsum("j,tjk,k->t", a, dK[:, k], b))
        if excess > 0:
            S, Si, G = _at(pk["S"], q, m), _at(pk["Si"], q, m), self.G[q, m]
            if pk["mu_output"][q, m] >= pk["mu_input"][q, m]:
                X = S @ _mu(S - _I2 / 2, True)[1].T @ (-S @ G)
            else:
                X = -G @ Si @ _mu(Si - _I2 / 2, True)[1].T @ Si
            grad += PENALTY * self.alpha * np.real(np.einsum("kj,tjk->t", X, dK[:, m]))
        return value, grad * _FREE, info


def _bfgs(fun, x0: NDArray, max_iterations: int, feasible) -> dict[str, Any]:
    """BFGS with a weak Wolfe line search (bisection and doubling; Lewis & Overton 2013) for a
    nonsmooth `fun` returning ``(value, gradient, info)``, ``inf`` where it is not defined.
    Stops after `max_iterations`, when the line search finds no step, or when 20 iterations
    gain less than 1e-4 of the value.  Returns the best iterate for which ``feasible(info)``
    holds (the start must be one)."""
    x = np.array(x0, float)
    f, g, info = fun(x)
    if not np.isfinite(f):
        raise ParameterError("H-infinity on the loop: the starting controller does not "
                             "stabilise every plant of the family; lower the bandwidths or "
                             "narrow the family")
    n = x.size
    H = np.eye(n)
    best = (f, x, info) if feasible(info) else (np.inf, x, info)
    history, message, restarted = [f], "iteration limit reached", False
    for _ in range(max_iterations):
        d = -H @ g
        if g @ d >= 0:  # not a descent direction: restart from the gradient
            H, d = np.eye(n), -g
        lo, hi, t, gd, found = 0.0, np.inf, 1.0, g @ d, False
        armijo = None  # the last step with sufficient decrease
        for _ in range(50):
            xn = x + t * d
            fn, gn, infon = fun(xn)
            if not fn <= f + 1e-4 * t * gd:  # sufficient decrease fails (inf included)
                hi = t
            else:
                armijo = (xn, fn, gn, infon)
                if gn @ d < 0.9 * gd:  # weak Wolfe curvature fails
                    lo = t
                else:
                    found = True
                    break
            t = 0.5 * (lo + hi) if np.isfinite(hi) else 2.0 * lo
        if not found:
            if armijo is None:  # no decrease along d: at a nonsmooth stationary point
                if restarted:
                    message = "no step found (a nonsmooth stationary point)"
                    break
                H, restarted = np.eye(n), True
                continue
            # the curvature condition cannot be bracketed at a kink: take the decrease
            xn, fn, gn, infon = armijo
        restarted = False
        sk, yk = xn - x, gn - g
        if sk @ yk > 0:
            r = 1.0 / (sk @ yk)
            V = np.eye(n) - r * np.outer(sk, yk)
            H = V @ H @ V.T + r * np.outer(sk, sk)
        x, f, g, info = xn, fn, gn, infon
        history.append(f)
        if feasible(info) and f < best[0]:
            best = (f, x, info)
        if len(history) > 20 and history[-21] - f < 1e-4 * abs(f):
            message = "converged (less than 1e-4 of the value in 20 iterations)"
            break
    return {"x": best[1], "value": best[0], "info": best[2], "history": np.array(history),
            "iterations": len(history) - 1, "message": message}


def design_grid(dt: float, refine: int = GRID_REFINE) -> NDArray[np.float64]:
    """`default_omega` refined `refine` times: ``299 refine + 1`` frequencies [rad/s],
    log-spaced from 0.01 Hz to ``0.49 / dt`` [Hz], holding `default_omega`'s 300 (every
    `refine`-th point).

    Parameters
    ----------
    dt : float
        Sample period [s].
    refine : int
        The refinement (1: `default_omega` itself).

    Returns
    -------
    ndarray, shape (299 refine + 1,)
        ``2 pi f`` [rad/s].
    """
    return 2 * np.pi * np.logspace(-2, np.log10(0.49 / dt), 299 * int(refine) + 1)


def applied_gains(controller: Controller, family: PlantFamily, loop: LoopConfig,
                  params: Params, model=None) -> NDArray[np.float64]:
    """The gains a controller's schedule puts on its errors at every point of a family, where
    the law reads them (`empact.control.law.LoopLaw.at_rest`: the measured ratio, the
    set-point's torque ratio and the clamping feedforward's force, not the family's grid
    values); ones without a schedule.

    Parameters
    ----------
    controller : Controller
        Scheduled or not.
    family : PlantFamily
        Every point trimmed.
    loop : LoopConfig
        The loop it runs in.
    params : Params
        The parameter set.
    model : EmpactModel, optional
        The machine's model (default: `nonlinear_model` with the family's options).

    Returns
    -------
    ndarray, shape ``family.shape + (2,)``
        The gains on the ratio and slip errors [-, per unit of error].
    """
    n_e = len(controller.measured)
    if controller.schedule is None:
        return np.ones(family.shape + (n_e,))
    if model is None:
        model = nonlinear_model(params, **family.options)
    cfg = loop.ideal()
    out = np.empty(family.shape + (n_e,))
    for idx in np.ndindex(*family.shape):
        point = {k: float(family.operating[k][idx]) for k in ("r_g", "nu", "omega_p", "T_l",
                                                            "F_s")}
        rest = LoopLaw(controller, model, point, np.zeros(2), cfg).at_rest()
        out[idx] = controller.schedule(rest["schedule_point"])
    return out


def loop_mixed_sensitivity(lm: LoopModel, gains: NDArray, bandwidth_hz, servo_limits,
                           omega: NDArray | None = None) -> dict[str, Any]:
    """The weighted mixed-sensitivity norm of the design on the loop (module notes) of the
    controller a loop model holds, at every plant, from the loop model's own responses
    (``G`` of `LoopModel.plant_response`, ``K`` of `LoopModel.controller_response`: the
    discrete loop that runs).

    Parameters
    ----------
    lm : LoopModel
        Stacked over a family (`family_loops`), with the controller.
    gains : ndarray, shape ``lm.shape + (2,)``
        The schedule's gains at the points (`applied_gains`; ones without a schedule): the
        loop model's errors are the scheduled ones, the weights act on the measured ones.
    bandwidth_hz : (ratio, slip)
        ``W1``'s bandwidths [Hz].
    servo_limits : (T_mp_max, T_ms_max)
        ``W2``'s servo torques [N m].
    omega : ndarray, optional
        Frequencies [rad/s] (default `design_grid`, the design's grid).

    Returns
    -------
    dict
        ``gamma`` (the norm: the largest over plants and frequencies) [-], ``terms`` (the
        largest of each of ``W1 S``, ``W2 K S``, ``W3 T``) [-], ``gamma_by_point`` (shape
        ``lm.shape``), ``worst_index`` (the grid index of the largest), ``f_hz`` (its
        frequency) [Hz], ``disk_margin`` (the smallest, from ``mu`` in closed form) [-],
        ``points`` and ``frequencies`` (the grid's size).
    """
    w = design_grid(lm.dt) if omega is None else np.asarray(omega, float)
    G = lm.plant_response(w).reshape((-1, len(w), 2, 2))
    K = lm.controller_response(w) * lm.mask[None, :, None]
    E = 1.0 / (np.asarray(Y_SCALE) * np.abs(np.asarray(gains, float).reshape(-1, 2)))
    pk = _peaks(_parts(G), _parts(K), E, loop_weights(w, bandwidth_hz, servo_limits),
                terms=True)
    gam = pk["gamma"]
    p, k = np.unravel_index(int(np.argmax(gam)), gam.shape)
    mu = np.maximum(pk["mu_output"], pk["mu_input"])
    return {"gamma": float(gam[p, k]),
            "terms": {n: float(t.max()) for n, t in pk["terms"].items()},
            "gamma_by_point": gam.max(axis=1).reshape(lm.shape),
            "worst_index": [int(i) for i in np.unravel_index(int(p), lm.shape)],
            "f_hz": float(w[k] / (2 * np.pi)), "disk_margin": float(1.0 / mu.max()),
            "points": int(G.shape[0]), "frequencies": int(len(w))}


def _loop_gains(lm: LoopModel, bandwidth_hz, nominal: tuple[int, ...],
                schedule: bool) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The schedule's gains (shape ``lm.shape + (2,)``): ``sign_j / |G_jj(e^(j w_b,j dt))|``
    of the loop's own (unscheduled) augmented plant, one sign per loop (the nominal's:
    negative feedback with a phase lag of 45 deg), and the diagonal gains ``|G_jj|``."""
    wb = _TWO_PI * np.asarray(bandwidth_hz, float)
    G = lm.plant_response(wb)  # shape + (2 frequencies, 2, 2)
    gjj = np.stack([G[..., j, j, j] for j in range(2)], -1)
    sign = np.sign((gjj[nominal] * np.exp(1j * np.pi / 4)).real)
    sign = np.where(sign == 0, 1.0, sign)
    gains = sign / np.abs(gjj)
    if not schedule:
        gains = np.broadcast_to(gains[nominal], gains.shape).copy()
    return gains, np.abs(gjj)


def _design_hinf_loop(family: PlantFamily, bandwidth_hz, slip: str, nominal, loop: LoopConfig,
                      params: Params | None, alpha_min: float, schedule: bool | None,
                      max_iterations: int) -> Controller:
    """`design_hinf` on the loop that runs (module notes)."""
    t0, c0 = time.perf_counter(), time.process_time()
    params, alpha_min, bw = check_loop_design("design_hinf", family, slip, alpha_min,
                                              bandwidth_hz, params)
    if len(bw) != 2:
        raise ParameterError(f"bandwidth_hz = {bandwidth_hz}: two values RATIO,SLIP [Hz]")
    if not isinstance(max_iterations, (int, np.integer)) or not 1 <= max_iterations <= 10_000:
        raise ParameterError(f"max_iterations = {max_iterations!r}: an integer 1-10000")
    schedule = True if schedule is None else bool(schedule)
    if schedule:
        bad = [a for a in family.axes if a not in SCHEDULE_VARIABLES]
        if bad:
            raise ParameterError(f"a schedule runs over {', '.join(SCHEDULE_VARIABLES)}; the "
                                 f"family also varies {', '.join(bad)}")
    nominal = tuple(s_ // 2 for s_ in family.shape) if nominal is None else tuple(nominal)
    measured, outputs = ("r_g", slip), ("T_mp", "T_ms")
    servo = (params.servo.T_mp_max, params.servo.T_ms_max)
    model = nonlinear_model(params, **family.options)
    wb = _TWO_PI * np.array(bw)
    theta0 = np.concatenate([[1.0, 0.0, 0.0, 1.0], [np.log(START_INTEGRAL * wb[0]), 0.0, 0.0,
                             np.log(START_INTEGRAL * wb[1])], np.log(START_ROLLOFF * wb),
                             [0.0, 0.0], np.log(wb), np.log(wb)])
    for name, value in FIXED.items():
        theta0[list(STRUCTURE).index(name)] = value
    start = Controller(*structure_state_space(theta0), measured, outputs, 0.0, "hinf")
    lm0 = family_loops(family, start, loop, params, model)
    gains, gjj = _loop_gains(lm0, bw, nominal, schedule)
    sched = Schedule(axes=dict(family.axes), gains=gains) if schedule else None
    applied = (applied_gains(Controller(start.A, start.B, start.C, start.D, measured, outputs,
                                        schedule=sched), family, loop, params, model)
               if schedule else gains)
    w = design_grid(lm0.dt)
    problem = _LoopProblem(lm0, applied, w, bw, servo, alpha_min)
    dense = _LoopProblem(lm0, applied, design_grid(lm0.dt, CHECK_REFINE), bw, servo,
                         alpha_min)
    theta, rounds, history = theta0, [], []
    for r in range(REFINE_ROUNDS):
        out = _bfgs(problem, theta, int(max_iterations) if r == 0 else
                    max(1, int(max_iterations) // 4),
                    lambda info: info.get("disk_margin", 0.0) >= alpha_min)
        if not np.isfinite(out["value"]):
            if r == 0:
                raise ParameterError(f"H-infinity on the loop: no iterate kept every plant's "
                                     f"disk margin at {alpha_min:g}; lower alpha_min or the "
                                     "bandwidths")
            # the added frequencies cost the margin and no iterate regained it: the previous
            # round's controller stays (its fine-grid figures are recorded)
            rounds.append({"frequencies": int(problem.omega.size),
                           "iterations": out["iterations"],
                           "message": "no iterate kept the margin: the previous round's "
                                      "controller kept"})
            break
        theta = out["x"]
        history += out["history"].tolist()
        # the same controller on the grid 16 times as fine: a lightly damped peak between
        # the design's frequencies is added to them (each plant's local peaks beyond the
        # design's figures) and the search goes on from there
        pk = dense.peaks(theta)
        mu = np.maximum(pk["mu_output"], pk["mu_input"])
        gam = pk["gamma"]
        rounds.append({"frequencies": int(problem.omega.size), "iterations": out["iterations"],
                       "gamma": out["info"]["gamma"], "disk_margin": out["info"]["disk_margin"],
                       "gamma_fine": float(gam.max()), "disk_margin_fine": float(1 / mu.max()),
                       "message": out["message"]})
        over = (mu >= 1 / alpha_min) | (gam > (1 + FINE_TOLERANCE) * out["info"]["gamma"])
        if not over.any():
            break
        peak = np.zeros_like(over)
        peak[:, 1:-1] = ((mu[:, 1:-1] >= mu[:, :-2]) & (mu[:, 1:-1] >= mu[:, 2:])) | (
            (gam[:, 1:-1] >= gam[:, :-2]) & (gam[:, 1:-1] >= gam[:, 2:]))
        new = np.setdiff1d(dense.omega[np.unique(np.nonzero(over & peak)[1])], problem.omega)
        if new.size == 0:
            break
        problem.extend(new)
    A, B, C, D = structure_state_space(theta)
    if sched is not None:
        ctrl = Controller(A, B, C, D, measured, outputs, 0.0, "hinf", {}, sched)
    else:
        g = gains[nominal]
        ctrl = Controller(A, B * g, C, D * g, measured, outputs, 0.0, "hinf")
    # every figure below from the loop that runs, rebuilt with the designed controller
    lm1 = family_loops(family, ctrl, loop, params, model)
    axes = dict(family.axes)
    worst = loop_summary(lm1, axes)  # `control check`'s grid
    gm, pm = disk_gain_phase(worst["disk_margin"])
    ms_gains = applied if schedule else np.ones_like(gains)
    on_design = loop_mixed_sensitivity(lm1, ms_gains, bw, servo, problem.omega)
    pk = dense.peaks(theta)
    fine = {"gamma": float(pk["gamma"].max()), "frequencies": int(dense.omega.size),
            "disk_margin": float(1 / np.maximum(pk["mu_output"], pk["mu_input"]).max())}
    at_start = loop_mixed_sensitivity(problem.lm.with_controller(start), applied, bw, servo, w)
    spread = (gjj.reshape(-1, 2).max(0) / gjj.reshape(-1, 2).min(0)).tolist()
    design = {
        "synthesis": "multi-model fixed-structure H-infinity on the loop that runs "
                     "(hinfstruct / systune idea): the worst weighted mixed-sensitivity norm "
                     "over every plant of the family minimised, subject to stability and the "
                     "disk margin at every plant (empact.control.hinf, module notes)",
        "why_multi_model": "over the family the loop's diagonal gain at the bandwidths "
                           f"varies {spread[0]:.3g}-fold (ratio) and {spread[1]:.3g}-fold "
                           "(slip): an uncertainty weight covering it exceeds 1 at the "
                           "crossover, and a full-order controller would have the augmented "
                           f"loop's {lm0.Aa.shape[-1]} states; multi-model keeps every plant "
                           "as it is and the controller at 8 states",
        "loop_gain_spread": {"ratio": spread[0], "slip": spread[1]},
        "structure": "u = diag(R_j(s) Lambda_j(s)) (K_p + K_i / s) diag(g(sigma)) e; R_j = "
                     "w_f^2 / (s^2 + 2 zeta w_f s + w_f^2), Lambda_j = (s / w_z + 1) / (s / "
                     "w_p + 1); K_p, K_i 2 x 2 with K_21 = 0; g the schedule (the inverse of "
                     "the "
                     "loop's own diagonal gain at the bandwidths); Tustin at the loop's rate",
        "parameters": {k: float(v) for k, v in zip(STRUCTURE, theta)},
        "fixed": dict(FIXED),
        "fixed_why": "the clamping servo does not act on the ratio error: in a shift the "
                     "servo limits hold the ratio back and its error leaves the small-signal "
                     "range (with K_21 free: macro slip in shift-low-od)",
        "parameters_start": {k: float(v) for k, v in zip(STRUCTURE, theta0)},
        "n_states": int(A.shape[0]),
        "bandwidth_hz": list(bw), "alpha_min": alpha_min,
        "weights": {"W1": "(s / 2 + w_b) / (s + 1e-3 w_b), w_b = 2 pi bandwidth_hz per loop",
                    "W2": "(s + 1e-3 w_u) / (1e-3 s + w_u) / U, w_u = 2 pi effort_hz, U the "
                          "servo torque limit per loop",
                    "W3": "(s + w_t / 2) / (0.01 s + w_t), w_t = 2 pi rolloff_hz",
                    **LOOP_WEIGHTS, "servo_limits_nm": list(servo), "y_scale": list(Y_SCALE)},
        "objective": "gamma = max over plants and frequencies of sbar([W1 Sy S Sy^-1; W2 K S "
                     "Sy^-1; W3 Sy T Sy^-1]), S = (I + G K)^-1 at the errors of the sampled "
                     "loop (z = e^(j w dt)), T = I - S, Sy = diag(1 / y_scale); subject to "
                     "|z| < 1 and disk margin >= alpha_min at every plant; minimised: gamma + "
                     f"{PENALTY:g} max(0, (alpha_min + {ALPHA_RESERVE:g}) mu_max - 1)",
        "optimizer": "BFGS with a weak Wolfe line search for nonsmooth functions (Lewis & "
                     "Overton 2013, HIFOO), exact subgradient of the peak; deterministic",
        "iterations": sum(r["iterations"] for r in rounds),
        "evaluations": problem.evaluations,
        "message": out["message"], "rounds": rounds, "objective_history": history,
        "gamma_start": at_start["gamma"], "gamma": on_design["gamma"],
        "gamma_terms": on_design["terms"],
        "gamma_worst_point": {k: float(v[i]) for (k, v), i in zip(axes.items(),
                                                                   on_design["worst_index"])},
        "gamma_worst_f_hz": on_design["f_hz"],
        "frequency_grid": {
            "design": {"points": on_design["frequencies"], "from_hz": 0.01,
                       "to_hz": 0.49 / lm1.dt, "gamma": on_design["gamma"],
                       "disk_margin": on_design["disk_margin"]},
            "fine": {"points": fine["frequencies"], "gamma": fine["gamma"],
                     "disk_margin": fine["disk_margin"]},
            "grid_error": {"gamma": fine["gamma"] - on_design["gamma"],
                           "disk_margin": fine["disk_margin"] - on_design["disk_margin"]},
            "note": f"the design's grid is control check's ({len(default_omega(lm1.dt))} "
                    f"points) refined {GRID_REFINE} times, with the peaks the grid "
                    f"{CHECK_REFINE} times as fine finds added (rounds); the fine grid's "
                    "figures are the search's loop model's (the rebuilt loop's to 1e-5)"},
        "worst": {**{k: worst[k] for k in ("disk_margin", "spectral_radius", "all_stable",
                                           "ms", "bandwidth_hz", "worst_point")},
                  "gain_margin_db": float(gm), "phase_margin_deg": float(pm),
                  "loop": "the loop that runs (empact.control.loop.family_loops: sampled, "
                          "sensors, delay, counting window, feedforwards, decoupler), on "
                          "control check's frequency grid"},
        "nominal": {k: float(v[nominal]) for k, v in family.operating.items()},
        "family_axes": {k: v.tolist() for k, v in family.axes.items()},
        "family_fixed": dict(family.fixed), "slip": slip, "scheduled": schedule,
        "loop": loop_specification(loop),
        "wall_time_s": time.perf_counter() - t0, "cpu_time_s": time.process_time() - c0}
    return Controller(ctrl.A, ctrl.B, ctrl.C, ctrl.D, measured, outputs, 0.0, "hinf", design,
                      ctrl.schedule)
