"""The paper's claims as data (`empact.reproduction`): every claim the report checks, with its
verdict; the deviations from the paper are pinned by key."""
import json

import pytest

from empact.report.sections import SECTIONS
from empact.reproduction.claims import Claim

#: Claims the model does not reproduce, with the reason in the claim's explanation (README,
#: "Paper inconsistencies"); an unexpected failure or pass changes this set.
KNOWN_DEVIATIONS = {
    # Sec. 2.2: the uncoupled sides' labels (15.5 Hz primary, 24.6 Hz secondary) fit no
    # parameter set of Fig. 7 together with Table 2; empact uses them swapped
    "fig9.labels",
    # Sec. 3: nu_r (the slip at the operating ratio) has a real RHP zero at every ratio (9-26
    # Hz, where the ratio's own response wins), not only at r_g = 0.5
    "nmp.nu_r",
    # Sec. 3 on Fig. 2: the 48 Hz chain mode, which the belt does not reach, keeps its linear
    # damping, and its zeros lie just below its pole, not above it
    "fig2.damping_48hz", "fig2.zeros_48hz",
    # Sec. 4 / Fig. 14: the phase of T_mp -> theta_mp rises near 1.8 Hz, not in 2-6 Hz (the
    # creep rate that would move it there makes the bench unstable), and the machine's
    # secondary servo clamps (flat T_ms -> theta_ms)
    "fig14.phase_rise", "fig14.slope.T_ms",
    # issue 21 (beyond the paper): the servo limits stop the shift below 1 /s on the bench
    # (the creep mode at LOW, the clamping for the dynamometer's inertia torque at OD)
    "control.shift-low-od", "control.shift_rate",
    # issue 34 (beyond the paper), WLTC 3b quasi-static: slip control on the hydraulic
    # reference saves 0.6 %, not 04CVT-39's 5 % (the clamping sits at its 3 kN floor most of
    # the cycle, the pump's leakage and friction at that pressure dominate); the reference
    # pump's shaft power is 04CVT-49's ideal V omega p over its 0.85 efficiency (+18 %)
    "cycle.slip_control_saving", "cycle.pump_power",
    # issue 33 item 3: with the reserve ahead and the honoured torque request one 50 % step
    # within the servo's capacity misses 0.6 pp: r_g = 0.5 at 5 kN (0.77 pp), a light-load
    # peak of the loop that neither protection addresses (the servo has room)
    "control.saturation",
    # issue 34, the car: LOW -> OD reaches 0.87 /s, not 1 /s (the engine's inertia torque at
    # LOW, the ratio loop lagging at low primary speed), faster than the bench's 0.33-0.43
    "control.vehicle-upshift", "cycle.car_shift_rate",
    # issue 33 item 4: the PI designed and tuned on the measured driveshaft torque's loop,
    # on the estimates' loops over the design family: the engine-torque estimate's stable at
    # every plant with a worst disk margin of 0.31 (light-load overdrive, 3 kN), the
    # observer's unstable at 3 plants (overdrive, 8 kN, where the feedforward gain steps up)
    "control.pi.estimate_family",
    # issue 33 item 6 with issue 34's car: the H-infinity controller, designed on the bench's
    # family, macro-slips in the car's two shifts (vehicle-upshift, vehicle-kickdown) where
    # the PI does not; on the car's design family with the upshift's loop 104 of 105 loops
    # are stable (the PI: 105, worst disk margin 0.524); every bench scenario's targets met
    "control.hinf.targets",
}


CHEAP = ("table1", "table2", "fig4-5", "fig6", "fig8", "fig9", "fig10", "fig13")


@pytest.fixture(scope="session")
def claims(full_report):
    """Every claim, as the one full report build wrote them (claims.json: the records of
    `empact.reproduction`, one per claim, with their section)."""
    res, out = full_report
    assert res.exit_code == 0, res.output
    return json.loads((out / "claims.json").read_text())


def test_every_section_checks_claims(claims):
    keys = [c["key"] for c in claims]
    assert len(keys) == len(set(keys))  # unique keys
    assert {c["section"] for c in claims} == {s.anchor for s in SECTIONS}


@pytest.mark.parametrize("anchor", CHEAP)
def test_records_come_from_the_analysis(params, claims, anchor):
    """The analysis functions return the records the report wrote (same keys, verdicts)."""
    sec = next(s for s in SECTIONS if s.anchor == anchor)
    records = sec.compute(params).claims
    assert all(isinstance(c, Claim) for c in records)
    written = [(c["key"], c["shown"]) for c in claims if c["section"] == anchor]
    assert [(c.key, c.shown) for c in records] == written


def test_regression_only_the_known_deviations_are_not_shown(claims):
    """Regression guard: the set of claims NOT shown is pinned (`KNOWN_DEVIATIONS`); a model
    change that makes one more fail, or one of them pass, must change the set on purpose."""
    failed = {c["key"] for c in claims if not c["shown"]}
    assert failed == KNOWN_DEVIATIONS
    # every NOT-shown claim says why
    assert all(c["explanation"] for c in claims if not c["shown"])


def test_claim_needs_an_explanation_when_not_shown():
    with pytest.raises(ValueError, match="no explanation"):
        Claim(key="x", source="s", claim="c", computed="v", shown=False)


def test_claims_record_the_slip_reading(claims):
    """Issue 20: the Fig. 11 / 12 / 13 claims carry the reading of the slips the paper does
    not state."""
    read = [c for c in claims if c["key"].startswith(("fig11.", "fig12a.", "fig12b.", "fig13."))]
    assert read and all("the paper gives none; read near the traction peak" in c["reading"]
                        for c in read)


@pytest.mark.slow
def test_drive_cycle_claims(params):
    """Issue 34's section: the anchors beside the results (SAE 04CVT-49: 0.63 / 1.27 / 3.17
    kW at 2000 rpm and 10 / 20 / 50 bar, the ideal V omega p of a 19 cc/rev pump; issue 34:
    about 11 kW of mean positive wheel power on WLTC 3b for 1300 kg)."""
    import math

    from numpy.testing import assert_allclose

    from empact.reproduction.drive_cycle import PUMP_ANCHORS, drive_cycle

    sec = drive_cycle(params)
    by = {c.key: c for c in sec.claims}
    h = params.hydraulic
    for (w, p, P), row in zip(PUMP_ANCHORS, sec.pump_rows):
        # the anchor is the ideal pump (published to 2-3 digits: 0.633 kW is "0.63")
        assert_allclose(h.displacement * w * p, P, rtol=1e-2)
        # the reference pump's shaft power, V omega p / eta_hm (empact.actuation_energy notes;
        # the table rounds to 1 W)
        assert_allclose(row[2] * 1e3, h.displacement * w * p / h.eta_hm, atol=0.5)
    assert by["cycle.mean_wheel_power"].shown
    assert_allclose(by["cycle.mean_wheel_power"].values["mean_wheel_power"], 11e3, rtol=0.15)
    assert by["cycle.electromechanical_saving"].shown
    assert not by["cycle.slip_control_saving"].shown
    assert by["cycle.slip_control_saving"].values["saving_hydraulic"] > 0
    assert math.isfinite(by["cycle.slip_control_saving"].values["saving_servo"])
    # the dynamic runs (issue 34, item 4): the variator's losses agree within 10 % with the
    # quasi-static cycle's over the same stretches; the slip strategy neither macro-slips
    # nor lets the belt go slack; the saving keeps its sign
    assert by["cycle.dynamic_loss_agreement"].shown
    assert by["cycle.dynamic_macro_slip"].values["slip"] == {"macro_slip": False,
                                                             "belt_slack": False}
    # every strategy: no macro slip or slack, within the WLTP's 2 km/h (the safety-factor
    # strategies since their clamping holds through a tip-out and their ratio loop is
    # scheduled at their own clamping: 1.0 pp of slip reserve, 1.21 km/h, measured)
    assert by["cycle.dynamic_macro_slip"].shown and by["cycle.dynamic_speed"].shown
    assert by["cycle.dynamic_saving"].shown
    assert sec.dynamic is not None and sec.dynamic.runs["slip"].complete


def test_energy_saving_sign_at_a_band_end_is_recomputed(params, claims):
    """Issue 32: the claim ``control.clamping_saving`` states the energy saving's sign over
    the loss and servo parameters' plausible bands; at one band end (``losses.lambda_F`` at
    its low end, 1.5e-3) the saving it records equals a recomputation of the same two runs
    (the same code: 1e-12), and its sentence names that end among the flips exactly when a
    scenario's saving changes sign there."""
    from empact.control.closed_loop import (
        control_example_path,
        run_closed_loop,
        safety_factor_twin,
    )
    from empact.nonlinear.scenario import load_scenario
    from empact.params import parameter_sources
    from empact.reproduction.control import _energy_saving

    claim = next(c for c in claims if c["key"] == "control.clamping_saving")
    low = float(parameter_sources()["losses.lambda_F"]["band"][0])
    p = params.from_dotted({"losses.lambda_F": low})
    n = "slip-load-step-r1"
    sc = load_scenario(control_example_path(n))
    got = _energy_saving((run_closed_loop(sc, p),
                          run_closed_loop(safety_factor_twin(sc, p, "ratio-blind"), p)), p)
    stated = claim["values"][f"{n}@energy@losses.lambda_F={low:g}"]
    assert got == pytest.approx(stated, rel=1e-12, abs=1e-12)
    v = claim["values"]
    names = [k.split("@")[0] for k in v if k.endswith(f"@energy@losses.lambda_F={low:g}")]
    flips = [m for m in names
             if (v[f"{m}@energy@losses.lambda_F={low:g}"] > 0) != (v[f"{m}@energy"] > 0)]
    assert (f"losses.lambda_F = {low:g} (" in claim["computed"]) == bool(flips)
    if n in flips:
        assert f"{n} {100 * got:+.1f} %" in claim["computed"]


def test_fair_saving_claim(claims):
    """Issue 33 item 7: `control.fair_saving` is shown (slip control never macro-slips under
    the traction errors, the open loop at its reserve does at some error, both safety
    factors clamp more at the exact estimate); its values record each case's macro slip
    (1.0 / 0.0): slip control's are all 0 and the open loop's at -10 % all 1 (measured:
    every ratio; the machine cannot hold its clamping)."""
    by = {c["key"]: c for c in claims}
    c = by["control.fair_saving"]
    assert c["shown"]
    v = c["values"]
    slip = [x for k, x in v.items() if k.endswith("@slip control (tau = 0.9)")]
    open_10 = [x for k, x in v.items() if "@-0.1@open loop" in k]
    assert len(slip) == 9 and not any(slip)
    assert len(open_10) == 3 and all(open_10)


def test_estimate_family_claim_records_both_loops(claims):
    """Issue 33 item 4: `control.pi.estimate_family` checks the shipped PI on the loop with
    the feedforward on the engine-torque estimate and on the driveshaft-torque observer
    over the 105-point design family (the loop model covers both since this round);
    measured: the estimate's 105 stable, worst disk margin 0.307, the observer's 102 (its
    worst margin 0); the claim is not shown while either is short of the design's 0.5."""
    c = next(c for c in claims if c["key"] == "control.pi.estimate_family")
    v = c["values"]
    for sig in ("T_e_est", "T_ds_est"):
        assert v[f"{sig}.points"] == 105
    ok = all(v[f"{s}.stable"] == 105 and v[f"{s}.disk_margin"] >= 0.5
             for s in ("T_e_est", "T_ds_est"))
    assert c["shown"] == ok
