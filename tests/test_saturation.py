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
    not before.  The linear loop model refuses it (it covers
    the sensors' feedforward only)."""
    sc = _scenario(feedforward_signal="T_e_est", sensors={"engine_torque_error": 0.15})
    law = build_law(sc, params, ideal=True)
    assert law.measured == RAW_SIGNALS and law.n_pre == 7 * law._n_buf + 2 + 21
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
    with pytest.raises(ParameterError, match="engine-torque estimate"):
        linear_preprocess(law)


def test_the_driveshaft_torque_observer_integrates_the_twist_rate(params):
    """``T_ds_est``: the law reads the wheel speed after its sensors; at rest it holds its
    state; a wheel speed ``dw`` below the output speed raises the observed torque by ``k_ds
    dt dw`` in one sample (the driveline's stiffness times the twist; to 1e-9 relative) and
    the clamping feedforward follows it."""
    sc = _scenario(feedforward_signal="T_ds_est")
    law = build_law(sc, params, ideal=True)
    assert law.measured == RAW_SIGNALS + ("omega_l",)
    n = law.n_pre
    o = n - 1  # the observer's state, last of the pre-processing's
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
    the servo's 15 N m hold about 31 kN): without protection the belt goes slack (the run
    stops) after macro slip; with the honoured torque request the run completes without
    macro slip, the load is limited for a while, the peak slip error stays within issue
    21's 0.6 percentage points, and the metrics say what the law did."""
    base = load_scenario(control_example_path("slip-load-step-r1"))
    sc = replace(base, duration=1.5, initial=replace(base.initial, F_s=25e3))
    plain = run_closed_loop(sc, params).metrics
    assert not plain["complete"] and plain["macro_slip"]
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
                                          ("T_e_est", "T_ds_est") for err in (-0.15, 0.15)]
    peak = {k: v[0].value for k, v in est[name].items()}
    assert peak["T_ds"] < min(peak["T_e_est -15 %"], peak["T_e_est +15 %"])
    res = SimpleNamespace(estimate=est, loop=LoopConfig.of(params))
    html = estimate_table(Context(params, tmp_path), res)
    assert "feedforward on T_e_est +15 %" in html and "20 ms late" in html
    assert (tmp_path / "control_estimate.csv").is_file()
