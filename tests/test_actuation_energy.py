"""The servos' electrical power, their transmissions and the hydraulic reference
(empact.actuation_energy), against closed forms and the published pump figures."""
import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from empact.actuation_energy import (
    PRESSURE_ANGLE,
    SERVO_TERMS,
    hydraulic_power,
    line_pressure,
    motor_power,
    servo_power,
    thread_efficiency,
    transmissions,
)
from empact.errors import ParameterError
from empact.hardware import HydraulicParams
from empact.params import default_params, describe_parameters


def test_thread_efficiency_is_the_closed_form_of_lead_and_friction_angles():
    """A screw (phi_n = 0): forward tan(g) / tan(g + rho), backward tan(g - rho) / tan(g),
    rho = atan(mu) (the textbook power-screw forms), to 1e-12."""
    g = np.radians([1.0, 5.0, 16.7, 30.0])
    for mu in (0.005, 0.05, 0.15):
        rho = math.atan(mu)
        f, b = thread_efficiency(g, mu)
        assert_allclose(f, np.tan(g) / np.tan(g + rho), rtol=1e-12, atol=0)
        assert_allclose(b, np.tan(g - rho) / np.tan(g), rtol=1e-12, atol=1e-15)


def test_self_locking_exactly_when_the_lead_is_below_the_friction_angle():
    """The backward efficiency changes sign where tan(lead) = mu / cos(phi_n) (the worm's
    friction angle atan(mu / cos(phi_n))): below it the worm self-locks."""
    mu = 0.1
    edge = math.atan(mu / math.cos(PRESSURE_ANGLE))
    for lead in (0.5 * edge, 0.99 * edge, 1.01 * edge, 2 * edge):
        f, b = thread_efficiency(lead, mu, PRESSURE_ANGLE)
        assert 0 < f < 1
        assert (b <= 0) == (math.tan(lead) <= mu / math.cos(PRESSURE_ANGLE)), lead


def test_the_shipped_worm_back_drives():
    """The shipped worm (lead atan(3/10) = 16.7 deg, mu 0.05, phi_n 20 deg) is not
    self-locking: its friction angle is 3.05 deg; even at a static mu of 0.15 it is
    9.1 deg.  So the primary servo holds the ratio with current."""
    p = default_params()
    tr = transmissions(p)
    sv = p.servo
    assert tr.worm_self_locking == (math.tan(sv.worm_lead)
                                    <= sv.worm_mu / math.cos(PRESSURE_ANGLE))
    assert not tr.worm_self_locking
    assert math.degrees(tr.worm_friction_angle) == pytest.approx(3.046, abs=1e-3)
    assert math.atan(0.15 / math.cos(PRESSURE_ANGLE)) < sv.worm_lead
    # each path: the product of its stages (worm or chain, epicyclic set, screw)
    assert tr.primary[0] == pytest.approx(tr.worm[0] * sv.eta_epicyclic * tr.screw[0],
                                          rel=1e-12)
    assert tr.secondary[1] == pytest.approx(sv.eta_chain * sv.eta_epicyclic * tr.screw[1],
                                            rel=1e-12)


def test_holding_torque_costs_copper_loss():
    """A servo holding 8 N m at rest draws (T / k_m)^2 in its windings (the issue's 7.6-8.5
    N m of the secondary servo), and the drive's share (1 / eta - 1) of it; exact."""
    p = default_params()
    terms = servo_power(p, T_mp=0.0, T_ms=8.0, omega_mp=0.0, omega_ms=0.0)
    k_m, eta = p.servo.k_m_ms, p.servo.eta_drive
    assert terms["copper_ms"] == pytest.approx((8.0 / k_m) ** 2, rel=1e-12)
    assert terms["drive_ms"] == pytest.approx((1 / eta - 1) * (8.0 / k_m) ** 2, rel=1e-12)
    assert terms["mechanical_ms"] == 0.0 and terms["gear_ms"] == 0.0
    assert 170 < terms["copper_ms"] < 180  # 177.8 W at the shipped 0.6 N m/sqrt(W)


def test_motor_power_driving_back_driven_and_self_locking():
    """Quasi-static billing of a transmission of efficiencies (0.8, 0.5) and a self-locking
    one (0.8, -0.2), by hand: T = 2 N m, omega = +-10 rad/s, k_m = 1, drive 0.9."""
    d = motor_power(2.0, 10.0, 1.0, (0.8, 0.5), 0.9)   # the servo drives: T_m = 2 / 0.8
    assert d["mechanical"] == pytest.approx(25.0, rel=1e-12)
    assert d["gear"] == pytest.approx(5.0, rel=1e-12)
    assert d["copper"] == pytest.approx(2.5 ** 2, rel=1e-12)
    assert d["drive"] == pytest.approx((1 / 0.9 - 1) * (25.0 + 6.25), rel=1e-12)
    b = motor_power(2.0, -10.0, 1.0, (0.8, 0.5), 0.9)  # driven back: T_m = 0.5 * 2
    assert b["mechanical"] == pytest.approx(-10.0, rel=1e-12)
    assert b["gear"] == pytest.approx(10.0, rel=1e-12)
    assert b["drive"] == pytest.approx(0.1 * 9.0, rel=1e-12)  # regenerates 9 W: 10 % lost
    s = motor_power(2.0, -10.0, 1.0, (0.8, -0.2), 0.9)  # self-locking: the servo must drive
    assert s["mechanical"] == pytest.approx(4.0, rel=1e-12)
    assert s["gear"] == pytest.approx(24.0, rel=1e-12)
    h = motor_power(2.0, 0.0, 1.0, (0.8, -0.2), 0.9)    # and holds for nothing
    assert all(h[k] == 0.0 for k in SERVO_TERMS)
    for terms in (d, b, s, h):
        assert all(terms[k] >= 0 for k in ("gear", "copper", "drive"))


def test_line_pressure_and_the_pump_of_04CVT_49():
    """SAE 04CVT-49: a 19 cc/rev pump at 2000 rpm delivers 0.63 / 1.27 / 3.17 kW of hydraulic
    power at 10 / 20 / 50 bar (V n p).  The pump's terms sum to V omega p / eta_hm; times
    eta_hm that is the published hydraulic power (to its rounding, 0.005 kW)."""
    h = HydraulicParams(p_margin=0.0, A_p=1e-2, A_s=5e-3)
    omega = 2000 * 2 * math.pi / 60
    for bar, kw in ((10, 0.63), (20, 1.27), (50, 3.17)):
        p = bar * 1e5
        assert_allclose(line_pressure(h, 0.5 * p * 1e-2, p * 5e-3), p, rtol=1e-12, atol=0)
        terms = hydraulic_power(h, 0.0, p * 5e-3, omega)
        shaft = sum(terms.values())
        assert shaft == pytest.approx(19e-6 * 2000 / 60 * p / h.eta_hm, rel=1e-12)
        assert shaft * h.eta_hm / 1e3 == pytest.approx(kw, abs=0.005)  # 2 decimals
        assert all(v >= 0 for v in terms.values())
    # the margin is added to the larger cylinder's need
    h2 = HydraulicParams()
    assert_allclose(line_pressure(h2, 3e4, 1e4), 3e4 / h2.A_p + h2.p_margin, rtol=1e-12,
                    atol=0)


def test_shift_flow_and_a_pump_too_small():
    """Filling a cylinder at 0.01 m/s takes A v of the flow; emptying takes none; a demand
    above the pump's delivery shows as negative relief."""
    h = HydraulicParams()
    still = hydraulic_power(h, 1e4, 1e4, 300.0)
    fill = hydraulic_power(h, 1e4, 1e4, 300.0, fill_p=0.01, fill_s=-0.01)
    p = line_pressure(h, 1e4, 1e4)
    assert fill["shift"] == pytest.approx(h.A_p * 0.01 * p, rel=1e-12)
    assert sum(fill.values()) == pytest.approx(sum(still.values()), rel=1e-12)
    short = hydraulic_power(h, 1e4, 1e4, 300.0, fill_p=1.0)
    assert short["relief"] < 0


def test_the_new_parameters_are_checked_and_sourced():
    """[servo] and [hydraulic] keys: one-line errors naming the field; each has a source and
    a band that holds the shipped value."""
    with pytest.raises(ParameterError, match=r"hydraulic\.eta_vol = 1\.5"):
        HydraulicParams(eta_vol=1.5)
    with pytest.raises(ParameterError, match=r"servo\.k_m_ms"):
        default_params().from_dotted({"servo.k_m_ms": 0.0})
    infos = {i.name: i for i in describe_parameters()}
    for name in ("servo.k_m_mp", "servo.k_m_ms", "servo.eta_drive", "servo.overload",
                 "servo.worm_lead", "servo.worm_mu", "servo.screw_d", "servo.screw_mu",
                 "servo.eta_chain", "servo.eta_epicyclic", "servo.omega_hold",
                 "hydraulic.displacement", "hydraulic.eta_vol", "hydraulic.eta_hm",
                 "hydraulic.c_leak", "hydraulic.A_p", "hydraulic.A_s", "hydraulic.p_margin",
                 "hydraulic.pump_ratio"):
        info = infos[name]
        assert info.source, name
        assert info.band[0] <= info.value <= info.band[1], name


def test_a_simulation_billed_by_term():
    """servo-torque-steps (0.5 s): each energy is the trapezoidal integral of its power term
    (1e-12), the servos' electrical energy their sum; the run starts holding, so its mean
    electrical power is at least the secondary servo's copper loss at its smallest torque
    magnitude; the hydraulic reference's pump runs at V omega p / eta_hm over the run."""
    from empact.actuation_energy import actuation_energy
    from empact.nonlinear.scenario import example_path, load_scenario
    from empact.nonlinear.simulation import run_scenario

    p = default_params()
    res = run_scenario(load_scenario(example_path("servo-torque-steps")), p)
    assert res.complete
    e = actuation_energy(res, p)
    t = res.t
    terms = servo_power(p, res.output("T_mp_act"), res.output("T_ms_act"),
                        res.output("omega_mp"), res.output("omega_ms"))
    for k, v in terms.items():
        assert e.energy[k] == pytest.approx(np.trapezoid(v, t), rel=1e-12, abs=1e-12), k
    assert e.energy["servo_electrical"] == pytest.approx(sum(e.energy[k] for k in terms),
                                                         rel=1e-12)
    assert e.duration == pytest.approx(0.5, rel=1e-9)
    T_ms_min = np.abs(res.output("T_ms_act")).min()
    assert e.mean_power["servo_electrical"] > (T_ms_min / p.servo.k_m_ms) ** 2
    assert all(e.energy[f"{k}_{s}"] >= 0 for k in ("gear", "copper", "drive")
               for s in ("mp", "ms"))
    h = p.hydraulic
    line = line_pressure(h, res.output("F_p"), res.output("F_s"))
    shaft = h.displacement * h.pump_ratio * res.output("omega_p") * line / h.eta_hm
    assert e.hydraulic["pump"] == pytest.approx(np.trapezoid(shaft, t), rel=1e-9)
    assert e.continuous_torque["ms"] == pytest.approx(p.servo.T_ms_max / p.servo.overload,
                                                      rel=1e-12)
