"""A measured shift-speed map (the creep coefficient K_c per ratio and clamping force) in place
of the analytic creep law: read from CSV/TOML, interpolated by the compiled kernel exactly as
in numpy, and equal to the analytic model where it tabulates the analytic law."""
import numpy as np
import pytest

from empact import OperatingPoint
from empact.errors import ParameterError
from empact.nonlinear import _kernel as K
from empact.nonlinear.equilibrium import trim
from empact.nonlinear.model import nonlinear_model
from empact.params import default_params
from empact.variator.shift_law import CreepMap, creep_coefficient, creep_damping, load_creep_map

P = default_params()


def _analytic_map(ratios, forces):
    """The analytic K_c sampled on a grid (divided by the gain, which the map keeps)."""
    F_s, K_c = [], []
    for r in ratios:
        F_s.append(np.asarray(forces, float))
        K_c.append(creep_coefficient(P, r, forces) / P.shift.gain)
    return CreepMap(tuple(ratios), tuple(F_s), tuple(K_c), source="analytic samples")


def test_kernel_interpolates_the_map_as_numpy():
    """The compiled `creep_coefficient` with a map equals `CreepMap.K_c` (times the gain) at
    random points inside and outside the table (held constant outside), to 1e-14."""
    cmap = CreepMap((0.5, 1.0, 2.0), (np.array([5e3, 2e4]), np.array([5e3, 1e4, 3e4]),
                                      np.array([4e3, 2e4])),
                    (np.array([1e-3, 2e-3]), np.array([2e-3, 2.5e-3, 4e-3]),
                     np.array([3e-3, 5e-3])))
    m = nonlinear_model(P, creep_map=cmap)
    rng = np.random.default_rng(3)
    for r, F in zip(np.exp(rng.uniform(np.log(0.4), np.log(2.4), 40)),
                    rng.uniform(2e3, 4e4, 40)):
        got = K.creep_coefficient(r, 0.06, F, m.p)
        assert got == pytest.approx(P.shift.gain * float(cmap.K_c(r, F)), rel=1e-14)


def test_map_of_the_analytic_law_reproduces_the_model():
    """A dense table of the analytic K_c (41 ratios geometric 0.45-2.2, 30 forces 2-40 kN)
    gives the analytic model's creep damping and trimmed state within the table's linear
    interpolation error (1e-3 relative; the law is smooth)."""
    ratios = np.geomspace(0.45, 2.2, 41)
    cmap = _analytic_map(ratios, np.linspace(2e3, 4e4, 30))
    for r in (0.6, 1.0, 1.7):
        a = creep_damping(P, r, 300.0, 1.2e4).C_lambda
        b = creep_damping(P, r, 300.0, 1.2e4, creep_map=cmap).C_lambda
        assert b == pytest.approx(a, rel=1e-3)
    op = OperatingPoint(r_g=1.3, omega_p=300.0, nu=0.006, F_s=1.1e4)
    x0 = trim(nonlinear_model(P), op)
    x1 = trim(nonlinear_model(P, creep_map=cmap), op)
    A0 = x0.model.jacobian(x0.x, x0.u)[0]
    A1 = x1.model.jacobian(x1.x, x1.u)[0]
    assert np.abs(x1.x - x0.x).max() <= 1e-3 * np.abs(x0.x).max()
    assert np.abs(A1 - A0).max() <= 1e-3 * np.abs(A0).max()


def test_creep_map_files_and_bad_input(tmp_path):
    path = tmp_path / "kc.csv"
    path.write_text("r_g,F_s,K_c\n0.5,5000,0.001\n0.5,20000,0.002\n2,5000,0.003\n2,20000,0.004\n")
    cmap = load_creep_map(path)
    # tol 1e-12 rel: linear in F_s between the file's two points (reference: their mean)
    assert cmap.ratios == (0.5, 2.0) and cmap.K_c(0.5, 12500.0) == pytest.approx(0.0015,
                                                                                 rel=1e-12)
    toml = tmp_path / "kc.toml"
    toml.write_text("[[curve]]\nr_g = 1.0\nF_s = [5000.0, 20000.0]\nK_c = [0.001, 0.002]\n")
    # held outside (tol 1e-12 rel; reference: the file's last value)
    assert load_creep_map(toml).K_c(3.0, 1e6) == pytest.approx(0.002, rel=1e-12)
    for text, match in (("r_g,F_s,K_c\n1,5000,0.001\n1,2000,0.002\n", "F_s must increase"),
                        ("r_g,F_s,K_c\n1,5000,0.001\n1,8000,-1\n", r"K_c\[1\] = -1: allowed "
                                                                  r"range is \(0, inf\)"),
                        ("r_g,F_s\n1,5000\n", "must name exactly the columns r_g, F_s, K_c")):
        path.write_text(text)
        with pytest.raises(ParameterError, match=match):
            load_creep_map(path)


def test_creep_map_cli(tmp_path):
    from click.testing import CliRunner

    from empact.cli import main

    path = tmp_path / "kc.csv"
    path.write_text("r_g,F_s,K_c\n0.5,5000,0.003\n0.5,20000,0.003\n2,5000,0.003\n2,20000,0.003\n")
    res = CliRunner().invoke(main, ["linearize", "--creep-map", str(path), "--json"])
    assert res.exit_code == 0, res.output
    assert '"creep_map":' in res.output
