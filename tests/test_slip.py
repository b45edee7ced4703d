"""Slip dynamics of the variator coupling (issue 3; paper Sec. 2.2, eqs. 1-3, Figs. 9-13)."""
import control
import numpy as np
import pytest
from numpy.testing import assert_allclose

from empact import paper
from empact.linear.driveline import driveline_model
from empact.lti import oscillatory, track_branches
from empact.params import OperatingPoint, ParameterError
from empact.slip import (
    INPUTS,
    OUTPUTS,
    STATES,
    belt_root_locus,
    belt_torque,
    coupled_limit,
    dynamic_poles,
    linearize_belt,
    pole_sweep,
    reduced_matrices,
    slip,
    slip_model,
    slip_state_space,
    stability_map,
    stability_measures,
    state_matrices,
    zero_locus,
)

FIG11 = OperatingPoint(**{**paper.FIG11_POINT, "nu": 0.01})  # r_g 1, 10 kN, 300 rad/s


def hz(p):
    return np.abs(p) / (2 * np.pi)


def by_imag(z):
    """Sort by imaginary, then real part (robust to rounding noise in the real parts)."""
    z = np.asarray(z)
    return z[np.lexsort((z.real, np.round(z.imag, 6)))]


def oscillatory_hz(poles):
    p = poles[poles.imag > 1e-3]  # structural zeros show up to ~1e-5 rad/s (rounding)
    return np.sort(hz(p)), (-p.real / np.abs(p))[np.argsort(hz(p))]


# -- eqs. 1-3 ---------------------------------------------------------------------------------
def nonlinear_torque(params, r_g, w_p, w_s, F_s):
    """Eqs. 1-2: belt torque on the secondary from the shaft speeds."""
    return belt_torque(params, slip(w_p, w_s, r_g), r_g, F_s)


@pytest.mark.parametrize("nu0", [0.002, 0.01, 0.04])
def test_c_b_of_eq3_is_the_derivative_of_eqs1_2_at_ratio_1(params, nu0):
    op = FIG11.replace(nu=nu0)
    lin = linearize_belt(params, op)
    w_s, h = op.omega_s, 1e-7 * op.omega_p  # a slip step of 1e-7 (the knee is 1e-3 wide)
    fd_s = (nonlinear_torque(params, 1.0, op.omega_p, w_s + h, op.F_s)
            - nonlinear_torque(params, 1.0, op.omega_p, w_s - h, op.F_s)) / (2 * h)
    # eq. 3: T_b~ = c_b (q3'/q2' q2'~ - q3'~) -> dT_b/domega_s = -c_b; central difference of the
    # smooth eqs. 1-2: truncation ~ (1e-7 / 1e-3)^2, rounding ~ 1e-16 T_b / h: rtol 1e-5
    assert_allclose(fd_s, -lin.c_b, rtol=1e-5)
    hp = 1e-7 * op.omega_p
    fd_p = (nonlinear_torque(params, 1.0, op.omega_p + hp, w_s, op.F_s)
            - nonlinear_torque(params, 1.0, op.omega_p - hp, w_s, op.F_s)) / (2 * hp)
    assert_allclose(fd_p, lin.c_b * w_s / op.omega_p, rtol=1e-5)  # eq. 3, q3'/q2' factor
    hf = 1.0
    fd_f = (nonlinear_torque(params, 1.0, op.omega_p, w_s, op.F_s + hf)
            - nonlinear_torque(params, 1.0, op.omega_p, w_s, op.F_s - hf)) / (2 * hf)
    assert_allclose(fd_f, lin.g_F, rtol=1e-9)  # eq. 3 input term 2 mu R_s / cos(beta); linear


def test_paper_c_b_is_the_primary_side_damping_away_from_ratio_1(params):
    # r_g = 2: the paper's c_b (with R_p) is r_g times the secondary-side derivative
    op = OperatingPoint(r_g=2.0, nu=0.01, F_s=1e4, omega_p=300.0)
    lin = linearize_belt(params, op)
    w_s, h = op.omega_s, 1e-7 * op.omega_s

    def fd(scale):
        return scale * (nonlinear_torque(params, 2.0, op.omega_p, w_s + h, op.F_s)
                        - nonlinear_torque(params, 2.0, op.omega_p, w_s - h, op.F_s)) / (2 * h)

    assert_allclose(fd(2.0), -lin.c_b, rtol=1e-5)  # d(r_g T_b)/d omega_s = -c_b (paper eq. 3)
    assert_allclose(fd(1.0), -lin.c_s, rtol=1e-5)  # d T_b / d omega_s = -c_s = -c_b / r_g
    assert_allclose(lin.c_b, 2.0 * lin.c_s, rtol=1e-14)


def test_slip_definition_and_standstill(params):
    assert_allclose(slip(300.0, 0.99 * 2.0 * 300.0, 2.0), 0.01, rtol=1e-12)  # eq. 2
    with pytest.raises(ParameterError, match=r"omega_p = 0: .*undefined"):
        slip([300.0, 0.0], 100.0, 1.0)
    with pytest.raises(ParameterError, match=r"omega_p = 0: .*undefined"):
        OperatingPoint(r_g=1.0, nu=0.01, F_s=1e4, omega_p=0.0)


@pytest.mark.parametrize("kw, match", [
    (dict(nu=1.5), r"nu = 1\.5: allowed range is \(-1, 1\)"),
    (dict(F_s=-5.0), r"F_s = -5: allowed range is \[0, inf\) \[N\]"),
    (dict(omega_p=-1.0), r"omega_p = -1: allowed range is \(0, inf\)"),
    (dict(r_g=0.0), r"r_g = 0: allowed range is \(0, inf\)"),
])
def test_bad_operating_points(kw, match):
    with pytest.raises(ParameterError, match=match):
        FIG11.replace(**kw)


def test_slip_outside_the_curve_and_ratio_outside_the_variator(params):
    with pytest.raises(ParameterError, match=r"nu = 0\.5: outside the valid slip range"):
        slip_model(params, FIG11.replace(nu=0.5))
    with pytest.raises(ParameterError, match=r"r_g = 3: outside the geometric ratio range"):
        slip_model(params, FIG11.replace(r_g=3.0))


# -- the state-space model ------------------------------------------------------------------
def test_state_space_is_named_and_reduces_to_the_beltless_driveline(params):
    sys = slip_state_space(params, FIG11.replace(F_s=0.0))  # no clamping: no belt damping
    assert isinstance(sys, control.StateSpace)
    assert list(sys.input_labels) == list(INPUTS) and list(sys.output_labels) == list(OUTPUTS)
    assert list(sys.state_labels) == list(STATES)
    ref = driveline_model(params, 1.0, belt=False).state_space(["T_d", "T_l"])
    assert_allclose(sys.A, ref.A, rtol=1e-15, atol=0)  # same M, K; C_b = 0 exactly
    assert_allclose(sys.B[:, 1:], ref.B, rtol=1e-15, atol=0)


def test_slip_output_is_the_linearised_eq2(params):
    m = slip_model(params, FIG11)
    dw = np.array([0.3, -0.2])  # perturbations of omega_p, omega_s [rad/s]
    x = np.zeros(8)
    x[5], x[6] = dw
    nu_lin = (m.C @ x)[OUTPUTS.index("nu")]
    nu_fd = (slip(FIG11.omega_p + 1e-3 * dw[0], FIG11.omega_s + 1e-3 * dw[1], 1.0)
             - slip(FIG11.omega_p - 1e-3 * dw[0], FIG11.omega_s - 1e-3 * dw[1], 1.0)) / 2e-3
    assert_allclose(nu_lin, nu_fd, rtol=1e-7)  # central difference of eq. 2: rtol 1e-7


def test_frequency_response_matches_python_control(params):
    m = slip_model(params, FIG11)
    w = np.array([3.0, 30.0, 97.0, 300.0])
    ours = m.frequency_response(w, ["F_s", "T_d"], ["nu", "T_b"]).H
    theirs = m.state_space(["F_s", "T_d"], ["nu", "T_b"])(1j * w)
    assert_allclose(ours, theirs, rtol=1e-9)  # same formula C (jw - A)^-1 B + D


def test_batched_matrices_equal_single_models(params):
    nu = np.array([0.001, 0.02, 0.04])
    r = np.array([0.5, 1.0, 2.0])
    A, B, C, D = state_matrices(params, r, nu, 8e3, 250.0)
    for k in range(3):
        m = slip_model(params, OperatingPoint(r[k], nu[k], 8e3, 250.0))
        assert_allclose(A[k], m.A, rtol=1e-14)
        assert_allclose(B[k], m.B, rtol=1e-14)


def test_reduced_model_has_the_non_structural_poles(params):
    nu = np.linspace(0.001, 0.06, 13)
    r = np.linspace(0.45, 2.4, 13)
    A8 = state_matrices(params, r, nu, 1e4, 300.0)[0]
    A5 = reduced_matrices(params, r, nu, 1e4, 300.0)
    full = np.array([by_imag(p) for p in dynamic_poles(np.linalg.eigvals(A8))])
    red = np.array([by_imag(p) for p in np.linalg.eigvals(A5)])
    # exact reduction; the 8x8 structural zeros perturb the rest by rounding only: 1e-8
    assert_allclose(full, red, rtol=1e-8, atol=1e-8 * np.abs(red).max())
    zeros = np.sort(np.abs(np.linalg.eigvals(A8)), axis=1)[:, :3]
    assert zeros.max() < 1e-4  # the three structural zeros (rounding of a Jordan block)


# -- Fig. 9: root locus over c_b ------------------------------------------------------------


def test_root_locus_end_points(params):
    rl = belt_root_locus(params, 1.0)
    # paper Sec. 2.2: uncoupled sides 15.5 and 24.6 Hz (labels swapped, model notes Sec. 3),
    # coupled 4.14 and 22.5 Hz (Table 2, r_g = 1): within 1 %
    assert_allclose(rl.uncoupled_hz, [15.5, 24.6], rtol=0.01)
    assert_allclose(rl.coupled_hz, paper.COUPLED_R1_HZ, rtol=0.01)
    # two rigid-body modes per side at c_b = 0 (double zeros: rounding ~ sqrt(eps) |A|)
    assert np.sum(np.abs(rl.start) < 1e-5) == 4
    # the computed locus runs into the exact end points: at the largest c_b the oscillatory
    # poles are within 0.1 % of the coupled limit and one real pole runs off to the left: for
    # large c_s it is -c_s (r_g rho / J_p + 1 / J_s) (the two pulleys' relative speed damped
    # by the belt, the springs too soft to matter), within 2 %
    f_end, _ = oscillatory_hz(rl.locus.poles[-1])
    assert_allclose(f_end, rl.coupled_hz, rtol=1e-3)
    d = params.driveline
    c_s = 1e4  # the locus' last c_b (`belt_root_locus`'s range) = c_s at r_g = 1
    assert rl.locus.poles[-1].real.min() == pytest.approx(-c_s * (1 / d.J_p + 1 / d.J_s),
                                                          rel=0.02)
    f_start, _ = oscillatory_hz(rl.locus.poles[0])
    assert_allclose(f_start, rl.uncoupled_hz, rtol=1e-3)


def test_coupled_limit_is_table2_with_a_rigid_belt(params):
    for r in (0.5, 1.0, 2.0):
        f = np.sort(hz(coupled_limit(params, r)))[-4::2]
        # Table 2 modes 2 and 3 within 1 % (the finite belt stiffness moves them < 0.5 %)
        assert_allclose(f, paper.TABLE2_HZ[r][1:3], rtol=0.01)


# -- Fig. 11 and 12: poles over slip -------------------------------------------------------
def test_fig12a_full_coupling_at_0_1_percent(params):
    f, zeta = oscillatory_hz(slip_model(params, FIG11.replace(nu=0.001)).poles())
    # paper Fig. 12a: "at nu = 0.1 % the system is fully coupled": natural frequencies within
    # 2 % of the coupled 4.14 and 22.5 Hz (Table 2)
    assert_allclose(f, paper.COUPLED_R1_HZ, rtol=0.02)


def test_fig11_right_half_plane_pair_at_4_percent(params):
    p = slip_model(params, FIG11.replace(nu=0.04)).poles()
    rhp = p[(p.real > 1e-6) & (p.imag > 1e-6)]
    assert len(rhp) >= 1  # paper Figs. 11/12a: unstable at nu = 4 %


def test_fig11_damping_falls_as_slip_grows(params):
    # paper Fig. 11 at its slips read near the traction peak (2.5-4.5 %, the paper gives
    # none): both pairs turn toward the imaginary axis
    lo, hi = paper.FIG11_SLIPS
    sw = pole_sweep(params, "nu", np.linspace(lo, hi, 15), FIG11)
    zeta = np.array([sw.oscillatory(k)[1] for k in range(15)])
    assert zeta.shape == (15, 2) and np.all(np.diff(zeta, axis=0) < 0)
    # weak coupling there: poles within 3 % of the uncoupled 15.5 / 24.6 Hz
    f = np.array([sw.oscillatory(k)[0] for k in range(15)])
    assert_allclose(f, np.broadcast_to([15.5, 24.6], f.shape), rtol=0.03)
    # Fig. 12a slips (a reading between 0.1 % and 4 %): the damping of both resonances falls
    z12 = np.array([oscillatory_hz(slip_model(params, FIG11.replace(nu=n)).poles())[1]
                    for n in paper.FIG12_SLIPS[1:]])
    assert np.all(np.diff(z12, axis=0) < 0)


@pytest.mark.parametrize("r_g", [0.5, 1.0, 2.0])
def test_sign_of_largest_real_part_follows_sign_of_the_traction_slope(params, r_g):
    nus = np.array([0.001, 0.003, 0.01, 0.02, 0.03, 0.04, 0.06, 0.1])
    sw = pole_sweep(params, "nu", nus, FIG11.replace(r_g=r_g))
    away = np.abs(sw.dmu) > 1e-3  # skip the peak itself, where mu' ~ 0 is marginal
    assert away.sum() >= 6
    assert np.all((sw.max_real[away] > 0) == (sw.dmu[away] < 0))
    # and the full 8x8 model with python-control agrees (three structural zeros left out)
    for k in np.flatnonzero(away):
        p = slip_state_space(params, FIG11.replace(r_g=r_g, nu=nus[k])).poles()
        assert (stability_measures(p)[0] > 0) == (sw.dmu[k] < 0)


# -- Figs. 12b and 13: zeros ----------------------------------------------------------------
def test_zeros_are_the_coupled_poles_and_ignore_the_traction_slope(params):
    for r in (0.5, 1.0, 2.0):
        for op in (FIG11.replace(r_g=r, nu=0.001), FIG11.replace(r_g=r, nu=0.04, F_s=3e3,
                                                                 omega_p=100.0)):
            z = slip_model(params, op).zeros("F_s", "nu")
            assert np.sum(np.abs(z) < 1e-5 * np.abs(z).max()) == 3  # three at the origin
            nz = z[np.abs(z) >= 1e-5 * np.abs(z).max()]
            c = coupled_limit(params, r, op.nu)
            # zeros = coupled-limit poles, to rounding (generalised eigenvalues): rtol 1e-8
            assert_allclose(by_imag(nz), by_imag(c[np.abs(c) > 0]), rtol=1e-8,
                            atol=1e-8 * np.abs(c).max())
            assert np.abs(nz.real).max() < 1e-6 * np.abs(nz).max()  # on the imaginary axis


def test_zeros_match_python_control(params):
    m = slip_model(params, FIG11.replace(r_g=0.7))
    ours = oscillatory(m.zeros("F_s", "nu"))[0]
    theirs = oscillatory(m.state_space(["F_s"], ["nu"]).zeros())[0]
    assert_allclose(ours, theirs, rtol=1e-8)  # same pencil, QZ both: rounding only


def test_zero_locus_moves_with_the_ratio(params):
    zl = zero_locus(params, np.linspace(0.5, 2.0, 7), FIG11)
    f = zl.zero_hz
    assert np.all(np.diff(f[:, 0]) > 0) and np.all(np.diff(f[:, 1]) < 0)  # Fig. 13 / Table 2
    assert_allclose(f[[0, 2, 6]], [paper.TABLE2_HZ[r][1:3] for r in (0.5, 1.0, 2.0)], rtol=0.01)
    assert_allclose(zl.zeros, track_branches(zl.zeros), rtol=0, atol=0)  # already tracked


# -- stability map ------------------------------------------------------------------------
def test_map_agrees_with_python_control_per_point(params):
    nu = np.array([0.001, 0.01, 0.025, 0.04, 0.07])
    F = np.array([2e3, 1e4, 3e4])
    for method in ("reduced", "full"):
        sm = stability_map(params, "nu", nu, "F_s", F, base=FIG11, method=method, chunk_size=4)
        for i, j in [(0, 0), (1, 2), (2, 3), (0, 4), (2, 1)]:
            sys = slip_state_space(params, FIG11.replace(nu=nu[j], F_s=F[i]))
            mr, mz = stability_measures(sys.poles())
            scale = np.abs(sys.poles()).max()
            assert_allclose(sm.max_real[i, j], mr, atol=1e-9 * scale)  # same poles, rounding
            assert_allclose(sm.min_damping[i, j], mz, atol=1e-9)


def test_map_is_independent_of_chunking_and_threads(params):
    nu, r = np.linspace(0.001, 0.05, 17), np.linspace(0.5, 2.2, 11)
    a = stability_map(params, "nu", nu, "r_g", r, base=FIG11)
    b = stability_map(params, "nu", nu, "r_g", r, base=FIG11, chunk_size=5, workers=2)
    # the same up to rounding: the vectorised radius iteration (geometry.radii) stops when the
    # whole chunk has converged, so a point's R_s can differ in the last bits between chunkings
    assert_allclose(a.max_real, b.max_real, rtol=1e-10, atol=1e-12)
    assert a.max_real.shape == (11, 17)
    assert np.array_equal(a.unstable, a.max_real > a.tol)


@pytest.mark.parametrize("kw, match", [
    (dict(x_name="nu", y_name="nu"), r"over 'nu' twice"),
    (dict(x_name="speed"), r"operating-point variable = 'speed': must be one of r_g, nu"),
    (dict(x_name="omega_p", x=[0.0, 100.0]), r"omega_p = 0: .*undefined"),
    (dict(chunk_size=0), r"chunk_size = 0: must be a whole number in \[1, inf\)"),
])
def test_map_bad_input(params, kw, match):
    args = dict(x_name="nu", x=[0.01, 0.02], y_name="F_s", y=[1e3, 2e3])
    args.update(kw)
    with pytest.raises(ParameterError, match=match):
        stability_map(params, args.pop("x_name"), args.pop("x"), args.pop("y_name"),
                      args.pop("y"), **args)
