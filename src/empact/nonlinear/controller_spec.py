"""The ``[controller]`` table of a scenario (`ControllerSpec`): the controller file, its
sample rate, the clamping strategy and its feedforwards, the decoupler, the noise seed - data
only, validated on construction.  `empact.nonlinear.scenario` reads it from a scenario file
(and re-exports it); `empact.control.closed_loop` loads the controller and builds the loop law
(`empact.control.law`) from it.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from .._validate import check_bool, check_choice, check_number
from ..errors import ParameterError

__all__ = ["ControllerSpec", "CLAMPING", "MU_DESIGN", "FF_SIGNALS", "TORQUE_REQUEST"]

#: clamping strategies of a closed-loop scenario: the slip loop, or a production CVT's
#: open-loop safety factor
CLAMPING = ("feedback", "safety-factor")
#: the safety-factor strategy's traction coefficient: one for all ratios, or per ratio
MU_DESIGN = ("ratio-blind", "ratio-aware")
#: what the clamping feedforward may use: the driveshaft torque, the load motor's torque, or
#: an engine-torque estimate (the torque source's torque as its controller reports it: late
#: and off by the ``[sensors]`` ``engine_torque_delay`` and ``engine_torque_error``)
FF_SIGNALS = ("T_ds", "T_l_act", "T_e_est", "T_ds_est")
#: the torque request of a saturating secondary servo: none, requested (computed and
#: reported, nobody honours it), or honoured (the bench's load torque follows it)
TORQUE_REQUEST = ("off", "requested", "honoured")


@dataclass(frozen=True)
class ControllerSpec:
    """The ``[controller]`` table of a scenario (data only: `empact.control.closed_loop`
    loads the file and builds the loop law, `empact.control.law`).

    Attributes
    ----------
    file : str
        Controller file (absolute, or relative to the scenario's folder once loaded) or
        ``"shipped:NAME"``.
    rate : float
        Sample rate [Hz]; the commands are held between samples.
    feedforward : bool
        Clamping feedforward of a measured torque.
    feedforward_gain : float
        Share of the measured torque the feedforward clamps for (below 1 the belt keeps part
        of its damping of the driveshaft mode, which a full feedforward cancels); with
        `feedforward_gain_table`, its gain at its largest force.
    feedforward_gain_table : tuple of (float, float), optional
        The feedforward's incremental gain scheduled over the full feedforward force
        ``F_full`` (the clamping at gain 1) [N]: pairs ``(F_full, gain)``, forces increasing
        from 0, gains in [0, 1.5], linear between them and held beyond; the feedforward
        clamps for ``int_0^F_full gain(F) dF`` (so that the gain of a change is the table's
        at every load, issue 33).  None: ``feedforward_gain`` at every load.
    feedforward_signal : {"T_ds", "T_l_act", "T_e_est", "T_ds_est"}
        The driveshaft torque a bench measures, the load motor's torque (exact, one sample
        late), or an engine-torque estimate: the torque of the machine's torque source as
        its controller reports it, ``engine_torque_delay`` late and ``(1 +
        engine_torque_error)`` times the truth (`empact.hardware.SensorParams`); on the test
        bench (drive speed-, load torque-controlled) the source is the load motor, which
        sets the torque the belt carries as a car's engine does; no torque sensor.
        ``"T_ds_est"``: the driveshaft torque observed without a torque sensor, the
        driveline's twist rate (the output speed less the wheel speed, which a car's
        wheel-speed sensors give) times its stiffness integrated, pulled to the
        engine-torque estimate below ``observer_hz``.
    observer_hz : float
        Corner of the driveshaft-torque observer's correction by the engine-torque estimate
        [Hz] (``"T_ds_est"``; default 0.1: at 0.5 the estimate's 15 % error reaches the
        clamping within the load steps' settling window, and the slip misses its 0.2 pp
        there at r_g 1 and 2; the observer reads the shaft speeds unquantised).
    feedforward_filter_hz : float
        Corner of the feedforward's first-order low-pass [Hz].
    traction_error : float
        Factor on the feedforward's traction coefficient (1.05: the estimate 5 % high).
    clamping : {"feedback", "safety-factor"}
    safety_factor : float
    mu_design : {"ratio-blind", "ratio-aware"}
        The safety-factor strategy's traction coefficient: the smallest peak over the ratio
        range, or the peak at the measured ratio.
    decoupling : bool
        The primary servo torque follows the feedforward's clamping (the holding torques'
        ratio at the reference ratio), so that a clamping change keeps the thrust ratio.
    decoupling_filter_hz : float
        Corner of the decoupler's first-order low-pass [Hz].
    shift_feedforward : bool
        Coordinated shifting: the primary servo torque of the reference's ratio rate and the
        clamping of the secondary side's acceleration, fed forward.
    torque_request : {"off", "requested", "honoured"}
        Protection of a saturating secondary servo: the law computes ``T_request`` [N m],
        the secondary-shaft torque the servo can clamp for at the slip set-point with
        ``torque_request_margin`` of its torque limit held back (the engine's share is
        ``r_g T_request``), and reports it (``"requested"``); ``"honoured"``: the test
        bench's load torque ``T_l`` follows it (``|T_l| <= T_request``, the load-torque
        demand otherwise), as an engine honours a transmission's torque request.
    torque_request_margin : float
        Share of the secondary servo's torque limit held back from the request for the slip
        loop's transients [-], in [0, 0.9] (default 0.25: on a 50 % load step at r_g = 0.5
        the loop's clamping overshoots its new steady value by about 20 %, 33.7 kN for 28
        kN at 18 kN; at 0.1 that step macro-slips with the servo at its limit).
    reserve_ahead : bool
        Raise the torque reserve ahead from the secondary servo's remaining capacity: the
        headroom ``h = 1 - F_full / F_max`` (``F_full`` the clamping that holds the
        set-point at the measured torque, ``F_max`` the clamping the servo's torque limit
        holds over its holding torque's constant share) below `reserve_ahead_headroom`
        moves the slip set-point from the reference's towards the one at the torque ratio
        `reserve_ahead_tau`, in proportion ``w = (h_0 - h) / h_0`` (at most 1), and never
        past the clamping the servo holds (``w <= mu* h / (mu* - mu_lo)``); the feedforward
        clamps for the moved set-point at once.  ``F_max`` is the servo's rating
        (``[servo] T_ms_max``; also where the loop runs without limits, so that the linear
        model's law is the one that runs).
    reserve_ahead_headroom : float
        The headroom share ``h_0`` below which the set-point moves [-], in (0, 1].
    reserve_ahead_tau : float
        The lowest set-point's torque ratio [-], in [0.5, 0.99] (above the reference's: no
        move).
    slip_guard : bool
        The slip-runaway guard: when the measured slip passes its set-point by more than
        `slip_guard_margin` of it, the clamping rises at once by ``slip_guard_gain`` times
        the excess beyond the margin (as a share of the clamping ``F_full`` that holds the
        set-point, at most all of it), held as a force - the driveshaft torque's swings do
        not move it - and released with the time constant `slip_guard_release`.  Needs the
        clamping feedforward.  Off by default; on in the bench's shipped slip-control
        scenarios (the load and small steps, the two slip-controlled shifts), where no
        nominal run reaches its margin (their metrics are those without it), not in the
        car's.  Measured on the wide Monte Carlo spread (issue 33 item 8, 200 runs a ratio,
        seed 0; runs without macro slip or belt slack): without it 96.5 / 93.0 / 100 % at
        r_g = 0.5 / 1 / 2, with it 100 / 98.5 / 100 %.  An earlier guard held a share of the
        live feedforward clamping instead of a force: while it held, it raised the
        feedforward's gain on the driveshaft torque and pumped the driveline's 3.3 Hz
        shuffle into belt slack (88.0 % at r_g = 0.5).
    slip_guard_margin : float
        [-], in (0, 2].
    slip_guard_gain : float
        [-], in (0, 20].
    slip_guard_release : float
        [s], in (0, 60].
    min_clamping : float
        The lowest clamping force the secondary servo is commanded to [N] (0: none): its
        torque held at or beyond the torque that clamps it (the holding torque's share that
        does not scale with the clamping, at the start, plus the servo torque per newton
        times it), a limit of the anti-windup like the servo's torque limit.  A car's slip
        loop needs it where the belt carries almost no torque (coasting: no slip to control,
        the loop would open the belt) and the safety-factor clamping where the torque
        crosses zero (issue 34; the quasi-static cycle's 3 kN, `empact.drive_cycle`).
    clamping_release : float
        The safety-factor clamping's release time constant [s], in [0, 60] (0: none): the
        torque it clamps for rises at once and falls as a first-order lag, so that the
        clamping holds through a tip-out while the driveline's twist and the engine's
        inertia still push the old torque through the belt (issue 34: the car's
        safety-factor strategies use one period of the car's shuffle mode,
        `empact.dynamic_cycle`).  The default keeps the bench's strategies as they were.
    anti_windup : bool
    sensors, limits : bool
        The parameter set's (and the scenario's) sensors and servo limits; False: ideal.
    seed : int
        Seed of the sensor noise.
    """

    file: str
    rate: float = 1000.0
    feedforward: bool = False
    feedforward_gain: float = 0.9
    feedforward_gain_table: tuple[tuple[float, float], ...] | None = None
    feedforward_signal: str = "T_ds"
    feedforward_filter_hz: float = 100.0
    observer_hz: float = 0.1
    traction_error: float = 1.0
    clamping: str = "feedback"
    safety_factor: float = 1.3
    mu_design: str = "ratio-blind"
    decoupling: bool = False
    decoupling_filter_hz: float = 5.0
    shift_feedforward: bool = False
    torque_request: str = "off"
    torque_request_margin: float = 0.25
    reserve_ahead: bool = False
    reserve_ahead_headroom: float = 0.6
    reserve_ahead_tau: float = 0.8
    slip_guard: bool = False
    slip_guard_margin: float = 0.3
    slip_guard_gain: float = 2.0
    slip_guard_release: float = 1.0
    min_clamping: float = 0.0
    clamping_release: float = 0.0
    anti_windup: bool = True
    sensors: bool = True
    limits: bool = True
    seed: int = 0

    def __post_init__(self) -> None:
        rate = check_number("controller.rate", self.rate, 1.0, 1e5, unit="Hz")
        object.__setattr__(self, "rate", rate)
        object.__setattr__(self, "feedforward_filter_hz", check_number(
            "controller.feedforward_filter_hz", self.feedforward_filter_hz, 0.0, 0.5 * rate,
            lo_open=True, unit="Hz", note="below the Nyquist frequency"))
        object.__setattr__(self, "decoupling_filter_hz", check_number(
            "controller.decoupling_filter_hz", self.decoupling_filter_hz, 0.0, 0.5 * rate,
            lo_open=True, unit="Hz", note="below the Nyquist frequency"))
        object.__setattr__(self, "observer_hz", check_number(
            "controller.observer_hz", self.observer_hz, 0.0, 0.5 * rate, lo_open=True,
            unit="Hz", note="below the Nyquist frequency"))
        object.__setattr__(self, "traction_error", check_number(
            "controller.traction_error", self.traction_error, 0.5, 2.0))
        object.__setattr__(self, "feedforward_gain", check_number(
            "controller.feedforward_gain", self.feedforward_gain, 0.0, 1.5, lo_open=False))
        if self.feedforward_gain_table is not None:
            object.__setattr__(self, "feedforward_gain_table", _gain_table(
                self.feedforward_gain_table, self.feedforward_gain))
        object.__setattr__(self, "safety_factor", check_number(
            "controller.safety_factor", self.safety_factor, 1.0, 3.0))
        check_choice("controller.clamping", self.clamping, CLAMPING)
        check_choice("controller.mu_design", self.mu_design, MU_DESIGN)
        check_choice("controller.feedforward_signal", self.feedforward_signal, FF_SIGNALS)
        check_choice("controller.torque_request", self.torque_request, TORQUE_REQUEST)
        object.__setattr__(self, "torque_request_margin", check_number(
            "controller.torque_request_margin", self.torque_request_margin, 0.0, 0.9,
            lo_open=False))
        for name, lo, hi, lo_open in (("reserve_ahead_headroom", 0.0, 1.0, True),
                                      ("reserve_ahead_tau", 0.5, 0.99, False),
                                      ("slip_guard_margin", 0.0, 2.0, True),
                                      ("slip_guard_gain", 0.0, 20.0, True),
                                      ("slip_guard_release", 0.0, 60.0, True),
                                      ("clamping_release", 0.0, 60.0, False)):
            object.__setattr__(self, name, check_number(
                f"controller.{name}", getattr(self, name), lo, hi, lo_open=lo_open,
                unit="s" if name.endswith("_release") else ""))
        if self.slip_guard and not self.feedforward:
            raise ParameterError("controller.slip_guard = true: needs the clamping "
                                 "feedforward (controller.feedforward = true)")
        object.__setattr__(self, "min_clamping", check_number(
            "controller.min_clamping", self.min_clamping, 0.0, 1e5, lo_open=False, unit="N"))
        if self.torque_request != "off" and not self.limits:
            raise ParameterError(f"controller.torque_request = {self.torque_request!r}: needs "
                                 "the servo limits (controller.limits = true)")
        for name in ("feedforward", "decoupling", "shift_feedforward", "anti_windup",
                     "sensors", "limits", "reserve_ahead", "slip_guard"):
            check_bool(f"controller.{name}", getattr(self, name))
        seed = check_number("controller.seed", self.seed, 0, 2**32 - 1, lo_open=False)
        if seed != int(seed):
            raise ParameterError(f"controller.seed = {self.seed!r}: must be a whole number")
        object.__setattr__(self, "seed", int(seed))


def _gain_table(table, gain: float) -> tuple[tuple[float, float], ...]:
    """``controller.feedforward_gain_table`` checked: at least two ``[F_full, gain]`` pairs,
    forces from 0 increasing, gains in [0, 1.5], the last gain `gain` (``feedforward_gain``)."""
    name = "controller.feedforward_gain_table"
    try:
        rows = tuple((float(f), float(g)) for f, g in table)
    except (TypeError, ValueError):
        raise ParameterError(f"{name} = {table!r}: must be pairs [F_full (N), gain]") from None
    forces = [f for f, _ in rows]
    if len(rows) < 2 or forces[0] < 0 or any(b <= a for a, b in zip(forces, forces[1:])) \
            or not all(map(math.isfinite, forces)):
        raise ParameterError(f"{name} = {table!r}: at least two pairs, forces from 0 [N] "
                             "finite and increasing")
    for _, g in rows:
        check_number(name, g, 0.0, 1.5, lo_open=False, note="each pair's gain")
    if rows[-1][1] != gain:
        raise ParameterError(f"controller.feedforward_gain = {gain!r}: with {name} it is the "
                             f"table's gain at its largest force ({rows[-1][1]!r})")
    return rows
