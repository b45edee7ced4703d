"""The command line (`empact.cli`): every command's output, JSON and files; bad input gets
one line and exit status 2 with nothing written; output folders are never clobbered."""
import json
import os
import re
import stat
from importlib import resources

import numpy as np
import pytest
import scipy.signal as sig
from click.testing import CliRunner
from numpy.testing import assert_allclose
from test_outputs import COMMANDS as COMMAND_TREE

from empact import paper
from empact.cli import COMMANDS, main
from empact.params import OperatingPoint, load_params
from empact.slip import STATES, slip_model


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def write(tmp_path, text, name="p.toml"):
    path = tmp_path / name
    path.write_text(text)
    return path


# -- output of every command ----------------------------------------------------------------
def test_cli_show_round_trips(tmp_path, params):
    res = CliRunner().invoke(main, ["params", "show"])
    assert res.exit_code == 0
    assert load_params(write(tmp_path, res.output)) == params


def test_modes_json_driveline():
    res = run("modes", "driveline", "--ratio", "1", "--json")
    assert res.exit_code == 0, res.output
    data = json.loads(res.stdout)
    for key in ("model", "r_g", "coordinates", "springs", "frequencies_hz", "energy_fraction",
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
    data = json.loads(res.stdout)
    assert data["inputs"] == ["T_mp"] and data["outputs"] == ["theta_mp"]
    assert np.array(data["H"]).shape == (1, 1, 50, 2)
    assert plot.stat().st_size > 1000


def test_cli_poles_json():
    res = run("slip", "poles", "--slip", "0.001,0.04", "--json")
    assert res.exit_code == 0, res.output
    data = json.loads(res.stdout)
    # [operating] given by its torque ratio, resolved to the slip the linear model needs
    p = load_params()
    assert data["operating_point"] == p.operating.resolve(p).to_dict()
    assert data["variable"] == "nu" and len(data["points"]) == 2
    poles = np.array(data["points"][1]["poles"])
    assert poles.shape == (8, 2)  # [re, im] in rad/s
    assert not data["points"][1]["stable"] and data["points"][0]["stable"]


def test_cli_statespace_json(params):
    res = run("slip", "statespace", "--ratio", "2", "--slip", "0.02", "--json")
    assert res.exit_code == 0, res.output
    data = json.loads(res.stdout)
    assert {"A", "B", "C", "D", "inputs", "outputs", "states"} <= set(data)
    m = slip_model(params, OperatingPoint(2.0, 0.02, 1e4, 300.0))
    assert_allclose(np.array(data["A"]), m.A, rtol=1e-15)  # JSON floats round-trip exactly
    assert data["states"] == list(STATES)


def test_cli_rootlocus_zeros_frf_map():
    res = run("slip", "rootlocus", "--json")
    assert res.exit_code == 0, res.output
    assert_allclose(json.loads(res.stdout)["coupled_hz"], paper.COUPLED_R1_HZ, rtol=0.01)
    res = run("slip", "zeros", "--ratio", "0.5:2:4", "--json")
    assert res.exit_code == 0, res.output
    assert len(json.loads(res.stdout)["zeros"]) == 4
    res = run("slip", "frf", "--slip", "0.001,0.04", "--n", "20", "--json")
    assert res.exit_code == 0, res.output
    assert len(json.loads(res.stdout)["responses"]) == 2
    res = run("slip", "map", "--slip", "0.001:0.06:6", "--clamp", "2000:20000:4", "--json")
    assert res.exit_code == 0, res.output
    data = json.loads(res.stdout)
    assert np.array(data["max_real"]).shape == (4, 6) and data["x"]["name"] == "nu"


def test_cli_plot(tmp_path):
    out = tmp_path / "map.png"
    res = run("slip", "map", "--slip", "0.001:0.06:8", "--ratio", "0.5:2:6", "--plot", str(out))
    assert res.exit_code == 0, res.output
    assert out.stat().st_size > 1000


def test_cli_traction_table_and_bad_table(tmp_path):
    good = tmp_path / "good.csv"
    good.write_text("r_g,nu,mu\n1,0,0\n1,0.01,0.09\n1,0.05,0.1\n")
    res = CliRunner().invoke(main, ["slip", "traction", "--traction", str(good), "--ratio", "1",
                                    "--slip", "0:0.05:6", "--json"])
    assert res.exit_code == 0, res.output
    bad = tmp_path / "bad.csv"
    bad.write_text("r_g,nu,mu\n1,0,0\n1,0.02,0.09\n1,0.01,0.1\n")
    res = CliRunner().invoke(main, ["slip", "poles", "--traction", str(bad)])
    assert res.exit_code == 2
    lines = res.output.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error:") and "nu must increase" in lines[0]


def test_cli_simulate_linearize_nmp(tmp_path):
    sim = tmp_path / "sim"
    res = run("simulate", "--example", "servo-torque-steps", "--out", sim, "--quiet",
              "--duration", "0.1")
    assert res.exit_code == 0, res.output
    text = (sim / "servo-torque-steps.csv").read_text().splitlines()
    assert text[0].startswith("# empact simulation") and "r_g [-]" in text[1]
    assert "F_s [N]" in text[1] and len(text) == 2 + 201
    assert (sim / "servo-torque-steps.png").stat().st_size > 1000
    # the figure is PNG unless --formats asks for vector ones beside it
    assert sorted(p.suffix for p in sim.iterdir()) == [".csv", ".png"]
    res = run("simulate", "--example", "servo-torque-steps", "--out", tmp_path / "vec",
              "--quiet", "--duration", "0.01", "--formats", "png,svg")
    assert res.exit_code == 0, res.output
    assert sorted(p.suffix for p in (tmp_path / "vec").iterdir()) == [".csv", ".png", ".svg"]
    # the simulation's CSV reads back as records (comment line, units in the header, each a
    # unit `load_records` converts); two signals that vary in 10 ms (T_ms is constant there:
    # a dead channel, refused since issue 35)
    res = run("frf-estimate", sim / "servo-torque-steps.csv", "--input", "omega_ms",
              "--output", "omega_mp", "--time", "time", "--nperseg", "64", "--json")
    assert res.exit_code == 0, res.output
    res = run("linearize", "--ratio", "0.5", "--slip", "0.004", "--clamp", "1e4", "--speed",
              "300", "--json")
    assert res.exit_code == 0, res.output
    data = json.loads(res.stdout)
    assert data["schema"] == {"name": "empact.linearize", "version": 1}
    # control inputs, the load as the named disturbance, both slip signals
    assert data["inputs"] == ["T_mp", "T_ms", "T_l"]
    assert data["outputs"] == ["r_g", "nu", "nu_r"]
    assert data["disturbance_inputs"] == ["T_l"] and data["control_inputs"] == ["T_mp", "T_ms"]
    assert data["states_units"][4] == "m" and data["inputs_units"] == ["N m"] * 3
    # the test bench by default (drive speed-controlled: its PI's integral state z_d), as
    # `empact plants`; --drive torque gives the bare machine's 18 states
    assert np.array(data["A"]).shape == (19, 19) and data["states"][-1] == "z_d"
    # tol 1e-12 rel: the requested ratio (the parameter file's 0.5), which trim holds
    assert data["operating_point"]["r_g"] == pytest.approx(0.5, rel=1e-12)
    res = run("linearize", "--drive", "torque", "--json")
    assert len(json.loads(res.stdout)["states"]) == 18
    res = run("linearize", "--load", "speed", "--json")
    assert json.loads(res.stdout)["inputs"] == ["T_mp", "T_ms", "omega_l_ref"]
    # without --json or --out: a summary (it printed 696 lines of JSON): the point, the
    # signals with units, the 19 poles (pairs once), no matrix
    res = run("linearize", "--ratio", "0.5", "--slip", "0.004", "--clamp", "1e4", "--speed",
              "300", "--quiet")
    assert res.exit_code == 0, res.output
    lines = res.stdout.splitlines()
    assert lines[0].startswith("linear plant at r_g = 0.5 -, nu = 0.004 -") and len(lines) < 30
    assert lines[2] == "inputs (3): T_mp [N m], T_ms [N m], T_l [N m]"
    assert lines[3] == "outputs (3): r_g [-], nu [-], nu_r [-]"
    assert lines[4].startswith("poles (19, ")
    pole_rows = [ln for ln in lines if "rad/s" in ln and ln.startswith("  ")]
    assert sum(2 if "+/-" in ln else 1 for ln in pole_rows) == 19
    mat = tmp_path / "plant.mat"
    res = run("linearize", "--ratio", "2", "--slip", "0.004", "--clamp", "1e4", "--speed",
              "300", "--format", "mat", "--out", str(mat))
    assert res.exit_code == 0, res.output
    from scipy.io import loadmat
    assert loadmat(mat)["A"].shape == (19, 19)
    res = run("nmp", "--json", "--slip-signal", "nu_r")
    assert res.exit_code == 0, res.output
    data = json.loads(res.stdout)
    assert data["n_rhp_real"][0] == 1 and data["slip_signal"] == "nu_r"


def test_rig_cli_composes_with_frf_estimate(tmp_path):
    out = tmp_path / "rec.csv"
    r = CliRunner().invoke(main, ["rig", "--excite", "T_ms", "--duration", "4.096",
                                  "--out", str(out)])
    assert r.exit_code == 0, r.output
    r = CliRunner().invoke(main, ["frf-estimate", str(out), "--input", "T_ms", "--output",
                                  "theta_ms", "--time", "time", "--json"])
    assert r.exit_code == 0, r.output


@pytest.fixture(scope="module")
def records(tmp_path_factory):
    """A seeded record of a known discrete filter, with little output noise."""
    rng = np.random.default_rng(7)
    fs, n = 500.0, 16384
    u = rng.normal(size=n)
    b, a = sig.butter(2, 0.1)
    y = sig.lfilter(b, a, u) + 1e-3 * rng.normal(size=n)
    path = tmp_path_factory.mktemp("rec") / "rec.csv"
    np.savetxt(path, np.c_[np.arange(n) / fs, u, y], delimiter=",", header="time,u,y",
               comments="")
    return path, (b, a), fs


def test_estimate_matches_known_filter(records, tmp_path):
    path, (b, a), fs = records
    plot = tmp_path / "frf.svg"
    res = run("frf-estimate", path, "--input", "u", "--output", "y", "--time", "time", "--json",
              "--plot", plot)
    assert res.exit_code == 0, res.output
    data = json.loads(res.stdout)
    assert data["fs_hz"] == pytest.approx(fs, rel=1e-9)  # from the uniform time column
    f = np.array(data["frequencies_hz"])
    H = np.array(data["H"])[0, 0, :, 0] + 1j * np.array(data["H"])[0, 0, :, 1]
    coh = np.array(data["coherence"])[0, 0]
    _, H_true = sig.freqz(b, a, worN=f, fs=fs)
    good = coh >= 0.9
    err = np.abs(H[good] - H_true[good]) / np.abs(H_true[good])
    # issue 5 item 6: median <= 2 %, 95th percentile <= 5 % where coherence >= 0.9
    assert np.median(err) <= 0.02 and np.percentile(err, 95) <= 0.05
    assert plot.stat().st_size > 1000


def test_estimate_text_leaves_out_frequencies_without_input_power(tmp_path):
    """A multisine excites only its lines: the text table shows the excited frequencies and
    says how many it left out (no rows of nan); --json keeps every frequency, null there."""
    fs, n = 100.0, 4096
    t = np.arange(n) / fs
    u = sum(np.sin(2 * np.pi * f * t + k) for k, f in enumerate((1.5625, 3.125, 6.25)))
    path = tmp_path / "ms.csv"
    np.savetxt(path, np.column_stack([t, u, 2 * u]), delimiter=",", header="time,u,y",
               comments="")
    res = run("frf-estimate", path, "--input", "u", "--output", "y", "--time", "time",
              "--nperseg", "256")
    assert res.exit_code == 0, res.output
    lines = res.stdout.strip().splitlines()
    assert "nan" not in res.stdout
    assert lines[-1].startswith("(") and "frequencies where the inputs carry no power are " \
        "left out" in lines[-1]
    shown = [float(ln.split()[0]) for ln in lines[1:-1]]
    assert 0 < len(shown) < 129  # some rows left out, the lines' neighbourhoods kept
    data = json.loads(run("frf-estimate", path, "--input", "u", "--output", "y", "--time",
                          "time", "--nperseg", "256", "--json").stdout)
    coh = data["coherence"][0][0]
    assert len(coh) == 129 and sum(c is None for c in coh) == 129 - len(shown)


def test_identify_draws_its_figure_only_when_asked(tmp_path):
    """`identify --out` writes the step responses and models, no figure; --plot FILE draws
    Fig. 2 (format from the suffix)."""
    res = run("identify", "--ratios", "1", "--out", tmp_path / "a", "--quiet")
    assert res.exit_code == 0, res.output
    assert sorted(p.name for p in (tmp_path / "a").iterdir()) == ["models.json",
                                                                  "steps_rg_1.csv"]
    res = run("identify", "--ratios", "1", "--quiet", "--plot", tmp_path / "fig2.svg")
    assert res.exit_code == 0, res.output
    assert (tmp_path / "fig2.svg").read_text().lstrip().startswith("<?xml")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a", "fig2.svg"]


def test_reproduce_writes_complete_report(full_report):
    """The one full build of the suite: every section, figure and table, and the claims."""
    res, out = full_report
    assert res.exit_code == 0, res.output
    html = (out / "index.html").read_text()
    for stem in ("fig4_actuation_modes", "fig5_actuation_energy", "fig6_actuation_frf",
                 "fig8_driveline_modes", "fig8_driveline_energy", "fig9_root_locus_cb",
                 "slip_stability_map", "fig2_identified_plant", "fig14_rig_T_mp"):
        assert (out / f"{stem}.png").exists() and (out / f"{stem}.svg").exists()
        assert f"{stem}.png" in html
    assert (out / "table1.csv").exists() and (out / "table2.csv").exists()
    claims = json.loads((out / "claims.json").read_text())
    assert len(claims) > 40 and all(c["verdict"] in ("shown", "NOT shown") for c in claims)
    leftovers = [p.name for p in out.parent.iterdir() if p.name != "rep"]
    assert leftovers == []  # the temporary folder was moved into place
    assert max(p.stat().st_size for p in out.glob("*.svg")) < 1_000_000  # rasterised layers
    # text is escaped: every "<" opens a tag or a comment (a bare "< 0.2" in a caption did not)
    stray = re.findall(r".{20}<(?![A-Za-z/!]).{20}", html)
    assert stray == []
    ids = re.findall(r"""\bid=["']([^"']+)["']""", html)
    assert len(ids) > 100 and sorted({i for i in ids if ids.count(i) > 1}) == []  # unique




def _numeric_keys(obj, units, out=None):
    """Keys whose values are numbers or arrays of numbers, anywhere in a JSON document (the
    subtree of a key that has a unit inherits it)."""
    out = set() if out is None else out
    if isinstance(obj, dict):
        for k, v in obj.items():
            flat = np.asarray(v, dtype=object).ravel() if isinstance(v, list) else [v]
            if len(flat) and all(isinstance(x, (int, float)) and not isinstance(x, bool)
                                 or x is None for x in flat) and any(x is not None for x in flat):
                out.add(k)
            if k not in units:
                _numeric_keys(v, units, out)
    elif isinstance(obj, list):
        for v in obj:
            _numeric_keys(v, units, out)
    return out


JSON_COMMANDS = [
    ("modes", "driveline"), ("frf", "actuation", "--n", "5"),
    ("slip", "statespace"), ("slip", "poles", "--slip", "0.01,0.02"), ("slip", "rootlocus"),
    ("slip", "frf", "--n", "5"), ("slip", "zeros", "--ratio", "0.5,1"),
    ("slip", "map", "--slip", "0.01:0.05:3", "--ratio", "0.5:2:3"), ("slip", "traction"),
    ("linearize",), ("nmp", "--ratios", "0.5"),
    ("efficiency", "--torque", "50", "--ratio", "1", "--strategy", "slip,hydraulic"),
]
# keys that are counts, indices, flags or free text rather than quantities with a unit
UNITLESS = {"n_rhp", "n_rhp_real", "zeros_at_origin", "n_averages", "order", "stable",
            "unstable", "version"}


@pytest.mark.parametrize("args", JSON_COMMANDS, ids=[" ".join(a) for a in JSON_COMMANDS])
def test_json_has_schema_and_units_for_every_quantity(args, tmp_path):
    res = run(*args, "--json")
    assert res.exit_code == 0, res.output
    doc = json.loads(res.stdout)
    assert doc["schema"]["version"] == 1 and doc["schema"]["name"].startswith("empact.")
    missing = {k for k in _numeric_keys(doc, doc["units"]) if k not in doc["units"]
               and k not in UNITLESS
               and not k.endswith("_units")}
    # every operating-point variable is spelled as in the paper, never 'ratio' or 'slip'
    assert missing <= {"operating_point"} | set(), missing
    assert not ({"ratio", "ratios", "slip"} & set(doc)), doc.keys()
    out = tmp_path / "o.json"
    res = run(*args, "--json-out", out) if args[0] != "linearize" else \
        run(*args, "--out", out)
    assert res.exit_code == 0, res.output
    assert json.loads(out.read_text())["schema"] == doc["schema"]


def test_reproduce_draws_vector_figures_on_request(tmp_path):
    """`reproduce` writes PNG figures by default (the page's) and SVG or PDF beside them only
    when --formats asks (issue 23: the SVGs added about 13 % to a whole build)."""
    for formats, want in ((None, {".png"}), ("png,svg", {".png", ".svg"}),
                          ("png,pdf", {".png", ".pdf"})):
        out = tmp_path / f"rep-{formats}"
        res = run("reproduce", "--out", out, "--sections", "fig10", "--quiet",
                  *(["--formats", formats] if formats else []))
        assert res.exit_code == 0, res.output
        assert {p.suffix for p in out.glob("fig10_*")} - {".csv"} == want, formats


def test_files_are_world_readable(tmp_path):
    old = os.umask(0o022)
    try:
        out = tmp_path / "rep"
        res = run("reproduce", "--out", out, "--sections", "table1", "--formats", "png",
                  "--quiet")
        assert res.exit_code == 0, res.output
    finally:
        os.umask(old)
    assert stat.S_IMODE(out.stat().st_mode) == 0o755
    assert all(stat.S_IMODE(p.stat().st_mode) == 0o644 for p in out.iterdir())


# -- bad input: one line, exit 2, nothing written ---------------------------------------------
GOOD_TARGETS = ('free = ["driveline.k_tc"]\n[[target]]\nmodel = "driveline"\n'
                'uncoupled = "primary"\nfrequency_hz = 24.6\n')
SCENARIO = ("[scenario]\nduration = 0.05\n[initial]\nr_g = 1.0\nomega_p = 300.0\nF_s = 1e4\n"
            "T_l = 20.0\n")
RECORDS = "time,u,y\n" + "".join(f"{i / 100},{np.sin(i)},{np.cos(i)}\n" for i in range(64))


@pytest.fixture
def files(tmp_path, monkeypatch):
    """Input files in a fresh working folder (outputs go there too)."""
    monkeypatch.chdir(tmp_path)
    w = lambda name, text: (tmp_path / name).write_text(text)  # noqa: E731
    w("neg.toml", "[driveline]\nJ_p = -1.0\n")
    w("huge_int.toml", "[actuation]\nk_w = " + "9" * 400 + "\n")
    (tmp_path / "binary.toml").write_bytes(bytes(range(256)) * 4)
    (tmp_path / "latin1.toml").write_bytes("[driveline]\n# r\xe9glage\nJ_d = 0.2\n"
                                           .encode("latin-1"))
    w("kw.toml", "[actuation]\nk_w = 1e300\n")
    w("beta.toml", "[variator]\nbeta = 1e-300\n")
    w("scaled.toml", "[actuation]\nk_tp = 6e19\nk_ts = 6e19\n")
    w("nu.toml", "[operating]\nnu = 0.99\n")
    w("rmax.toml", "[variator]\nR_max = 0.07\n")
    w("unknown.toml", "[driveline]\nJ_x = 1.0\n")
    w("string.toml", "[driveline]\nJ_p = \"heavy\"\n")
    w("syntax.toml", "[driveline\n")
    (tmp_path / "folder.toml").mkdir()
    w("targets.toml", GOOD_TARGETS)
    w("bad_targets.toml", 'free = ["driveline.k_xx"]\n')
    w("bad_traction.csv", "r_g,nu,mu\n1,0,0\n1,0.02,0.09\n1,0.01,0.1\n")
    w("neg_map.csv", "r_g,omega_in,T_in [N m],F_s,T_loss [N m]\n1,300,0,1e4,1\n1,300,50,1e4,-1\n")
    w("hole_map.csv", "r_g,omega_in,T_in,F_s,T_loss\n1,300,0,1e4,1\n2,300,50,1e4,2\n")
    w("ok_map.csv", "r_g,omega_in,T_in,F_s,T_loss\n1,300,0,1e4,1\n1,300,50,1e4,2\n")
    w("sc_input.toml", SCENARIO + "[inputs]\nT_zz = [[0, 1]]\n")
    w("sc_times.toml", SCENARIO + "[inputs]\nT_l = [[0.5, 1], [0.2, 3]]\n")
    w("sc_rtol.toml", SCENARIO + "[solver]\nrtol = 2.0\n")
    w("sc_belt.toml", SCENARIO + "[model]\nbelt = 'glued'\n")
    w("sc_table.toml", SCENARIO + "[extra]\na = 1\n")
    w("sc_nodur.toml", "[scenario]\nname = 'x'\n")
    w("rec.csv", RECORDS)
    w("rec_x.csv", "time,u,y\n" + "".join(f"{i},1,x\n" for i in range(20)))
    w("rec_nan.csv", "time,u,y\n" + "".join(f"{i},1,nan\n" for i in range(20)))
    w("rec_short.csv", "time,u,y\n" + "".join(f"{i},1,2\n" for i in range(5)))
    w("rec_uneven.csv", "time,u,y\n" + "".join(f"{i * i},1,{i}\n" for i in range(20)))
    (tmp_path / "rec_bin.csv").write_bytes(b"\x00\x01\x02" * 50)
    (tmp_path / "rec_latin1.csv").write_bytes(("time,u,\xfc\n" + "1,2,3\n" * 20)
                                              .encode("latin-1"))
    w("existing.png", "not yours to overwrite")
    sp = '[spread."actuation.k_w"]\n'
    w("sp_ok.toml", sp + 'distribution = "normal"\nrel_std = 0.05\n')
    w("sp_kind.toml", sp + 'distribution = "gaussian"\nstd = 1\n')
    w("sp_name.toml", '[spread."actuation.k_x"]\ndistribution = "uniform"\nlower = 1\n'
                      'upper = 2\n')
    w("sp_std.toml", sp + 'distribution = "normal"\n')
    w("sp_bounds.toml", sp + 'distribution = "uniform"\nlower = 2\nupper = 1\n')
    w("sp_tail.toml", sp + 'distribution = "normal"\nstd = 1\nlower = 100\nupper = 101\n')
    w("sp_key.toml", sp + 'distribution = "normal"\nstd = 1\nsigma = 2\n')
    w("sp_empty.toml", "# nothing\n")
    w("sp_ln.toml", sp + 'distribution = "lognormal"\n')
    (tmp_path / "full").mkdir()
    w("full/thesis.tex", "precious")
    # issue 22: files that were accepted or leaked internals
    w("rec_dup.csv", "time,u,u,y\n" + "".join(f"{i / 100},1,2,{i}\n" for i in range(20)))
    w("rec_dup2.csv", "time,u,y,z,z\n" + "".join(f"{i / 100},1,{i},2,3\n" for i in range(20)))
    w("rec_back.csv", "time,u,y\n" + "".join(f"{(2 if i == 5 else i) / 100},1,{i}\n"
                                             for i in range(20)))
    w("text.npz", "a text file, not an archive\n")
    np.savez(tmp_path / "noarrays.npz", x=np.zeros(3))
    (tmp_path / "trunc.npz").write_bytes((tmp_path / "noarrays.npz").read_bytes()[:100])
    w("family.mat", "named .mat")
    pi = json.loads(resources.files("empact.data").joinpath("control", "pi.json").read_text())
    w("pi.json", json.dumps(pi))
    w("hinf.json", resources.files("empact.data").joinpath("control", "hinf.json").read_text())
    for name, change in {"c_str": {"D": [["1", "2"], ["3", "4"]]},
                         "c_flat": {"D": [1, 2, 3, 4, 5, 6]},
                         "c_rows": {"D": [[1, 2, 3], [4, 5, 6]]},
                         "c_out": {"outputs": ["T_xx", "T_ms"]},
                         "c_meas": {"measured": ["r_g", "nu_x"]},
                         "c_bool": {"A": [[True] * 6] * 6}, "c_dt": {"dt": "fast"},
                         "c_schema": {"schema": {"name": "other"}}}.items():
        w(f"{name}.json", json.dumps({**pi, **change}))
    w("c_text.json", "not JSON")
    step = resources.files("empact.data").joinpath("control", "slip-load-step-r1.toml") \
        .read_text()
    assert "tau = [[0.0, 0.9]]" in step  # the set-point by torque ratio
    w("ref_nu.toml", step.replace("tau = [[0.0, 0.9]]", "nu = [[0.0, 0.01], [1.0, 2.0]]"))
    w("ref_rg.toml", step.replace("tau = [[0.0, 0.9]]",
                                  "tau = [[0.0, 0.9]]\nr_g = [[0.0, 1.0], [1.0, 9.0]]"))
    # issue 31 / 35: a scenario's references beyond the model's ranges, refused by the loader
    w("ref_peak.toml", step.replace("tau = [[0.0, 0.9]]", "nu = [[0.0, 0.01], [1.0, 0.15]]"))
    shift = resources.files("empact.data").joinpath("scenarios", "shift-and-load-step.toml") \
        .read_text()
    assert "[5.2, 2.2500]]" in shift and "F_s_ref = [[0.0, 30000.0]]" in shift
    w("open_rg.toml", shift.replace("[5.2, 2.2500]]", "[5.2, 9.0]]"))
    w("open_fs.toml", shift.replace("F_s_ref = [[0.0, 30000.0]]",
                                    "F_s_ref = [[0.0, 30000.0], [1.0, -5000.0]]"))
    w("sp_out.toml", sp + 'distribution = "uniform"\nlower = -2\nupper = -1\n')
    w("sp_nu.toml", '[spread."operating.nu"]\ndistribution = "uniform"\nlower = 0.3\n'
                    'upper = 0.4\n')
    w("t_nofree.toml", '[[target]]\nmodel = "driveline"\n')
    w("op_load.toml", "[operating]\nT_l = 1e5\nF_s = 1e4\n")
    w("out.json", "mine")
    w("out.png", "mine")
    w("out.csv", "mine")
    # issue 35: the campaign's classes (OS errors, guarded readers, units, symlinks, ranges)
    os.mkfifo(tmp_path / "fifo.toml")
    os.mkfifo(tmp_path / "fifo.json")
    os.mkfifo(tmp_path / "fifo.csv")
    w("deep.json", "[" * 100_000 + "]" * 100_000)
    w("deep.toml", "a = " + "[" * 100_000 + "]" * 100_000 + "\n")
    w("deep40.json", json.dumps({**pi, "design": json.loads("[" * 40 + "]" * 40)}))
    w("c99.json", json.dumps({**pi, "schema": {**pi["schema"], "version": 99}}))
    w("c_units.json", json.dumps({**pi, "outputs_units": ["N m"]}))
    w("c_rpm.json", json.dumps({**pi, "outputs_units": ["N m", "rpm"]}))
    os.symlink(tmp_path / "nowhere" / "x.npz", tmp_path / "dang.npz")
    os.symlink(tmp_path / "nowhere" / "x.csv", tmp_path / "dang.csv")
    os.symlink(tmp_path / "out.json", tmp_path / "link.json")
    rows = "".join(f"{i},{np.sin(i)},{np.cos(i)}\n" for i in range(64))
    w("rec_unit.csv", "time [fortnight],u,y\n" + rows)
    w("rec_tq.csv", "time [N m],u,y\n" + rows)
    w("rec_yunit.csv", "time [ms],u [furlong],y\n" + rows)
    w("rec_dead.csv", "time,u,y\n" + "".join(f"{i / 100},{np.sin(i)},0\n" for i in range(64)))
    w("rec_flat.csv", "time,u,y\n" + "".join(f"{i / 100},2.5,{np.sin(i)}\n" for i in range(64)))
    np.savez(tmp_path / "fam_nan.npz", axes=np.array(["r_g"]), axis_r_g=np.array([1.0, 2.0]),
             A=np.array([[[np.nan]], [[-1.0]]]), B=np.ones((2, 1, 1)), C=np.ones((2, 1, 1)),
             D=np.zeros((2, 1, 1)), states=np.array(["x"]), inputs=np.array(["T_mp"]),
             outputs=np.array(["nu"]), ok=np.array([True, True]), reason=np.array(["", ""]))
    w("t_inf.toml", GOOD_TARGETS.replace("24.6", "inf"))
    w("t_miss.toml", GOOD_TARGETS.replace("frequency_hz = 24.6\n", ""))
    w("sc_steps.toml", SCENARIO + "[solver]\nmax_steps = 1.5\n")
    w("sp_ln100.toml", sp + 'distribution = "lognormal"\nsigma = 100\n')
    # issue 35, round 4: the campaign on cycle, efficiency, tune, fmu export, --resume, --at
    hdr = "time [s],speed [km/h]\n"
    for name, rows in {"t_back": "0,0\n2,10\n1,20\n4,0\n", "t_neg": "0,0\n2,-10\n4,0\n",
                       "t_one": "0,0\n", "t_text": "0,0\n2,fast\n4,0\n",
                       "t_huge": "0,0\n10,100000\n20,0\n", "t_dup": "0,0\n2,10\n2,12\n"}.items():
        w(f"{name}.csv", hdr + rows)
    w("t_knots.csv", "time [s],speed [knots]\n0,0\n2,5\n")
    w("t_rpm.csv", "time [s],speed [rpm]\n0,0\n2,5\n")
    w("t_fortnight.csv", "time [fortnight],speed [km/h]\n0,0\n2,5\n")
    w("t_nounit.csv", "time [s],speed\n0,0\n2,5\n")
    w("t_semi.csv", "time [s];speed [km/h]\n0;0\n2;5\n")
    w("t_phase.csv", "time [s],speed [km/h],phase\n0,0," + "p" * 300 + "\n2,5,x\n")
    w("veh_neg.toml", "[vehicle]\nmass = -1300\n")
    w("k_disc.json", json.dumps({**pi, "dt": 0.001}))
    man = {"schema": {"name": "empact.study.manifest", "version": 1}, "spec_hash": "0",
           "spec": {}, "runs": 4, "chunk_size": 4, "chunks": [[0, 4]], "completed": [0]}
    for name, doc in {"st_v99": {**man, "schema": {**man["schema"], "version": 99}},
                      "st_chunks": {**man, "chunks": [["a", "b"]]},
                      "st_gap": {**man, "chunks": [[0, 2], [3, 4]]},
                      "st_done": {**man, "completed": [-5, 10**9]},
                      "st_schema": {**man, "schema": {"name": "other"}}}.items():
        (tmp_path / name).mkdir()
        w(f"{name}/manifest.json", json.dumps(doc))
    (tmp_path / "st_bad").mkdir()
    w("st_bad/manifest.json", "{not json")
    (tmp_path / "st_deep").mkdir()
    w("st_deep/manifest.json", "[" * 50_000 + "]" * 50_000)
    return tmp_path


#: a file name longer than any file system allows (255 bytes)
LONG = "x" * 300


BAD_INPUT = [
    # click's own usage errors
    (["--nope"], "no such option"),
    (["nosuchcmd"], "no such command"),
    (["modes"], "missing argument"),
    (["modes", "gearbox"], "invalid value for"),
    (["frf", "actuation", "--n", "1e8"], "'1e8' is not a valid integer"),
    (["slip", "poles", "--bogus"], "no such option"),
    # the FMU export
    (["fmu", "export", "--out", "m.txt"], "--out m.txt: file suffix '.txt' must be one of .fmu"),
    (["fmu", "export", "--out", "m.fmu", "--rtol", "nan"], "--rtol = nan: must be a finite"),
    (["fmu", "export", "--out", "m.fmu", "--duration", "0"], "--duration = 0: allowed range"),
    (["fmu", "export", "--out", "m.fmu", "--tau", "2"], "--tau = 2: allowed range"),
    (["fmu", "export", "--out", "m.fmu", "--controller", "no.json"], "no.json: no such "
     "controller file"),
    (["fmu", "export", "--out", "m.fmu", "--params", "neg.toml"], "driveline.J_p = -1"),
    # parameter files
    (["params", "validate", "missing.toml"], "missing.toml: no such parameter file"),
    (["params", "validate", "neg.toml"], "neg.toml: driveline.J_p = -1: allowed range"),
    (["params", "validate", "huge_int.toml"], "huge_int.toml: actuation.k_w = 99999999...(400"),
    (["params", "validate", "binary.toml"], "binary.toml: a binary file, not a parameter file"),
    (["params", "validate", "latin1.toml"], "latin1.toml: not a UTF-8 text file"),
    (["params", "validate", "kw.toml"], "kw.toml: actuation.k_w = 1e+300: allowed range"),
    (["params", "validate", "beta.toml"], "beta.toml: variator.beta = 1e-300: allowed range"),
    (["params", "validate", "scaled.toml"], "scaled.toml: actuation.k_tp = 6e+19"),
    (["params", "validate", "nu.toml"], "nu.toml: operating.nu = 0.99: outside the valid slip"),
    (["params", "validate", "unknown.toml"], "unknown.toml: unknown key 'driveline.J_x'"),
    (["params", "validate", "string.toml"], "string.toml: driveline.J_p = 'heavy': must be a"),
    (["params", "validate", "syntax.toml"], "syntax.toml: not valid TOML"),
    (["params", "validate", "folder.toml"], "File 'folder.toml' is a directory"),
    (["params", "show", "kw.toml"], "kw.toml: actuation.k_w = 1e+300"),
    (["modes", "actuation", "--params", "nu.toml"], "nu.toml: operating.nu = 0.99"),
    # linear models
    (["modes", "driveline", "--ratio", "7"], "--ratio = 7: outside the geometric ratio range"),
    (["modes", "driveline", "--ratio", "nan"], "--ratio = nan: must be a finite number"),
    (["frf", "actuation", "--n", "100000000"], "--n = 100000000: must be a whole number in"),
    (["frf", "actuation", "--n", "1"], "--n = 1: must be a whole number in [2, 100000]"),
    (["frf", "actuation", "--fmin", "10", "--fmax", "1"], "--fmax = 1: allowed range is (10,"),
    (["frf", "actuation", "--fmin", "-1"], "--fmin = -1: allowed range is (0,"),
    (["frf", "actuation", "--output", "theta_xx"], "unknown output 'theta_xx'"),
    (["frf", "actuation", "--input", "T_zz"], "unknown input 'T_zz'"),
    (["frf", "actuation", "--plot", "nodir/x.png"], "--plot nodir/x.png: folder nodir does not"),
    (["frf", "actuation", "--plot", "x.gif"], "--plot x.gif: file suffix '.gif' must be one of"),
    (["frf", "actuation", "--plot", "/proc/x.png"], "--plot /proc/x.png: cannot write in /proc"),
    (["frf", "actuation", "--plot", "existing.png"], "--plot existing.png: exists; give --force"),
    (["frf", "actuation", "--json-out", "full"], "File 'full' is a directory"),
    (["calibrate", "bad_targets.toml", "--out", "c.toml"], "free parameter 'driveline.k_xx'"),
    (["calibrate", "targets.toml", "--out", "no/c.toml"], "--out no/c.toml: folder no does not"),
    (["calibrate", "targets.toml", "--out", "/proc/c.toml"], "cannot write in /proc"),
    (["calibrate", "targets.toml", "--out", "c.toml", "--tolerance", "0"], "--tolerance = 0"),
    (["calibrate", "targets.toml", "--out", "c.toml", "--params", "neg.toml"], "neg.toml: "),
    (["calibrate", "targets.toml", "--out", "c.toml", "--tie", "driveline.k_ds"],
     "--tie 'driveline.k_ds': expected DEPENDENT=FREE"),
    (["calibrate", "targets.toml", "--out", "c.toml", "--tie", "driveline.k_ds=driveline.J_p"],
     "driveline.J_p is not a free parameter"),
    (["calibrate", "targets.toml", "--out", "c.toml", "--tie", "driveline.J_p=driveline.k_tc"],
     "units differ"),
    (["calibrate", "targets.toml", "--out", "c.toml", "--kinematics", "sideways"],
     "invalid value for '--kinematics'"),
    (["linearize", "--thrust-ratio", "nosuch.csv"], "nosuch.csv: no such thrust-ratio table"),
    (["linearize", "--shift-law", "magic"], "invalid value for '--shift-law'"),
    (["nmp", "--slip-signal", "eq2"], "invalid value for '--slip-signal'"),
    (["frf", "actuation", "--pulley-damping", "creep", "--clamp", "-5"], "--clamp = -5"),
    (["plants", "--ratio", "0.1:2:3"], "--ratio = 0.1: outside the geometric ratio range"),
    (["plants", "--slip", "0.01", "--clamp", "1e4", "--load-torque", "50"],
     "give at most two of"),
    (["plants", "--load", "50"], "the load torque is --load-torque now"),
    (["plants", "--slip", "0.01", "--tau", "0.9"], "give the slip as --slip or as --tau, not both"),
    (["linearize", "--load-torque", "50"], "also give one of them"),
    (["plants", "--out", "x.txt"], "--out x.txt: file suffix '.txt' must be one of"),
    (["plants", "--clamp", "-3"], "--clamp = -3"),
    (["plants", "--cruise"], "--cruise: the road load needs --driveline vehicle"),
    (["plants", "--driveline", "vehicle", "--cruise", "--tau", "0.9", "--clamp", "5e3"],
     "--cruise: give at most one of"),
    (["plants", "--driveline", "vehicle", "--drive", "speed"],
     "--drive: not with --driveline vehicle"),
    (["plants", "--driveline", "car"], "invalid value for '--driveline'"),
    (["plants", "--scheduler", ""], "--scheduler: an empty value"),
    (["plants", "--scheduler", "local", "--workers", "0"], "--workers = 0: must be a whole"),
    (["plants", "--scheduler-timeout", "0"], "--scheduler-timeout = 0: allowed range"),
    (["slip", "map", "--slip", "0.001:0.02:4", "--ratio", "0.5:2:3", "--workers", "0"],
     "--workers = 0"),
    # Monte Carlo
    (["montecarlo"], "--spread: give a spread file (--example-spread prints one)"),
    (["montecarlo", "--spread", "nosuch.toml"], "nosuch.toml: no such spread file"),
    (["montecarlo", "--spread", "sp_kind.toml"], "distribution = 'gaussian'; choose one of"),
    (["montecarlo", "--spread", "sp_name.toml"], "unknown parameter 'actuation.k_x'"),
    (["montecarlo", "--spread", "sp_std.toml"], "give one of std or rel_std"),
    (["montecarlo", "--spread", "sp_bounds.toml"], "lower = 2 must be below upper = 1"),
    (["montecarlo", "--spread", "sp_tail.toml"], "keep no probability"),
    (["montecarlo", "--spread", "sp_key.toml"], "unknown key 'sigma' for a normal"),
    (["montecarlo", "--spread", "sp_empty.toml"], "no [spread.\"section.name\"] table"),
    (["montecarlo", "--spread", "sp_ln.toml"], "a lognormal distribution needs sigma"),
    (["montecarlo", "--spread", "sp_ok.toml", "--runs", "0"], "--runs = 0: must be a whole"),
    (["montecarlo", "--spread", "sp_ok.toml", "--seed", "-2"], "--seed = -2"),
    (["montecarlo", "--spread", "sp_ok.toml", "--analysis", "closed-loop"],
     "give exactly one of --scenario FILE or --example NAME"),
    (["montecarlo", "--spread", "sp_ok.toml", "--example", "slip-load-step-r1"],
     "--analysis plant: --scenario, --example and --controller belong to"),
    (["montecarlo", "--spread", "sp_ok.toml", "--analysis", "closed-loop", "--example",
      "nosuch"], "unknown control example 'nosuch'"),
    (["montecarlo", "--spread", "sp_ok.toml", "--out", "full"], "not empty"),
    (["montecarlo", "--spread", "sp_ok.toml", "--scheduler", "local", "--workers", "999"],
     "--workers = 999"),
    (["control", "design", "--bandwidth", "1", "--out", "c.json"],
     "--bandwidth '1': two numbers RATIO,SLIP"),
    (["control", "design", "--bandwidth", "0,1", "--out", "c.json"], "--bandwidth = 0"),
    # (an ill-posed H-infinity problem: tests/test_control.py's
    # test_hinf_refuses_ill_posed_problems; the torque-driven machine's rigid-body mode that
    # made one here is damped by the variator's drag since issue 32, so the design is posed)
    (["control", "design", "--nominal", "9,9", "--out", "c.json"],
     "--nominal '9,9': indices in a grid of shape (7, 3, 5)"),
    (["control", "check", "nosuch.json", "--family", "f.npz"], "nosuch.json: no such controller"),
    (["control", "simulate"], "give exactly one of SCENARIO or --example"),
    (["control", "simulate", "--example", "nosuch"], "unknown control example 'nosuch'"),
    # slip dynamics
    (["slip", "poles", "--slip", "0.001:0.04"], "a range is start:stop:count"),
    (["slip", "poles", "--slip", "0.001:0.06:100000000"], "count 100000000 must be in [2, "),
    (["slip", "poles", "--slip", "0.001:0.04:x"], "count must be a whole number"),
    (["slip", "poles", "--slip", "abc"], "not a number"),
    (["slip", "poles", "--ratio", "5"], "--ratio = 5: outside the geometric ratio range"),
    (["slip", "poles", "--speed", "0"], "--speed = 0: allowed range is (0, 2000] [rad/s]"),
    (["slip", "statespace", "--slip", "0.3"], "--slip = 0.3: allowed range is [-0.2, 0.2]"),
    (["slip", "statespace", "--clamp", "-1"], "--clamp = -1: allowed range is [0, inf) [N]"),
    (["slip", "poles", "--slip", "0.01,0.02", "--ratio", "1,2"], "at most 1"),
    (["slip", "map", "--slip", "0.001:0.04:5"], "exactly 2"),
    (["slip", "map", "--slip", "0.001:0.06:3000", "--ratio", "0.5:2:3000"],
     "3000 x 3000 = 9000000 points; at most 4000000"),
    (["slip", "map", "--slip", "0.01:0.04:3", "--ratio", "0.5:2:3", "--chunk", "0"],
     "--chunk = 0"),
    (["slip", "map", "--slip", "0.001:0.04:5", "--speed", "0:300:4"], "--speed = 0"),
    (["slip", "rootlocus", "--cb-min", "-1"], "--cb-min = -1: allowed range is (0, inf)"),
    (["slip", "rootlocus", "--cb-min", "10", "--cb-max", "1"], "--cb-max = 1"),
    (["slip", "poles", "--traction", "bad_traction.csv"], "nu must increase"),
    (["slip", "traction", "--traction", "missing.csv"], "missing.csv"),
    (["slip", "frf", "--n", "1"], "--n = 1"),
    (["slip", "zeros", "--clamp", "1000,2000"], "only --ratio may be a list or range"),
    (["slip", "map", "--slip", "0.01:0.04:3", "--ratio", "0.5:2:3", "--plot", "m.bmp"],
     "file suffix '.bmp'"),
    # the nonlinear model
    (["simulate"], "give exactly one of SCENARIO or --example"),
    (["simulate", "--example", "nope"], "example 'nope': choose from"),
    (["simulate", "missing.toml"], "missing.toml: no such scenario file"),
    (["simulate", "--example", "servo-torque-steps", "--duration", "-1"],
     "--duration = -1: allowed range is (0, 3600] [s]"),
    (["simulate", "--example", "servo-torque-steps", "--duration", "1e9"], "--duration = 1e+09"),
    (["simulate", "--example", "servo-torque-steps", "--out", "."], "current folder"),
    (["simulate", "--example", "servo-torque-steps", "--out", ".."], "current folder"),
    (["simulate", "--example", "servo-torque-steps", "--out", "full"], "not empty"),
    (["simulate", "--example", "servo-torque-steps", "--out", "existing.png"], "is a file"),
    (["simulate", "--example", "servo-torque-steps", "--formats", "png,eps"],
     "--formats = 'eps': must be one of png, svg, pdf"),
    (["simulate", "sc_input.toml"], "unknown input 'T_zz'"),
    (["simulate", "sc_times.toml"], "must be >= 0 and non-decreasing"),
    (["simulate", "sc_rtol.toml"], "solver.rtol = 2: allowed range"),
    (["simulate", "sc_belt.toml"], "belt = 'glued': must be one of"),
    (["simulate", "sc_table.toml"], "unknown table [extra]"),
    (["simulate", "sc_nodur.toml"], "missing scenario.duration"),
    (["linearize", "--ratio", "9"], "--ratio = 9: outside the geometric ratio range"),
    (["linearize", "--clamp", "-5"], "--clamp = -5: allowed range is (0, inf) [N]"),
    (["linearize", "--clamp", "0"], "--clamp = 0: allowed range is (0, inf) [N]"),
    (["linearize", "--slip", "0.5"], "--slip = 0.5: allowed range is [-0.2, 0.2]"),
    (["linearize", "--format", "mat"], "--format mat needs --out FILE"),
    (["linearize", "--out", "p.xyz"], "--out p.xyz: file suffix '.xyz' must be one of"),
    (["nmp", "--ratios", "a,b"], "--ratios 'a,b': must be comma-separated numbers"),
    (["efficiency", "--strategy", "sf2"], "--strategy = 'sf2': must be one of"),
    (["efficiency", "--speed", "0"], "--speed = 0"),
    (["efficiency", "--json-out", "out.json"], "--json-out out.json: exists; give --force"),
    (["cycle", "--cycle", "wltc"], "--cycle 'wltc': not a shipped cycle"),
    (["cycle", "--cycle", "nedc", "--strategies", "sf2"], "--strategies = 'sf2': must be one"),
    (["cycle", "--cycle", "nedc", "--rate", "500"], "--rate: only with --dynamic"),
    (["cycle", "--cycle", "nedc", "--dynamic", "--rate", "5"], "--rate = 5"),
    (["cycle", "--cycle", "nedc", "--dynamic", "--output-rate", "0"], "--output-rate = 0"),
    (["cycle", "--cycle", "nedc", "--json-out", "out.json"],
     "--json-out out.json: exists; give --force"),
    # a measured loss map (issue 32): read while the options are parsed
    (["efficiency", "--loss-map", "neg_map.csv"],
     "--loss-map: neg_map.csv: T_loss = -1 at r_g = 1, omega_in = 300 rad/s, T_in = 50 N m"),
    (["cycle", "--cycle", "nedc", "--loss-map", "nosuch_map.csv"], "nosuch_map.csv"),
    (["simulate", "--example", "servo-torque-steps", "--loss-map", "hole_map.csv"],
     "not a full grid: 2 rows for 2 x 1 x 2 x 1 = 4 points"),
    (["linearize", "--loss-map", "bad_traction.csv"], "must name the columns r_g, omega_in"),
    (["nmp", "--loss-map", "sp_ok.toml"], "a loss map must be .csv, not '.toml'"),
    (["control", "simulate", "--example", "slip-load-step-r1", "--loss-map", "neg_map.csv"],
     "must be >= 0 [N m]"),
    (["control", "check", "pi.json", "--family", "f.npz", "--loss-map", "ok_map.csv"],
     "--loss-map: give it with the design family, not with --family"),
    (["plants", "--loss-map", ""], "--loss-map: an empty value"),
    (["montecarlo", "--spread", "sp_ok.toml", "--analysis", "slip", "--loss-map",
      "ok_map.csv"], "--loss-map: the slip analysis's linear slip model has no torque loss"),
    (["identify", "--loss-map", "hole_map.csv"], "not a full grid"),
    (["rig", "--loss-map", "neg_map.csv", "--out", "r.csv"], "must be >= 0 [N m]"),
    (["nmp", "--fmax", "-1"], "--fmax = -1: allowed range is (0, 100000]"),
    (["nmp", "--ratios", "9"], "--ratios = 9: outside the geometric ratio range"),
    (["nmp", "--speed", "-300"], "--speed = -300"),
    # identification
    (["identify", "--ratios", "0.5,x"], "--ratios '0.5,x'"),
    (["identify", "--ratios", "9"], "--ratios = 9"),
    (["identify", "--order", "0"], "--order = 0: must be a whole number in [1, 200]"),
    (["identify", "--step", "0"], "--step = 0: must be a non-zero torque"),
    (["identify", "--out", "."], "current folder"),
    (["identify", "--out", "full"], "not empty"),
    (["rig", "--band", "5:1", "--out", "r.csv"], "--band (high end) = 1"),
    (["rig", "--band", "abc", "--out", "r.csv"], "--band 'abc': give LO:HI"),
    (["rig", "--duration", "-1", "--out", "r.csv"], "--duration = -1"),
    (["rig", "--duration", "1e9", "--out", "r.csv"], "--duration = 1e+09"),
    (["rig", "--fs", "1e5", "--duration", "100", "--out", "r.csv"], "samples; at most 2000000"),
    (["rig", "--out", "nodir/r.csv"], "--out nodir/r.csv: folder nodir does not exist"),
    (["rig", "--seed", "-1", "--out", "r.csv"], "--seed = -1"),
    (["rig", "--rms", "0", "--out", "r.csv"], "--rms = 0"),
    (["rig", "--ratio", "9", "--out", "r.csv"], "--ratio = 9"),
    (["frf-estimate", "rec.csv", "--input", "u", "--output", "zz", "--fs", "500"],
     "rec.csv: no column 'zz'"),
    (["frf-estimate", "rec.csv", "--input", "u", "--output", "y"], "give exactly one of --fs"),
    (["frf-estimate", "rec.csv", "--input", "u", "--output", "y", "--fs", "-3"], "--fs = -3"),
    (["frf-estimate", "rec.csv", "--input", "u", "--output", "y", "--fs", "500", "--method",
      "H3"], "invalid value for '--method'"),
    (["frf-estimate", "rec.csv", "--input", "u", "--output", "y", "--fs", "100", "--nperseg",
      "1"], "--nperseg = 1: must be a whole number in [8, 64]"),
    (["frf-estimate", "missing.csv", "--input", "u", "--output", "y", "--fs", "1"],
     "missing.csv: no such data file"),
    (["frf-estimate", "rec_x.csv", "--input", "u", "--output", "y", "--time", "time"],
     "'x' is not a number"),
    (["frf-estimate", "rec_nan.csv", "--input", "u", "--output", "y", "--time", "time"],
     "is not finite"),
    (["frf-estimate", "rec_short.csv", "--input", "u", "--output", "y", "--time", "time"],
     "at least 16"),
    (["frf-estimate", "rec_uneven.csv", "--input", "u", "--output", "y", "--time", "time"],
     "not uniformly sampled"),
    (["frf-estimate", "rec_bin.csv", "--input", "u", "--output", "y", "--fs", "1"],
     "rec_bin.csv: a binary file"),
    (["frf-estimate", "rec_latin1.csv", "--input", "u", "--output", "y", "--fs", "1"],
     "rec_latin1.csv: not a UTF-8 text"),
    # the report
    (["reproduce", "--out", "."], "current folder"),
    (["reproduce", "--out", "full"], "not empty"),
    (["reproduce", "--out", "r", "--formats", "gif"], "--formats = 'gif': must be one of"),
    (["reproduce", "--out", "r", "--sections", "fig99"], "--sections = 'fig99': must be one"),
    (["reproduce", "--out", "r", "--params", "rmax.toml"],
     "rmax.toml: variator (R_min = 0.03 m, R_max = 0.07 m) gives the ratio range"),
    # -- issue 22 ---------------------------------------------------------------------------
    # an existing file is never replaced without --force (every output option: test_outputs)
    (["modes", "driveline", "--json-out", "out.json"], "--json-out out.json: exists; give"),
    (["slip", "poles", "--json-out", "out.json"], "--json-out out.json: exists; give --force"),
    (["nmp", "--json-out", "out.json"], "--json-out out.json: exists; give --force"),
    (["nmp", "--plot", "out.png"], "--plot out.png: exists; give --force to replace it"),
    (["frf-estimate", "rec.csv", "--input", "u", "--output", "y", "--fs", "100", "--json-out",
      "out.json"], "--json-out out.json: exists; give --force"),
    (["identify", "--json-out", "out.json"], "--json-out out.json: exists; give --force"),
    (["montecarlo", "--spread", "sp_ok.toml", "--json-out", "out.json"], "out.json: exists"),
    (["control", "check", "c_str.json", "--family", "f.npz", "--json-out", "out.json"],
     "--json-out out.json: exists; give --force"),
    (["control", "simulate", "--example", "slip-load-step-r1", "--out", "out.csv"],
     "--out out.csv: exists; give --force"),
    (["rig", "--out", "out.csv"], "--out out.csv: exists; give --force to replace it"),
    # the format follows the suffix, and --format must match it
    (["linearize", "--format", "mat", "--out", "plant.npz"],
     "--out plant.npz: file suffix '.npz' does not match --format mat"),
    (["modes", "driveline", "--json-out", "modes.txt"], "file suffix '.txt' must be one of"),
    (["rig", "--out", "rec.txt"], "--out rec.txt: file suffix '.txt' must be one of .csv"),
    (["calibrate", "targets.toml", "--out", "c.json"], "file suffix '.json' must be one of"),
    (["control", "design", "--out", "c.json", "--json-out", "c.json"],
     "--json-out c.json: the same file as --out"),
    # plant families: a corrupt or foreign file is one line, no zipfile / numpy text
    (["control", "check", "pi.json", "--family", "text.npz"],
     "text.npz: not a plant family (not a readable .npz archive; write one with `empact "
     "plants --out FILE.npz`)"),
    (["control", "check", "pi.json", "--family", "trunc.npz"],
     "trunc.npz: not a plant family (not a readable .npz archive"),
    (["control", "check", "pi.json", "--family", "noarrays.npz"],
     "noarrays.npz: not a plant family (no axes, A, B, C, D"),
    (["control", "check", "pi.json", "--family", "family.mat"],
     "family.mat: a plant family is read from .npz, not '.mat' (write one with `empact "
     "plants --out FILE.npz`)"),
    (["control", "check", "pi.json", "--family", "nosuch.npz"],
     "nosuch.npz: no such plant family file"),
    # controllers: every key checked, named with its value and what is allowed
    (["control", "check", "c_schema.json", "--family", "f.npz"], "not a controller file"),
    (["control", "check", "c_text.json", "--family", "f.npz"],
     "c_text.json: not a controller file (not JSON text)"),
    (["control", "check", "c_str.json", "--family", "f.npz"],
     "c_str.json: D[0][0] = '1': must be a number"),
    (["control", "check", "c_flat.json", "--family", "f.npz"],
     "c_flat.json: D must be a list of rows (expected 2 x 2 (outputs x measured))"),
    (["control", "check", "c_rows.json", "--family", "f.npz"],
     "c_rows.json: D has 2 rows of 3 entries; expected 2 x 2 (outputs x measured)"),
    (["control", "check", "c_out.json", "--family", "f.npz"],
     "c_out.json: outputs names 'T_xx'; allowed: T_mp, T_ms"),
    (["control", "check", "c_meas.json", "--family", "f.npz"],
     "c_meas.json: measured names 'nu_x'; allowed: r_g, nu, nu_r"),
    (["control", "check", "c_bool.json", "--family", "f.npz"],
     "c_bool.json: A[0][0] = True: must be a number"),
    (["control", "check", "c_dt.json", "--family", "f.npz"],
     "c_dt.json: dt = 'fast': must be a number of seconds"),
    (["control", "simulate", "--example", "slip-load-step-r1", "--controller", "c_str.json"],
     "c_str.json: D[0][0] = '1': must be a number"),
    (["montecarlo", "--spread", "sp_ok.toml", "--analysis", "closed-loop", "--example",
      "slip-load-step-r1", "--controller", "c_out.json"], "c_out.json: outputs names 'T_xx'"),
    # a slip reference of 200 % (or a ratio out of range) is refused before the run
    (["control", "simulate", "ref_nu.toml"],
     "ref_nu.toml: references.nu = 2: allowed range is [-0.2, 0.2] (a slip fraction"),
    (["control", "simulate", "ref_rg.toml"],
     "ref_rg.toml: references.r_g = 9: outside the geometric ratio range"),
    (["simulate", "ref_nu.toml"], "ref_nu.toml: references.nu = 2: allowed range is"),
    (["montecarlo", "--spread", "sp_ok.toml", "--analysis", "closed-loop", "--scenario",
      "ref_nu.toml"], "ref_nu.toml: references.nu = 2: allowed range is [-0.2, 0.2]"),
    # issue 35's "checked too late": a ratio reference of 9, a negative clamping reference and
    # a slip reference beyond the traction peak (inside the curve's valid range), each refused
    # by the scenario loader against the model's ranges, before any integration
    (["simulate", "open_rg.toml"],
     "open_rg.toml: inputs.r_g_ref = 9: outside the geometric ratio range"),
    (["simulate", "open_fs.toml"],
     "open_fs.toml: inputs.F_s_ref = -5000: allowed range is (0, inf) [N]"),
    (["simulate", "ref_peak.toml"], "ref_peak.toml: references.nu = 0.15: allowed range is (0, "),
    (["control", "simulate", "ref_peak.toml"],
     "ref_peak.toml: references.nu = 0.15: allowed range is (0, "),
    (["montecarlo", "--spread", "sp_ok.toml", "--analysis", "closed-loop", "--scenario",
      "ref_peak.toml"], "ref_peak.toml: references.nu = 0.15: allowed range is (0, "),
    # a spread that no value of the parameter may take (every run would fail)
    (["montecarlo", "--spread", "sp_out.toml"],
     "spread.'actuation.k_w': uniform on [-2, -1] lies wholly outside the values "
     "actuation.k_w may take (allowed range is (0.001, 1e+08] [N m/rad])"),
    (["montecarlo", "--spread", "sp_nu.toml"],
     "spread.'operating.nu': uniform on [0.3, 0.4] lies wholly outside the values"),
    # records: a column named twice, one signal given twice, time running backwards
    (["frf-estimate", "rec_dup.csv", "--input", "u", "--output", "y", "--time", "time"],
     "rec_dup.csv: column 'u' appears 2 times (columns 2, 3); name each column once"),
    (["frf-estimate", "rec_dup2.csv", "--input", "u", "--output", "y", "--time", "time"],
     "rec_dup2.csv: column 'z' appears 2 times (columns 4, 5); name each column once"),
    (["frf-estimate", "rec.csv", "--input", "u", "--output", "u", "--time", "time"],
     "--output u: the column is already the input"),
    (["frf-estimate", "rec.csv", "--input", "u", "--input", "u", "--output", "y", "--fs",
      "100"], "--input u: given twice"),
    (["frf-estimate", "rec.csv", "--input", "time", "--output", "y", "--time", "time"],
     "--time time: the column is already the input"),
    (["frf-estimate", "rec_back.csv", "--input", "u", "--output", "y", "--time", "time"],
     "column 'time' must increase: data row 6 has 0.02 after 0.04"),
    # one list parser: an empty item is refused everywhere
    (["nmp", "--ratios", "0.5,,2"], "--ratios '0.5,,2': an empty item"),
    (["nmp", "--ratios", "0.5,nan"], "--ratios '0.5,nan': values must be finite"),
    (["identify", "--ratios", "0.5,,1"], "--ratios '0.5,,1': an empty item"),
    (["identify", "--ratios", ",".join(["1"] * 51)], "51 values; give 1 to 50"),
    (["frf", "actuation", "--input", "T_mp", "--input", "T_mp"], "--input T_mp: given twice"),
    # options added since issue 10: --tau, --load-torque, --drive, --load, --thrust-ratio, ...
    (["linearize", "--tau", "2"], "--tau = 2: allowed range is [-1, 1] (the torque ratio"),
    (["linearize", "--tau", "nan"], "--tau = nan: must be a finite number in [-1, 1]"),
    (["linearize", "--tau", "0.9", "--slip", "0.01"],
     "give the slip as --slip or as --tau, not both"),
    (["linearize", "--load-torque", "1e9", "--clamp", "1e4"],
     "--load-torque = 1e+09: allowed range is [-10000, 10000] [N m]"),
    (["linearize", "--tau", "0.9", "--load-torque", "60", "--clamp", "1e4"],
     "give at most two of --slip (or --tau), --clamp, --load-torque"),
    (["linearize", "--drive", "fast"], "invalid value for '--drive'"),
    (["linearize", "--load", "50"], "invalid value for '--load'"),
    (["linearize", "--speed", "inf"], "--speed = inf: must be a finite number in (0, 2000]"),
    (["linearize", "--thrust-ratio", "bad_traction.csv"], "must name exactly the columns r_g, "
                                                          "tau, kappa"),
    (["nmp", "--tau", "5"], "--tau = 5: allowed range is [-1, 1]"),
    (["nmp", "--load-torque", "50"], "--load-torque with the parameter file's point given by"),
    (["nmp", "--drive", "x"], "invalid value for '--drive'"),
    (["plants", "--tau", "2"], "--tau = 2: allowed range is [-1, 1]"),
    (["plants", "--slip", "0.5"], "--slip = 0.5: allowed range is [-0.2, 0.2] (a fraction"),
    (["plants", "--ratio", "0.5:2:1000", "--slip", "0.005:0.02:1000"],
     "1000000 grid points; at most 200000"),
    (["plants", "--drive", "x"], "invalid value for '--drive'"),
    (["plants", "--scheduler-timeout", "nan"], "--scheduler-timeout = nan"),
    (["control", "design", "--out", "c.json", "--alpha-min", "-1"],
     "--alpha-min = -1: allowed range is [0.05, 1.9]"),
    (["control", "design", "--method", "hinf", "--out", "c.json", "--alpha-min", "2"],
     "--alpha-min = 2: allowed range is [0.05, 1.9]"),
    (["control", "design", "--out", "c.json", "--slip", "0.5"], "--slip = 0.5: allowed range"),
    (["control", "design", "--out", "c.json", "--tau", "0.9,2"], "--tau = 2"),
    (["control", "design", "--out", "c.json", "--bandwidth", "nan,1"], "--bandwidth = nan"),
    (["rig", "--out", "r.csv", "--duration", "0.001"],
     "--duration x --fs = 0.001 s x 1000 Hz = 1 samples; at least 64"),
    (["rig", "--out", "r.csv", "--band", "1:2:3"], "--band '1:2:3': give LO:HI in Hz"),
    (["rig", "--out", "r.csv", "--friction", "-1"], "--friction = -1: allowed range"),
    (["montecarlo", "--spread", "sp_ok.toml", "--runs", "1e3"], "'1e3' is not a valid integer"),
    (["params", "validate", "op_load.toml"],
     "op_load.toml: [operating] operating point: T_l = 100000 needs mu = 88.11, above the "
     "traction peak"),
    (["calibrate", "t_nofree.toml", "--out", "c.toml"],
     "t_nofree.toml: missing free (the list of parameters to fit"),
    (["simulate", "--example", "servo-torque-steps", "--duration", "nan"], "--duration = nan"),
    (["modes", "driveline", "--ratio", "inf"], "--ratio = inf: must be a finite number"),
    # issue 35, OS errors before any work: a name too long, a FIFO or device, a path through a
    # file (one check of every path option, `check_path`)
    (["simulate", "--example", "servo-torque-steps", "--out", LONG],
     "--out xxxxxxxxxxxxxxxxxxxxxxxxxxxxxx...(300 characters): a file name of 300 bytes"),
    (["linearize", "--out", LONG + ".json"], "a file name of 305 bytes; file names hold at most "
                                             "255"),
    (["modes", "driveline", "--json-out", LONG + ".json"], "--json-out xxx"),
    (["rig", "--out", LONG + ".csv"], "--out xxx"),
    (["reproduce", "--out", LONG], "a file name of 300 bytes"),
    (["plants", "--out", LONG + ".npz"], "a file name of 304 bytes"),
    (["control", "discretize", "pi.json", "--rate", "100", "--out", LONG + ".json"],
     "a file name of 305 bytes"),
    (["control", "design", "--out", LONG + ".json"], "a file name of 305 bytes"),
    (["montecarlo", "--spread", "sp_ok.toml", "--out", LONG], "a file name of 300 bytes"),
    (["frf", "actuation", "--plot", LONG + ".png"], "--plot xxx"),
    (["params", "validate", LONG + ".toml"], "...(305 characters): a file name of 305 bytes"),
    (["simulate", LONG + ".toml"], "a file name of 305 bytes"),
    (["linearize", "--params", "out.json/p.toml"], "--params out.json/p.toml: a part of the path "
                                                   "is a file"),
    (["params", "validate", "fifo.toml"], "fifo.toml: is a FIFO (named pipe), not a file"),
    (["simulate", "fifo.toml"], "fifo.toml: is a FIFO (named pipe)"),
    (["modes", "driveline", "--params", "fifo.toml"], "--params fifo.toml: is a FIFO"),
    (["control", "check", "fifo.json", "--family", "f.npz"], "fifo.json: is a FIFO"),
    (["frf-estimate", "fifo.csv", "--input", "u", "--output", "y", "--fs", "1"],
     "fifo.csv: is a FIFO"),
    (["slip", "poles", "--traction", "fifo.csv"], "--traction fifo.csv: is a FIFO"),
    (["calibrate", "fifo.toml", "--out", "c.toml"], "fifo.toml: is a FIFO"),
    (["montecarlo", "--spread", "fifo.toml"], "--spread fifo.toml: is a FIFO"),
    (["params", "validate", "/dev/null"], "/dev/null: is a device, not a file"),
    (["modes", "driveline", "--json-out", "/dev/null"], "--json-out /dev/null: is a device"),
    (["rig", "--out", "fifo.csv", "--force"], "--out fifo.csv: is a FIFO (named pipe), not a"),
    # one guarded reader: nesting depth, schema versions, units of a controller
    (["control", "check", "deep.json", "--family", "f.npz"],
     "deep.json: nested deeper than 32 levels; not a controller file"),
    (["control", "check", "deep40.json", "--family", "f.npz"], "deep40.json: nested deeper"),
    (["params", "validate", "deep.toml"], "deep.toml: nested deeper than 32 levels"),
    (["simulate", "deep.toml"], "deep.toml: nested deeper than 32 levels"),
    (["control", "check", "c99.json", "--family", "f.npz"],
     "c99.json: controller schema version 99 is newer than this empact reads (up to 2)"),
    (["control", "discretize", "c99.json", "--rate", "100", "--out", "d.json"],
     "controller schema version 99 is newer"),
    # control tune (issue 33 item 2): every option checked before the family is built
    (["control", "tune", "pi.json", "--out", "t.json", "--min-disk-margin", "3"],
     "--min-disk-margin = 3"),
    (["control", "tune", "pi.json", "--out", "t.json", "--max-ms", "0.5"],
     "--max-ms 0.5: 0 for none, or above 1"),
    (["control", "tune", "pi.json", "--out", "t.json", "--parameters", "kp_gear"],
     "--parameters kp_gear: choose distinct names from kp_ratio"),
    (["control", "tune", "pi.json", "--out", "t.json", "--parameters", "kp_slip,kp_slip"],
     "--parameters kp_slip,kp_slip: choose distinct names"),
    (["control", "tune", "pi.json", "--out", "t.json", "--bandwidth-floor", "0.1"],
     "--bandwidth-floor '0.1': two numbers RATIO,SLIP [Hz]"),
    (["control", "tune", "pi.json", "--out", "t.json", "--bandwidth-floor", "0.1,-1"],
     "--bandwidth-floor = -1"),
    (["control", "tune", "pi.json", "--out", "t.json", "--maxiter", "0"], "--maxiter = 0"),
    (["control", "tune", "pi.json", "--out", "t.json", "--seed", "-1"], "--seed = -1"),
    (["control", "tune", "pi.json", "--out", "t.txt"], "--out t.txt: file suffix '.txt'"),
    (["control", "tune", "pi.json", "--out", "out.json"], "--out out.json: exists; give"),
    (["control", "tune", "c99.json", "--out", "t.json"], "controller schema version 99"),
    (["control", "tune", "hinf.json", "--out", "t.json"],
     "hinf.json: tune: a continuous two-loop PI (method 'pi', 6 states) is tuned"),
    (["control", "check", "c_units.json", "--family", "f.npz"],
     "c_units.json: outputs_units has 1 units for 2 outputs signals"),
    (["control", "check", "c_rpm.json", "--family", "f.npz"],
     "c_rpm.json: outputs_units gives 'rpm' where the signal's unit is 'N m'"),
    (["control", "check", "pi.json", "--family", "fam_nan.npz"],
     "fam_nan.npz: A holds a value that is not finite (NaN or infinite) at grid index (0,)"),
    # an empty option value is an error naming the option (never "not given")
    (["simulate", "--example", "servo-torque-steps", "--out", ""],
     "--out: an empty value; give a value or leave the option out"),
    (["montecarlo", "--out", ""], "--out: an empty value"),
    (["control", "design", "--nominal", "", "--out", "c.json"], "--nominal: an empty value"),
    (["slip", "poles", "--traction", ""], "--traction: an empty value"),
    (["linearize", "--params", " "], "--params: an empty value"),
    (["params", "validate", ""], "FILE: an empty value"),
    (["frf-estimate", "rec.csv", "--input", "", "--output", "y", "--fs", "1"],
     "--input: an empty value"),
    (["calibrate", "targets.toml", "--out", "c.toml", "--tie", ""], "--tie: an empty value"),
    # units in CSV headers: converted when known, refused otherwise; dead channels
    (["frf-estimate", "rec_unit.csv", "--input", "u", "--output", "y", "--time", "time"],
     "rec_unit.csv: column 'time' has unit [fortnight], which empact does not convert"),
    (["frf-estimate", "rec_tq.csv", "--input", "u", "--output", "y", "--time", "time"],
     "rec_tq.csv: column 'time' has unit [N m], a unit of torque; the column is a time (s, "
     "ms, us, min)"),
    (["frf-estimate", "rec_yunit.csv", "--input", "u", "--output", "y", "--time", "time"],
     "column 'u' has unit [furlong]"),
    (["frf-estimate", "rec_dead.csv", "--input", "u", "--output", "y", "--fs", "100"],
     "output 'y' is constant (0 in every sample): a dead channel carries no response"),
    (["frf-estimate", "rec_flat.csv", "--input", "u", "--output", "y", "--fs", "100"],
     "input 'u' is constant (2.5 in every sample): a dead channel excites nothing"),
    (["slip", "rootlocus", "--slip", "0.5"], "--slip = 0.5: allowed range is [-0.2, 0.2]"),
    # a symbolic link, dangling or not, is an existing file (--force replaces the link)
    (["plants", "--ratio", "1", "--out", "dang.npz"],
     "--out dang.npz: exists (a symbolic link); give --force to replace it"),
    (["rig", "--out", "dang.csv"], "--out dang.csv: exists (a symbolic link)"),
    (["modes", "driveline", "--json-out", "link.json"], "--json-out link.json: exists (a "
                                                        "symbolic link)"),
    (["simulate", "--example", "servo-torque-steps", "--out", "dang.npz"],
     "--out dang.npz: a dangling symbolic link"),
    # scenario, targets and spread values range-checked when loaded, before any run
    (["simulate", "sc_steps.toml"],
     "sc_steps.toml: solver.max_steps = 1.5: must be a whole number in [1, 1000000000]"),
    (["montecarlo", "--spread", "sp_ok.toml", "--analysis", "closed-loop", "--scenario",
      "sc_steps.toml"],
     "solver.max_steps = 1.5"),
    (["calibrate", "t_inf.toml", "--out", "c.toml"],
     "t_inf.toml: target 1: frequency_hz = inf: must be a finite number in (0, 1e+06] [Hz]"),
    (["calibrate", "t_miss.toml", "--out", "c.toml"],
     "t_miss.toml: target 1: missing frequency_hz (each target needs model, frequency_hz)"),
    (["montecarlo", "--spread", "sp_ln100.toml"],
     "lies for the most part (90 % of its quantiles) outside the values actuation.k_w may "
     "take"),
    # no library words
    (["montecarlo", "--spread", "sp_ok.toml", "--scheduler", "tcp:/x"],
     "--scheduler tcp:/x: give none, local or a scheduler address HOST:PORT"),
    (["plants", "--ratio", "1", "--scheduler", "host:99999"], "a port from 1 to 65535"),
    (["slip", "poles", "--slip", "0.001,,0.04"], "--slip '0.001,,0.04': not a number"),
    (["slip", "rootlocus", "--cb-max", "inf"], "--cb-max = inf: must be a finite number"),
    # issue 35, round 4: a campaign on the commands added since (cycle, efficiency, control
    # tune, fmu export, montecarlo --resume, control check --strict, control discretize --at)
    (["cycle", "--cycle", "t_back.csv"], "t_back.csv: data row 3: time = 1 s: must increase"),
    (["cycle", "--cycle", "t_neg.csv"], "t_neg.csv: data row 2: speed = -10: must be finite"),
    (["cycle", "--cycle", "t_one.csv"], "t_one.csv: 1 samples: a trace needs at least 2"),
    (["cycle", "--cycle", "t_text.csv"], "t_text.csv: data row 2: '2', 'fast': not numbers"),
    (["cycle", "--cycle", "t_dup.csv"], "t_dup.csv: data row 3: time = 2 s: must increase"),
    (["cycle", "--cycle", "t_knots.csv"],
     "t_knots.csv: column 'speed' has unit [knots], which empact does not convert; give one "
     "of m/s, km/h, mph"),
    (["cycle", "--cycle", "t_rpm.csv"], "column 'speed' has unit [rpm], a unit of angular "
     "speed; the column is a speed"),
    (["cycle", "--cycle", "t_fortnight.csv"], "column 'time' has unit [fortnight], which"),
    (["cycle", "--cycle", "t_nounit.csv"], "t_nounit.csv: column 'speed' has no unit"),
    (["cycle", "--cycle", "t_semi.csv"], "need the columns 'time [s]' and 'speed [km/h]'"),
    (["cycle", "--cycle", "t_phase.csv"], "(300 characters): a phase name holds at most 40"),
    (["cycle", "--cycle", "t_huge.csv"], "t_huge.csv: speed 1e+05 km/h at t = 10 s (1 sample "
     "above): the car's top speed by its gearing is 293.6 km/h"),
    (["cycle", "--cycle", "fifo.csv"], "fifo.csv: is a FIFO (named pipe), not a trace file"),
    (["cycle", "--cycle", LONG], "--cycle 'xxxxxxxxxxxxxxxxxxxxxxxxxxxxxx...(300 characters)'"),
    (["cycle", "--cycle", "nedc", "--strategies", "sf1.3,,slip"], "--strategies = ''"),
    (["cycle", "--cycle", "nedc", "--params", "veh_neg.toml"], "vehicle.mass = -1300"),
    (["cycle", "--cycle", "nedc", "--out", "out.csv"], "Directory 'out.csv' is a file"),
    (["efficiency", "--torque", "1e6"], "--torque = 1e+06: allowed range is (0, 10000] [N m]"),
    (["efficiency", "--speed", "1e6"], "--speed = 1e+06: allowed range is (0, 2000] [rad/s]"),
    (["efficiency", "--torque", "-5"], "--torque = -5: allowed range is (0, 10000]"),
    (["efficiency", "--ratio", "5"], "--ratio = 5: outside the geometric ratio range"),
    (["efficiency", "--clamp", "1:2"], "--clamp '1:2': a clamping sweep is A:B:N"),
    (["efficiency", "--clamp", "0:1000:3", "--torque", "50", "--ratio", "1"], "--clamp = 0"),
    (["efficiency", "--clamp", "1000:30000:3"], "--clamp: give one --torque, one --speed"),
    (["efficiency", "--tau", "1"], "--tau = 1: allowed range is (0, 1)"),
    (["efficiency", "--torque", "1:200:10000"], "120000 points: at most 20000 per map"),
    (["control", "tune", "pi.json", "--out", "t.json", "--parameters", "kp_ratio,,ki_slip"],
     "--parameters kp_ratio,,ki_slip: choose distinct names from kp_ratio"),
    (["control", "tune", "k_disc.json", "--out", "t.json"], "k_disc.json: tune: a continuous "
     "two-loop PI"),
    (["control", "tune", "shipped:nope", "--out", "t.json"],
     "controller 'shipped:nope': no shipped controller 'nope' (shipped: hinf, pi)"),
    (["control", "tune", "pi.json", "--family", "text.npz", "--out", "t.json"], "text.npz"),
    (["fmu", "export", "--out", "m.fmu", "--rate", "0"], "--rate = 0: allowed range"),
    (["fmu", "export", "--out", "m.fmu", "--max-step", "0"], "--max-step = 0: allowed range"),
    (["fmu", "export", "--out", "m.fmu", "--ratio", "9"], "--ratio = 9"),
    (["fmu", "export", "--out", "m.fmu", "--clamp", "-1"], "--clamp = -1"),
    (["fmu", "export", "--out", "m.fmu", "--speed", "1e6"], "--speed = 1e+06: allowed range "
     "is (0, 2000] [rad/s]"),
    (["fmu", "export", "--out", "m.fmu", "--controller", "c_text.json"], "c_text.json"),
    (["fmu", "export", "--out", "m.fmu", "--controller", "fifo.json"], "fifo.json: is a FIFO"),
    (["fmu", "export", "--out", "m.fmu", "--controller", "shipped:x"], "no shipped controller"),
    (["montecarlo", "--spread", "sp_ok.toml", "--runs", "4", "--resume", "--out", "st_bad"],
     "st_bad/manifest.json: not a study manifest file (not JSON text)"),
    (["montecarlo", "--spread", "sp_ok.toml", "--runs", "4", "--resume", "--out", "st_deep"],
     "st_deep/manifest.json: nested deeper than 32 levels"),
    (["montecarlo", "--spread", "sp_ok.toml", "--runs", "4", "--resume", "--out", "st_v99"],
     "manifest.json: schema version 99 is newer than this empact reads (up to 1)"),
    (["montecarlo", "--spread", "sp_ok.toml", "--runs", "4", "--resume", "--out", "st_chunks"],
     "manifest.json: chunks must be a list of [start, stop] run pairs"),
    (["montecarlo", "--spread", "sp_ok.toml", "--runs", "4", "--resume", "--out", "st_gap"],
     "manifest.json: chunks must cover the runs from 0, in order"),
    (["montecarlo", "--spread", "sp_ok.toml", "--runs", "4", "--resume", "--out", "st_done"],
     "manifest.json: completed must list chunk indices 0 to 0"),
    (["montecarlo", "--spread", "sp_ok.toml", "--runs", "4", "--resume", "--out", "st_schema"],
     "manifest.json: schema 'empact.study.manifest' expected"),
    (["montecarlo", "--spread", "sp_ok.toml", "--runs", "4", "--resume", "--out", "full"],
     "--resume full: not a study folder (no manifest.json)"),
    (["control", "check", "pi.json", "--family", "f.npz", "--strict", "--min-disk-margin",
      "nan"], "--min-disk-margin = nan: must be a finite number"),
    (["control", "check", "pi.json", "--family", "f.npz", "--strict", "--min-disk-margin",
      "-0.1"], "--min-disk-margin = -0.1"),
    (["control", "check", "pi.json", "--family", "f.npz", "--strict", "--loop-scenario",
      "sc_rtol.toml"], "sc_rtol.toml: solver.rtol = 2"),
    (["control", "check", "shipped:nope", "--strict"], "no shipped controller 'nope'"),
    (["control", "discretize", "pi.json", "--out", "k.json", "--at", "r_g=1,r_g=2,tau=0.9"],
     "--at 'r_g=1,r_g=2,tau=0.9': r_g given twice"),
    (["control", "discretize", "pi.json", "--out", "k.json", "--at", "x=1,tau=0.9"],
     "'x' is not an operating variable; give r_g and two of nu (or tau), F_s, T_l"),
    (["control", "discretize", "pi.json", "--out", "k.json", "--at", "r_g=1,tau=0.9,F_s=1e9"],
     "--at F_s=1e+09: allowed range is [0, 1e+06] [N]"),
    (["control", "discretize", "pi.json", "--out", "k.json", "--at", "r_g=9,tau=0.9"],
     "--at r_g=9: outside the geometric ratio range"),
    (["control", "discretize", "pi.json", "--out", "k.json", "--at", "r_g=1,tau=2"],
     "--at tau=2: allowed range is [-1, 1]"),
    (["control", "discretize", "pi.json", "--out", "k.json", "--at", "r_g=1,nu=0.5"],
     "--at nu=0.5: allowed range is"),
    (["control", "discretize", "pi.json", "--out", "k.json", "--at", "r_g=1,tau=0.9,nu=0.01"],
     "give nu or tau, not both"),
    (["control", "discretize", "pi.json", "--out", "k.json", "--at",
      "r_g=1,tau=0.9,F_s=1e4,T_l=5"], "give at most two of nu (or tau), F_s, T_l"),
    (["control", "discretize", "pi.json", "--out", "k.json", "--at", "r_g=1;tau=0.9"],
     "is not NAME=VALUE with a number"),
    (["control", "discretize", "k_disc.json", "--out", "k.json", "--at", "r_g=1,tau=0.9"],
     "k_disc.json: already discrete (dt = 0.001 s)"),
]


def _snapshot(folder):
    """Every entry of `folder` with its modification time and type (a symbolic link as a link,
    dangling or not)."""
    return sorted((p.relative_to(folder), p.lstat().st_mtime_ns, stat.S_IFMT(p.lstat().st_mode))
                  for p in folder.rglob("*"))


@pytest.mark.parametrize("args, match", BAD_INPUT, ids=[" ".join(a)[:60] for a, _ in BAD_INPUT])
def test_bad_input_one_line_exit_2_nothing_written(files, args, match):
    before = _snapshot(files)
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 2, res.output
    # (a progress line shows only after a second of work: a slow machine's, not an error)
    lines = [ln for ln in res.output.strip().splitlines() if not PROGRESS.match(ln)]
    assert len(lines) == 1 and lines[0].startswith("error: "), res.output
    assert match in lines[0], lines[0]
    assert LEAKS.search(res.output) is None, res.output  # no internals
    assert _snapshot(files) == before  # nothing written, nothing replaced (a link stays one)


#: a progress line (`empact._progress`): a bar ("desc: 50%|", desc may hold a colon) or the
#: work indicator of a command without one ("linearize: working, 00:01 elapsed")
PROGRESS = re.compile(r"^.+?: (?: +\d+%\||working, [\d:]+ elapsed$)")

#: what an error line must never show: exception class names, tracebacks, Python and numpy
#: reprs, numpy's or Python's own messages
LEAKS = re.compile(r"Traceback|\b[A-Z][A-Za-z]*(Error|Exception|Warning)\b|np\.\w+\(|array\(|"
                   r"<class|<function|allow_pickle|pickle|zipfile|BadZip|not in tuple|"
                   r"cannot reshape|"
                   r"has no attribute|unsupported operand|invalid literal|could not convert|"
                   r"index out of range|Errno|dtype|\bNone\b|\bTrue\b(?! *:)|\bFalse\b")


def test_the_leak_scan_sees_leaks():
    """The scan of the table's messages finds each kind of leak the issue listed."""
    for text in ("error: x: bad controller data (cannot reshape array of size 6 into shape "
                 "(2,2))", "error: tuple.index(x): x not in tuple", "error: --x = "
                 "np.float64(0.5)", "error: f.npz: not a plant family (This file contains "
                 "pickled (object) data ... allow_pickle=)", "zipfile.BadZipFile: File is not a "
                 "zip file", "error: KeyError: 'axes is not a file in the archive'"):
        assert LEAKS.search(text), text


def test_bad_input_table_covers_every_command():
    covered = {a[0] for a, _ in BAD_INPUT}
    assert set(COMMANDS) <= covered, set(COMMANDS) - covered
    assert len(BAD_INPUT) >= 380  # 159 before issue 22, 244 before issue 35, 325 before
    # its round 4


def test_failed_calibration_exits_1_and_writes_nothing(tmp_path):
    targets = write(tmp_path, 'free = ["driveline.k_tc"]\n[[target]]\nmodel = "driveline"\n'
                              'uncoupled = "primary"\nfrequency_hz = 24.6\n[[target]]\n'
                              'model = "driveline"\nuncoupled = "primary"\n'
                              'frequency_hz = 50.0\n', "t.toml")
    out = tmp_path / "c.toml"
    res = run("calibrate", targets, "--out", out)
    assert res.exit_code == 1 and "misses driveline uncoupled primary by" in res.output
    assert "nothing written" in res.output and not out.exists()
    res = run("calibrate", targets, "--out", out, "--tolerance", "100")
    assert res.exit_code == 0 and out.exists()  # within a (very loose) tolerance: written


def test_calibrate_with_kinematics_and_ties(tmp_path):
    """Three machine targets, worm / chain / bearings free, k_ts tied on the command line: the
    frequencies are met (0.1 %) and the written file holds k_ts = k_tp exactly; with
    --kinematics paper-sec2.1 the same targets are judged on the Sec. 2.1 rows (whose
    stiffnesses, [paper_sec21], are not free here: only the label and the check change)."""
    from empact.params import load_params

    targets = write(tmp_path, 'free = ["actuation.k_w", "actuation.k_c", "actuation.k_tp"]\n'
                    + "".join(f'[[target]]\nmodel = "actuation"\nratio = 1.0\nmode = {m}\n'
                              f'frequency_hz = {f}\n'
                              for m, f in ((2, 10.7), (3, 17.3), (4, 47.9))), "t.toml")
    out = tmp_path / "c.toml"
    res = run("calibrate", targets, "--out", out, "--tie", "actuation.k_ts=actuation.k_tp",
              "--tolerance", "0.1")
    assert res.exit_code == 0, res.output
    a = load_params(str(out)).actuation
    assert a.k_ts == a.k_tp
    res = run("calibrate", targets, "--out", tmp_path / "d.toml", "--kinematics",
              "paper-sec2.1", "--tie", "actuation.k_ts=actuation.k_tp", "--tolerance", "100")
    assert res.exit_code == 0, res.output
    assert "actuation (paper-sec2.1) r_g=1 mode 2" in res.output


def test_simulation_that_stops_early_writes_only_when_asked(tmp_path):
    sc = write(tmp_path, "[scenario]\nname = 'brake'\nduration = 2.0\n[model]\n"
                         "drive = 'torque'\n[initial]\nr_g = 1.0\nomega_p = 50.0\nF_s = 2e4\n"
                         "T_l = 10.0\n[inputs]\nT_l = [[0.0, 10.0], [0.0, 150.0]]\n", "s.toml")
    res = run("simulate", sc, "--out", tmp_path / "a", "--quiet")
    assert res.exit_code == 1 and "stopped early, nothing written" in res.output
    assert not (tmp_path / "a").exists()
    res = run("simulate", sc, "--out", tmp_path / "b", "--quiet", "--keep-partial")
    assert res.exit_code == 1 and "incomplete" in res.output
    assert "INCOMPLETE" in (tmp_path / "b" / "brake.csv").read_text().splitlines()[0]


# -- no clobbering: every command that writes a folder -----------------------------------------
FOLDER_COMMANDS = {
    "simulate": ["simulate", "--example", "servo-torque-steps", "--duration", "0.02", "--quiet"],
    "identify": ["identify", "--ratios", "1"],
    "reproduce": ["reproduce", "--sections", "table1", "--formats", "png", "--quiet"],
}


@pytest.mark.parametrize("name", list(FOLDER_COMMANDS))
def test_output_folder_never_clobbered(tmp_path, monkeypatch, name):
    monkeypatch.chdir(tmp_path)
    out = tmp_path / "work"
    out.mkdir()
    (out / "thesis.tex").write_text("mine")
    args = FOLDER_COMMANDS[name] + ["--out", "work"]
    res = run(*args)  # refused: the folder is not empty
    assert res.exit_code == 2 and "not empty" in res.output
    assert [p.name for p in out.iterdir()] == ["thesis.tex"]
    res = run(*args, "--force")  # replaces only its own files
    assert res.exit_code == 0, res.output
    assert (out / "thesis.tex").read_text() == "mine" and len(list(out.iterdir())) > 1
    if name != "identify":  # (the slowest) - again: its own files replaced, nothing else
        res = run(*args, "--force")
        assert res.exit_code == 0, res.output
        assert (out / "thesis.tex").read_text() == "mine"
    for target in (".", ".."):  # never the current folder or a parent, even with --force
        res = run(*(FOLDER_COMMANDS[name] + ["--out", target, "--force"]))
        assert res.exit_code == 2 and "current folder" in res.output
    assert sorted(p.name for p in tmp_path.iterdir()) == ["work"]


SHIPPED_PI = resources.files("empact") / "data" / "control" / "pi.json"


@pytest.fixture(scope="module")
def shipped_pi_check(tmp_path_factory):
    """The shipped PI's ``control check --strict --json`` on two plants of its family (r_g 0.8
    and 1.25, tau 0.9, 16 kN), which passes: the family file and the check's JSON (shared by
    the two tests of the strict gate)."""
    fam = tmp_path_factory.mktemp("shipped_pi_check") / "family.npz"
    res = run("plants", "--ratio", "0.8,1.25", "--tau", "0.9", "--clamp", "16000", "--out", fam,
              "--quiet")
    assert res.exit_code == 0, res.output
    res = run("control", "check", SHIPPED_PI, "--family", fam, "--strict", "--quiet", "--json")
    assert res.exit_code == 0, res.output
    return fam, json.loads(res.stdout)


def test_control_check_strict_gates_a_script(shipped_pi_check):
    """`control check --strict` exits 0 when every plant is stable and the worst disk margin
    reaches --min-disk-margin, 1 with one error line when it does not (issue 21, item 7); the
    margin it prints is the one it judges."""
    pi = SHIPPED_PI
    fam, data = shipped_pi_check
    worst = data["worst"]["disk_margin"]
    assert data["passed"] is True and data["worst"]["all_stable"] is True
    assert worst == pytest.approx(min(data["disk_margin"]), rel=0, abs=0)  # what it judges
    assert 0.3 <= worst < 1.0  # the shipped PI's floor over its design family is 0.30
    res = run("control", "check", pi, "--family", fam, "--strict", "--quiet",
              "--min-disk-margin", f"{worst + 0.01:.3f}")
    assert res.exit_code == 1
    assert res.output.strip().splitlines()[-1].startswith("error: check failed: 0 unstable "
                                                          "plants, worst disk margin")
    # without --strict it reports and exits 0
    res = run("control", "check", pi, "--family", fam, "--quiet", "--min-disk-margin", "0.99")
    assert res.exit_code == 0, res.output


def test_control_check_strict_gates_on_the_design_margin(shipped_pi_check, tmp_path):
    """Without --min-disk-margin, `control check --strict` judges the controller's own design
    margin (its record's alpha_min; issue 33, item 9): the shipped PI on two plants of its
    family passes at its alpha_min, and the same file promising more than the check finds
    exits 1 naming the promise."""
    pi = SHIPPED_PI
    fam, data = shipped_pi_check
    doc = json.loads(pi.read_text())
    assert data["gate"] == {"min_disk_margin": doc["design"]["alpha_min"],
                            "source": "the design's alpha_min"}
    worst = data["worst"]["disk_margin"]
    doc["design"]["alpha_min"] = round(worst + 0.01, 3)  # a design promising more
    promised = tmp_path / "promised.json"
    promised.write_text(json.dumps(doc))
    res = run("control", "check", promised, "--family", fam, "--strict", "--quiet")
    assert res.exit_code == 1
    assert res.output.strip().splitlines()[-1] == (
        f"error: check failed: 0 unstable plants, worst disk margin {worst:.3f} (required "
        f"{doc['design']['alpha_min']:g}: the design's alpha_min)")
    # an explicit --min-disk-margin replaces the design's
    res = run("control", "check", promised, "--family", fam, "--strict", "--quiet",
              "--min-disk-margin", "0.1")
    assert res.exit_code == 0, res.output


def test_control_export_closes_from_the_file_alone(tmp_path):
    """`control discretize --at` writes the shipped scheduled PI folded at an operating point
    with the loop that runs there; a plain python-control loop built from that file alone has
    the closed-loop poles `control check` computes at the point (issue 33, item 5): every pole
    of |z| >= 0.05 to 1e-6 (measured 3e-8); the 12 or so poles within |z| < 0.05 are the
    counting window's and the delay's shift registers (eigenvalue 0 of a Jordan chain of ~10,
    which any eigensolver places only to about eps ** (1 / 10) ~ 0.03): both lists have them
    there, and as many."""
    import scipy.io
    from scipy.optimize import linear_sum_assignment

    ct = pytest.importorskip("control")
    pi = resources.files("empact") / "data" / "control" / "pi.json"
    fam = tmp_path / "point.npz"
    res = run("plants", "--ratio", "1", "--tau", "0.9", "--clamp", "10000", "--out", fam,
              "--quiet")
    assert res.exit_code == 0, res.output
    res = run("control", "check", pi, "--family", fam, "--quiet", "--json")
    assert res.exit_code == 0, res.output
    poles = np.array(json.loads(res.stdout)["poles_z"], float)
    p_check = poles[..., 0] + 1j * poles[..., 1]
    out = tmp_path / "k.json"
    res = run("control", "discretize", pi, "--at", "r_g=1,tau=0.9,F_s=10000", "--out", out)
    assert res.exit_code == 0, res.output
    k = json.loads(out.read_text())  # the file alone from here on
    assert k["schema"] == {"name": "empact.controller", "version": 2}
    assert k["dt"] == 1e-3 and k["schedule"] is None
    lp = k["design"]["loop_plant"]
    K = ct.ss(k["A"], k["B"], k["C"], k["D"], k["dt"])
    P = ct.ss(lp["A"], lp["B"], lp["C"], np.zeros((2, 2)), lp["dt"])
    p_file = ct.feedback(K, P, sign=1).poles()
    assert p_file.shape == p_check.shape
    cost = np.abs(p_check[:, None] - p_file[None, :])
    i, j = linear_sum_assignment(cost)
    slow = np.abs(p_check[i]) >= 0.05
    assert slow.sum() >= 30
    assert cost[i, j][slow].max() < 1e-6
    assert np.all(np.abs(p_file[j][~slow]) < 0.05)
    assert np.abs(p_file).max() < 1  # stable, as the check says
    # the loop's whole specification rides along
    spec = k["design"]["loop"]
    assert spec["controller"]["feedforward_gain"] == 0.9 and spec["delay_samples"] == 1
    assert spec["speed_window_samples"] == 10 and spec["servo_limits"]["T_ms_max"] == 15.0
    # the .mat carries the same for MATLAB (`feedback(K, P, +1)`)
    mat = tmp_path / "k.mat"
    res = run("control", "discretize", pi, "--at", "r_g=1,tau=0.9,F_s=10000", "--out", mat)
    assert res.exit_code == 0, res.output
    m = scipy.io.loadmat(mat)
    assert_allclose(m["loop_plant_A"], lp["A"], rtol=0, atol=0)
    assert_allclose(m["B"], k["B"], rtol=0, atol=0)
    # bad points: one line naming the value
    res = run("control", "discretize", pi, "--at", "r_g=1,tau", "--out", tmp_path / "x.json")
    assert res.exit_code == 2 and "'tau' is not NAME=VALUE" in res.output


@pytest.mark.parametrize("example, status", [("slip-small-step-r1", 0), ("shift-low-od", 1)])
def test_control_simulate_strict_exits_1_on_a_missed_target(example, status):
    """`control simulate --strict` exits 1 when a [targets] entry is missed (shift-low-od's
    ratio rate of 1 /s: the servo limits stop it at 0.33 /s), 0 when all are met."""
    res = run("control", "simulate", "--example", example, "--strict", "--quiet")
    assert res.exit_code == status, res.output
    if status:
        assert "ratio_rate" in res.output and "MISSED" in res.output.upper()


# -- issue 35: every registered command and option, checked by walking them -------------------
ALL_COMMANDS = COMMAND_TREE  # every command the groups hand out (new ones included)


def _options(kind):
    import click

    rows = []
    for path, cmd in ALL_COMMANDS:
        for p in cmd.params:
            if getattr(p, "is_flag", False) or p.name in ("help", "version"):
                continue
            if kind == "path" and not isinstance(p.type, click.Path):
                continue
            opt = max(p.opts, key=len) if isinstance(p, click.Option) else None
            rows.append((path, opt))
    return rows


def test_every_command_takes_quiet():
    """`--quiet` on every command (7 of 17 refused it before issue 35)."""
    missing = [" ".join(path) for path, cmd in ALL_COMMANDS
               if not any(p.name == "quiet" for p in cmd.params)]
    assert missing == [] and len(ALL_COMMANDS) >= 25


@pytest.mark.parametrize("path, option", _options("any"),
                         ids=[" ".join(p) + f" {o}" for p, o in _options("any")])
def test_every_option_refuses_an_empty_value(tmp_path, monkeypatch, path, option):
    """An empty value is an error naming the option (it meant "not given" for `--out ''`,
    `--nominal ''`, `--traction ''`): one line, exit 2, nothing written."""
    monkeypatch.chdir(tmp_path)
    args = [*path, option, ""] if option else [*path, ""]
    res = CliRunner().invoke(main, args)
    lines = [ln for ln in res.output.strip().splitlines() if not PROGRESS.match(ln)]
    assert res.exit_code == 2 and len(lines) == 1 and lines[0].startswith("error: "), \
        (args, res.output)
    if option:
        assert option in lines[0], lines[0]
    assert LEAKS.search(res.output) is None and list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("path, option", _options("path"),
                         ids=[" ".join(p) + f" {o}" for p, o in _options("path")])
def test_every_path_option_goes_through_one_check(tmp_path, monkeypatch, path, option):
    """Every path option and argument: a name too long for the file system (it crashed six
    commands with OSError) and a FIFO (it hung a reader) are one line and exit 2 before any
    work."""
    monkeypatch.chdir(tmp_path)
    os.mkfifo(tmp_path / "pipe")
    for value, match in ((LONG, "a file name of 300 bytes; file names hold at most 255"),
                         ("pipe", "pipe: is a FIFO (named pipe), not a file")):
        args = [*path, option, value] if option else [*path, value]
        res = CliRunner().invoke(main, args)
        lines = [ln for ln in res.output.strip().splitlines() if not PROGRESS.match(ln)]
        assert res.exit_code == 2 and len(lines) == 1, (args, res.output)
        assert match in lines[0] and (option is None or option in lines[0]), lines[0]
        assert [p.name for p in tmp_path.iterdir()] == ["pipe"]


def test_a_full_disk_is_refused_before_work(tmp_path, monkeypatch):
    """An output on a full file system (less than 1 MiB free) is one line, exit 2, before any
    work; an OS error while writing (a disk that fills up mid-run) is one line, exit 1."""
    import empact.cli._common as common

    class Full:
        f_bavail, f_frsize = 10, 4096

    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(common.os, "statvfs", lambda path: Full())
    res = run("modes", "driveline", "--json-out", "m.json")
    assert res.exit_code == 2, res.output
    assert res.output.strip() == "error: --json-out m.json: the disk holding . is full (40 KiB " \
                                 "free)"
    monkeypatch.undo()
    monkeypatch.chdir(tmp_path)

    def no_space(path, text):
        raise OSError(28, "No space left on device", str(path))

    monkeypatch.setattr(common, "atomic_write_text", no_space)
    res = run("modes", "driveline", "--json-out", "m.json")
    assert res.exit_code == 1, res.output
    assert res.output.strip() == "error: m.json: no space left on device; nothing written"
    assert list(tmp_path.iterdir()) == []


def test_a_group_without_a_subcommand_prints_its_usage():
    """`empact control` (any group) alone: its usage and commands, as ``--help`` shows them,
    on stderr, exit 2 (it was folded into one ``error:`` line)."""
    for group in (["control"], ["slip"], ["params"]):
        res = CliRunner().invoke(main, group)
        assert res.exit_code == 2
        assert res.stderr.startswith(f"Usage: empact {group[0]} ") and "Commands:" in res.stderr
        assert not res.stdout and "error:" not in res.stderr


def test_csv_header_units_are_converted(tmp_path):
    """`frf-estimate` reads ``time [ms]`` as milliseconds (it ignored the unit: frequencies
    1000x too low); the sample rate is 1 / (1 ms) = 1000 Hz exactly (uniform samples)."""
    rows = "".join(f"{i},{np.sin(0.3 * i)},{np.cos(0.3 * i)}\n" for i in range(256))
    for unit, fs in (("ms", 1000.0), ("s", 1.0), ("min", 1 / 60), ("us", 1e6)):
        data = write(tmp_path, f"time [{unit}],u,y\n" + rows, f"r_{unit}.csv")
        res = run("frf-estimate", data, "--input", "u", "--output", "y", "--time", "time",
                  "--json", "--quiet")
        assert res.exit_code == 0, res.output
        assert_allclose(json.loads(res.stdout)["fs_hz"], fs, rtol=1e-12, atol=0)


def test_json_lists_of_numbers_on_one_line():
    """`slip poles --json` over 8 slips: a list of numbers (or of [re, im] pairs) is one line
    (1992 lines of one number each before issue 35); the document reads back the same."""
    from empact.cli._common import compact_json

    doc = {"a": [1, 2.5, None], "b": [[1.0, -2.0], [3.0, 4.0]], "c": [{"d": []}, {}], "e": {}}
    assert json.loads(compact_json(doc)) == doc
    assert compact_json(doc).splitlines()[1] == ' "a": [1, 2.5, null],'
    res = run("slip", "poles", "--slip", "0.001,0.002,0.005,0.01,0.02,0.03,0.04,0.05", "--json",
              "--quiet")
    assert res.exit_code == 0, res.output
    assert len(res.stdout.splitlines()) < 200 and len(json.loads(res.stdout)["points"]) == 8


def test_a_closing_line_names_the_files_written(tmp_path, monkeypatch):
    """`frf --plot`, `modes --json-out` (and every --plot / --json-out) end with one line
    naming what was written (they printed nothing); --quiet leaves stderr to errors."""
    monkeypatch.chdir(tmp_path)
    res = run("frf", "actuation", "--n", "20", "--plot", "f.png")
    assert res.exit_code == 0, res.output
    assert res.stderr.splitlines()[-1] == "written: f.png" and res.stdout == ""
    res = run("frf", "actuation", "--n", "20", "--json-out", "f.json", "--plot", "g.png")
    assert res.exit_code == 0, res.output
    assert res.stderr.splitlines()[-1] in ("written: f.json, g.png", "written: g.png, f.json")
    res = run("modes", "driveline", "--json-out", "m.json")
    assert res.exit_code == 0, res.output
    assert res.stderr.splitlines()[-1] == "written: m.json"
    res = run("modes", "driveline", "--json-out", "q.json", "--quiet")
    assert res.exit_code == 0 and res.stderr == "" and (tmp_path / "q.json").is_file()


# -- issue 35, round 4 ---------------------------------------------------------------------------
def test_modes_names_the_parameter_of_every_spring(tmp_path):
    """`modes` says which stiffness each spring is (`spring_parameters`): the actuation's
    belt is actuation.k_belt (paper_sec21.k_belt with the Sec. 2.1 rows), the driveline's is
    driveline.k_belt; each named parameter's value is the stiffness the model used."""
    from empact.linear.actuation import actuation_model
    from empact.linear.driveline import driveline_model

    p = load_params()
    for name, model in (("actuation", actuation_model(p, 1.0)),
                        ("paper", actuation_model(p, 1.0, kinematics="paper-sec2.1")),
                        ("driveline", driveline_model(p, 1.0))):
        names = model.modes().spring_parameters
        assert len(names) == len(model.springs), name
        for key, k in zip(names, model.stiffness):
            section, field = key.split(".")
            assert getattr(getattr(p, section), field) == k, (name, key)
    res = run("modes", "driveline", "--json", "--quiet")
    assert json.loads(res.stdout)["spring_parameters"] == ["driveline.k_tc", "driveline.k_belt",
                                                           "driveline.k_ds"]
    res = run("modes", "actuation", "--kinematics", "paper-sec2.1", "--quiet")
    assert "belt = paper_sec21.k_belt" in res.stdout, res.stdout


def test_validate_lists_values_outside_their_band_with_what_they_are_for(tmp_path):
    """`params validate` accepts a value outside its plausible band and lists it by its
    dotted name with its meaning: a driveline.k_belt of 1000 N/m says it is the linear
    driveline's belt and the nonlinear model's only with belt = "locked"."""
    f = write(tmp_path, "[driveline]\nk_belt = 1e3\n")
    res = run("params", "validate", f, "--quiet")
    assert res.exit_code == 0, res.output
    lines = res.stdout.splitlines()
    assert lines[0] == f"{f}: ok (1 value outside the plausible band, below)"
    assert lines[1].startswith("  driveline.k_belt = 1000 [N/m]: outside the plausible band "
                               "[5e+06, 5e+07] [N/m]; pushbelt stiffness as a torque-carrying")
    assert 'belt = "locked"' in lines[1] and len(lines) == 2
    res = run("params", "validate", write(tmp_path, "", "empty.toml"), "--quiet")
    assert res.stdout.strip().endswith("empty.toml: ok")


def test_every_controller_reader_takes_a_shipped_name(tmp_path):
    """``shipped:pi`` names the shipped controller for every reader (`load_controller`), as
    the docs say: `control discretize` took a file only (the campaign's `check`, `tune`,
    `fmu export` and `discretize` refused it); an unknown name lists the shipped ones."""
    from importlib import resources

    from empact.control.controller import load_controller

    shipped = load_controller("shipped:pi")
    path = resources.files("empact.data").joinpath("control", "pi.json")
    np.testing.assert_array_equal(shipped.B, load_controller(str(path)).B)
    res = run("control", "discretize", "shipped:pi", "--rate", "1000", "--out",
              tmp_path / "k.json", "--quiet")
    assert res.exit_code == 0 and (tmp_path / "k.json").is_file(), res.output


def test_a_map_with_no_point_trimmed_exits_1_and_writes_nothing(tmp_path, monkeypatch):
    """`efficiency` over clamping forces none of which carries the torque: exit 1, one line
    naming a point and why, nothing written (it exited 0 with a table of failures)."""
    monkeypatch.chdir(tmp_path)
    res = run("efficiency", "--clamp", "100:200:3", "--torque", "150", "--ratio", "1",
              "--strategy", "slip", "--json-out", "e.json", "--quiet")
    assert res.exit_code == 1, res.output
    assert res.output.startswith("error: none of the 3 points trims (e.g. slip at r_g = 1, "
                                 "T_in = 150 N m: ") and res.output.count("\n") == 1
    assert list(tmp_path.iterdir()) == []
