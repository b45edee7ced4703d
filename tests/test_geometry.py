"""Variator geometry, eqs. 4-6 (issue 2, item 3)."""
import numpy as np
import pytest
from numpy.testing import assert_allclose

from empact.params import ParameterError
from empact.variator.geometry import belt_length, radii, ratio_range, variator_state, wrap_angle

RATIOS = np.array([0.43, 0.5, 0.8, 1.0, 1.6, 2.0, 2.25])


def test_radii_keep_belt_length_and_ratio(params):
    v = params.variator
    st = variator_state(RATIOS, v)
    assert_allclose(st.L, v.L_belt, rtol=1e-12)  # the root find's own tolerance
    assert_allclose(st.R_p / st.R_s, RATIOS, rtol=1e-12)


def test_medium_ratio_closed_form(params):
    v = params.variator
    R_p, R_s = radii(1.0, v.L_belt, v.a)
    # phi = 0: L = 2 a + 2 pi R  ->  R = (L - 2a) / (2 pi), exact
    assert_allclose([R_p, R_s], (v.L_belt - 2 * v.a) / (2 * np.pi), rtol=1e-14)


def test_delta_x_eq5(params):
    v = params.variator
    st = variator_state(RATIOS, v)
    # eq. 5: x_p - x_s = a sin(phi) tan(beta), exact identity of eq. 4 and x = (R - R0) tan(beta)
    assert_allclose(st.x_p - st.x_s, v.a * np.sin(st.phi) * np.tan(v.beta), rtol=1e-12, atol=1e-15)
    # sign of eq. 5 with eq. 4: Delta_x has the sign of R_p - R_s, i.e. of r_g - 1
    assert np.all(np.sign(st.delta_x) == np.sign(RATIOS - 1))


def test_length_derivatives_identity(params):
    a = params.variator.a
    R_p, R_s, h = 0.04, 0.07, 1e-7
    phi = wrap_angle(R_p, R_s, a)
    # dL/dR_p = pi + 2 phi, dL/dR_s = pi - 2 phi (model notes Sec. 1); central difference, O(h^2)
    dLp = (belt_length(R_p + h, R_s, a) - belt_length(R_p - h, R_s, a)) / (2 * h)
    dLs = (belt_length(R_p, R_s + h, a) - belt_length(R_p, R_s - h, a)) / (2 * h)
    assert_allclose([dLp, dLs], [np.pi + 2 * phi, np.pi - 2 * phi], rtol=1e-7)


def test_ratio_range_is_symmetric_and_binding(params):
    v = params.variator
    lo, hi = ratio_range(v)
    assert_allclose(lo * hi, 1.0, rtol=1e-10)  # eq. 6 is symmetric under swapping the pulleys
    R_p, R_s = radii(hi, v.L_belt, v.a)
    # at the top of the range one radius limit binds (to the root-find tolerance)
    assert min(abs(R_s - v.R_min), abs(R_p - v.R_max)) < 1e-9
    assert R_s >= v.R_min - 1e-12 and R_p <= v.R_max + 1e-12
    assert lo < 0.43 and hi > 2.25  # the paper's LOW and OD ratios (Fig. 10) are reachable


@pytest.mark.parametrize("r", [0.1, 3.0, -1.0, float("nan")])
def test_out_of_range_ratio(params, r):
    with pytest.raises(ParameterError, match="r_g = "):
        variator_state(r, params.variator)


def test_primary_radius_per_ratio_is_the_derivative_of_the_radii(params):
    """dR_p/dr_g along a shift at constant belt length against a central difference of
    `radii` (relative step 1e-6: error ~1e-10), 1e-7 relative."""
    from empact.variator.geometry import primary_radius_per_ratio

    v = params.variator
    for r in (0.45, 0.8, 1.0, 1.6, 2.2):
        e = 1e-6
        fd = (radii(r * (1 + e), v.L_belt, v.a)[0] - radii(r * (1 - e), v.L_belt, v.a)[0]) \
            / (2 * e * r)
        assert float(primary_radius_per_ratio(r, v)) == pytest.approx(float(fd), rel=1e-7)
