"""Measured traction curves in the nonlinear model (issue 31, item 6): the compiled law of
`empact.variator._traction_table` against `TabulatedTraction` (scipy's PCHIP), its peak
``mu_max`` against a dense search, and a model built on a table sampled from the shipped
magic formula against the analytic model.

References and tolerances:

* ``mu``, ``dmu``: `TabulatedTraction.mu` / `.dmu` (scipy `PchipInterpolator` and its
  derivative), to 1e-12 absolute (the same cubic, formed alike, evaluated in another order:
  measured 3e-17);
* ``mu_max``: the largest of `TabulatedTraction.mu` on 20001 slips, refined by a bounded
  scalar search to 1e-13 in slip (`scipy.optimize.minimize_scalar`): 1e-12;
* the analytic model: a table sampling the magic formula at its three knot ratios (0.43, 1.0,
  2.25) on 602 slips equals the formula there to the PCHIP error (measured: 4.3e-6 of the
  peak on the curve, 4.6e-6 relative on the peak, which falls between two samples); the
  trims at those ratios agree to 5e-5 relative (measured 1.3e-5: the slip near the peak
  amplifies the peak's error).  A 0.2 s load step at r_g = 1 shifts the ratio by 2.7e-3, off
  the knot ratio, where the table (linear in r_g between the curves) and the formula
  (coefficients linear in ln r_g) are two different interpolations: the outputs agree to
  2e-3 of their largest value (measured 3.9e-4 for the slip, 1.7e-4 for tau).
"""
import re

import numpy as np
import pytest
from numpy.testing import assert_allclose

from empact.nonlinear import _kernel as K
from empact.nonlinear import _tangent as KT
from empact.nonlinear.equilibrium import traction_peak, trim
from empact.nonlinear.model import nonlinear_model
from empact.nonlinear.simulation import simulate
from empact.params import OperatingPoint, ParameterError
from empact.variator import _traction_table as T
from empact.variator.traction import TabulatedTraction, traction_from_params

KNOTS = (0.43, 1.0, 2.25)

#: a measured-like table: four ratios, different slip grids, one curve not through (0, 0)
MEASURED = TabulatedTraction.from_curves({
    0.5: ([0.0, 0.002, 0.006, 0.015, 0.03, 0.06, 0.12],
          [0.0, 0.03, 0.07, 0.105, 0.118, 0.11, 0.095]),
    1.0: ([0.0, 0.003, 0.01, 0.02, 0.04, 0.08, 0.15],
          [0.0, 0.035, 0.08, 0.1, 0.104, 0.098, 0.09]),
    1.6: ([-0.05, -0.01, 0.0, 0.004, 0.012, 0.025, 0.05, 0.1],
          [-0.09, -0.06, 0.0, 0.04, 0.085, 0.097, 0.093, 0.085]),
    2.2: ([0.0, 0.005, 0.02, 0.05, 0.1], [0.0, 0.045, 0.09, 0.092, 0.088]),
}, source="test table")


@pytest.fixture(scope="module")
def sampled(params):
    """The magic formula sampled at its knot ratios on 602 slips (geometric below 1 %, then
    every 0.0475 %)."""
    magic = traction_from_params(params)
    nu = np.concatenate([[0.0], np.geomspace(1e-6, 0.01, 200, endpoint=False),
                         np.linspace(0.01, 0.2, 401)])
    return TabulatedTraction.from_curves({r: (nu, magic.mu(nu, r)) for r in KNOTS},
                                         source="sampled magic formula")


def _kernel_values(tab, nu, r):
    n = nu.size
    out = [np.empty(n) for _ in range(4)]
    T.table_many(nu, r, tab.encode(), 0, *out)
    return out


@pytest.mark.parametrize("which", ["measured", "sampled"])
def test_the_compiled_law_equals_the_scipy_interpolant(which, sampled):
    tab = MEASURED if which == "measured" else sampled
    lo, hi = tab.nu_range
    rng = np.random.default_rng(31)
    knots = np.concatenate(tab.nu_data)
    nu = np.concatenate([rng.uniform(lo, hi, 400), knots[(knots >= lo) & (knots <= hi)]])
    ratios = np.concatenate([tab.ratios, [0.3, 0.7, 1.3, 1.9, 2.5, 3.0]])
    NU, R = (a.ravel() for a in np.meshgrid(nu, ratios))
    mu, dmu, _, _ = _kernel_values(tab, NU, R)
    assert_allclose(mu, tab.mu(NU, R), rtol=0, atol=1e-12)
    assert_allclose(dmu, tab.dmu(NU, R), rtol=0, atol=1e-12)
    # and the model's kernel takes the same branch (`traction_mu`)
    m = _model(tab)
    assert_allclose(m.traction(NU, R), tab.mu(NU, R), rtol=0, atol=1e-12)


def _model(tab, **options):
    from empact.params import default_params

    return nonlinear_model(default_params(), traction=tab, **options)


def _dense_peak(tab, r):
    from scipy.optimize import minimize_scalar

    lo, hi = tab.nu_range
    grid = np.linspace(lo, hi, 20001)
    k = int(np.argmax(tab.mu(grid, r)))
    a, b = grid[max(k - 1, 0)], grid[min(k + 1, grid.size - 1)]
    res = minimize_scalar(lambda x: -float(tab.mu(x, r)), bounds=(a, b), method="bounded",
                          options={"xatol": 1e-13})
    return max(float(-res.fun), float(tab.mu(grid[k], r)))


@pytest.mark.parametrize("which", ["measured", "sampled"])
def test_mu_max_is_the_peak_of_the_interpolant(which, sampled):
    tab = MEASURED if which == "measured" else sampled
    ratios = np.array([0.3, *tab.ratios, 0.7, 1.2, 1.3, 1.9, 2.0, 3.0])
    ref = np.array([_dense_peak(tab, r) for r in ratios])
    assert_allclose(tab.mu_max(ratios), ref, rtol=0, atol=1e-12)
    m = _model(tab)
    assert_allclose(m.mu_max(ratios), ref, rtol=0, atol=1e-12)
    nu_pk, mu_pk = traction_peak(m, ratios)
    assert_allclose(mu_pk, ref, rtol=0, atol=1e-12)
    assert_allclose(tab.mu(nu_pk, ratios), mu_pk, rtol=0, atol=1e-15)


def _dense_peak_any(tab, r):
    """The largest value of `tab` at ratio `r`: 40001 slips, each of the five highest local
    maxima of the grid refined by a bounded scalar search (to 1e-13 in slip)."""
    from scipy.optimize import minimize_scalar

    lo, hi = tab.nu_range
    grid = np.linspace(lo, hi, 40001)
    v = tab.mu(grid, r)
    peaks = [k for k in range(grid.size) if (k == 0 or v[k] >= v[k - 1])
             and (k == grid.size - 1 or v[k] >= v[k + 1])]
    best = float(v.max())
    for k in sorted(peaks, key=lambda k: -v[k])[:5]:
        a, b = grid[max(k - 1, 0)], grid[min(k + 1, grid.size - 1)]
        res = minimize_scalar(lambda x: -float(tab.mu(x, r)), bounds=(a, b),
                              method="bounded", options={"xatol": 1e-13})
        best = max(best, float(-res.fun))
    return best


def test_mu_max_of_random_many_peaked_tables():
    """Seeded random tables (3-25 knots per curve on different grids, values with several
    local maxima): the compiled peak (its pruned search included) equals the dense search's
    to 1e-12, between and outside the tabulated ratios."""
    rng = np.random.default_rng(6)
    for _ in range(12):
        k = int(rng.integers(1, 4))
        curves = {}
        for r in np.sort(rng.uniform(0.4, 2.5, k)):
            n = int(rng.integers(3, 26))
            nu = np.sort(rng.choice(np.linspace(0.0, 0.2, 401)[1:], n, replace=False))
            curves[float(r)] = (nu, rng.uniform(0.0, 0.2, n))
        tab = TabulatedTraction.from_curves(curves, source="random")
        ratios = np.concatenate([tab.ratios, rng.uniform(0.3, 2.7, 6)])
        ref = np.array([_dense_peak_any(tab, r) for r in ratios])
        assert_allclose(tab.mu_max(ratios), ref, rtol=0, atol=1e-12)


def test_table_helpers_against_the_complex_step():
    """`table_mu_d` and `table_peak` (the forward mode's partials) equal the complex step of
    `table_mu` and `table_mu_max` (the kernel's complex routines), at and between knots and
    tabulated ratios and outside both."""
    h = 1e-30
    p = MEASURED.encode()
    for r in (0.3, 0.5, 0.8, 1.0, 1.3, 1.6, 2.0, 2.2, 2.6):
        for nu in (-0.2, -0.05, -0.01, 0.0, 0.003, 0.006, 0.01, 0.017, 0.05, 0.1, 0.2):
            v, s_nu, s_lr = T.table_mu_d(nu, r, p, 0)
            z_nu = T.table_mu(complex(nu, h), r + 0j, p, 0)
            z_lr = T.table_mu(nu + 0j, r * np.exp(complex(0.0, h)), p, 0)
            assert v == z_nu.real
            # rel 1e-13 of slopes O(1-10); abs 1e-15: rounding where the slope is 0 (a knot
            # at a local extremum: the real and the complex Horner sums round differently)
            assert s_nu == pytest.approx(z_nu.imag / h, rel=1e-13, abs=1e-15)
            assert s_lr == pytest.approx(z_lr.imag / h, rel=1e-12, abs=1e-15)
        _, pk, pk_lr = T.table_peak(r, p, 0)
        z = T.table_mu_max(r * np.exp(complex(0.0, h)), p, 0)
        assert pk == z.real
        assert pk_lr == pytest.approx(z.imag / h, rel=1e-12, abs=1e-15)


def test_forward_mode_equals_complex_step_on_a_table(params):
    """The exact Jacobian of a tabulated model (free and locked belt) against the complex
    step, at the norm and the points of `tests/test_jacobian.py`."""
    from test_jacobian import _check, _pair, _points

    for options in ({}, {"drive": "speed", "load": "speed", "ratio_control": True},
                    {"belt": "locked", "ratio_control": True}):
        m = nonlinear_model(params, traction=MEASURED, **options)
        for k, (x, u) in enumerate(_points(m, np.random.default_rng(7), 6)):
            _check(*_pair(m, x, u), (options, k))
            dx0, y0, dx1, y1 = np.empty(m.n), np.empty(K.NY), np.empty(m.n), np.empty(K.NY)
            K._eval(x, u, m.p, m.ix, dx0, y0)
            Sx, Su, Fd, Yd = KT._full_seeds(m.n, 4)
            KT._eval_tangent(x, u, m.p, m.ix, Sx, Su, dx1, y1, Fd, Yd)
            assert np.array_equal(dx0, dx1) and np.array_equal(y0, y1)


def test_the_analytic_law_is_untouched(params):
    """Without a table the offset is 0 (the analytic branch) and the vector is as long as
    before plus the new offset entry only (then issue 32's losses, then the traction laws'
    part generated from their registry)."""
    m = nonlinear_model(params)
    assert m.p[K.P_MTAB] == 0.0 and m.p.size == K.NP
    assert K.PARAMETER_NAMES[K.P_MTAB] == "traction_table"
    assert K.PARAMETER_NAMES[K.P_MTAB + 1:K.P_TRACTION] == (
        "loss_lambda_F", "loss_k_T", "loss_c_v", "loss_c_q", "loss_T_smooth", "loss_table"
    ) + K.VEHICLE_PARAMETER_NAMES
    t = _model(MEASURED)
    assert t.p[K.P_MTAB] == K.NP and t.p.size == K.NP + MEASURED.encode().size


@pytest.mark.parametrize("r_g", KNOTS)
def test_a_sampled_table_reproduces_the_analytic_trim(params, sampled, r_g):
    analytic = nonlinear_model(params)
    tabled = nonlinear_model(params, traction=sampled)
    assert tabled.mu_max(r_g) == pytest.approx(analytic.mu_max(r_g), rel=2e-5)
    for op in (OperatingPoint(r_g=r_g, omega_p=300.0, nu=0.01, F_s=1e4),
               OperatingPoint(r_g=r_g, omega_p=300.0, F_s=1e4, tau=0.9),
               OperatingPoint(r_g=r_g, omega_p=300.0, F_s=1e4, T_l=40.0)):
        a, b = trim(analytic, op), trim(tabled, op)
        for name in ("nu", "tau", "T_l", "F_s", "T_b"):
            assert getattr(b, name) == pytest.approx(getattr(a, name), rel=5e-5), (op, name)


def test_a_sampled_table_reproduces_a_load_step(params, sampled):
    op = OperatingPoint(r_g=1.0, omega_p=300.0, F_s=1e4, tau=0.6)
    out = []
    for m in (nonlinear_model(params), nonlinear_model(params, traction=sampled)):
        tr = trim(m, op)
        T_l = np.array([[0.0, tr.u[3]], [0.05, tr.u[3]], [0.06, 1.3 * tr.u[3]]])
        res = simulate(m, tr.x, {"T_l": T_l}, 0.2, u0=tr.u)
        out.append(res)
    a, b = out
    assert a.complete and b.complete
    assert abs(a.output("r_g") - 1.0).max() < 5e-3  # the ratio stays near the knot ratio
    for name in ("nu", "tau", "T_b", "omega_s", "r_g"):
        scale = np.abs(a.output(name)).max()
        assert np.abs(b.output(name) - a.output(name)).max() <= 2e-3 * scale, name


def test_a_table_is_refused_as_an_option_when_not_a_table(params):
    with pytest.raises(ParameterError, match="traction = .*TabulatedTraction"):
        nonlinear_model(params, traction=traction_from_params(params))


# -- the command line -----------------------------------------------------------------------
def _write_sampled(path, params):
    """The shipped magic formula sampled at its knot ratios as a CSV table (r_g,nu,mu)."""
    magic = traction_from_params(params)
    nu = np.concatenate([[0.0], np.geomspace(1e-5, 0.01, 40, endpoint=False),
                         np.linspace(0.01, 0.2, 77)])
    rows = [f"{r:g},{n:.10g},{float(magic.mu(n, r)):.12g}" for r in KNOTS for n in nu]
    path.write_text("r_g,nu,mu\n" + "\n".join(rows) + "\n")
    return path


#: every command that builds the nonlinear model (and the slip commands), with arguments
#: that would run it
MODEL_COMMANDS = [["simulate", "--example", "servo-torque-steps"], ["linearize"], ["nmp"],
                  ["plants"], ["rig", "--out", "r.csv"], ["identify"],
                  ["control", "design", "--out", "c.json"], ["control", "check", "c.json"],
                  ["control", "simulate", "--example", "slip-load-step-r1"],
                  ["montecarlo", "--spread", "s.toml"], ["slip", "poles"]]


@pytest.mark.parametrize("args", MODEL_COMMANDS, ids=lambda a: " ".join(a[:2]))
def test_a_bad_table_is_one_line_before_any_work(tmp_path, args):
    from click.testing import CliRunner

    from empact.cli import main

    bad = tmp_path / "bad.csv"
    bad.write_text("r_g,nu,mu\n1,0,0\n1,0.02,0.09\n1,0.01,0.1\n")
    res = CliRunner().invoke(main, args + ["--traction", str(bad)])
    assert res.exit_code == 2, res.output
    lines = res.output.strip().splitlines()
    assert len(lines) == 1, lines
    assert lines[0].startswith("error:") and "--traction" in lines[0] \
        and "nu must increase" in lines[0]


def test_control_simulate_with_a_table_meets_its_targets(tmp_path, params):
    """``control simulate --example slip-load-step-r1 --traction table.csv``: the closed loop
    on a table sampled from the shipped formula meets the scenario's targets, and its metrics
    are the analytic run's to within the interpolation (measured: slip error 0.0936 against
    0.0918 percentage points, peak slip error 0.2789 against 0.2795)."""
    import json

    from click.testing import CliRunner

    from empact.cli import main

    table = _write_sampled(tmp_path / "table.csv", params)
    runs = {}
    for name, extra in (("table", ["--traction", str(table)]), ("analytic", [])):
        res = CliRunner().invoke(main, ["control", "simulate", "--example",
                                        "slip-load-step-r1", "--json", "--quiet", "--strict",
                                        *extra])
        assert res.exit_code == 0, res.output
        runs[name] = json.loads(res.output)
    t, a = runs["table"], runs["analytic"]
    assert all(c["met"] for c in t["targets"]) and t["metrics"]["complete"]
    for key in ("slip_error", "peak_slip_error", "mean_clamping_force", "ratio_error"):
        assert t["metrics"][key] == pytest.approx(a["metrics"][key], rel=0.05), key
    assert t["metrics"] != a["metrics"]  # the table was used


def test_the_model_commands_take_a_table(tmp_path, params):
    """linearize names the table in its model options; a family records it and a check on the
    saved family rebuilds the model from it; a scenario's [model] table names it relative
    to the scenario file."""
    import json

    from click.testing import CliRunner

    from empact.cli import main
    from empact.nonlinear.scenario import load_scenario

    table = _write_sampled(tmp_path / "table.csv", params)
    res = CliRunner().invoke(main, ["linearize", "--traction", str(table), "--json"])
    assert res.exit_code == 0, res.output
    doc = json.loads(res.stdout)
    assert doc["model_options"]["traction"] == str(table)
    fam = tmp_path / "fam.npz"
    res = CliRunner().invoke(main, ["plants", "--ratio", "0.5,1,2", "--tau", "0.9",
                                    "--traction", str(table), "--out", str(fam), "--quiet"])
    assert res.exit_code == 0, res.output
    z = np.load(fam)
    assert str(z["options_traction"]) == str(table)
    (tmp_path / "sc.toml").write_text(
        '[scenario]\nname = "t"\nduration = 0.1\n[model]\ntraction = "table.csv"\n'
        '[initial]\nr_g = 1.0\nomega_p = 300.0\nnu = 0.01\nF_s = 10000.0\n')
    sc = load_scenario(tmp_path / "sc.toml")
    assert sc.options.traction is not None and sc.options.traction.source == str(table)


def test_controller_types_come_from_one_registry_with_the_api_defaults():
    """The CLI's --method choices are the registry's; its design options have no default of
    their own (the design function's apply), and those are the shipped designs' recipe
    (`SHIPPED_DESIGNS`, the ``design`` records of data/control/pi.json and hinf.json)."""
    import json
    from importlib import resources

    from empact.cli.control import design_cmd
    from empact.control.designs import CONTROLLER_TYPES
    from empact.reproduction.control import SHIPPED_DESIGNS

    opts = {p.name: p for p in design_cmd.params}
    assert list(opts["method"].type.choices) == list(CONTROLLER_TYPES)
    for name in ("bandwidth", "alpha_min", "schedule"):
        assert opts[name].default is None, name
    for kind, recipe in SHIPPED_DESIGNS.items():
        defaults = CONTROLLER_TYPES[kind].defaults()
        shipped = json.loads(resources.files("empact.data").joinpath(
            "control", f"{kind}.json").read_text())["design"]
        assert tuple(defaults["bandwidth_hz"]) == tuple(recipe["bandwidth_hz"])
        if "alpha_min" in recipe:
            assert defaults["alpha_min"] == recipe["alpha_min"] == shipped["alpha_min"]
        if kind == "hinf":
            assert list(defaults["bandwidth_hz"]) == shipped["bandwidth_hz"]
    # schedule: on when the design runs on the loop (as the shipped PI), as the CLI does
    assert CONTROLLER_TYPES["pi"].defaults()["schedule"] is None


def test_design_hinf_from_the_cli_uses_the_api_default(tmp_path):
    from click.testing import CliRunner

    from empact.cli import main
    from empact.control.controller import load_controller

    out = tmp_path / "k.json"
    res = CliRunner().invoke(main, ["control", "design", "--method", "hinf", "--ratio",
                                    "0.8,1,1.25", "--tau", "0.9", "--clamp", "16000", "--out",
                                    str(out), "--quiet"])
    assert res.exit_code == 0, res.output
    design = load_controller(out).design
    assert design["bandwidth_hz"] == [0.1, 0.2] and design["alpha_min"] == 0.5
    assert design["worst"]["all_stable"] and design["worst"]["disk_margin"] >= 0.5
    res = CliRunner().invoke(main, ["control", "design", "--method", "hinf", "--alpha-min",
                                    "0.01", "--out", str(tmp_path / "k2.json")])
    assert res.exit_code == 2 and "--alpha-min" in res.output
    assert not (tmp_path / "k2.json").exists()


def test_a_table_where_it_cannot_apply_is_one_line(tmp_path, params):
    """--traction with a family file (whose options are recorded in it) and with the slip
    Monte Carlo analysis (which draws the analytic curve's coefficients): one line, exit 2."""
    from importlib import resources

    from click.testing import CliRunner

    from empact.cli import main

    table = _write_sampled(tmp_path / "table.csv", params)
    spread = tmp_path / "s.toml"
    spread.write_text(resources.files("empact.data").joinpath(
        "montecarlo", "example-spread.toml").read_text())
    for args, match in ((["control", "check", "c.json", "--family", "f.npz"],
                         "--traction: give it with the design family, not with --family"),
                        (["montecarlo", "--spread", str(spread), "--analysis", "slip"],
                         "--traction: the slip analysis draws the analytic curve")):
        res = CliRunner().invoke(main, args + ["--traction", str(table)])
        assert res.exit_code == 2, res.output
        lines = res.output.strip().splitlines()
        assert len(lines) == 1 and match in lines[0], lines


# -- the parameter file: [traction] table = "curves.csv" ------------------------------------
def _params_with_table(tmp_path, params, table='"t.csv"'):
    """A parameter file in `tmp_path` naming a table next to it (relative path)."""
    _write_sampled(tmp_path / "t.csv", params)
    path = tmp_path / "p.toml"
    path.write_text(f"[traction]\ntable = {table}\n")
    return path


def test_a_parameter_file_names_a_table_the_model_uses(tmp_path, params, monkeypatch):
    """The table is read relative to the parameter file (not the working folder), once; the
    model of that set holds it: its parameter vector ``p`` equals, bitwise, the one built
    with the same table as an explicit option; an explicit option wins over the file's."""
    from empact.params import load_params
    from empact.variator.traction import load_traction

    path = _params_with_table(tmp_path, params)
    monkeypatch.chdir(tmp_path.parent)  # a relative path would not resolve from here
    p = load_params(path)
    assert p.traction_table_file == str(tmp_path / "t.csv")
    assert p.traction_table is not None and p.traction == params.traction
    explicit = nonlinear_model(params, traction=load_traction(tmp_path / "t.csv"))
    model = nonlinear_model(p)
    assert model.options.traction is p.traction_table
    assert np.array_equal(model.p, explicit.p)
    assert not np.array_equal(model.p, nonlinear_model(params).p)
    assert np.array_equal(nonlinear_model(p, traction=MEASURED).p,
                          nonlinear_model(params, traction=MEASURED).p)
    # a changed copy keeps the loaded table (not read again) and the set stays hashable
    q = p.from_dotted({"actuation.k_w": 2 * params.actuation.k_w})
    assert q.traction_table is p.traction_table and hash(q) != hash(p)


@pytest.mark.parametrize("value, match", [
    ('"missing.csv"', r"missing\.csv': no such traction table file$"),
    ('"bad.csv"', r"nu must increase"),
    ("3", r"must be the path of a traction table"),
], ids=["missing", "bad-file", "wrong-type"])
def test_a_bad_table_in_a_parameter_file_is_one_line(tmp_path, params, value, match):
    from empact.params import load_params

    (tmp_path / "bad.csv").write_text("r_g,nu,mu\n1,0,0\n1,0.02,0.09\n1,0.01,0.1\n")
    path = _params_with_table(tmp_path, params, value)
    with pytest.raises(ParameterError) as err:
        load_params(path)
    msg = str(err.value)
    assert "\n" not in msg and msg.startswith(f"{path}: traction.table = ") and \
        re.search(match, msg), msg


def test_a_table_round_trips_through_the_file_and_leaves_the_default_alone(tmp_path, params):
    """`dumps_params` writes the table's (resolved) path as ``traction.table`` and
    `load_params` reads it back to an equal set; the shipped set names no table and its text
    has no ``table`` key."""
    from empact.params import default_params, dumps_params, load_params

    p = load_params(_params_with_table(tmp_path, params))
    again = tmp_path / "sub" / "again.toml"
    again.parent.mkdir()
    again.write_text(dumps_params(p))
    q = load_params(again)
    assert q == p and q.traction_table_file == p.traction_table_file
    assert default_params().traction_table is None
    assert "table" not in dumps_params(default_params())
    assert load_params(None).to_dict() == default_params().to_dict()


def test_the_cli_takes_a_table_from_the_parameter_file(tmp_path, params):
    """``params validate`` accepts the file; ``control simulate --params file.toml`` runs on
    its table: the metrics equal, exactly, those of ``--traction t.csv`` (the same table by
    the other road) and differ from the analytic run's."""
    import json

    from click.testing import CliRunner

    from empact.cli import main

    path = _params_with_table(tmp_path, params)
    res = CliRunner().invoke(main, ["params", "validate", str(path)])
    assert res.exit_code == 0, res.output
    runs = {}
    for name, extra in (("file", ["--params", str(path)]),
                        ("option", ["--traction", str(tmp_path / "t.csv")])):
        res = CliRunner().invoke(main, ["control", "simulate", "--example",
                                        "slip-load-step-r1", "--json", "--quiet", *extra])
        assert res.exit_code == 0, res.output
        runs[name] = json.loads(res.output)
    assert runs["file"]["metrics"] == runs["option"]["metrics"]
    assert all(c["met"] for c in runs["file"]["targets"])
