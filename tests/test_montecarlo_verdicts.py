"""Closed-loop Monte Carlo verdicts (issue 33 item 8, issue 35): each run's scenario targets
judged and counted, macro slip and belt slack flagged, ``montecarlo --strict``; the
``scenario.*`` spread variables, validated against the scenario and reaching the run; the
shipped wide spread."""
from __future__ import annotations

import json
from dataclasses import replace
from importlib import resources

import numpy as np
import pytest
from click.testing import CliRunner
from test_cli import PROGRESS

from empact.cli import main
from empact.control.closed_loop import control_example_path, run_closed_loop
from empact.errors import ParameterError
from empact.montecarlo import load_spread, monte_carlo, spread_from_dict
from empact.montecarlo.analyses import AnalysisContext, prepare
from empact.montecarlo.spread import apply_scenario, peak_slip, resolve_peak_slips
from empact.montecarlo.study import MonteCarloResult
from empact.nonlinear.scenario import load_scenario
from empact.params import default_params
from empact.sweep import SweepOptions
from empact.variator.traction import traction_from_params

P = default_params()
SC = load_scenario(control_example_path("slip-load-step-r1"))

#: a band of the traction peak and the clamping level (B, D and F_s reach the run)
SPREAD = {"spread": {"traction.B_med": {"distribution": "uniform", "lower": 70.0,
                                        "upper": 95.0},
                     "traction.D_med": {"distribution": "uniform", "lower": 0.095,
                                        "upper": 0.105},
                     "scenario.initial.F_s": {"distribution": "uniform", "lower": 9000.0,
                                              "upper": 11000.0}}}

#: a peak |nu - nu*| of 0.001 % (far below what any load step gives: 0.18-0.29 pp measured
#: on the shipped spread), so that every completed run misses it
TIGHT = 1e-5


def _wide() -> str:
    return str(resources.files("empact.data").joinpath("montecarlo", "wide-spread.toml"))


def test_verdicts_count_missed_targets_and_failed_runs():
    """A table built by hand: run 0 meets everything, run 1 misses ratio_error with macro
    slip, run 2 stopped on a slack belt, run 3 failed otherwise; a failed run misses every
    target and only the slack stop counts as belt slack."""
    spread = spread_from_dict({"spread": {"traction.D_med": {"distribution": "uniform",
                                                             "lower": 0.09, "upper": 0.11}}}, P)
    outputs = ("macro_slip", "belt_slack", "met.macro_slip", "met.ratio_error")
    nan = np.nan
    values = np.array([[0, 0, 1, 1], [1, 0, 0, 0], [nan] * 4, [nan] * 4], float)
    res = MonteCarloResult(
        analysis="closed-loop", seed=0, spread=spread, samples=np.zeros((4, 1)),
        outputs=outputs, units=dict.fromkeys(("traction.D_med", *outputs), "-"),
        values=values, ok=np.array([True, True, False, False]),
        reasons=("", "", "stopped: clamping force F_s fell to zero: belt slack",
                 "error: something else"))
    v = res.verdicts()
    assert res.targets == ("macro_slip", "ratio_error")
    assert v["targets"] == {"macro_slip": {"missed": 3, "missed_failed": 2},
                            "ratio_error": {"missed": 3, "missed_failed": 2}}
    assert (v["runs_missing_any"], v["macro_slip"], v["belt_slack"], v["failed_other"],
            v["clean"]) == (3, 1, 1, 1, 1)
    assert v["clean_fraction"] == pytest.approx(0.25, abs=0)
    assert res.summary()["verdicts"] == v


def test_a_tight_target_is_missed_by_every_run_and_counted():
    """Three closed-loop runs with a deliberately tight peak_slip_error target: each run's
    verdict is recomputed from its own peak_slip_error output; the other targets of the
    shipped scenario are judged as `check_targets` does."""
    sc = replace(SC, targets={**SC.targets, "peak_slip_error": (-np.inf, TIGHT)})
    res = monte_carlo(P, spread_from_dict(SPREAD, P, scenario=sc), 3, "closed-loop",
                      seed=4, scenario=sc)
    assert res.ok.all(), res.reasons
    col = {n: res.values[:, res.outputs.index(n)] for n in res.outputs}
    np.testing.assert_array_equal(col["met.peak_slip_error"],
                                  (col["peak_slip_error"] <= TIGHT).astype(float))
    np.testing.assert_array_equal(col["met.ratio_error"],
                                  (col["ratio_error"] <= SC.targets["ratio_error"][1]))
    v = res.summary()["verdicts"]
    assert v["targets"]["peak_slip_error"] == {"missed": 3, "missed_failed": 0}
    assert v["runs_missing_any"] == 3
    assert v["clean"] == 3 - v["macro_slip"] - v["belt_slack"]


def test_spread_variables_reach_the_run():
    """A drawn B, D and initial F_s are the run's parameters and scenario; the study's run 0
    equals the closed loop run by hand on them (bitwise)."""
    spread = spread_from_dict(SPREAD, P, scenario=SC)
    row = spread.sample(2, [0])[0]
    ctx = AnalysisContext("closed-loop", SC, None, P)
    p, c = prepare(P, spread, row, ctx)
    assert p.get("traction.B_med") == row[0] and p.get("traction.D_med") == row[1]
    assert c.scenario.initial.F_s == row[2] and SC.initial.F_s == 10000.0
    assert c.scenario.initial.r_g == SC.initial.r_g  # the rest of the point is kept
    res = monte_carlo(P, spread, 1, "closed-loop", seed=2, scenario=SC)
    m = run_closed_loop(c.scenario, p, nominal=P).metrics
    for name in ("peak_slip", "mean_clamping_force", "slip_error"):
        assert res.values[0, res.outputs.index(name)] == m[name], name


def test_same_seed_gives_the_same_table_bitwise():
    spread = spread_from_dict(SPREAD, P, scenario=SC)
    a, b = (monte_carlo(P, spread, 2, "closed-loop", seed=9, scenario=SC) for _ in range(2))
    np.testing.assert_array_equal(a.samples, b.samples)
    np.testing.assert_array_equal(a.values, b.values)
    assert a.to_csv() == b.to_csv()


@pytest.mark.parametrize("table, message", [
    ({"scenario.initial.F_s": {"distribution": "uniform", "lower": -5000.0,
                               "upper": -1000.0}},
     "spread.'scenario.initial.F_s': uniform on [-5000, -1000] lies wholly outside"),
    ({"scenario.initial.r_g": {"distribution": "uniform", "lower": 3.0, "upper": 4.0}},
     "spread.'scenario.initial.r_g': uniform on [3, 4] lies wholly outside"),
    ({"scenario.load_step": {"distribution": "uniform", "lower": 2.5, "upper": 3.0}},
     "spread.'scenario.load_step': uniform on [2.5, 3] lies wholly outside"),
    ({"scenario.initial.T_l": {"distribution": "uniform", "lower": 1.0, "upper": 2.0}},
     "spread.'scenario.initial.T_l': unknown scenario variable 'scenario.initial.T_l' "
     "(choose from scenario.initial.F_s"),
])
def test_scenario_variables_are_checked_against_the_scenario(table, message):
    with pytest.raises(ParameterError) as exc:
        spread_from_dict({"spread": table}, P, "s.toml", scenario=SC)
    assert str(exc.value).startswith("s.toml: " + message), str(exc.value)


def test_scenario_variables_need_a_scenario():
    with pytest.raises(ParameterError, match="a variable of a closed-loop scenario"):
        spread_from_dict({"spread": {"scenario.load_step": {
            "distribution": "uniform", "lower": 0.4, "upper": 0.6}}}, P)


def test_apply_scenario_refuses_a_value_out_of_range():
    with pytest.raises(ParameterError, match=r"^scenario.load_step = 2.5"):
        apply_scenario(SC, {"scenario.load_step": 2.5}, P)
    assert apply_scenario(SC, {"scenario.load_step": 0.4}, P).load_step == 0.4


def test_wide_spread_loads_on_every_ratio_and_varies_the_shape_at_all_three():
    for r in ("0.5", "1", "2"):
        sc = load_scenario(control_example_path(f"slip-load-step-r{r}"))
        spread = load_spread(_wide(), P, sc)
    for k in ("peak_slip", "C", "D"):
        assert {f"traction.{k}_{x}" for x in ("low", "med", "od")} <= set(spread.names)
    assert {"scenario.initial.F_s", "scenario.load_step"} <= set(spread.names)
    # peak slip +-30 % of the nominal curve's (issue 33 item 8; the file rounds to 4 digits)
    d = {x.name: x for x in spread.distributions}
    for x in ("low", "med", "od"):
        nu0 = peak_slip(*(P.get(f"traction.{c}_{x}") for c in "BCE"))
        lo, hi = d[f"traction.peak_slip_{x}"].loc, d[f"traction.peak_slip_{x}"].scale
        assert lo == pytest.approx(0.7 * nu0, rel=2e-4) and hi == pytest.approx(1.3 * nu0,
                                                                                rel=2e-4)


@pytest.mark.parametrize("E", [0.0, -1.5, 0.6])
def test_a_drawn_peak_slip_puts_the_curves_peak_there(E):
    """``traction.peak_slip_*`` sets ``B`` so that the run's magic formula (with its drawn
    ``C`` and the set's ``E``) peaks at the drawn slip: the traction model's own curve at the
    LOW ratio, sampled every 5e-7, peaks at the grid point nearest it (within 8.3e-6
    relative; asserted 1e-5), and `peak_slip` inverts it to 1e-12."""
    base = P.from_dotted({"traction.E_low": E})
    values = resolve_peak_slips({"traction.peak_slip_low": 0.03, "traction.C_low": 1.4}, base)
    assert set(values) == {"traction.B_low", "traction.C_low"}
    p = base.from_dotted(values)
    nu = np.linspace(1e-4, 0.15, 300001)
    mu = traction_from_params(p).mu(nu, np.full_like(nu, p.traction.r_low))
    assert nu[np.argmax(mu)] == pytest.approx(0.03, rel=1e-5)
    assert peak_slip(values["traction.B_low"], 1.4, E) == pytest.approx(0.03, rel=1e-12)


@pytest.mark.parametrize("lower, upper", [(-0.02, -0.01), (2.0, 3.0)])
def test_a_peak_slip_outside_the_formulas_slips_is_refused_before_any_run(lower, upper):
    """A peak slip is in (0, 0.2), the slips the magic formula is used at: a spread wholly
    outside is one line when it is loaded (a 2-3 peak slip used to load, and every run
    failed on its B)."""
    data = {"spread": {"traction.peak_slip_med": {"distribution": "uniform", "lower": lower,
                                                  "upper": upper}}}
    with pytest.raises(ParameterError, match=r"lies wholly outside .*a peak slip is in "
                                             r"\(0, 0.2\)") as err:
        spread_from_dict(data, P)
    assert "\n" not in str(err.value)


def test_a_peak_slip_and_its_stiffness_together_are_one_line():
    data = {"spread": {"traction.peak_slip_med": {"distribution": "uniform", "lower": 0.02,
                                                  "upper": 0.04},
                       "traction.B_med": {"distribution": "uniform", "lower": 60.0,
                                          "upper": 100.0}}}
    with pytest.raises(ParameterError, match="traction.peak_slip_med and traction.B_med both "
                                             "given"):
        spread_from_dict(data, P)


#: issue 33 item 8's target: at least this share of the wide spread's runs without macro
#: slip or belt slack, at each of the three ratios
WIDE_CLEAN_TARGET = 0.95


@pytest.mark.slow
@pytest.mark.parametrize("ratio", ["0.5", "1", "2"])
def test_the_shipped_load_steps_keep_95_percent_of_the_wide_spread_clean(ratio):
    """Issue 33 item 8 on the shipped scenario (its controller, the slip guard on) and the
    shipped wide spread, 200 runs, seed 0: at least 95 % of the runs complete without macro
    slip or belt slack (measured at stop 44: 100 / 98.5 / 100 % at r_g 0.5 / 1 / 2; 96.5 /
    93.0 / 100 % without the guard), and every run's scenario targets are judged."""
    sc = load_scenario(control_example_path(f"slip-load-step-r{ratio}"))
    res = monte_carlo(P, load_spread(_wide(), P, sc), 200, "closed-loop", seed=0, scenario=sc,
                      sweep=SweepOptions(workers=2))
    v = res.verdicts()
    assert v["clean_fraction"] >= WIDE_CLEAN_TARGET, v
    assert set(v["targets"]) == {"macro_slip", "peak_slip_error", "slip_error", "ratio_error"}


def test_example_spread_wide_prints_the_file():
    res = CliRunner().invoke(main, ["montecarlo", "--example-spread", "wide"])
    assert res.exit_code == 0 and res.output == open(_wide()).read()
    res = CliRunner().invoke(main, ["montecarlo", "--example-spread"])
    assert res.exit_code == 0 and "[spread.\"actuation.k_w\"]" in res.output


def test_wide_spread_without_a_scenario_is_one_line_exit_2(tmp_path):
    res = CliRunner().invoke(main, ["montecarlo", "--spread", _wide(), "--runs", "2",
                                    "--out", str(tmp_path / "o")])
    assert res.exit_code == 2
    # (a progress line shows after a second of start-up on a loaded machine: not an error)
    lines = [ln for ln in res.stderr.splitlines() if not PROGRESS.match(ln)]
    assert len(lines) == 1 and lines[0].startswith("error: "), res.stderr
    assert "scenario.initial.F_s is a variable of a closed-loop scenario" in res.stderr
    assert not (tmp_path / "o").exists()


def test_strict_needs_the_closed_loop(tmp_path):
    res = CliRunner().invoke(main, ["montecarlo", "--spread", _wide(), "--strict"])
    assert res.exit_code == 2 and "--strict: judges the scenario targets" in res.stderr


def test_strict_exit_codes(tmp_path):
    """--strict: 0 when every run met its targets, 1 with one line when a run missed; the
    verdicts are in runs.csv, runs.json and the --json summary either way."""
    spread = tmp_path / "s.toml"
    spread.write_text('[spread."traction.D_med"]\ndistribution = "uniform"\nlower = 0.099\n'
                      'upper = 0.101\n')
    text = control_example_path("slip-load-step-r1").read_text()
    tight = tmp_path / "tight.toml"
    tight.write_text(text.replace("peak_slip_error = 0.006", f"peak_slip_error = {TIGHT}"))
    args = ["montecarlo", "--spread", str(spread), "--runs", "2", "--analysis", "closed-loop",
            "--strict", "--quiet"]
    ok = CliRunner().invoke(main, args + ["--example", "slip-load-step-r1", "--json"])
    assert ok.exit_code == 0, ok.output
    doc = json.loads(ok.stdout)
    assert doc["verdicts"]["runs_missing_any"] == 0
    assert doc["verdicts"]["targets"]["peak_slip_error"]["missed"] == 0
    out = tmp_path / "out"
    bad = CliRunner().invoke(main, args + ["--scenario", str(tight), "--out", str(out)])
    assert bad.exit_code == 1
    assert bad.stderr == ("error: --strict: 2 of 2 runs missed a scenario target "
                          "(peak_slip_error 2; 0 failed to simulate)\n")
    assert "peak_slip_error        missed by     2 runs" in bad.stdout
    header = next(line for line in (out / "runs.csv").read_text().splitlines()
                  if line.startswith("run,"))
    assert "met.peak_slip_error [-]" in header and "belt_slack [-]" in header
    runs = json.loads((out / "runs.json").read_text())["runs"]
    assert [r["met.peak_slip_error"] for r in runs] == [0.0, 0.0]
    summary = json.loads((out / "summary.json").read_text())
    assert summary["verdicts"]["targets"]["peak_slip_error"]["missed"] == 2
