"""Command line of the linear models and the report (issue 2, items 8-9)."""
import json

import numpy as np
import pytest
from click.testing import CliRunner

from empact import paper
from empact.cli import main


def run(*args):
    return CliRunner().invoke(main, list(args))


def test_modes_json_driveline():
    res = run("modes", "driveline", "--ratio", "1", "--json")
    assert res.exit_code == 0, res.output
    data = json.loads(res.output)
    for key in ("model", "ratio", "coordinates", "springs", "frequencies_hz", "energy_fraction",
                "shapes", "mass_matrix", "stiffness_matrix", "uncoupled_hz"):
        assert key in data
    assert set(data["uncoupled_hz"]) == {"primary", "secondary"}
    # Table 2 at r_g = 1 within 1 % (paper)
    np.testing.assert_allclose(data["frequencies_hz"][1:], paper.TABLE2_HZ[1.0][1:], rtol=0.01)
    assert np.array(data["energy_fraction"]).shape == (4, 3)


def test_modes_table_actuation():
    res = run("modes", "actuation", "--ratio", "0.5")
    assert res.exit_code == 0 and "worm" in res.output


def test_frf_json_and_plot(tmp_path):
    plot = tmp_path / "frf.png"
    res = run("frf", "actuation", "--input", "T_mp", "--output", "theta_mp", "--damping",
              "moderate", "--ratio", "1", "--n", "50", "--json", "--plot", str(plot))
    assert res.exit_code == 0, res.output
    data = json.loads(res.output)
    assert data["inputs"] == ["T_mp"] and data["outputs"] == ["theta_mp"]
    assert np.array(data["H"]).shape == (1, 1, 50, 2)
    assert plot.stat().st_size > 1000


@pytest.mark.parametrize("args, match", [
    (("modes", "driveline", "--ratio", "7"), "r_g = 7: outside the geometric ratio range"),
    (("frf", "actuation", "--output", "theta_xx"), "unknown output 'theta_xx'"),
    (("frf", "actuation", "--input", "T_zz"), "unknown input 'T_zz'"),
    (("frf", "actuation", "--fmin", "10", "--fmax", "1"), "need 0 < fmin < fmax"),
    (("modes", "driveline", "--params", "/nonexistent.toml"), "no such parameter file"),
])
def test_bad_options_one_line_exit_2(args, match, tmp_path):
    res = run(*args)
    assert res.exit_code == 2
    assert match in res.output
    assert len(res.output.strip().splitlines()) == 1


def test_bad_plot_path_leaves_nothing(tmp_path):
    plot = tmp_path / "frf.png"
    res = run("frf", "actuation", "--ratio", "9", "--plot", str(plot))
    assert res.exit_code == 2 and not plot.exists()


def test_reproduce_writes_complete_report(tmp_path):
    out = tmp_path / "rep"
    res = run("reproduce", "--out", str(out), "--quiet")
    assert res.exit_code == 0, res.output
    html = (out / "index.html").read_text()
    for stem in ("fig4_actuation_modes", "fig5_actuation_energy", "fig6_actuation_frf",
                 "fig8_driveline_modes", "fig8_driveline_energy"):
        assert (out / f"{stem}.png").exists() and (out / f"{stem}.svg").exists()
        assert f"{stem}.png" in html
    assert (out / "table1.csv").exists() and (out / "table2.csv").exists()
    assert "NOT shown" not in html  # every paper claim checked in the report holds
    leftovers = [p.name for p in tmp_path.iterdir() if p.name != "rep"]
    assert leftovers == []  # the temporary folder was moved into place
