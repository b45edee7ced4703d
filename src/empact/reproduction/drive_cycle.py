"""Beyond the paper: the machine in a car over WLTC class 3b, quasi-static and dynamic (issue
34), with the published anchors beside the results.

The dynamic runs (`empact.dynamic_cycle`: the nonlinear vehicle driveline with the loop law
at 1 kHz and the driver) are the reference's and the slip strategy's (`DYNAMIC_STRATEGIES`):
the saving's two ends, about a minute of CPU each on a quiet machine; the car's shifts are
the shipped ``vehicle-*`` examples (a few seconds each).

Anchors (copied here with their sources; the project reads nothing else at run time):

* SAE 04CVT-39 (van der Laan, van Drogen, Brandsma, 2004): slip control of a hydraulic
  pushbelt CVT saves about 5 % fuel (`SLIP_CONTROL_SAVING`).
* SAE 04CVT-49 (Veenhuizen, Bonsen, Klaassen et al., 2004): the hydraulic pump takes 0.63 /
  1.27 / 3.17 kW at 2000 rpm and 10 / 20 / 50 bar (`PUMP_ANCHORS`).
* Issue 34: a mean positive wheel power of about 11 kW on WLTC 3b for a 1300 kg car.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..actuation_energy import hydraulic_power
from ..control.closed_loop import control_example_path, run_closed_loop
from ..cycles import load_cycle
from ..drive_cycle import MIN_CLAMPING, STRATEGIES, TERMS, CycleResult, quasi_static_cycle
from ..dynamic_cycle import DynamicCycleResult, dynamic_cycle
from ..nonlinear.scenario import load_scenario
from ..params import Params
from .claims import Claim

__all__ = ["SLIP_CONTROL_SAVING", "PUMP_ANCHORS", "MEAN_WHEEL_POWER", "DYNAMIC_STRATEGIES",
           "SPEED_TOLERANCE_KMH", "LOSS_AGREEMENT", "DriveCycleSection", "drive_cycle"]

#: SAE 04CVT-39: fuel saved by slip control on a hydraulic CVT [-]
SLIP_CONTROL_SAVING = 0.05
#: SAE 04CVT-49: (pump speed [rad/s], line pressure [Pa], pump power [W])
PUMP_ANCHORS = tuple((2000 * math.pi / 30, p * 1e5, P * 1e3)
                     for p, P in ((10, 0.63), (20, 1.27), (50, 3.17)))
#: issue 34: mean positive wheel power on WLTC 3b for a 1300 kg car [W]
MEAN_WHEEL_POWER = 11e3
#: the strategies the section runs dynamically (the saving's two ends)
DYNAMIC_STRATEGIES = ("hydraulic-sf1.3", "slip")
#: the WLTP's speed tolerance [km/h] (UN GTR 15: +-2 km/h within +-1 s; here the plain
#: difference at the same time, which is stricter)
SPEED_TOLERANCE_KMH = 2.0
#: issue 34: the quasi-static and dynamic variator loss energies agree within this share
LOSS_AGREEMENT = 0.10
#: issue 34 (the bench's shift-low-od): the shift-rate target [1/s]
SHIFT_TARGET = 1.0


@dataclass(frozen=True)
class DriveCycleSection:
    """The drive-cycle section.

    Attributes
    ----------
    result : CycleResult
        WLTC 3b, quasi-static, every strategy of `empact.drive_cycle.STRATEGIES`.
    rows : list of list
        Per strategy: name, energy by term [kJ] (`TERMS`), variator and transmission
        efficiency [%], fuel [g], [l/100 km], saving against hydraulic-sf1.3 [%].
    phase_rows : list of list
        Per strategy: name, fuel [l/100 km] per phase.
    pump_rows : list of list
        Per `PUMP_ANCHORS`: pressure [bar], published and computed pump power [kW].
    claims : tuple of Claim
    dynamic : DynamicCycleResult
        WLTC 3b, dynamic, `DYNAMIC_STRATEGIES`.
    dynamic_rows : list of list
        Per dynamic strategy: name, energy by term [kJ] (`TERMS`, brakes), fuel [g],
        [l/100 km], saving [%] dynamic and quasi-static, largest speed error [km/h], macro
        slip, belt slack, the variator's losses over the dynamic stretches [kJ] dynamic and
        quasi-static and their difference [%].
    shift_rows : list of list
        The car's shifts (``vehicle-*``): name, ratio rate [1/s], ratio span, peak slip
        [%], macro slip, peak servo torques [N m].
    """

    result: CycleResult
    rows: list[list[object]]
    phase_rows: list[list[object]]
    pump_rows: list[list[float]]
    claims: tuple[Claim, ...]
    dynamic: DynamicCycleResult | None = None
    dynamic_rows: list[list[object]] = field(default_factory=list)
    shift_rows: list[list[object]] = field(default_factory=list)


def drive_cycle(params: Params) -> DriveCycleSection:
    """WLTC 3b on the shipped car, quasi-static, with the anchors (module notes).

    Parameters
    ----------
    params : Params
        The parameter set (its ``[vehicle]``, ``[engine]``, ``[servo]``, ``[hydraulic]``).

    Returns
    -------
    DriveCycleSection
    """
    res = quasi_static_cycle(params, load_cycle("wltc3b"), strategies=tuple(STRATEGIES))
    doc = res.to_dict()
    S = doc["strategies"]
    rows: list[list[object]] = []
    for s, d in S.items():
        rows.append([s, *(round(d["energy_J"][k] / 1e3, 1) for k in TERMS),
                     round(100 * d["variator_efficiency"], 2),
                     round(100 * d["transmission_efficiency"], 2), round(d["fuel_g"], 1),
                     round(d["fuel_l_per_100km"], 3), round(100 * d["saving"], 2)])
    phase_rows = [[s, *(round(d["phases"][p]["fuel_l_per_100km"], 3) for p in doc["phases"])]
                  for s, d in S.items()]
    h = params.hydraulic
    pump_rows = []
    for w, p, P in PUMP_ANCHORS:
        F = (p - h.p_margin) * h.A_s
        terms = hydraulic_power(h, np.array([F]), np.array([F]), np.array([w]))
        got = float(np.sum([np.asarray(v, float)[0] for v in terms.values()]))
        pump_rows.append([p / 1e5, P / 1e3, round(got / 1e3, 3)])
    fuel = {s: d["fuel_g"] for s, d in S.items()}
    hyd_slip = 1 - fuel["hydraulic-slip"] / fuel["hydraulic-sf1.3"]
    em_slip = 1 - fuel["slip"] / fuel["sf1.3"]
    moving = res.v > 0
    floor = {s: float(np.mean(res.F_s[s][moving] <= MIN_CLAMPING * (1 + 1e-9)))
             for s in ("hydraulic-sf1.3", "hydraulic-slip")}
    e_ref, e_slip = S["hydraulic-sf1.3"]["energy_J"], S["hydraulic-slip"]["energy_J"]
    trac = moving & (res.P_wheel > 0)
    mean_wheel = float(np.mean(res.P_wheel[trac]))
    pump_err = max(abs(r[2] / r[1] - 1) for r in pump_rows)
    src39 = "SAE 04CVT-39 (van der Laan, van Drogen, Brandsma 2004)"
    claims = (
        Claim(key="cycle.slip_control_saving", source=src39,
              claim="slip control saves about 5 % fuel in a hydraulic pushbelt CVT "
                    "(checked: 3-7 %)",
              computed=f"WLTC 3b, quasi-static: hydraulic-slip against hydraulic-sf1.3 "
                       f"{100 * hyd_slip:.2f} % ({fuel['hydraulic-slip']:.1f} against "
                       f"{fuel['hydraulic-sf1.3']:.1f} g); on the servos, slip against sf1.3 "
                       f"{100 * em_slip:.2f} %",
              shown=0.03 <= hyd_slip <= 0.07,
              explanation=(
                  "The pump's cost barely follows the clamping on this cycle: the clamping "
                  f"is at its {MIN_CLAMPING / 1e3:g} kN floor in "
                  f"{100 * floor['hydraulic-sf1.3']:.0f} % (sf1.3) and "
                  f"{100 * floor['hydraulic-slip']:.0f} % (slip) of the moving samples, "
                  "and the pump's leakage and friction at the line pressure of that floor "
                  "dominate; slip control lowers the pump energy from "
                  f"{e_ref['pump'] / 1e3:.0f} to {e_slip['pump'] / 1e3:.0f} kJ "
                  f"and the clamping loss from {e_ref['clamp'] / 1e3:.0f} to "
                  f"{e_slip['clamp'] / 1e3:.0f} kJ, but raises the slip loss from "
                  f"{e_ref['slip'] / 1e3:.0f} to {e_slip['slip'] / 1e3:.0f} kJ. 04CVT-39's "
                  "gain includes a lower clamping floor and the wear-based choice of the "
                  "safety factor of a production line-pressure map, which this model does "
                  "not have (the floor is the shipped loop's lowest design clamping)."),
              values={"saving_hydraulic": hyd_slip, "saving_servo": em_slip, **{
                  f"floor_{k}": v for k, v in floor.items()}}),
        Claim(key="cycle.pump_power", source="SAE 04CVT-49 (Veenhuizen et al. 2004)",
              claim="the hydraulic pump takes 0.63 / 1.27 / 3.17 kW at 2000 rpm and 10 / 20 "
                    "/ 50 bar (checked: within 15 %)",
              computed="; ".join(f"{r[0]:g} bar: {r[2]:.2f} kW" for r in pump_rows)
                       + f"; over WLTC 3b the pump takes "
                       f"{e_ref['pump'] / res.cycle.duration:.0f} W on average",
              shown=pump_err <= 0.15,
              explanation=(
                  f"The computed shaft power is {100 * pump_err:.0f} % above at worst. "
                  "04CVT-49's figures are the pump's displacement flow times the pressure "
                  f"({h.displacement * 2 * math.pi * 1e6:.0f} cc/rev x 2000 rpm x p = "
                  + " / ".join(f"{h.displacement * w * p / 1e3:.2f}"
                               for w, p, _ in PUMP_ANCHORS)
                  + " kW: an ideal pump); the reference pump's shaft power ([hydraulic], "
                  "empact.actuation_energy) is that over its hydromechanical efficiency "
                  f"({h.eta_hm:g}), all its flow at line pressure."),
              values={"pump_W": [r[2] * 1e3 for r in pump_rows]}),
        Claim(key="cycle.mean_wheel_power", source="issue 34",
              claim="WLTC 3b asks a mean positive wheel power of about 11 kW of a 1300 kg car "
                    "(checked: within 15 %)",
              computed=f"{mean_wheel / 1e3:.2f} kW over the {int(trac.sum())} samples that "
                       f"draw; traction energy {doc['wheel_energy_J'] / 1e6:.2f} MJ",
              shown=abs(mean_wheel / MEAN_WHEEL_POWER - 1) <= 0.15,
              explanation="The shipped car's road load or mass is off the issue's estimate.",
              values={"mean_wheel_power": mean_wheel}),
        Claim(key="cycle.electromechanical_saving", source="issue 34 (the energy issue)",
              claim="electromechanical actuation saves fuel against the hydraulic reference "
                    "at the same clamping (sf1.3)",
              computed=f"sf1.3 against hydraulic-sf1.3: "
                       f"{100 * S['sf1.3']['saving']:.2f} % ({fuel['sf1.3']:.1f} g); "
                       f"actuation {S['sf1.3']['energy_J']['servo_electrical'] / 1e3:.0f} kJ "
                       f"electrical (+{S['sf1.3']['energy_J']['alternator'] / 1e3:.0f} kJ in "
                       f"the alternator) against {e_ref['pump'] / 1e3:.0f} kJ of pump",
              shown=S["sf1.3"]["saving"] > 0,
              explanation="The servos' holding power and the alternator cost more than "
                          "the pump.",
              values={"saving": S["sf1.3"]["saving"]}),
    )
    dyn = dynamic_cycle(params, res.cycle, strategies=DYNAMIC_STRATEGIES, quasi_static=res)
    dyn_rows, dyn_claims = _dynamic(dyn, S)
    shift_rows, shift_claims = _shifts(params)
    return DriveCycleSection(result=res, rows=rows, phase_rows=phase_rows,
                             pump_rows=pump_rows, claims=claims + dyn_claims + shift_claims,
                             dynamic=dyn, dynamic_rows=dyn_rows, shift_rows=shift_rows)


def _dynamic(dyn: DynamicCycleResult, qs: dict) -> tuple[list[list[object]], tuple[Claim, ...]]:
    """The dynamic table and its claims (`DriveCycleSection.dynamic_rows`)."""
    d = dyn.to_dict()
    S = d["strategies"]
    rows: list[list[object]] = []
    agree = {}
    for s, e in S.items():
        dl, ql = e["variator_loss_J"], e["quasi_static_variator_loss_J"]
        agree[s] = dl / ql - 1
        saving = "" if e["saving"] is None else round(100 * e["saving"], 2)
        qsave = "" if qs[s]["saving"] is None else round(100 * qs[s]["saving"], 2)
        rows.append([s, *(round(e["energy_J"][k] / 1e3, 1) for k in TERMS + ("brakes",)),
                     round(e["fuel_g"], 1), round(e["fuel_l_per_100km"], 3), saving, qsave,
                     round(e["speed_error_max_kmh"], 2), e["macro_slip"], e["belt_slack"],
                     round(dl / 1e3, 1), round(ql / 1e3, 1), round(100 * agree[s], 2)])
    err = max(e["speed_error_max_kmh"] for e in S.values())
    bad = [s for s, e in S.items() if e["macro_slip"] or e["belt_slack"]
           or not e["complete"]]
    worst = max(agree, key=lambda k: abs(agree[k]))
    cov = d["dynamic_duration_s"]
    src = "issue 34 (item 4)"
    claims: tuple[Claim, ...] = (
        Claim(key="cycle.dynamic_speed", source=src,
              claim=f"the dynamic WLTC 3b run follows the trace within the WLTP's +-"
                    f"{SPEED_TOLERANCE_KMH:g} km/h",
              computed="largest |v - v*| " + ", ".join(
                  f"{s} {e['speed_error_max_kmh']:.2f} km/h" for s, e in S.items())
                       + f" over the {cov:.0f} s of dynamic stretches (at and above "
                       f"{3.6 * d['v_launch_m_s']:.1f} km/h)",
              shown=err <= SPEED_TOLERANCE_KMH,
              explanation="The driver (a PI at 0.5 Hz with the trace's acceleration fed "
                          "forward) or the engine's full load cannot follow the trace.",
              values={"speed_error_max_kmh": err}),
        Claim(key="cycle.dynamic_macro_slip", source=src,
              claim="no macro slip and no belt slack over the dynamic WLTC 3b run",
              computed="; ".join(f"{s}: macro slip {e['macro_slip']}, belt slack "
                                 f"{e['belt_slack']}, smallest slip reserve "
                                 f"{100 * e['slip_reserve']:.2f} pp, lowest clamping "
                                 f"{e['min_clamping_force'] / 1e3:.2f} kN"
                                 for s, e in S.items()),
              shown=not bad,
              explanation=("Macro slip or belt slack in " + ", ".join(bad) + " (the "
                           "table's slip reserve and clamping name where).")
              if bad else "The safety-factor clamping holds the engine's torque through "
                          "a tip-out (released over one period of the car's shuffle mode, "
                          "empact.dynamic_cycle.clamping_release): the driveline's twist "
                          "and the engine's inertia push the old torque through the belt "
                          "for about half that period.",
              values={s: {"macro_slip": e["macro_slip"], "belt_slack": e["belt_slack"]}
                      for s, e in S.items()}),
        Claim(key="cycle.dynamic_loss_agreement", source=src,
              claim=f"the quasi-static and dynamic variator loss energies agree within "
                    f"{100 * LOSS_AGREEMENT:.0f} % on WLTC 3b",
              computed="over the dynamic stretches, dynamic against quasi-static: "
                       + ", ".join(f"{s} {r[-3]:.1f} / {r[-2]:.1f} kJ ({r[-1]:+.2f} %)"
                                   for s, r in zip(S, rows)),
              shown=abs(agree[worst]) <= LOSS_AGREEMENT,
              explanation=(
                  "The rest: the dynamic run's slip follows the slip loop's transients and "
                  "the clamping the engine's lagged torque (the quasi-static one sits at "
                  "each sample's trim), its ratio lags the operating line's, the engine's "
                  "and the car's inertia move power between samples, and the quasi-static "
                  "model puts no variator loss into the accelerations' engine-inertia "
                  "torque."),
              values={"agreement": agree}),
    )
    if "slip" in S and S["slip"]["saving"] is not None:
        claims += (Claim(
            key="cycle.dynamic_saving", source=src,
            claim="slip control on the servos saves fuel against hydraulic-sf1.3 in the "
                  "dynamic run as in the quasi-static one",
            computed=f"dynamic {100 * S['slip']['saving']:.2f} % ({S['slip']['fuel_g']:.1f} "
                     f"against {S['hydraulic-sf1.3']['fuel_g']:.1f} g), quasi-static "
                     f"{100 * qs['slip']['saving']:.2f} %",
            shown=S["slip"]["saving"] > 0,
            explanation="The dynamic run's transients cost the slip strategy more than the "
                        "reference.",
            values={"dynamic": S["slip"]["saving"], "quasi_static": qs["slip"]["saving"]}),)
    return rows, claims


def _shifts(params: Params) -> tuple[list[list[object]], tuple[Claim, ...]]:
    """The car's shifts (the shipped ``vehicle-*`` examples) and the shift-rate claim."""
    rows: list[list[object]] = []
    metrics = {}
    for name in ("vehicle-upshift", "vehicle-kickdown"):
        m = run_closed_loop(load_scenario(control_example_path(name)), params).metrics
        metrics[name] = m
        span = m["ratio_span"]
        rows.append([name, round(m["ratio_rate"], 3), f"{span[0]:.3f} -> {span[1]:.3f}",
                     round(100 * m["peak_slip"], 2), m["macro_slip"],
                     f"{m['peak_T_mp']:.2f} / {m['peak_T_ms']:.2f}"])
    up = metrics["vehicle-upshift"]
    claim = Claim(
        key="cycle.car_shift_rate", source="issue 34 (item 5)",
        claim=f"in the car LOW -> OD reaches {SHIFT_TARGET:g} /s without macro slip within "
              "the servo limits (the bench's shift-low-od misses it)",
        computed=f"vehicle-upshift: {up['ratio_rate']:.3f} /s over its window (ratio "
                 f"{up['ratio_span'][0]:.2f} -> {up['ratio_span'][1]:.2f}), macro slip "
                 f"{up['macro_slip']}, peak servo torques {up['peak_T_mp']:.2f} / "
                 f"{up['peak_T_ms']:.2f} N m (limits {up['T_mp_max']:g} / "
                 f"{up['T_ms_max']:g})",
        shown=up["ratio_rate"] >= SHIFT_TARGET and not up["macro_slip"],
        explanation=(
            "Faster than the bench (0.33-0.43 /s there: its speed-held drive makes the belt "
            "accelerate the 1 kg m^2 load motor, (J_s + J_l) omega_p dr_g/dt, about 312 N m "
            "at 1 /s and 300 rad/s, while the load torque stays), but short of 1 /s: in the "
            "car the engine's inertia torque (J_e + J_p) omega_p dr_g/dt / r_g^2 limits the "
            "rate at LOW (the reference is geometric for it) and the ratio loop, whose gain "
            "does not follow the primary speed (450 -> 130 rad/s over the shift), lags its "
            "reference at the end."),
        values={"ratio_rate": up["ratio_rate"], "macro_slip": up["macro_slip"]})
    return rows, (claim,)
