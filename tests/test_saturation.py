"""Issue 33 items 3 and 4: the loop law's protection of a saturating secondary servo (the
torque request, honoured by the bench's load torque) and its clamping feedforward on an
engine-torque estimate (late and off) instead of the driveshaft-torque sensor."""
from dataclasses import replace

import numpy as np
import pytest

from empact.control.closed_loop import build_law, control_example_path, run_closed_loop
from empact.control.law import RAW_SIGNALS
from empact.control.loop import linear_preprocess
from empact.errors import ParameterError
from empact.nonlinear.scenario import load_scenario, scenario_from_dict


def _scenario(name="slip-load-step-r1", sensors=None, **spec):
    sc = load_scenario(control_example_path(name))
    return replace(sc, controller=replace(sc.controller, **spec),
                   sensors={**sc.sensors, **(sensors or {})})


@pytest.mark.parametrize("controller, sensors, message", [
    ({"torque_request": "yes"}, {}, "controller.torque_request = 'yes'"),
    ({"torque_request": "honoured", "torque_request_margin": 0.95}, {},
     "controller.torque_request_margin = 0.95"),
    ({"torque_request": "honoured", "limits": False}, {},
     "controller.torque_request = 'honoured': needs the servo limits"),
    ({"feedforward_signal": "T_e"}, {}, "controller.feedforward_signal = 'T_e'"),
    ({}, {"engine_torque_error": 0.8}, "sensors.engine_torque_error = 0.8"),
    ({}, {"engine_torque_delay": -0.01}, "sensors.engine_torque_delay = -0.01"),
    ({"reserve_ahead_headroom": 0.0}, {}, "controller.reserve_ahead_headroom = 0"),
    ({"reserve_ahead_tau": 1.2}, {}, "controller.reserve_ahead_tau = 1.2"),
    ({"slip_guard_gain": -1}, {}, "controller.slip_guard_gain = -1"),
    ({"slip_guard_release": 0}, {}, "controller.slip_guard_release = 0"),
    ({"slip_guard": True, "feedforward": False}, {},
     "controller.slip_guard = true: needs the clamping feedforward"),
    ({"reserve_ahead": "yes"}, {}, "controller.reserve_ahead"),
])
def test_bad_saturation_or_estimate_input_is_one_line(controller, sensors, message):
    data = {"scenario": {"duration": 1.0}, "model": {"drive": "speed", "load": "torque"},
            "initial": {"r_g": 1.0, "omega_p": 300.0, "tau": 0.9, "F_s": 1e4},
            "controller": {"file": "shipped:pi", **controller}, "sensors": sensors}
    with pytest.raises(ParameterError) as err:
        scenario_from_dict(data, "s.toml")
    text = str(err.value)
    assert message in text and "\n" not in text


def test_the_engine_torque_estimate_is_late_and_off(params):
    """The feedforward on the estimate (the torque source's, the bench's load motor's,
    20 ms late at 1 kHz, +15 %): at rest the law's pre-processing holds its state (its
    buffer starts settled); a step of the source's torque reaches the feedforward's filter
    exactly 20 samples later, by ``(1 - alpha) (ff(T_0 + 1.15 dT) - ff(T_0))`` with ``T_0``
    the estimate at rest (the feedforward's law: the gain table schedules on the whole
    estimated torque, so the step is not ``ff(1.15 dT)``; to 1e-9 relative, rounding), and
    not before.  The linear loop model covers it: the delay line's first entry takes the
    torque source's signal (1 to 1e-9) and the feedforward's filter does not (0)."""
    sc = _scenario(feedforward_signal="T_e_est", sensors={"engine_torque_error": 0.15})
    law = build_law(sc, params, ideal=True)
    # the buffers, the two filters, the 21-sample delay line, the (shipped) slip guard
    assert law.measured == RAW_SIGNALS and law.n_pre == 7 * law._n_buf + 2 + 21 + 1
    n = law.n_pre
    s0, raw0 = law.z0[:n], law.raw0
    s1, _, u_rest, _ = law.preprocess(s0, raw0, 0, ideal=True)
    np.testing.assert_allclose(s1, s0, rtol=1e-12, atol=0)
    nb = len(RAW_SIGNALS) * law._n_buf  # the feedforward filter's state
    raw = raw0.copy()
    dT = 20.0
    raw[RAW_SIGNALS.index("T_l_act")] += dT
    s = s0
    for k in range(20):
        s, _, u, _ = law.preprocess(s, raw, 0, ideal=True)
        assert s[nb] == s0[nb], k
    s, _, u, _ = law.preprocess(s, raw, 0, ideal=True)
    r = raw0[0]
    T0, mu = law._ff_torque0(), law.refs.mu[0]  # the estimate at rest, 1.15 T_l
    np.testing.assert_allclose(T0, 1.15 * raw0[RAW_SIGNALS.index("T_l_act")], rtol=1e-15,
                               atol=0)
    want = (1 - law._alpha_ff) * (law._ff_force(T0 + 1.15 * dT, r, mu)
                                  - law._ff_force(T0, r, mu))
    np.testing.assert_allclose(s[nb] - s0[nb], want, rtol=1e-9, atol=0)
    lp = linear_preprocess(law)
    j = RAW_SIGNALS.index("T_l_act")
    assert lp["Sy"][nb + 2, j] == pytest.approx(1.0, rel=1e-9)
    assert lp["Sy"][nb, j] == 0.0


def test_the_driveshaft_torque_observer_integrates_the_twist_rate(params):
    """``T_ds_est``: the law reads the wheel speed after its sensors; at rest it holds its
    state; a wheel speed ``dw`` below the output speed raises the observed torque by ``k_ds
    dt dw`` in one sample (the driveline's stiffness times the twist; to 1e-9 relative) and
    the clamping feedforward follows it."""
    sc = _scenario(feedforward_signal="T_ds_est")
    law = build_law(sc, params, ideal=True)
    assert law.measured == RAW_SIGNALS + ("omega_l",)
    n = law.n_pre
    o = n - 2  # the observer's state, before the (shipped) slip guard's
    s0, raw0 = law.z0[:n], law.raw0
    s1, _, _, _ = law.preprocess(s0, raw0, 0, ideal=True)
    np.testing.assert_allclose(s1, s0, rtol=1e-12, atol=0)
    raw = raw0.copy()
    dw = 0.01
    raw[-1] -= dw
    s1, _, _, _ = law.preprocess(s0, raw, 0, ideal=True)
    k_ds = params.driveline.k_ds
    np.testing.assert_allclose(s1[o] - s0[o], k_ds * law.dt * dw, rtol=1e-9, atol=0)
    nb = len(RAW_SIGNALS) * law._n_buf
    assert s1[nb] > s0[nb]  # the feedforward's filter moves with it


def test_the_torque_request_is_what_the_servo_can_clamp(params):
    """The request is the secondary-shaft torque the servo's torque limit less its margin
    clamps for at the set-point's traction coefficient, ``F_cap 2 mu* R_s / cos(beta)``,
    ``F_cap = (+-(1 - margin) T_ms_max - T_0) / tpf``; honoured, the bench's load torque is
    its demand below the request and the request above it (to 1e-12 relative)."""
    sc = replace(_scenario(torque_request="honoured"),
                 initial=replace(load_scenario(control_example_path(
                     "slip-load-step-r1")).initial, F_s=20e3))
    law = build_law(sc, params)
    assert law.commands == ("T_mp", "T_ms", "T_l")
    lim = law.config.limits
    T_0 = law.u0[1] - law._tpf * law.point["F_s"]
    keep = 1 - law.config.spec.torque_request_margin
    assert keep == 0.75  # the default
    F_cap = (np.copysign(keep * lim.T_ms_max, law._tpf) - T_0) / law._tpf
    np.testing.assert_allclose(law.servo_capacity, F_cap, rtol=1e-12, atol=0)
    assert 20e3 < F_cap < 25e3 < lim.T_ms_max / abs(law._tpf)
    R_s = law._R_s(law.raw0[0])
    T_req = F_cap * 2 * law.refs.mu[0] * R_s / law._cosb
    _, u = law.update(law.z0, law.raw0, 0)
    np.testing.assert_allclose(law.request_trace[0, 0], T_req, rtol=1e-12, atol=0)
    np.testing.assert_allclose(u[2], law.point["T_l"], rtol=1e-12, atol=0)  # below it
    k_after = int(round(0.6 / law.dt))  # after the 50 % step: beyond the request
    assert law._load[k_after] > T_req
    _, u = law.update(law.z0, law.raw0, k_after)
    np.testing.assert_allclose(u[2], T_req, rtol=1e-12, atol=0)


def test_a_saturating_servo_requests_torque_before_the_belt_goes(params):
    """25 kN and a 50 % load step at r_g = 1 (the issue's case: the step needs about 39 kN,
    the servo's 15 N m hold about 31 kN): without the request the belt macro-slips (as
    shipped, the slip guard holding its clamping, it no longer goes slack; without the guard
    the run stopped slack at 0.74-0.80 s); with the honoured torque request it completes without
    macro slip, the load is limited for a while, the peak slip error stays within issue
    21's 0.6 percentage points, and the metrics say what the law did."""
    base = load_scenario(control_example_path("slip-load-step-r1"))
    sc = replace(base, duration=1.5, initial=replace(base.initial, F_s=25e3))
    plain = run_closed_loop(sc, params).metrics
    assert plain["complete"] and plain["macro_slip"] and plain["min_clamping_force"] > 0
    assert "torque_request_min" not in plain
    prot = run_closed_loop(replace(sc, controller=replace(
        sc.controller, torque_request="honoured")), params).metrics
    assert prot["complete"] and not prot["macro_slip"]
    assert prot["peak_slip_error"] <= 0.006
    assert prot["torque_request_honoured"] and prot["torque_limited_time"] > 0.5
    assert prot["torque_reduction"] > 0 and prot["peak_T_ms"] <= 15.0


def test_the_report_shows_the_targets_with_the_torque_estimate(params, tmp_path):
    """`estimate_targets` runs a scenario with the feedforward on the estimate at both
    errors next to its checks as shipped, and `estimate_table` shows one row per target
    with a column per feedforward (its CSV beside): here the small step at r_g = 2, whose
    peak slip error with the estimate is larger than with the driveshaft torque (the
    estimate misses the driveline's swing) and within its 0.2 pp either way (measured
    0.18-0.25 pp: the +15 % estimate misses it)."""
    from types import SimpleNamespace

    from empact.control.closed_loop import check_targets
    from empact.control.law import LoopConfig
    from empact.report.context import Context
    from empact.report.control import estimate_table
    from empact.reproduction.control import estimate_label, estimate_targets

    name = "slip-small-step-r2"
    sc = load_scenario(control_example_path(name))
    shipped = check_targets(run_closed_loop(sc, params).metrics, sc.targets)
    est = estimate_targets(params, {name: sc}, {name: shipped})
    assert list(est[name]) == ["T_ds"] + [estimate_label(sig, err) for sig in
                                          ("T_e_est", "T_ds_est") for err in (-0.15, 0.0,
                                                                               0.15)]
    peak = {k: v[0].value for k, v in est[name].items()}
    assert peak["T_ds"] < min(peak["T_e_est -15 %"], peak["T_e_est +15 %"])
    res = SimpleNamespace(estimate=est, loop=LoopConfig.of(params))
    html = estimate_table(Context(params, tmp_path), res)
    assert "feedforward on T_e_est +15 %" in html and "20 ms late" in html
    assert (tmp_path / "control_estimate.csv").is_file()


def _protected(F_s=15e3, r_g=0.5, **spec):
    name = "slip-load-step-r0.5" if r_g < 0.75 else "slip-load-step-r1"
    sc = _scenario(name, **{"reserve_ahead": True, "slip_guard": True, **spec})
    return replace(sc, duration=1.5, initial=replace(sc.initial, F_s=F_s, r_g=r_g))


def test_the_reserve_ahead_moves_the_setpoint_as_the_headroom_shrinks(params):
    """The set-point (`LoopLaw.setpoint`, the compiled sample's law) is the reference's while
    the servo's headroom ``h = 1 - F_full / F_max`` is above ``h_0``; below it the slip moves
    towards the lowest set-point's by ``w = (h_0 - h) / h_0``, and never past the clamping
    the servo holds (``w <= mu* h / (mu* - mu_lo)``: at the servo's capacity, none); the
    compiled pre-processing runs that set-point (to 1e-12 relative: the same arithmetic)."""
    law = build_law(_protected(F_s=10e3), params, ideal=True)
    spec = law.config.spec
    assert law._F_max == pytest.approx(15.0 / 0.4775e-3, rel=1e-3)  # 15 N m: about 31.4 kN
    r = float(law.raw0[0])
    slip0, mu0 = float(law.refs.slip[0]), float(law.refs.mu[0])
    slip_lo, mu_lo = float(law.refs.slip_lo[0]), float(law.refs.mu_lo[0])
    assert slip_lo < slip0 and mu_lo < mu0
    # the torque whose full clamping leaves the headroom h
    per_N = law._cosb / (2 * spec.traction_error * mu0 * law._R_s(r))  # F_full per N m

    def torque(h):
        return (1 - h) * law._F_max / per_N

    assert law.setpoint(torque(spec.reserve_ahead_headroom + 0.05), r) == (slip0, mu0)
    h = 0.5 * spec.reserve_ahead_headroom
    w = min(0.5, mu0 * h / (mu0 - mu_lo))
    got = law.setpoint(torque(h), r)
    np.testing.assert_allclose(got, (slip0 + w * (slip_lo - slip0), mu0 + w * (mu_lo - mu0)),
                               rtol=1e-9, atol=0)
    assert law.setpoint(torque(0.0), r) == (slip0, mu0)  # no headroom: nothing to raise
    # the compiled law's set-point at that torque (its trace of the sample)
    n = law.n_pre
    raw = law.raw0.copy()
    raw[RAW_SIGNALS.index("T_ds")] = torque(h)
    s = law.z0[:n]
    for _ in range(law._n_buf):  # the buffers full of the new torque
        s, _, _, _ = law.preprocess(s, raw, 0, ideal=True)
    np.testing.assert_allclose(law.setpoint_trace[0, 0], got[0], rtol=1e-12, atol=0)


def test_the_slip_guard_clamps_when_the_slip_runs_away(params):
    """The guard adds nothing while the measured slip stays within its margin of the
    set-point; past it, its clamping is ``gain (y / nu* - 1 - margin)`` of the set-point's
    ``F_full`` at once (the feedforward's filter moves with it), held as a force - the
    driveshaft torque's swings do not move it (issue 33 item 8: a share of the live torque
    pumped the shuffle) - and released by ``exp(-dt / release)`` a sample (to 1e-9
    relative), applied only within the servo's headroom."""
    law = build_law(_protected(F_s=10e3), params, ideal=True)
    spec = law.config.spec
    n, og, nb = law.n_pre, law.n_pre - 1, 7 * law._n_buf
    s0, raw0 = law.z0[:n], law.raw0.copy()
    nu_ref = float(law.refs.slip[0])

    def raw_at(slip, T_ds=None):
        raw = raw0.copy()
        raw[2] = raw[0] * raw[1] * (1 - slip)
        if T_ds is not None:
            raw[3] = T_ds
        return raw

    def settled(raw, s=None):
        s = s0 if s is None else s
        for _ in range(law._n_buf):
            s, _, _, meas = law.preprocess(s, raw, 0, ideal=True)
        return s, 1 - meas[2] / (meas[0] * meas[1])

    s, y = settled(raw_at(nu_ref * (1 + 0.5 * spec.slip_guard_margin)))
    assert s[og] == 0.0
    s, y = settled(raw_at(nu_ref * (1 + spec.slip_guard_margin + 0.2)))
    g = spec.slip_guard_gain * (y / nu_ref - 1 - spec.slip_guard_margin)
    np.testing.assert_allclose(law.setpoint_trace[0, 1], g, rtol=1e-9, atol=0)
    assert s[og] > 1e3 and s[nb] > s0[nb]  # a force [N]; the feedforward's filter moves
    s, y = settled(raw_at(nu_ref), s)  # the slip back within the margin: releasing
    held = s[og]
    assert 0 < held
    decay = np.exp(-law.dt / spec.slip_guard_release)
    for T_ds in (0.5 * raw0[3], 2.0 * raw0[3]):
        s1, _, _, _ = law.preprocess(s, raw_at(nu_ref, T_ds), 0, ideal=True)
        np.testing.assert_allclose(s1[og], decay * held, rtol=1e-12, atol=0)
    # never past the servo: with its last torque at its limit the guard holds its clamping
    # and applies none of it (a demand beyond the servo would unwind the controller)
    law._wk.u[1] = law._c.F_max * law._c.tpf
    s1, _, _, _ = law.preprocess(s, raw_at(nu_ref), 0, ideal=True)
    np.testing.assert_allclose(s1[og], decay * held, rtol=1e-12, atol=0)
    assert law.setpoint_trace[0, 1] == 0.0


def test_the_loop_model_is_the_law_with_its_protections_inactive_at_rest(params):
    """At a trim whose headroom is above ``h_0`` (10 kN) the reserve ahead and the guard add
    no coupling: the linearised pre-processing equals the unprotected law's on the common
    states (to 1e-9 of each matrix's largest entry); the guard's state is decoupled (it
    feeds only itself, by its release factor)."""
    plain = _scenario("slip-load-step-r1", slip_guard=False)
    prot = _scenario("slip-load-step-r1", reserve_ahead=True, slip_guard=True)
    a = linear_preprocess(build_law(plain, params, ideal=True))
    b = linear_preprocess(build_law(prot, params, ideal=True))
    n = a["Sz"].shape[0]
    assert b["Sz"].shape[0] == n + 1
    for k in a:
        got = b[k][:n] if k[0] == "S" else b[k]
        got = got[:, :n] if k[1] == "z" else got
        np.testing.assert_allclose(got, a[k], rtol=0,
                                   atol=1e-9 * max(np.abs(a[k]).max(), 1e-300))
    law = build_law(prot, params, ideal=True)
    decay = np.exp(-law.dt / law.config.spec.slip_guard_release)
    np.testing.assert_allclose(b["Sz"][n, n], decay, rtol=1e-6, atol=0)
    assert not np.any(b["Sz"][n, :n]) and not np.any(b["Sy"][n]) and not np.any(b["Ez"][:, n])


@pytest.mark.slow
def test_the_protections_meet_the_peak_within_the_servo_and_report_what_they_did(params):
    """Issue 33 item 3 at the points the sweep found hardest (bench notes in the CHANGELOG):
    r_g = 0.5 at 15 kN with a 50 % step peaks at 0.624 pp unprotected (target 0.6 pp); with
    the reserve ahead and the guard it meets 0.6 pp, and the run says what the law did (the
    set-point moved, the lowest below the reference's)."""
    sc = _protected()
    plain = run_closed_loop(replace(sc, controller=replace(
        sc.controller, reserve_ahead=False, slip_guard=False)), params).metrics
    assert plain["peak_slip_error"] > 0.006 and "slip_setpoint_lowest" not in plain
    prot = run_closed_loop(sc, params).metrics
    assert prot["complete"] and not prot["macro_slip"]
    assert prot["peak_slip_error"] <= 0.006
    assert prot["reserve_ahead_time"] > 0 and prot["slip_setpoint_lowest"] < prot["slip_setpoint"]
    assert np.isfinite(prot["guard_peak"]) and prot["guard_time"] >= 0


@pytest.mark.slow
def test_the_fair_saving_compares_equal_reserves_under_traction_error(params):
    """`fair_saving` at r_g = 1 with the machine's traction 20 % below the estimate: slip
    control's slip loop finds the machine's torque ratio (no macro slip), the open-loop
    clamping at the same reserve cannot hold the load (its start has no steady state), and
    at the exact estimate the open loop at slip control's reserve clamps within a few
    percent of slip control while the safety factor 1.3 clamps more."""
    from empact.reproduction.control import FAIR_STRATEGIES, fair_saving

    rows = fair_saving(params, ("slip-load-step-r1",), (0.0, -0.2))
    short = dict(zip(FAIR_STRATEGIES, ("slip", "blind", "aware", "open")))
    by = {(r["traction_error"], short[r["strategy"]]): r for r in rows}
    assert len(rows) == 8
    assert not by[(0.0, "slip")]["macro_slip"] and not by[(-0.2, "slip")]["macro_slip"]
    assert by[(-0.2, "open")]["macro_slip"]
    ol = by[(0.0, "open")]["force_over_slip_control"]
    assert 0.9 < ol < 1.1
    assert by[(0.0, "aware")]["force_over_slip_control"] > ol
    for r in rows:
        if r["start"] == "trimmed":
            assert r["total"] > r["variator_losses_total"] > 0 and r["actuation"] > 0


@pytest.mark.slow
def test_the_sweep_beyond_the_capacity_keeps_the_belt(params):
    """`saturation_sweep` at 25 kN and r_g = 1 (a 50 % step needs about 39 kN, the servo
    holds about 31 kN): beyond the capacity; as shipped (the slip guard on) the belt
    macro-slips, protected (reserve ahead, honoured request) it does not and the load is
    cut."""
    from empact.reproduction.control import saturation_sweep

    (row,) = saturation_sweep(params, {"r_g": (1.0,), "F_s": (25e3,)})
    assert not row["within_capacity"]
    assert row["plain"]["macro_slip"] and not row["plain"]["belt_slack"]
    assert not row["protected"]["belt_slack"] and not row["protected"]["macro_slip"]
    assert row["protected"]["peak_slip_error"] <= 0.006 and row["torque_reduction"] > 0
