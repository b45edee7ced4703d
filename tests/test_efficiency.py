"""Steady-state efficiency maps by clamping strategy (empact.efficiency, empact efficiency).

The checks hold for any set of variator losses: the terms sum to P_in - P_out, efficiencies
lie in (0, 1], the actuation's terms are not negative at a trim, the hydraulic and servo
terms match hand computations from the trimmed forces and holding torques."""
import json
import math

import numpy as np
import pytest
from click.testing import CliRunner
from numpy.testing import assert_allclose

from empact.cli import main
from empact.efficiency import STRATEGIES, efficiency_map, strategy_clamping
from empact.errors import ParameterError
from empact.nonlinear.equilibrium import trim_grid
from empact.nonlinear.model import nonlinear_model
from empact.params import default_params
from empact.variator.geometry import secondary_radius


@pytest.fixture(scope="module")
def grid():
    """2 torques x 1 speed x 2 ratios x the four strategies."""
    return efficiency_map(default_params(), [40.0, 120.0], [300.0], [0.6, 1.8])


def test_losses_sum_to_the_power_difference(grid):
    """Sum of the variator's loss terms == P_in - P_out (1e-9 relative to P_in), every point
    trimmed, the input torque met (1e-9 relative), efficiencies in (0, 1], the total below
    the variator's, the actuation's terms >= 0 (no power flows at a trim)."""
    assert grid.ok.all(), grid.reason
    assert len(grid.strategy) == 4 * 2 * 2 and grid.strategies == STRATEGIES
    loss = sum(grid.losses.values())
    assert_allclose(loss, grid.P_in - grid.P_out, rtol=0, atol=1e-9 * grid.P_in.max())
    assert_allclose(grid.P_in / grid.omega_in, grid.T_in, rtol=1e-9, atol=0)
    assert np.all((grid.efficiency > 0) & (grid.efficiency <= 1))
    assert np.all((grid.total_efficiency > 0) & (grid.total_efficiency < grid.efficiency))
    for rec in grid.points():
        assert all(v >= 0 for v in rec["actuation"].values()), rec
        assert rec["P_in"] - rec["P_out"] == pytest.approx(sum(rec["losses"].values()),
                                                           rel=1e-9)
        total = rec["P_out"] / (rec["P_in"] + sum(rec["actuation"].values()))
        assert rec["total_efficiency"] == pytest.approx(total, rel=1e-12)


def test_strategies_clamp_as_stated(grid):
    """slip: tau = the [operating] set-point (0.9) to 1e-9; sf1.3 ratio-blind: tau = mu /
    mu_max below the ratio-aware's; sf1.3-aware: tau = (1 / 1.3) T_b / T_l to 3e-3 (the law
    clamps for the load torque, which is the driveshaft torque the loop's law reads at a
    trim (exactly), while the belt also carries the secondary's drag, up to 2.7 % more at
    40 N m, r_g 1.8; and the law takes the unstretched belt's secondary radius, the trim the
    stretched one: 0.18 % apart at 120 N m), exactly (1e-12) with the radii's ratio;
    hydraulic clamps as sf1.3 (exactly)."""
    tau = {s: grid.grid("tau", s) for s in STRATEGIES}
    assert_allclose(tau["slip"], 0.9, rtol=1e-9, atol=0)
    # the sf1.3-aware points re-trimmed at their clamping and the load torque it was set for
    p = default_params()
    model = nonlinear_model(p)
    k = np.array(grid.strategy) == "sf1.3-aware"
    r, F_s = grid.r_g[k], grid.F_s[k]
    T_l = F_s / strategy_clamping(model, "sf1.3-aware", 1.0, r)
    g = trim_grid(model, r, grid.omega_in[k], F_s=F_s, T_l=T_l)
    assert g.ok.all() and g.y is not None
    y = {n: g.y[:, j] for j, n in enumerate(model.outputs)}
    assert_allclose(y["tau"], grid.tau[k], rtol=1e-9, atol=0)
    assert_allclose(y["T_ds"], T_l, rtol=1e-12, atol=0)
    assert_allclose(y["T_l_act"], T_l, rtol=1e-12, atol=0)
    belt = y["T_b"] / T_l
    assert np.all(belt > 1)  # the secondary's drag
    assert_allclose(y["tau"], belt / 1.3, rtol=3e-3, atol=0)
    R_s0 = np.array([secondary_radius(x, p.variator.L_belt, p.variator.a) for x in r])
    assert_allclose(y["tau"], belt * R_s0 / y["R_s"] / 1.3, rtol=1e-12, atol=0)
    assert np.all(tau["sf1.3"] < tau["sf1.3-aware"] + 1e-12)
    assert_allclose(grid.grid("F_s", "hydraulic"), grid.grid("F_s", "sf1.3"), rtol=0, atol=0)
    # the clamping ranks: ratio-blind >= ratio-aware > slip control at tau 0.9
    assert np.all(grid.grid("F_s", "sf1.3") >= grid.grid("F_s", "sf1.3-aware") * (1 - 1e-12))
    assert np.all(grid.grid("F_s", "sf1.3-aware") > grid.grid("F_s", "slip"))


def test_actuation_terms_by_hand(grid):
    """Servo strategies: copper loss (T / k_m)^2 of each holding torque (1e-12); hydraulic:
    the pump's shaft power V omega p / eta_hm with p = max(F_p / A_p, F_s / A_s) +
    p_margin from the point's own forces (1e-12)."""
    p = default_params()
    sv, h = p.servo, p.hydraulic
    for rec in grid.points():
        a = rec["actuation"]
        if rec["strategy"] == "hydraulic":
            line = max(rec["F_p"] / h.A_p, rec["F_s"] / h.A_s) + h.p_margin
            shaft = h.displacement * h.pump_ratio * rec["omega_in"] * line / h.eta_hm
            assert sum(a.values()) == pytest.approx(shaft, rel=1e-12)
        else:
            assert a["copper_ms"] == pytest.approx((rec["T_ms"] / sv.k_m_ms) ** 2, rel=1e-12)
            assert a["copper_mp"] == pytest.approx((rec["T_mp"] / sv.k_m_mp) ** 2, rel=1e-12,
                                                   abs=1e-12)


def test_sf_clamping_is_the_loops_law():
    """The map's ratio-blind and ratio-aware clamping equal the loop law's at rest (the
    safety-factor twin's starting clamping of a shipped scenario, to 1e-9)."""
    from empact.control.closed_loop import control_example_path, safety_factor_twin
    from empact.nonlinear.model import nonlinear_model
    from empact.nonlinear.scenario import load_scenario

    p = default_params()
    sc = load_scenario(control_example_path("slip-load-step-r1"))
    model = nonlinear_model(p)
    for md, strategy in (("ratio-blind", "sf1.3"), ("ratio-aware", "sf1.3-aware")):
        twin = safety_factor_twin(sc, p, md)
        F = strategy_clamping(model, strategy, twin.initial.T_l, twin.initial.r_g)
        assert float(F) == pytest.approx(twin.initial.F_s, rel=1e-9), md


def test_clamping_sweep_replaces_the_strategy():
    """--clamp: the trims sit at the sweep's forces (1e-9); points that cannot carry the
    torque are marked, not dropped."""
    m = efficiency_map(default_params(), [60.0], [300.0], [1.0], strategies=("slip", "hydraulic"),
                       F_s=[2e3, 6e3, 2e4])
    assert len(m.strategy) == 6
    F = m.grid("F_s", "slip").ravel()
    assert not m.ok[0] and "traction peak" in m.reason[0]  # 2 kN cannot carry 60 N m
    assert_allclose(F[1:], [6e3, 2e4], rtol=1e-9, atol=0)
    assert_allclose(m.grid("efficiency", "slip"), m.grid("efficiency", "hydraulic"),
                    rtol=1e-12, atol=0, equal_nan=True)


def test_bad_input_before_any_trim():
    p = default_params()
    with pytest.raises(ParameterError, match="strategy = 'sf2'"):
        efficiency_map(p, [50.0], [300.0], [1.0], strategies=("sf2",))
    with pytest.raises(ParameterError, match=r"T_in = 0: must be > 0"):
        efficiency_map(p, [0.0], [300.0], [1.0])
    with pytest.raises(ParameterError, match="outside the geometric ratio range"):
        efficiency_map(p, [50.0], [300.0], [9.0])
    with pytest.raises(ParameterError, match="tau = 1.2"):
        efficiency_map(p, [50.0], [300.0], [1.0], tau=1.2)


def test_cli_json_points_and_plot(tmp_path):
    """``empact efficiency --json``: one record per point with the contract's keys; --plot
    writes a figure; a clamping sweep at one point."""
    res = CliRunner().invoke(main, ["efficiency", "--torque", "50,100", "--ratio", "1",
                                    "--strategy", "slip,sf1.3", "--json", "--plot",
                                    str(tmp_path / "m.png")])
    assert res.exit_code == 0, res.output
    doc = json.loads(res.stdout)
    assert doc["schema"]["name"] == "empact.efficiency"
    assert doc["units"]["P_in"] == "W" and doc["units"]["T_in"] == "N m"
    pts = doc["points"]
    assert len(pts) == 4
    for rec in pts:
        assert {"strategy", "r_g", "T_in", "omega_in", "F_s", "tau", "P_in", "P_out", "losses",
                "actuation", "efficiency", "total_efficiency"} <= set(rec)
        assert math.isclose(sum(rec["losses"].values()), rec["P_in"] - rec["P_out"],
                            rel_tol=1e-9)
    assert (tmp_path / "m.png").stat().st_size > 0
    res = CliRunner().invoke(main, ["efficiency", "--torque", "60", "--ratio", "1",
                                    "--clamp", "6000:20000:3", "--strategy", "slip"])
    assert res.exit_code == 0, res.output
    assert len(res.output.strip().splitlines()) == 2 + 3


@pytest.mark.parametrize("args, match", [
    (["--strategy", "sf2"], "--strategy = 'sf2': must be one of"),
    (["--torque", "-5"], "--torque = -5"),
    (["--ratio", "9"], "outside the geometric ratio range"),
    (["--clamp", "1000:2000:3"], "--clamp: give one --torque"),
    (["--clamp", "5000"], "--clamp '5000': a clamping sweep is A:B:N"),
    (["--tau", "1"], "--tau = 1"),
])
def test_cli_bad_input_one_line_exit_2(args, match):
    res = CliRunner().invoke(main, ["efficiency", *args])
    assert res.exit_code == 2, res.output
    lines = res.output.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and match in lines[0], res.output


def test_run_energy_closes_on_the_variator():
    """A run's variator input minus output energy equals its losses' energy (each the
    trapezoidal integral of its power: 1e-9 of the input energy), and the servos' and the
    pump's energies are those of empact.actuation_energy."""
    from empact.actuation_energy import actuation_energy
    from empact.efficiency import run_energy
    from empact.nonlinear.scenario import example_path, load_scenario
    from empact.nonlinear.simulation import run_scenario

    p = default_params()
    res = run_scenario(load_scenario(example_path("servo-torque-steps")), p)
    e = run_energy(res, p)
    assert e["variator_in"] > 0
    assert e["variator_in"] - e["variator_out"] == pytest.approx(
        sum(e["losses"].values()), rel=0, abs=1e-9 * e["variator_in"])
    act = actuation_energy(res, p)
    assert e["servo_electrical"] == pytest.approx(act.energy["servo_electrical"], rel=1e-12)
    assert e["pump"] == pytest.approx(act.hydraulic["pump"], rel=1e-12)


def test_saving_table_in_energy():
    """control.clamping_saving's rows gain the energy terms: total = variator losses +
    actuation (1e-12), the hydraulic reference row beside the ratio-blind one (same motion,
    the pump as actuation), saving_energy = 1 - slip control's total / the row's."""
    from empact.control.closed_loop import control_example_path, run_closed_loop
    from empact.nonlinear.scenario import load_scenario
    from empact.reproduction.control import HYDRAULIC_ROW, _saving

    p = default_params()
    n = "slip-small-step-r1"
    sc = {n: load_scenario(control_example_path(n))}
    from empact.control.closed_loop import safety_factor_twin

    twins = {(n, md): run_closed_loop(safety_factor_twin(sc[n], p, md), p)
             for md in ("ratio-blind", "ratio-aware")}
    rows = _saving(p, sc, {n: run_closed_loop(sc[n], p)}, [n], twins)
    assert [r["strategy"] for r in rows] == ["slip control (tau = 0.9)",
                                            "safety factor 1.3, ratio-blind mu", HYDRAULIC_ROW,
                                            "safety factor 1.3, ratio-aware mu"]
    slip = rows[0]
    for r in rows:
        assert r["total"] == pytest.approx(r["variator_losses_total"] + r["actuation"],
                                           rel=1e-12)
        assert r["variator_losses_total"] == pytest.approx(sum(r["variator_losses"].values()),
                                                           rel=1e-12)
        assert r["saving_energy"] == pytest.approx(1 - slip["total"] / r["total"], rel=1e-12,
                                                   abs=1e-15)
        assert r["actuation"] > 0 and r["pump"] > 0
    assert rows[2]["actuation"] == rows[1]["pump"]
    assert rows[2]["mean_clamping_force"] == rows[1]["mean_clamping_force"]


def test_sensitivity_sentence_names_the_flips_and_the_corners():
    """`sensitivity_text` (the claim's sentence) lists the band ends where a scenario's
    saving changes sign, the parameters that keep it, the corners and the steady state, from
    the rows alone (a synthetic table: the rule, not the machine)."""
    from empact.reproduction.control import sensitivity_text

    steady = {"least": -0.01, "largest": 0.02, "untrimmed": []}
    rows = [{"case": "shipped", "parameter": "", "value": {}, "saving": {"a": 0.05, "b": 0.01},
             "steady": steady},
            {"case": "low", "parameter": "x.p", "value": 1.0,
             "saving": {"a": 0.02, "b": -0.03}, "steady": steady},
            {"case": "high", "parameter": "x.p", "value": 2.0,
             "saving": {"a": 0.08, "b": 0.02}, "steady": steady},
            {"case": "low", "parameter": "x.q", "value": 3.0,
             "saving": {"a": 0.04, "b": 0.005}, "steady": steady},
            {"case": "high", "parameter": "x.q", "value": 4.0,
             "saving": {"a": 0.06, "b": 0.015}, "steady": steady},
            {"case": "worst corner", "parameter": "", "value": {"x.p": 1.0, "x.q": 3.0},
             "saving": {"a": -0.01, "b": -0.05},
             "steady": {**steady, "untrimmed": ["sf1.3 at 25 N m: no trim"]}},
            {"case": "best corner", "parameter": "", "value": {"x.p": 2.0, "x.q": 4.0},
             "saving": {"a": 0.1, "b": 0.03}, "steady": steady}]
    text = sensitivity_text(rows)
    assert "the same sign at both ends of x.q;" in text
    assert "the sign flips at x.p = 1 (b -3.0 %)" in text
    assert "worst corner (each parameter at the end that lowers the mean saving): a -1.0 %, " \
           "b -5.0 %" in text
    assert "-1.0 to +2.0 % with the shipped values" in text
    assert "where sf1.3 at 25 N m: no trim" in text
