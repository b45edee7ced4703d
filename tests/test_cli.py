"""Command line of the linear models and the report (issue 2, items 8-9)."""
import json

import numpy as np
import pytest
from click.testing import CliRunner

from empact import paper
from empact.cli import main


KNOWN_DEVIATIONS = (
    # Sec. 2.3 / Sec. 3: with the Sec. 2.1 kinematics a right-half-plane zero of T_mp -> nu
    # appears at every ratio, r_g = 2 included
    "none at r_g = 2",
    # Sec. 3 on Fig. 2: the actuation modes of the nonlinear model carry the linear model's
    # damping (no extra dissipation in this construction) ...
    "every mode and ratio):",
    # ... and the 48 Hz zeros lie just below their pole, not above it
    "T_mp -> nu):",
    # Sec. 4 / Fig. 14: the servo angle falls with -1.73 rather than -1 between 1 and 2 Hz
    "Slope -1 (within 0.35) between 1 and 2 Hz, T_mp -> theta_mp",
)


def _not_shown(html):
    """The text before each NOT-shown verdict (the claim it judges), one string each."""
    import re

    text = re.sub(r"\s+", " ", re.sub(r"<[^>]+>", " ", html))
    return [text[max(0, m.start() - 160):m.start()] for m in re.finditer("NOT shown", text)]


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
    # every paper claim the report checks holds, except the documented deviations below
    # (README, "Paper inconsistencies"); an unexpected failure or pass changes this set
    snippets = _not_shown(html)
    matched = [[claim for claim in KNOWN_DEVIATIONS if claim in snip] for snip in snippets]
    assert all(len(m) == 1 for m in matched), snippets  # no unexplained failure
    assert sorted(m[0] for m in matched) == sorted(KNOWN_DEVIATIONS), snippets
    leftovers = [p.name for p in tmp_path.iterdir() if p.name != "rep"]
    assert leftovers == []  # the temporary folder was moved into place
