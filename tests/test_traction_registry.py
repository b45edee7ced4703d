"""The registry of analytic traction laws (`empact.variator._laws.TRACTION_LAWS`, issue 31
item 6: a law added in at most two files): for every registered law the compiled kernel
equals the NumPy model (`empact.variator.traction.AnalyticTraction`, the same plain-Python
functions on arrays) to 1e-12, its forward-mode partials equal the complex step (the norm of
`tests/test_jacobian.py`), and the options and the command line offer it; and a toy law
registered in a module of its own (not in the package) is all it takes for it to run through
the kernel, a trim and the exact Jacobian (in a fresh process with its own numba cache).
"""
import json
import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest
from click.testing import CliRunner
from numpy.testing import assert_allclose
from test_jacobian import _check, _pair, _points

from empact.cli import main
from empact.errors import ParameterError
from empact.nonlinear import ModelOptions, nonlinear_model
from empact.nonlinear import _kernel as K
from empact.nonlinear.equilibrium import trim
from empact.params import OperatingPoint
from empact.variator import _compiled, _laws
from empact.variator.traction import TRACTION_LAWS, traction_from_params

LAWS = list(TRACTION_LAWS)
H = 1e-30  # the complex step (no subtraction: exact to rounding)


def _samples(params, n=200, seed=31):
    """Random slips in the valid range and ratios inside and outside the knots, and the
    knots themselves."""
    rng = np.random.default_rng(seed)
    t = params.traction
    r = np.concatenate([np.exp(rng.uniform(np.log(0.3), np.log(3.0), n)),
                        [t.r_low, t.r_med, t.r_od]])
    return rng.uniform(-0.2, 0.2, r.size), r


def test_the_registry_holds_the_magic_formula_and_its_layout():
    """The shipped law goes through the registry like any other: its index 0 (no branch in
    the generated dispatch), its coefficients at the knots in the kernel's parameter vector
    after the explicit part, the typed constants built to match."""
    assert LAWS[0] == "magic-formula"
    names = _laws.traction_parameter_names()
    assert K.PARAMETER_NAMES[K.P_TRACTION:] == names and K.NP == K.P_TRACTION + len(names)
    assert names[:4] == ("traction_law", "ln_r_low", "ln_r_med", "ln_r_od")
    for law in _laws.TRACTION_LAWS.values():
        for c in law.coefficients:
            assert all(f"{c}_{k}" in names for k in _laws.TRACTION_KNOTS)
        assert "def traction_law_mu(" in _compiled.TRACTION_SOURCE
        assert law.mu.__name__ in _compiled.TRACTION_SOURCE
    assert "if p[k]" not in _compiled.TRACTION_SOURCE or len(LAWS) > 1
    assert K.KernelConstants._fields[-1] == "traction"


@pytest.mark.parametrize("name", LAWS)
def test_kernel_equals_numpy_for_every_law(params, name):
    """The kernel's traction, peak and slope (`_kernel.traction_mu`, `mu_peak`,
    `traction_mu_d`) equal the NumPy model of the same law to 1e-12 (relative, with 1e-15
    absolute at mu = 0): the same plain-Python functions, compiled and on arrays."""
    m = nonlinear_model(params, traction_law=name)
    tr = traction_from_params(params, name)
    assert m.traction_law == tr and m.p[K.P_TRACTION] == LAWS.index(name)
    nu, r = _samples(params)
    assert_allclose(m.traction(nu, r), tr.mu(nu, r), rtol=1e-12, atol=1e-15)
    assert_allclose(m.mu_max(r), tr.mu_max(r), rtol=1e-12, atol=1e-15)
    dmu = [K.traction_mu_d(nu[k], r[k], m.p)[1] for k in range(r.size)]
    assert_allclose(dmu, tr.dmu(nu, r), rtol=1e-12, atol=1e-15)


@pytest.mark.parametrize("name", LAWS)
def test_partials_equal_the_complex_step_for_every_law(params, name):
    """``traction_mu_d``'s partials in nu and ln r_g and ``mu_max_d``'s slope equal the
    complex step through the value functions (1e-10 of the scale, the norm of
    `tests/test_jacobian.py`), at random points, on the knots (the left segment's branch) and
    outside them; then the forward-mode Jacobian of a model on the law equals the complex
    step's."""
    m = nonlinear_model(params, traction_law=name)
    nu, r = _samples(params, 100)
    for k in range(r.size):
        mu, mu_nu, mu_lr = K.traction_mu_d(nu[k], r[k], m.p)
        assert mu == K.traction_mu(nu[k], r[k], m.p)
        cs_nu = K.traction_mu(nu[k] + 1j * H, r[k], m.p).imag / H
        cs_lr = K.traction_mu(nu[k], r[k] * np.exp(1j * H), m.p).imag / H
        scale = max(abs(cs_nu), abs(cs_lr), abs(mu), 1e-300)
        assert abs(mu_nu - cs_nu) <= 1e-10 * scale and abs(mu_lr - cs_lr) <= 1e-10 * scale
        lr = np.log(r[k])
        mm, mm_lr = K.mu_max_d(r[k], lr, m.p)
        cs = K.mu_peak(r[k] * np.exp(1j * H), lr + 1j * H, m.p)
        assert mm == cs.real and abs(mm_lr - cs.imag / H) <= 1e-10 * max(abs(mm), 1e-300)
    for k, (x, u) in enumerate(_points(m, np.random.default_rng(7), 3)):
        _check(*_pair(m, x, u), (name, k))


@pytest.mark.parametrize("name", LAWS)
def test_options_and_the_cli_offer_every_law(params, name):
    """`ModelOptions` accepts every registered law and refuses another in one line naming
    the choices; ``--traction-law`` offers them (its choices are the registry) and reaches
    the model (``empact linearize``'s JSON names a law that is not the default)."""
    assert ModelOptions(traction_law=name).traction_law == name
    with pytest.raises(ParameterError, match=r"traction_law = 'no-such-law': must be one of "
                                             + LAWS[0]):
        ModelOptions(traction_law="no-such-law")
    runner = CliRunner()
    out = runner.invoke(main, ["linearize", "--help"])
    assert out.exit_code == 0 and "--traction-law" in out.output and name in out.output
    bad = runner.invoke(main, ["linearize", "--traction-law", "no-such-law"])
    assert bad.exit_code == 2 and "no-such-law" in bad.output
    res = runner.invoke(main, ["linearize", "--traction-law", name, "--json"])
    assert res.exit_code == 0, res.output
    text = res.stdout
    assert ('"traction_law": "%s"' % name in text) == (name != LAWS[0])
    assert json.loads(text)["schema"]["name"] == "empact.linearize"


TOY = '''
"""A toy traction law registered outside the package: mu = B C D nu, the magic formula's
micro-slip line (its slope at nu = 0), peaking at D; it reuses the coefficients B, C, D of
[traction] (a law with coefficients of its own adds their fields to TractionParams)."""
from empact.variator._laws import register_traction


def line_mu(nu, B, C, D):
    return B * C * D * nu


def line_mu_d(nu, B, C, D, B_l, C_l, D_l):
    return B * C * D * nu, B * C * D, (B_l * C * D + B * C_l * D + B * C * D_l) * nu


def line_peak_d(B, C, D, B_l, C_l, D_l):
    return D, D_l


register_traction("micro-slip-line", ("B", "C", "D"), line_mu, line_mu_d, line_peak_d)
'''

CHECK = '''
import sys
import numpy as np
import toy_law  # noqa: F401  (registers the law: before the kernel is imported)
from click.testing import CliRunner
from empact.cli import main
from empact.nonlinear import ModelOptions, nonlinear_model
from empact.nonlinear import _kernel as K
from empact.nonlinear.equilibrium import trim
from empact.params import OperatingPoint, default_params
from empact.variator._compiled import TRACTION_SOURCE
from empact.variator.traction import traction_from_params

params = default_params()
assert "if p[k] == 1.0:" in TRACTION_SOURCE and "line_mu(" in TRACTION_SOURCE
assert ModelOptions(traction_law="micro-slip-line").traction_law == "micro-slip-line"
assert "micro-slip-line" in CliRunner().invoke(main, ["linearize", "--help"]).output
m = nonlinear_model(params, traction_law="micro-slip-line")
tr = traction_from_params(params, "micro-slip-line")
rng = np.random.default_rng(3)
r = np.exp(rng.uniform(np.log(0.3), np.log(3.0), 50))
nu = rng.uniform(-0.01, 0.01, 50)
mu = m.traction(nu, r)
assert np.allclose(mu, tr.mu(nu, r), rtol=1e-12, atol=1e-15)
assert np.allclose(m.mu_max(r), tr.mu_max(r), rtol=1e-12, atol=0)
# not the magic formula: the line lies above the curve it touches at nu = 0
magic = nonlinear_model(params)
assert np.all(np.abs(mu) > np.abs(magic.traction(nu, r)))
op = trim(m, OperatingPoint(r_g=1.2, omega_p=300.0, nu=0.004, F_s=1.2e4))
assert abs(op.nu - 0.004) < 1e-9 and abs(op.r_g - 1.2) < 1e-9
# the partials of the generated dispatch's new branch against the complex step
for k in range(r.size):
    v, v_nu, v_lr = K.traction_mu_d(nu[k], r[k], m.p)
    cs_nu = K.traction_mu(nu[k] + 1e-30j, r[k], m.p).imag / 1e-30
    cs_lr = K.traction_mu(nu[k], r[k] * np.exp(1e-30j), m.p).imag / 1e-30
    scale = max(abs(cs_nu), abs(cs_lr), abs(v))
    assert abs(v_nu - cs_nu) <= 1e-10 * scale and abs(v_lr - cs_lr) <= 1e-10 * scale
print("toy law ok", float(op.x[16]))
'''


def test_a_toy_law_registered_in_its_own_module_is_all_it_takes(tmp_path):
    """A law written in a module outside the package and registered there (one call) runs:
    the generated dispatch has its branch, `ModelOptions` and ``--traction-law`` offer it,
    the kernel equals its NumPy model (1e-12), its partials equal the complex step (1e-10 of
    the scale) and a trim solves on it (the full Jacobian of every law in the registry is
    `test_partials_equal_the_complex_step_for_every_law`'s; here it would double the
    compile).  In a fresh process with its own numba cache
    (``NUMBA_CACHE_DIR``): the package's cache holds the kernel compiled with the laws of
    ``_laws.py``, and `register_traction` refuses a law from elsewhere without one."""
    (tmp_path / "toy_law.py").write_text(textwrap.dedent(TOY))
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "numba"),
               PYTHONPATH=os.pathsep.join([str(tmp_path), os.environ.get("PYTHONPATH", "")]))
    run = subprocess.run([sys.executable, "-c", CHECK], env=env, capture_output=True,
                         text=True, timeout=900)
    assert run.returncode == 0, run.stderr[-3000:]
    assert "toy law ok" in run.stdout


def test_a_law_from_elsewhere_needs_its_own_cache(monkeypatch):
    """Registering outside ``_laws.py`` without ``NUMBA_CACHE_DIR`` is one clear error (the
    shared cache would hold a kernel without the law), as is registering after the dispatch
    was generated, or a name twice."""
    def f(nu, B):
        return B * nu

    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    with pytest.raises(RuntimeError, match="registered after the compiled dispatch"):
        _laws.register_traction("late", ("B",), f, f, f)
    monkeypatch.setattr(_laws, "_FROZEN", [])
    with pytest.raises(RuntimeError, match="NUMBA_CACHE_DIR"):
        _laws.register_traction("elsewhere", ("B",), f, f, f)
    with pytest.raises(ValueError, match="already registered"):
        _laws.register_traction("magic-formula", ("B",), _laws.magic_formula,
                                _laws.magic_formula_d, _laws.magic_peak_d)
    assert "elsewhere" not in _laws.TRACTION_LAWS and "late" not in _laws.TRACTION_LAWS


def test_trim_on_every_law(params):
    """Every law trims at an operating point to its slip (the law reaches the
    equilibrium solver, not only the right-hand side)."""
    point = OperatingPoint(r_g=1.2, omega_p=300.0, nu=0.004, F_s=1.2e4)
    for name in LAWS:
        op = trim(nonlinear_model(params, traction_law=name), point)
        assert abs(op.nu - 0.004) < 1e-9 and abs(op.r_g - 1.2) < 1e-9, name
