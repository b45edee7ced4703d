"""Decentralised PI design for a plant family: the ratio loop on the primary servo, the slip
loop on the secondary servo (through the clamping force).

Each loop is ``k_p (1 + w_i / s) / (1 + s / w_f)^2``: a PI with a second-order roll-off at
``w_f = 5 w_c`` that keeps the loop from exciting the lightly damped actuation modes (9-50 Hz;
the clamping mode near 9-12 Hz rises 100 times above the slip's response at 3 Hz).  The
proportional gain sets the crossover ``w_c`` on the nominal plant's diagonal channel, with
the sign that makes the loop negative feedback (``|k_p G_ii(j w_c)| = 1``).  The integral
action ``w_i = kappa w_c`` is then the largest ``kappa`` (bisection, 14 steps) for which every
plant of the family is closed-loop stable with a multiloop disk margin of at least
``alpha_min`` (`empact.control.robustness`); the crossover pair is chosen among scalings of the
requested bandwidths for the largest integral gains (``k_p w_i`` of both loops).  This is the
production recipe: robust PI with the highest integral gain the plant spread allows.
"""
from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from .._validate import check_number
from ..errors import ParameterError
from ..nonlinear.model import nonlinear_model
from ..params import Params
from .controller import SCHEDULE_VARIABLES, Controller, Schedule
from .family import PlantFamily
from .law import LoopConfig
from .loop import family_loops, loop_specification
from .robustness import (
    OMEGA,
    disk_gain_phase,
    frequency_responses,
    measured_rows,
    plant_responses,
    robustness_map,
)

__all__ = ["pi_controller", "design_pi", "check_loop_design"]

#: crossover scalings tried around the requested bandwidths
SCALES = (0.5, 0.7, 1.0, 1.4, 2.0)
#: roll-off of each loop at this multiple of its crossover
ROLL_OFF = 5.0


def pi_controller(kp, wi, wf, measured=("r_g", "nu"), outputs=("T_mp", "T_ms"),
                  design=None) -> Controller:
    """The diagonal controller ``diag(kp_j (1 + wi_j / s) / (1 + s / wf_j)^2)`` as a state
    space (three states per loop: the integrator and the second-order roll-off).

    Parameters
    ----------
    kp : array_like, shape (m,)
        Proportional gain of each loop [N m per unit of its error, e.g. N m for a ratio or
        slip error of 1].
    wi : array_like, shape (m,)
        Integral corner of each loop [rad/s].
    wf : array_like, shape (m,)
        Corner of each loop's second-order roll-off [rad/s].
    measured : tuple of str
        The measured signals, one per loop (default ratio and slip, ``("r_g", "nu")``).
    outputs : tuple of str
        The commanded servo torques, one per loop.
    design : dict, optional
        The design data the controller records.

    Returns
    -------
    Controller
        Continuous (``dt = 0``), ``3 m`` states, method ``"pi"``: loop j from the error of
        ``measured[j]`` to ``outputs[j]`` [N m].
    """
    kp, wi, wf = (np.asarray(v, float) for v in (kp, wi, wf))
    m = len(kp)
    A = np.zeros((3 * m, 3 * m))
    B = np.zeros((3 * m, m))
    C = np.zeros((m, 3 * m))
    for j in range(m):
        # x1' = e; x2' = wf (kp (e + wi x1) - x2); x3' = wf (x2 - x3); u = x3
        i1, i2, i3 = 3 * j, 3 * j + 1, 3 * j + 2
        B[i1, j] = 1.0
        A[i2, i1] = wf[j] * kp[j] * wi[j]
        A[i2, i2] = -wf[j]
        B[i2, j] = wf[j] * kp[j]
        A[i3, i2] = wf[j]
        A[i3, i3] = -wf[j]
        C[j, i3] = 1.0
    return Controller(A, B, C, np.zeros((m, m)), tuple(measured), tuple(outputs), 0.0, "pi",
                      design or {})


def design_pi(family: PlantFamily, bandwidth_hz=(0.5, 1.0), *, alpha_min: float = 0.5,
              slip: str = "nu", nominal: tuple[int, ...] | None = None,
              loop: LoopConfig | None = None, params: Params | None = None,
              schedule: bool | None = None) -> Controller:
    """The decentralised PI controller of the module notes for every plant of `family`.

    Parameters
    ----------
    family : PlantFamily
        All points must have trimmed.
    bandwidth_hz : (ratio, slip)
        Requested crossovers of the ratio and slip loops [Hz] on the nominal plant.
    alpha_min : float
        Smallest multiloop disk margin allowed at any grid point (the default 0.5, the
        shipped design's since issue 33: +-4.4 dB and +-28 deg in both loops at once; 0.3,
        issue 21's: +-2.6 dB and +-17 deg).
    slip : {"nu", "nu_r", "ln_nu", "ln_nu_r"}
        The measured slip signal, or its logarithm: the slip's response to the clamping
        force varies by orders of magnitude between micro-slip and the flat top of the
        traction curve, and the logarithm evens much of that out.
    nominal : grid index, optional
        The nominal plant (default: the grid's middle).
    loop : LoopConfig, optional
        Check every candidate on the loop that runs (`empact.control.loop.family_loops`:
        sampled at the loop's rate with its sensors and feedforwards; needs `params` and a
        family with `LOOP_FAMILY_OUTPUTS`); without it, on the continuous loop ``u = K (r -
        y)`` alone.
    params : Params
        With `loop`.
    schedule : bool, optional
        Gain-schedule the proportional gains over the family's axes (``r_g``, ``tau``,
        ``F_s``; with `loop`; default: scheduled when `loop` is given, as the shipped
        design, not scheduled without it): each loop's crossover is the requested one at every grid
        point (``|k_p(sigma) G_ii(j w_c; sigma)| = 1``), interpolated between them
        (`empact.control.controller.Schedule`).

    Returns
    -------
    Controller
        Continuous (``dt = 0``), measured ``(r_g, slip)`` errors -> ``(T_mp, T_ms)`` [N m];
        its ``design`` dict records the gains and the margins reached.

    Raises
    ------
    ParameterError
        When no PI keeps every plant stable with disk margin `alpha_min` at the requested
        crossovers (one line naming what to relax).

    Examples
    --------
    >>> import empact
    >>> family = empact.plant_family(empact.load_params(), r_g=[0.5, 1.0, 2.0],
    ...                              tau=[0.85, 0.95])
    >>> pi = empact.design_pi(family, bandwidth_hz=(0.1, 0.25), alpha_min=0.3)
    >>> pi.measured, pi.outputs
    (('r_g', 'nu'), ('T_mp', 'T_ms'))
    >>> check = empact.robustness_map(family, pi)
    >>> bool((check.max_real_pole < 0).all()), bool(check.disk_margin.min() >= 0.3)
    (True, True)
    """
    if schedule is None:
        schedule = loop is not None
    if loop is not None:
        return _design_pi_loop(family, bandwidth_hz, alpha_min, slip, nominal, loop, params,
                               schedule)
    if schedule:
        raise ParameterError("schedule = True needs the loop it runs in (loop=, params=)")
    if not np.all(family.ok):
        raise ParameterError("the family has points that did not trim; design on a family "
                             "whose every point trims")
    base = slip[3:] if slip.startswith("ln_") else slip
    if base not in family.outputs or base == "r_g":
        raise ParameterError(f"slip = {slip!r}: choose nu, nu_r, ln_nu or ln_nu_r")
    alpha_min = check_number("alpha_min", alpha_min, 0.05, 1.9)
    bw = [check_number("bandwidth", b, 1e-3, 50.0, lo_open=True, unit="Hz")
          for b in bandwidth_hz]
    nominal = tuple(s // 2 for s in family.shape) if nominal is None else tuple(nominal)
    measured, outputs = ("r_g", slip), ("T_mp", "T_ms")
    ii = [family.inputs.index(n) for n in outputs]
    A0, B0 = family.A[nominal], family.B[nominal][:, ii]
    C0 = measured_rows(family, measured)[nominal]

    def gains(scale):
        wc = 2 * np.pi * np.array(bw) * scale
        G = frequency_responses(A0, B0, C0, np.zeros((2, 2)), wc)  # (2, 2, 2): freq, out, in
        kp = np.empty(2)
        for j in range(2):
            g = G[j, j, j]
            sign = np.sign((g * np.exp(1j * np.pi / 4)).real) or 1.0
            kp[j] = sign / abs(g)
        return kp, wc

    w_check = OMEGA  # the grid the final robustness map uses
    G_check = plant_responses(family, outputs, measured, w_check)

    def check(kp, wc, kappa):
        ctrl = pi_controller(kp, kappa * wc, ROLL_OFF * wc, measured, outputs)
        rm = robustness_map(family, ctrl, omega=w_check, G=G_check)
        return bool(rm.stable.all() and rm.disk_margin.min() >= alpha_min), rm

    best = None
    for scale in SCALES:
        kp, wc = gains(scale)
        ok, _ = check(kp, wc, 1e-3)
        if not ok:
            continue
        lo, hi = 1e-3, 1.0
        if check(kp, wc, hi)[0]:
            lo = hi
        else:
            for _ in range(14):
                mid = np.sqrt(lo * hi)
                lo, hi = (mid, hi) if check(kp, wc, mid)[0] else (lo, mid)
        integral = float(np.prod(np.abs(kp) * lo * wc))
        if best is None or integral > best[0]:
            best = (integral, scale, kp, wc, lo)
    if best is None:
        raise ParameterError(
            f"no PI design keeps every plant of the family stable with disk margin >= "
            f"{alpha_min:g} at crossovers {bw[0]:g} / {bw[1]:g} Hz x {SCALES[0]:g}-"
            f"{SCALES[-1]:g}; lower the bandwidths or alpha_min, or narrow the family")
    _, scale, kp, wc, kappa = best
    ctrl = pi_controller(kp, kappa * wc, ROLL_OFF * wc, measured, outputs)
    rm = robustness_map(family, ctrl, G=G_check)
    worst = rm.worst()
    design = {"kp": kp.tolist(), "wi_rad_s": (kappa * wc).tolist(),
              "ki": (kp * kappa * wc).tolist(), "crossover_hz": (wc / 2 / np.pi).tolist(),
              "roll_off_hz": (ROLL_OFF * wc / 2 / np.pi).tolist(), "kappa": kappa,
              "bandwidth_scale": scale, "alpha_min": alpha_min, "worst": worst,
              "nominal": {k: float(v[nominal]) for k, v in family.operating.items()},
              "family_axes": {k: v.tolist() for k, v in family.axes.items()},
              "family_fixed": dict(family.fixed), "slip": slip}
    gm, pm = disk_gain_phase(alpha_min)
    design["alpha_min_margins"] = {"gain_db": float(gm), "phase_deg": float(pm)}
    return pi_controller(kp, kappa * wc, ROLL_OFF * wc, measured, outputs, design)


def _crossover_gains(family: PlantFamily, measured, wc) -> NDArray[np.float64]:
    """``k_p`` of each loop at every grid point: ``sign / |G_jj(j w_c_j)|`` with the sign of
    negative feedback (shape ``family.shape + (2,)``)."""
    ii = [family.inputs.index(n) for n in ("T_mp", "T_ms")]
    C = measured_rows(family, measured)
    G = frequency_responses(family.A, family.B[..., ii], C,
                            np.zeros(C.shape[:-1] + (2,)), wc)  # shape + (2 freq, 2, 2)
    kp = np.empty(family.shape + (2,))
    for j in range(2):
        g = G[..., j, j, j]
        sign = np.sign((g * np.exp(1j * np.pi / 4)).real)
        kp[..., j] = np.where(sign == 0, 1.0, sign) / np.abs(g)
    # one sign per loop over the family (the nominal's)
    return np.abs(kp) * np.sign(kp.reshape(-1, 2)[kp.size // 4])


def check_loop_design(who: str, family: PlantFamily, slip: str, alpha_min: float,
                      bandwidth_hz: Sequence[float], params: Params | None
                      ) -> tuple[Params, float, tuple[float, ...]]:
    """The arguments every design on the loop that runs checks first (`design_pi`,
    `empact.control.hinf.design_hinf`): the parameter set given, every family point trimmed,
    the slip signal, the margin and the bandwidths in range; one `ParameterError` line
    otherwise.

    Parameters
    ----------
    who : str
        The design function's name, for the message.
    family : PlantFamily
        The design family.
    slip : str
        ``nu``, ``nu_r``, ``ln_nu`` or ``ln_nu_r``.
    alpha_min : float
        The disk margin asked for [-], in [0.05, 1.9].
    bandwidth_hz : sequence of float
        The loops' bandwidths [Hz], each in (1e-3, 50].
    params : Params or None
        The parameter set of the loop.

    Returns
    -------
    params : Params
        `params`, known to be given.
    alpha_min : float
    bandwidths : tuple of float
        [Hz].
    """
    if params is None:
        raise ParameterError(f"{who} with a loop needs params")
    if not np.all(family.ok):
        raise ParameterError("the family has points that did not trim; design on a family "
                             "whose every point trims")
    base = slip[3:] if slip.startswith("ln_") else slip
    if base not in ("nu", "nu_r"):
        raise ParameterError(f"slip = {slip!r}: choose nu, nu_r, ln_nu or ln_nu_r")
    alpha_min = check_number("alpha_min", alpha_min, 0.05, 1.9)
    bw = tuple(check_number("bandwidth", b, 1e-3, 50.0, lo_open=True, unit="Hz")
               for b in bandwidth_hz)
    return params, alpha_min, bw


def _design_pi_loop(family, bandwidth_hz, alpha_min, slip, nominal, loop, params, schedule):
    """`design_pi` on the loop that runs (see there)."""
    params, alpha_min, bw = check_loop_design("design_pi", family, slip, alpha_min,
                                              bandwidth_hz, params)
    if schedule:
        bad = [a for a in family.axes if a not in SCHEDULE_VARIABLES]
        if bad:
            raise ParameterError(f"a schedule runs over {', '.join(SCHEDULE_VARIABLES)}; the "
                                 f"family also varies {', '.join(bad)}")
    nominal = tuple(s_ // 2 for s_ in family.shape) if nominal is None else tuple(nominal)
    measured, outputs = ("r_g", slip), ("T_mp", "T_ms")
    model = nonlinear_model(params, **family.options)
    best = None
    for scale in SCALES:
        wc = 2 * np.pi * np.array(bw) * scale
        kp = _crossover_gains(family, measured, wc)
        if schedule:
            sched = Schedule(axes=dict(family.axes), gains=kp)
            unit = pi_controller(np.ones(2), wc, ROLL_OFF * wc, measured, outputs)
            ctrl0 = Controller(unit.A, unit.B, unit.C, unit.D, measured, outputs,
                               schedule=sched)
        else:
            sched = None
            ctrl0 = pi_controller(kp[nominal], wc, ROLL_OFF * wc, measured, outputs)
        lm = family_loops(family, ctrl0, loop, params, model)

        def make(kappa):
            if sched is None:
                return pi_controller(kp[nominal], kappa * wc, ROLL_OFF * wc, measured, outputs)
            u = pi_controller(np.ones(2), kappa * wc, ROLL_OFF * wc, measured, outputs)
            return Controller(u.A, u.B, u.C, u.D, measured, outputs, schedule=sched)

        def check(kappa):
            m = lm.with_controller(make(kappa))
            dm = m.disk_margins()
            return bool(np.all(m.spectral_radius() < 1) and dm["alpha"].min() >= alpha_min)

        if not check(1e-3):
            continue
        lo, hi = 1e-3, 1.0
        if check(hi):
            lo = hi
        else:
            for _ in range(12):
                mid = np.sqrt(lo * hi)
                lo, hi = (mid, hi) if check(mid) else (lo, mid)
        # the largest integral action: the product of the loops' integral gains at the
        # nominal point
        integral = float(np.prod(np.abs(kp[nominal]) * lo * wc))
        if best is None or integral > best[0]:
            best = (integral, scale, kp, wc, lo, lm)
    if best is None:
        raise ParameterError(
            f"no PI design keeps every plant of the family stable with disk margin >= "
            f"{alpha_min:g} on this loop at crossovers {bw[0]:g} / {bw[1]:g} Hz x "
            f"{SCALES[0]:g}-{SCALES[-1]:g}; lower the bandwidths or alpha_min, or narrow the "
            "family")
    _, scale, kp, wc, kappa, lm = best
    ctrl = (lambda k: pi_controller(kp[nominal], k * wc, ROLL_OFF * wc, measured, outputs)
            if not schedule else None)(kappa)
    if schedule:
        u = pi_controller(np.ones(2), kappa * wc, ROLL_OFF * wc, measured, outputs)
        ctrl = Controller(u.A, u.B, u.C, u.D, measured, outputs,
                          schedule=Schedule(axes=dict(family.axes), gains=kp))
    m = lm.with_controller(ctrl)
    dm = m.disk_margins()
    rho = m.spectral_radius()
    worst = {"disk_margin": float(dm["alpha"].min()),
             "input_disk_margin": float(dm["input"].min()),
             "output_disk_margin": float(dm["output"].min()),
             "spectral_radius": float(rho.max()), "all_stable": bool(np.all(rho < 1))}
    gm, pm = disk_gain_phase(worst["disk_margin"])
    worst.update(gain_margin_db=float(gm), phase_margin_deg=float(pm))
    design = {"kp_nominal": kp[nominal].tolist(), "wi_rad_s": (kappa * wc).tolist(),
              "crossover_hz": (wc / 2 / np.pi).tolist(),
              "roll_off_hz": (ROLL_OFF * wc / 2 / np.pi).tolist(), "kappa": kappa,
              "bandwidth_scale": scale, "alpha_min": alpha_min, "worst": worst,
              "nominal": {k: float(v[nominal]) for k, v in family.operating.items()},
              "family_axes": {k: v.tolist() for k, v in family.axes.items()},
              "family_fixed": dict(family.fixed), "slip": slip, "scheduled": schedule,
              "loop": loop_specification(loop)}
    return Controller(ctrl.A, ctrl.B, ctrl.C, ctrl.D, measured, outputs, 0.0, "pi", design,
                      ctrl.schedule)
