"""LTI tools (`empact.lti`): frequency response, zeros, damping, phase, root locus."""
import control
import numpy as np
import pytest
from numpy.testing import assert_allclose

from empact.errors import ParameterError
from empact.lti import (
    DISCRETIZATIONS,
    channel_zeros,
    cont2discrete,
    damping_ratio,
    frequency_response,
    oscillatory,
    root_locus,
    statespace,
    system_response,
    track_branches,
    transmission_zeros,
    unwrapped_phase_deg,
)


def by_imag(p):
    """Sort by imaginary part, then real part (for comparing eigenvalue sets)."""
    p = np.asarray(p, complex)
    return p[np.lexsort((p.real, p.imag))]


def _mass_spring():
    # m x'' + c x' + k x = F, output x: H = 1 / (k - m w^2 + j c w)
    m, c, k = 2.0, 0.3, 50.0
    A = [[0.0, 1.0], [-k / m, -c / m]]
    return (m, c, k), A, [[0.0], [1 / m]], [[1.0, 0.0]], [[0.0]]


def test_frequency_response_closed_form():
    (m, c, k), A, B, C, D = _mass_spring()
    w = np.logspace(-1, 2, 50)
    H = frequency_response(A, B, C, D, w, ["F"], ["x"]).H[0, 0]
    # closed form of the mass-spring-damper, to rounding (1e-12 relative)
    assert_allclose(H, 1 / (k - m * w**2 + 1j * c * w), rtol=1e-12)
    sys = statespace(A, B, C, D, inputs=["F"], outputs=["x"], states=["x", "v"], name="m.s")
    assert isinstance(sys, control.StateSpace) and sys.name == "m_s"
    assert_allclose(system_response(sys, w).H, sys(1j * w).reshape(1, 1, -1), rtol=1e-12)


def test_zeros_closed_form_and_python_control():
    # (s + 2)(s - 3) / ((s + 1)(s + 4)(s + 5)): zeros -2 and +3 exactly
    num, den = np.poly([-2.0, 3.0]), np.poly([-1.0, -4.0, -5.0])
    sys = control.ss(control.tf(num, den))
    z = transmission_zeros(sys.A, sys.B, sys.C, sys.D)
    assert_allclose(np.sort(z.real), [-2.0, 3.0], rtol=1e-10)
    assert_allclose(z.imag, 0, atol=1e-10)
    named = statespace(sys.A, sys.B, sys.C, sys.D, inputs=["u"], outputs=["y"],
                       states=["a", "b", "c"])
    assert_allclose(np.sort(channel_zeros(named, "u", "y").real), [-2.0, 3.0], rtol=1e-10)
    with pytest.raises(ValueError, match="unknown input 'v'"):
        channel_zeros(named, "v", "y")


def test_damping_and_oscillatory():
    p = np.array([-1 + 10j, -1 - 10j, -3.0, 0.0, 2 + 5j])
    z = damping_ratio(p)
    # closed form: zeta = -Re(p) / |p| (1 for a real pole, and for the one at the origin)
    assert_allclose(z, [1 / np.sqrt(101), 1 / np.sqrt(101), 1.0, 1.0, -2 / np.sqrt(29)],
                    rtol=1e-12)
    f, zeta = oscillatory(p)
    # upper half-plane only, ascending in |p| / 2 pi
    assert_allclose(f, np.array([np.sqrt(29), np.sqrt(101)]) / (2 * np.pi), rtol=1e-12)
    assert_allclose(zeta, [-2 / np.sqrt(29), 1 / np.sqrt(101)], rtol=1e-12)


def test_phase_starts_in_principal_range_and_is_continuous():
    w = np.linspace(0, 20, 400)
    H = np.exp(-1j * (w + 3.5))  # a pure delay, starting at -3.5 rad = -200.5 deg
    ph = unwrapped_phase_deg(H)
    assert -180 < ph[0] <= 180
    assert np.max(np.abs(np.diff(ph))) < 10  # no wraps


def test_general_root_locus_on_a_damped_oscillator():
    # x'' + c x' + x = 0: poles (-c +- sqrt(c^2 - 4)) / 2, break-away at c = 2
    loc = root_locus(lambda c: [[0.0, 1.0], [-1.0, -c]], 0.0, 4.0)
    c = loc.parameter
    exact = np.stack([(-c + np.sqrt(c**2 - 4 + 0j)) / 2, (-c - np.sqrt(c**2 - 4 + 0j)) / 2], 1)
    for k in range(len(c)):  # every step matches the closed form (as a set); at the double
        # root c = 2 the eigenvalues split by ~sqrt(eps): atol 1e-6
        assert_allclose(by_imag(loc.poles[k]), by_imag(exact[k]), atol=1e-6)
    assert np.all(np.abs(np.diff(loc.poles, axis=0)) < 0.2)  # continuous branches
    assert len(c) > 61  # refined near the break-away point beyond the 60 initial steps

def test_general_root_locus_over_a_nonlinear_parameter():
    # stiffness k(p) = p^2 on a log grid: poles +-j p exactly
    loc = root_locus(lambda p: [[0.0, 1.0], [-p**2, 0.0]], 0.1, 100.0, spacing="log")
    assert_allclose(np.abs(loc.poles).max(axis=1), loc.parameter, rtol=1e-10)
    assert np.all(np.diff(loc.poles[:, np.argmax(loc.poles[-1].imag)].imag) > 0)  # one branch

def test_track_branches_reorders_swapped_columns():
    e = np.array([[1 + 1j, 5 + 0j], [5.1 + 0j, 1.1 + 1j], [1.2 + 1j, 5.2 + 0j]])
    t = track_branches(e)
    assert_allclose(t[:, 0], [1 + 1j, 1.1 + 1j, 1.2 + 1j], rtol=0, atol=0)  # moved, not changed


@pytest.mark.parametrize("method", DISCRETIZATIONS)
def test_cont2discrete_is_scipys(method):
    """`cont2discrete` is ``scipy.signal.cont2discrete`` (the reference, imported here only):
    the same formulas and LAPACK calls, so bitwise the same matrices, on seeded random
    systems of 1-6 states, 1-3 inputs and 1-2 outputs (a stable and an unstable one each)."""
    from scipy.signal import cont2discrete as scipy_c2d

    rng = np.random.default_rng(7)
    for n, m, p in ((1, 1, 1), (3, 2, 1), (6, 3, 2)):
        for shift in (-3.0, 0.5):
            A = rng.standard_normal((n, n)) + shift * np.eye(n)
            B, C, D = (rng.standard_normal(s) for s in ((n, m), (p, n), (p, m)))
            ours = cont2discrete(A, B, C, D, 2e-3, method)
            ref = scipy_c2d((A, B, C, D), 2e-3, method=method)[:4]
            for M, R in zip(ours, ref):
                np.testing.assert_array_equal(M, R)


def test_cont2discrete_refuses_an_unknown_method():
    with pytest.raises(ValueError, match="'euler': one of tustin, bilinear, zoh, foh"):
        cont2discrete([[0.0]], [[1.0]], [[1.0]], [[0.0]], 1e-3, "euler")
    from empact.control.pi import pi_controller

    with pytest.raises(ParameterError, match="discretization method 'gbt': one of tustin"):
        pi_controller([2.0, 3.0], [0.5, 0.5], [10.0, 10.0]).discretize(1e-3, "gbt")
