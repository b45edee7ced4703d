"""Traction curves mu(nu, r_g): analytic and tabulated models (issue 3, item 1; paper Fig. 10)."""
import numpy as np
import pytest
from numpy.testing import assert_allclose

from empact.params import ParameterError
from empact.variator.traction import (
    MagicFormulaTraction,
    TabulatedTraction,
    load_traction,
    traction_curves,
    traction_from_params,
)

RATIOS = (0.43, 1.0, 2.25)  # paper Fig. 10: LOW, MED, OD


@pytest.fixture(scope="module")
def magic(params):
    return traction_from_params(params)


def sampled_table(magic, ratios=RATIOS):
    """Curves sampling the analytic model densely (finer in the steep micro-slip region)."""
    nu = np.concatenate([[0.0], np.geomspace(1e-6, 0.1, 600)])
    return {r: (nu, magic.mu(nu, r)) for r in ratios}


# -- analytic model -------------------------------------------------------------------------
def test_magic_formula_is_odd_and_zero_at_zero(magic):
    nu = np.linspace(-0.1, 0.1, 41)
    for r in (0.5, 1.0, 2.0):
        # exact symmetry of sin(C arctan(phi)) with phi odd in nu: equal to rounding (1e-15)
        assert_allclose(magic.mu(-nu, r), -magic.mu(nu, r), atol=1e-15)
    assert magic.mu(0.0, 1.0) == 0.0


def test_magic_formula_slope_is_the_derivative(magic):
    nu = np.array([-0.03, 0.0002, 0.001, 0.005, 0.01, 0.02, 0.04, 0.08])
    r = np.array([0.43, 0.7, 1.0, 1.6, 2.25, 2.5, 1.0, 0.5])
    h = 1e-8
    fd = (magic.mu(nu + h, r) - magic.mu(nu - h, r)) / (2 * h)
    # central difference, truncation O(h^2 mu''') and rounding O(eps / h): rtol 1e-5
    assert_allclose(magic.dmu(nu, r), fd, rtol=1e-5, atol=1e-9)


def test_coefficients_interpolate_in_log_ratio(params):
    t = params.traction
    magic = MagicFormulaTraction.from_params(t)
    B, C, D, E = magic.coefficients([t.r_low, t.r_med, t.r_od, 0.3, 3.0])
    assert_allclose(B, [t.B_low, t.B_med, t.B_od, t.B_low, t.B_od], rtol=1e-15)  # knots; held
    assert_allclose(D, [t.D_low, t.D_med, t.D_od, t.D_low, t.D_od], rtol=1e-15)
    r_mid = np.sqrt(t.r_med * t.r_od)  # midpoint in log(r_g): the average, exactly
    assert_allclose(magic.coefficients(r_mid)[3], (t.E_med + t.E_od) / 2, rtol=1e-12)


#: issue 20's bands for the shipped curve: slip at 90 % of the peak about 1-2 % (1.0-2.0 %),
#: the peak at 2-4.5 % depending on ratio, peaks 0.09-0.12 (published pushbelt curves)
NU90_BAND, PEAK_BAND, MU_BAND = (0.010, 0.020), (0.020, 0.045), (0.09, 0.12)


@pytest.mark.parametrize("r_g", [0.43, 0.5, 1.0, 2.0, 2.25])
def test_shipped_curve_has_a_micro_slip_slope(magic, r_g):
    """At LOW, MED, OD and r_g = 0.5, 2: the slip at 90 % of the peak, the peak slip and the
    peak inside the issue's bands (on a 1e-5 slip grid: the statistics to 1e-5)."""
    nu = np.linspace(0.0, 0.1, 10001)
    mu = magic.mu(nu, r_g)
    k = int(np.argmax(mu))
    nu90 = nu[np.argmax(mu >= 0.9 * mu[k])]
    assert NU90_BAND[0] <= nu90 <= NU90_BAND[1]
    assert PEAK_BAND[0] <= nu[k] <= PEAK_BAND[1]
    assert MU_BAND[0] <= mu[k] <= MU_BAND[1]
    assert mu[k] == pytest.approx(float(magic.mu_max(r_g)), rel=1e-6)  # D is the peak


def test_shipped_curves_show_fig10_and_the_slip_claims(magic):
    """Fig. 10: rises to a maximum, declines beyond it (MED and OD within 10 %); at r_g = 1
    the slope is negative by 4 % (Fig. 11's instability), steep at 0.1 % (full coupling,
    mu' > 1) and small near the peak (weak coupling at the Fig. 11 slips read near it:
    mu' < 0.64 from 2.5 % on, model notes Sec. 4 with alpha = 10)."""
    curves = traction_curves(magic, RATIOS, np.linspace(0, 0.1, 4001))
    nu_pk, mu_pk = curves.peak()
    assert curves.mu[1, -1] < mu_pk[1] and curves.mu[2, -1] < mu_pk[2]
    assert magic.dmu(0.04, 1.0) < 0
    assert magic.dmu(0.001, 1.0) > 1
    assert np.all(np.abs(magic.dmu([0.025, 0.03, 0.035, 0.04, 0.045], 1.0)) < 0.64)


def test_slip_outside_the_range_is_an_error(magic):
    with pytest.raises(ParameterError, match=r"nu = 0\.3: outside the valid slip range "
                                             r"\[-0\.2, 0\.2\]"):
        magic.mu([0.01, 0.3], 1.0)
    with pytest.raises(ParameterError, match=r"r_g = -1: must be a positive finite ratio"):
        magic.dmu(0.01, -1.0)


def test_traction_follows_the_parameters(params):
    changed = params.from_dotted({"traction.D_med": 0.12})
    # at r_g = r_med the coefficients are the MED ones: mu scales with D exactly
    assert_allclose(traction_from_params(changed).mu(0.02, 1.0),
                    traction_from_params(params).mu(0.02, 1.0) * 0.12 / 0.1, rtol=1e-14)


# -- tabulated model ------------------------------------------------------------------------
def test_tabulated_agrees_with_the_analytic_curve_it_samples(magic):
    tab = TabulatedTraction.from_curves(sampled_table(magic))
    nu = np.linspace(-0.095, 0.095, 397)
    for r in RATIOS:
        # PCHIP through 600 log-spaced samples: interpolation error below 1e-6 (measured:
        # largest about 2e-8, in the micro-slip knee)
        assert_allclose(tab.mu(nu, r), magic.mu(nu, r), atol=1e-6)
        # slopes: the interpolant's derivative; within 5 % of the analytic slope plus 5e-3
        # absolute (about 0.1 % of the largest slope, 8-13: PCHIP's derivative error near
        # mu' = 0, where the curve's peak is)
        assert_allclose(tab.dmu(nu, r), magic.dmu(nu, r), rtol=0.05, atol=5e-3)


def test_tabulated_slope_is_the_derivative_of_the_interpolant(magic):
    tab = TabulatedTraction.from_curves(sampled_table(magic, (1.0,)))
    nu = np.array([-0.02, 0.0015, 0.0123, 0.0371, 0.0789])
    h = 1e-9
    fd = (tab.mu(nu + h, 1.0) - tab.mu(nu - h, 1.0)) / (2 * h)
    # central difference on a piecewise cubic (no knot inside +-h): rtol 1e-5
    assert_allclose(tab.dmu(nu, 1.0), fd, rtol=1e-5)


def test_odd_extension_and_linear_in_ratio():
    tab = TabulatedTraction.from_curves({0.5: ([0, 0.01, 0.05], [0, 0.08, 0.1]),
                                         2.0: ([0, 0.01, 0.05], [0, 0.06, 0.09])})
    assert tab.nu_range == (-0.05, 0.05)
    assert_allclose(tab.mu(-0.01, 0.5), -0.08, rtol=1e-15)  # odd extension, exact sample
    assert_allclose(tab.mu(0.01, 1.25), 0.07, rtol=1e-14)  # midway in r_g: the average
    assert_allclose(tab.mu(0.01, 3.0), 0.06, rtol=1e-15)  # held constant beyond the last ratio
    with pytest.raises(ParameterError, match=r"nu = 0\.06: outside the valid slip range"):
        tab.mu(0.06, 1.0)


def test_table_not_starting_at_zero_has_no_extension():
    tab = TabulatedTraction.from_curves({1.0: ([0.001, 0.01, 0.05], [0.05, 0.09, 0.1])})
    assert tab.nu_range == (0.001, 0.05)


@pytest.mark.parametrize("nu, mu, match", [
    ([0, 0.02, 0.01, 0.03], [0, 0.05, 0.06, 0.07], r"nu must increase strictly, but nu\[2\] = "
                                                   r"0\.01 follows nu\[1\] = 0\.02"),
    ([0, 0.01, np.nan], [0, 0.05, 0.06], r"nu\[2\] = nan: must be a finite number"),
    ([0, 0.01, 0.02], [0, np.nan, 0.06], r"mu\[1\] = nan: must be a finite number"),
    ([0, 0.01], [0, 0.05], r"2 points, need at least 3"),
    ([0, 0.01, 0.02], [0, 0.5, 1.2], r"mu\[2\] = 1\.2 \(at nu = 0\.02\): allowed range is "
                                     r"\[0, 1\]"),
    ([0, 0.01, 0.02], [0, -0.1, 0.06], r"mu\[1\] = -0\.1 .*allowed range is \[0, 1\]"),
    ([0, 0.01, 0.02, 0.03], [0, 0.05, 0.06], r"4 nu values but 3 mu values"),
])
def test_nonsense_tables_are_refused(nu, mu, match):
    with pytest.raises(ParameterError, match=match) as err:
        TabulatedTraction.from_curves({1.0: (nu, mu)}, source="t.csv")
    assert "\n" not in str(err.value) and "curve r_g = 1" in str(err.value)


def test_csv_and_toml_files(tmp_path, magic):
    csv_path = tmp_path / "mu.csv"
    rows = ["r_g,nu,mu"] + [f"{r},{n},{m}" for r in (0.5, 2.0)
                            for n, m in zip([0, 0.005, 0.02, 0.05], [0, 0.07, 0.09, 0.085])]
    csv_path.write_text("\n".join(rows) + "\n")
    toml_path = tmp_path / "mu.toml"
    toml_path.write_text("".join(f"[[curve]]\nr_g = {r}\nnu = [0, 0.005, 0.02, 0.05]\n"
                                 "mu = [0, 0.07, 0.09, 0.085]\n" for r in (2.0, 0.5)))
    a, b = load_traction(csv_path), load_traction(toml_path)
    nu = np.linspace(-0.05, 0.05, 11)
    assert_allclose(a.mu(nu, 1.0), b.mu(nu, 1.0), rtol=0, atol=0)  # same data: identical
    assert a.ratios == (0.5, 2.0)


@pytest.mark.parametrize("name, text, match", [
    ("a.csv", "ratio,nu,mu\n1,0,0\n", r"must name exactly the columns r_g, nu, mu"),
    ("a.csv", "r_g,nu,mu\n1,0,0\n1,x,0.1\n", r"row 3: 'x' is not a number"),
    ("a.csv", "r_g,nu,mu\n1,0,0\n1,0.01\n", r"row 3: 2 fields, expected 3"),
    ("a.toml", "[[curve]]\nr_g = 1\nnu = [0, 0.01, 0.02]\n", r"curve 1 has keys \['nu', 'r_g'\]"),
    ("a.toml", "[[curve]]\nr_g = 1\nnu = [0, 0.01, 0.02]\nmu = [0, 0.1, 0.1]\n[[curve]]\n"
               "r_g = 1\nnu = [0, 0.01, 0.02]\nmu = [0, 0.1, 0.1]\n", r"r_g = 1 given twice"),
    ("a.txt", "x", r"must be \.csv or \.toml"),
])
def test_bad_files_are_refused(tmp_path, name, text, match):
    path = tmp_path / name
    path.write_text(text)
    with pytest.raises(ParameterError, match=match):
        load_traction(path)


def test_numpy_curve_is_the_compiled_law(params, magic):
    """One law for both routes (issue 31): `MagicFormulaTraction.mu`, ``dmu`` and
    ``mu_max`` (numpy, `empact.variator._tables.interp_knots` for the coefficients) equal the
    compiled kernel's `traction_mu`, `traction_mu_d` and the peak at random slips and ratios,
    at the knots and outside them, to the rounding of the transcendental functions.

    The two routes run the same operations, but numpy evaluates ``sin``, ``cos`` and
    ``arctan`` on arrays with its own SIMD routines where the CPU has them (SVML on AVX-512
    hosts), the compiled kernel with libm's scalar ones: the CI host gave a ``dmu`` 3 ULP
    (4.7e-16 relative) from the kernel's (it was bitwise equal on this AVX2 machine).
    Tolerance: 1e-14 relative (about 45 ULP), with an absolute floor of 1e-14 of the slope's
    scale where ``dmu`` crosses zero at the peak; a different law or coefficient differs by
    orders of magnitude more."""
    from empact.nonlinear import _kernel as K
    from empact.nonlinear.model import nonlinear_model

    p = nonlinear_model(params).p
    rng = np.random.default_rng(31)
    r = np.concatenate([np.exp(rng.uniform(np.log(0.3), np.log(3.0), 300)), RATIOS,
                        [params.traction.r_low, params.traction.r_med, params.traction.r_od]])
    nu = rng.uniform(-0.2, 0.2, r.size)
    mu, dmu, peak = magic.mu(nu, r), magic.dmu(nu, r), magic.mu_max(r)
    k_mu = np.array([K.traction_mu(nu[k], r[k], p) for k in range(r.size)])
    k_dmu = np.array([K.traction_mu_d(nu[k], r[k], p)[1] for k in range(r.size)])
    k_peak = np.array([K.mu_peak(r[k], np.log(r[k]), p) for k in range(r.size)])
    assert_allclose(mu, k_mu, rtol=1e-14, atol=1e-14 * np.abs(k_mu).max())
    assert_allclose(dmu, k_dmu, rtol=1e-14, atol=1e-14 * np.abs(k_dmu).max())
    assert_allclose(peak, k_peak, rtol=1e-14, atol=0)
