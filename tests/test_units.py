"""One unit per quantity in machine-readable output (issue 22, item 5): slip is a fraction in
JSON and CSV (% only in text for people and on the report's page), every CSV header cell of a
quantity is ``name [unit]``, signed modal energy fractions say that they are signed."""
import csv
import html
import json
import re

import numpy as np
import pytest
from click.testing import CliRunner

from empact.cli import main
from empact.control.closed_loop import control_example_path, run_closed_loop
from empact.montecarlo import analyses
from empact.nonlinear.scenario import load_scenario

#: a header cell of a quantity, as empact writes it
CELL = re.compile(r"^[^\[\],]+ \[[^\[\]]+\]$")
#: columns that are not quantities
LABELS = {"run", "status", "reason"}


def _header(path):
    rows = [r for r in csv.reader(path.read_text().splitlines()) if r and not
            r[0].startswith("#")]
    return rows[0]


def test_control_simulate_gives_slips_as_fractions(tmp_path, params):
    res = CliRunner().invoke(main, ["control", "simulate", "--example", "slip-load-step-r1",
                                    "--json", "--out", str(tmp_path / "run.csv")])
    assert res.exit_code == 0, res.output
    doc = json.loads(res.stdout)
    assert doc["schema"] == {"name": "empact.control.simulate", "version": 3}
    m = doc["metrics"]
    assert not [k for k in m if k.endswith("_pp")]
    assert {doc["units"][k] for k in ("slip_error", "peak_slip", "peak_slip_error",
                                      "slip_setpoint", "slip_reserve")} == {"-"}
    # the targets are named as the metrics (schema 3)
    assert {t["name"] for t in doc["targets"]} <= set(m)
    # the library's metrics (fractions), exactly (the same deterministic run)
    ref = run_closed_loop(load_scenario(control_example_path("slip-load-step-r1")),
                          params).metrics
    assert m["slip_error"] == ref["slip_error"]
    assert m["peak_slip"] == ref["peak_slip"]
    # the set-point by torque ratio: the slip where mu = 0.9 mu_max at r_g = 1
    from empact.nonlinear.equilibrium import slip_at_torque_ratio
    from empact.nonlinear.model import nonlinear_model
    nu_star = float(slip_at_torque_ratio(nonlinear_model(params), 0.9, 1.0))
    assert m["slip_setpoint"] == ref["slip_setpoint"] == pytest.approx(nu_star, rel=1e-12)
    assert all(CELL.match(c) for c in _header(tmp_path / "run.csv"))


def test_control_simulate_text_keeps_percent(monkeypatch):
    """For people: the slips in percentage points and %, the other metrics with units, a
    dimensionless number as [-] (issue 35: 7 metrics showed no unit)."""

    class Run:
        metrics = {"complete": True, "message": "completed", "slip_error": 0.0005,
                   "peak_slip": 0.015, "ratio_error": 0.002, "mean_clamping_force": 9000.0,
                   "peak_slip_error": 0.003, "macro_slip": False}

        class result:
            complete = True

    monkeypatch.setattr("empact.control.closed_loop.run_closed_loop", lambda *a, **k: Run)
    res = CliRunner().invoke(main, ["control", "simulate", "--example", "slip-load-step-r1"])
    assert res.exit_code == 0, res.output
    lines = res.output.splitlines()
    assert "slip_error             0.05 [percentage points]" in lines
    assert "peak_slip              1.5 [%]" in lines
    assert "mean_clamping_force    9000 [N]" in lines
    assert "ratio_error            0.002 [-]" in lines
    assert "macro_slip             False" in lines  # a verdict, not a number


def test_montecarlo_closed_loop_outputs_are_fractions(monkeypatch, params):
    class Run:
        metrics = {"complete": True, "message": "", "slip_error": 0.0025, "peak_slip": 0.015,
                   "slip_setpoint": 0.01, "ratio_error": 0.01, "mean_clamping_force": 1.0,
                   "mean_slip_power": 2.0, "mean_actuation_power": 3.0, "mean_losses": 5.0,
                   "peak_slip_error": 0.005, "slip_reserve": 0.02, "macro_slip": False,
                   "peak_T_mp": 0.4, "peak_T_ms": 8.0, "min_clamping_force": 0.5}

    monkeypatch.setattr(analyses, "run_closed_loop", lambda *a, **k: Run)
    sc = load_scenario(control_example_path("slip-load-step-r1"))
    out = analyses.evaluate(params, analyses.AnalysisContext("closed-loop", sc, object()))
    assert out["slip_error"] == 0.0025 and out["peak_slip"] == 0.015
    assert out["belt_slack"] == 0.0 and out["met.macro_slip"] == 1.0  # F_s > 0, no macro slip
    assert analyses.OUTPUTS["closed-loop"]["slip_error"] == "-"
    assert not [k for k in analyses.OUTPUTS["closed-loop"] if k.endswith("_pp")]


def test_every_csv_header_has_units_in_one_style(tmp_path):
    rig = tmp_path / "rec.csv"
    res = CliRunner().invoke(main, ["rig", "--out", str(rig), "--duration", "0.1", "--quiet"])
    assert res.exit_code == 0, res.output
    assert _header(rig) == ["time [s]", "T_mp [N m]", "T_ms [N m]", "theta_mp [rad]",
                            "theta_ms [rad]", "nu [-]"]
    assert rig.read_text().startswith("# empact rig: multisine on T_mp at r_g = 0.5")
    res = CliRunner().invoke(main, ["simulate", "--example", "servo-torque-steps", "--duration",
                                    "0.02", "--quiet", "--out", str(tmp_path / "sim")])
    assert res.exit_code == 0, res.output
    sim = tmp_path / "sim" / "servo-torque-steps.csv"
    first = sim.read_text().splitlines()[0]
    assert first.startswith("# empact simulation 'servo-torque-steps': complete: ") \
        and "completed" not in first, first
    assert all(CELL.match(c) for c in _header(sim))
    spread = tmp_path / "s.toml"
    spread.write_text('[spread."actuation.k_w"]\ndistribution = "normal"\nrel_std = 0.05\n')
    res = CliRunner().invoke(main, ["montecarlo", "--spread", str(spread), "--runs", "3",
                                    "--analysis", "slip", "--quiet", "--out",
                                    str(tmp_path / "mc")])
    assert res.exit_code == 0, res.output
    head = _header(tmp_path / "mc" / "runs.csv")
    assert all(CELL.match(c) for c in head if c not in LABELS) and LABELS <= set(head)
    summary = json.loads((tmp_path / "mc" / "summary.json").read_text())
    assert summary["schema"] == {"name": "empact.montecarlo", "version": 2}


def test_modes_says_energy_fractions_are_signed():
    res = CliRunner().invoke(main, ["modes", "driveline", "--ratio", "0.5"])
    assert res.exit_code == 0
    assert "signed energy fraction per spring" in res.output
    assert re.search(r"-0\.96\d", res.output)  # a negative entry (the issue's -0.964)
    doc = json.loads(CliRunner().invoke(main, ["modes", "driveline", "--json"]).output)
    assert doc["units"]["energy_fraction"].startswith("- (signed")
    e = np.abs(np.array(doc["energy_fraction"]))[1:]
    np.testing.assert_allclose(e.sum(axis=1), 1.0, rtol=1e-12)  # magnitudes sum to 1


def test_report_csv_gives_slip_as_fraction(full_report):
    """The page shows the Fig. 11 slips in %; its CSV has them as fractions (the same
    numbers / 100, to the page's 4 significant digits)."""
    res, out = full_report
    assert res.exit_code == 0, res.output
    rows = list(csv.reader((out / "fig11_poles.csv").read_text().splitlines()))
    assert rows[0][0] == "nu [-]"
    page = (out / "index.html").read_text()
    table = page[page.index('<table id="tab-fig11_poles"'):]
    table = table[:table.index("</table>")]
    shown = [float(html.unescape(c)) for c in re.findall(r"<tr><td>([^<]*)</td>", table)]
    assert len(shown) == len(rows) - 1 > 3
    np.testing.assert_allclose([float(r[0]) for r in rows[1:]], np.array(shown) / 100,
                               rtol=1e-3)


def test_report_csv_gives_every_slip_column_as_a_fraction():
    """The report's CSV tables (machine-readable): a slip in % and every column in percentage
    points (a difference of slips: the error, the reserve to the peak) divided by 100 with
    the unit [-]; other percentages (a saving) and units stay."""
    from empact.report.context import csv_slip_columns

    head, row = csv_slip_columns(
        ["scenario", "peak slip [%]", "peak |nu - nu*| [pp]", "reserve to the peak [pp]",
         "saving in F_s [%]", "F_s [kN]"], [["a", 1.5, 0.5, 2.0, 20.0, 3.0]])
    assert head == ["scenario", "peak slip [-]", "peak |nu - nu*| [-]",
                    "reserve to the peak [-]", "saving in F_s [%]", "F_s [kN]"]
    assert row == ["a", 1.5 / 100, 0.5 / 100, 2.0 / 100, 20.0, 3.0]
