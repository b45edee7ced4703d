"""Plant families, controller design, robustness and the closed loop (issue 13)."""
import json

import control
import numpy as np
import pytest
from scipy.io import loadmat

from empact.control.closed_loop import control_example_path, run_closed_loop
from empact.control.controller import load_controller
from empact.control.family import PlantFamily, load_family, plant_family, save_family
from empact.control.hinf import check_wellposed, design_hinf, mixed_sensitivity_plant
from empact.control.pi import pi_controller
from empact.control.robustness import (
    closed_loop_matrix,
    disk_margin,
    frequency_responses,
    robustness_map,
)
from empact.errors import ParameterError
from empact.lti import system_response
from empact.nonlinear.linearization import plant
from empact.nonlinear.model import nonlinear_model
from empact.nonlinear.scenario import load_scenario


@pytest.fixture(scope="module")
def design_family(params):
    """Issue 21's design family (`ISSUE21_GRID`): the continuous H-infinity design's checks
    (the shipped one is designed on the loop that runs: tests/test_hinf_loop.py)."""
    from empact.control.family import ISSUE21_GRID, LOOP_FAMILY_OUTPUTS

    return plant_family(params, **ISSUE21_GRID, outputs=LOOP_FAMILY_OUTPUTS)


def test_family_points_equal_single_point_linearisation(params):
    """Batch trim + compiled complex-step loop against `plant` point by point: 1e-10."""
    r, nu = np.array([0.5, 0.9, 1.7]), np.array([0.004, 0.01])
    fam = plant_family(params, r_g=r, nu=nu, F_s=12e3)
    m = nonlinear_model(params, drive="speed", load="torque")
    assert fam.ok.all() and fam.shape == (3, 2)
    for i in range(3):
        for j in range(2):
            sys = plant(params, params.operating.replace(r_g=r[i], nu=nu[j], F_s=12e3),
                        model=m).system
            for got, ref in ((fam.A[i, j], sys.A), (fam.B[i, j], sys.B), (fam.C[i, j], sys.C),
                             (fam.D[i, j], sys.D)):
                ref = np.asarray(ref)
                assert np.abs(got - ref).max() <= 1e-10 * max(np.abs(ref).max(), 1e-300)
    assert fam.inputs == ("T_mp", "T_ms", "T_l") and fam.outputs == ("r_g", "nu", "nu_r")


def test_family_marks_points_that_do_not_trim(params):
    """A load beyond the traction peak at one point: that point is marked, not dropped."""
    fam = plant_family(params, r_g=np.array([1.0, 2.0]), F_s=3e3, T_l=60.0)
    assert fam.ok.tolist() == [False, False] or not fam.ok.all()
    assert all("traction peak" in str(r) for r, ok in zip(fam.reason, fam.ok) if not ok)
    assert np.isnan(fam.A[~fam.ok]).all()


def test_lpv_interpolation_error(params):
    """Grid 41 ratios (geometric, 0.5-2) x 9 torque ratios (0.5-0.95): the interpolated
    plant's frequency response at off-grid points (cell centres, 12 seeded) is within 2 %
    of the exact one, 0.1-100 Hz (relative 2-norm over frequency per channel of the control
    inputs; measured up to 0.84 % over all 360 centres; 21 ratios give 3.2 %, a slip axis
    instead of the torque ratio 5.7-6.5 %: on the micro-slip slope the plant follows the
    torque ratio more evenly than the slip)."""
    r, tau = np.geomspace(0.5, 2, 41), np.linspace(0.5, 0.95, 9)
    fam = plant_family(params, r_g=r, tau=tau)
    m = nonlinear_model(params, drive="speed", load="torque")
    w = 2 * np.pi * np.logspace(-1, 2, 200)
    rng = np.random.default_rng(13)
    for _ in range(12):
        i, j = rng.integers(0, 40), rng.integers(0, 8)
        rm, tm = np.sqrt(r[i] * r[i + 1]), 0.5 * (tau[j] + tau[j + 1])
        Hi = system_response(fam.interpolate(r_g=rm, tau=tm).state_space(), w).H[:, :2]
        exact = plant(params, params.operating.replace(r_g=rm, tau=tm), model=m).system
        He = system_response(exact, w).H[:, :2]
        err = np.linalg.norm(Hi - He, axis=-1) / np.linalg.norm(He, axis=-1)
        assert err.max() <= 0.02, (rm, tm, err.max())
    with pytest.raises(ParameterError, match="r_g = 3: allowed range"):
        fam.interpolate(r_g=3.0, tau=0.9)


def test_family_export_layouts(params, tmp_path):
    fam = plant_family(params, r_g=np.array([0.6, 1.0, 1.5]), nu=np.array([0.005, 0.01]))
    save_family(fam, tmp_path / "f.npz")
    back = load_family(tmp_path / "f.npz")
    assert np.array_equal(back.A, fam.A) and back.axes.keys() == fam.axes.keys()
    save_family(fam, tmp_path / "f.mat")
    mat = loadmat(tmp_path / "f.mat")
    n = fam.A.shape[-1]
    # MATLAB layout: n x n x N1 x N2, pages in grid order; ndgrid arrays of the axes
    assert mat["A"].shape == (n, n, 3, 2)
    assert np.array_equal(mat["A"][:, :, 2, 1], fam.A[2, 1])
    assert np.array_equal(mat["grid_r_g"], np.meshgrid(*fam.axes.values(), indexing="ij")[0])
    save_family(fam, tmp_path / "f.json")
    doc = json.loads((tmp_path / "f.json").read_text())
    assert doc["schema"]["name"] == "empact.plants" and doc["disturbance_inputs"] == ["T_l"]


def _family_of(A, B, C):
    """A one-point family around given matrices (outputs r_g, nu, nu_r)."""
    A, B, C = (np.asarray(M, float)[None] for M in (A, B, C))
    n = A.shape[-1]
    return PlantFamily(axes={"r_g": np.array([1.0])}, fixed={}, A=A, B=B, C=C,
                       D=np.zeros((1, C.shape[1], B.shape[2])),
                       states=tuple(f"x{i}" for i in range(n)), inputs=("T_mp", "T_ms", "T_l"),
                       outputs=("r_g", "nu", "nu_r"),
                       operating={k: np.array([v]) for k, v in (("r_g", 1.0), ("nu", 0.01),
                                                                 ("F_s", 1e4), ("omega_p", 300.0),
                                                                 ("T_l", 0.0))},
                       ok=np.array([True]), reason=np.array([""], dtype=object))


def test_pi_on_a_known_plant_gives_the_closed_form_poles():
    """Diagonal plant g_i / (s + a_i) with the PI-with-roll-off: the closed-loop poles are the
    roots of s (s + a)(1 + s/w_f)^2 + g k_p (s + w_i) for each loop (1e-9)."""
    a, g = np.array([2.0, 0.5]), np.array([3.0, 1.5])
    fam = _family_of(np.diag(-a), np.column_stack([np.diag(g), [0.0, 0.0]]),
                     np.vstack([np.eye(2), [0.0, 1.0]]))
    kp, wi, wf = np.array([1.2, 0.8]), np.array([0.7, 0.3]), np.array([20.0, 15.0])
    ctrl = pi_controller(kp, wi, wf)
    Acl = closed_loop_matrix(fam.A[0], fam.B[0][:, :2], fam.C[0][:2], ctrl.A, ctrl.B, ctrl.C,
                             ctrl.D)
    got = np.sort_complex(np.linalg.eigvals(Acl))
    ref = []
    for j in range(2):
        s = np.polynomial.polynomial
        lhs = s.polymul(s.polymul([0, 1], [a[j], 1]), s.polypow([1, 1 / wf[j]], 2))
        ref += list(np.roots(s.polyadd(lhs, g[j] * kp[j] * np.array([wi[j], 1]))[::-1]))
    np.testing.assert_allclose(got, np.sort_complex(np.array(ref)), rtol=1e-9)
    rm = robustness_map(fam, ctrl)
    assert rm.max_real_pole[0] == pytest.approx(max(np.real(ref)), rel=1e-9)


def test_disk_margin_agrees_with_python_control():
    """Multiloop disk margin of a coupled 2x2 loop against control.disk_margins (slycot
    ab13md), 1e-6 relative."""
    G = control.ss([[-1.0, 2.0], [-3.0, -4.0]], [[1.0, 0.5], [0.2, 1.0]], [[1.0, 0.3],
                                                                           [0.4, 1.0]], 0)
    K = control.ss([], [], [], [[2.0, 0.1], [0.3, 1.5]])
    w = np.logspace(-2, 3, 2000)
    L = frequency_responses(G.A, G.B, G.C, G.D, w) @ np.asarray(K.D)
    ours = disk_margin(L)
    ref = control.disk_margins(K * G, w)[0]
    assert ours == pytest.approx(ref, rel=1e-6)


def test_hinf_refuses_ill_posed_problems(params, design_family):
    """No W2 (D12 = 0): refused before the solver (python-control issue #973 would hang);
    a plant with an integrator (a pole on the imaginary axis): refused with the A1 line;
    on the design family a well-posed nominal exists."""
    G = control.ss(-np.eye(2), np.eye(2), np.eye(2), 0)
    P, *_ = mixed_sensitivity_plant(G, (1.0, 1.0))
    P0 = control.ss(P.A, P.B, P.C, np.where(np.abs(P.D) > 100, 0.0, P.D))  # drop W2's D
    with pytest.raises(ParameterError, match="A2"):
        check_wellposed(P0, 2, 2)
    Gi = control.ss(np.diag([0.0, -1.0]), np.eye(2), np.eye(2), 0)  # an integrator
    Pi, *_ = mixed_sensitivity_plant(Gi, (1.0, 1.0))
    with pytest.raises(ParameterError, match="imaginary axis|A1"):
        check_wellposed(Pi, 2, 2)
    # on the design family a well-posed nominal (r_g = 1, tau = 0.9, F_s = 16 kN) exists
    assert design_hinf(design_family, (0.1, 0.05), nominal=(3, 1, 1)).design["gamma"] < 1


def test_controller_file_roundtrip(tmp_path):
    c = pi_controller([1.0, 2.0], [0.5, 0.2], [10.0, 5.0], design={"note": "x"})
    c.save(tmp_path / "c.json")
    back = load_controller(tmp_path / "c.json")
    assert np.array_equal(back.A, c.A) and back.measured == ("r_g", "nu")
    c.save(tmp_path / "c.mat")
    assert loadmat(tmp_path / "c.mat")["A"].shape == c.A.shape
    (tmp_path / "bad.json").write_text('{"schema": {"name": "other"}}')
    with pytest.raises(ParameterError, match="not a controller file"):
        load_controller(tmp_path / "bad.json")
    d = c.discretize(1e-3)
    assert d.dt == 1e-3 and np.abs(np.linalg.eigvals(d.A)).max() <= 1.0


def test_closed_loop_metrics_are_the_runs_numbers(params):
    """The metrics are computed from the run's own time histories (recomputed here)."""
    run = run_closed_loop(load_scenario(control_example_path("slip-load-step-r1")), params)
    res, m = run.result, run.metrics
    after = res.t >= 0.5 + 0.3
    nu_ref = run.references["nu"]
    # a fraction [-], the largest |nu - nu*| from 0.3 s after the step, exactly
    # (tol 1e-12 rel for the mean: the same array reduced again)
    assert m["slip_error"] == np.abs(res.output("nu") - nu_ref)[after].max()
    assert m["mean_clamping_force"] == pytest.approx(res.output("F_s").mean(), rel=1e-12)
    assert m["complete"] == res.complete
    # the load step (50 % of the capacity T_l / tau at the start) reaches the load motor
    # (tol 1e-6 rel: the load motor's lag has settled by the end; reference: the step's size)
    assert res.output("T_l_act")[-1] == pytest.approx(run.op.T_l * (1 + 0.5 / run.op.tau),
                                                      rel=1e-6)
    r = res.output("r_g")
    assert m["ratio_error"] == pytest.approx(np.max(np.abs(r - 1.0)[after]), rel=1e-12)
    assert m["peak_T_ms"] == pytest.approx(np.abs(res.output("T_ms_act")).max(), rel=1e-12)


def test_family_point_is_the_default_plant(params):
    """With no options on either side a family point equals `plant` at that point (both the
    test bench by default), to 1e-10."""
    fam = plant_family(params, r_g=np.array([0.7, 1.4]))
    for i, r in enumerate((0.7, 1.4)):
        ref = plant(params, params.operating.replace(r_g=r))
        got = fam.plant(i)
        assert got.states == ref.states and got.inputs == ref.inputs
        for M in "ABCD":
            a, b = getattr(got, M), getattr(ref, M)
            assert np.abs(a - b).max() <= 1e-10 * max(np.abs(b).max(), 1e-300), M


def test_run_stopped_before_its_shift_window_is_reported_not_a_crash(params):
    """Issue 20 item 7: a closed-loop shift run that ends before its shift window has no ratio
    rate (NaN, stated), and every other metric is a finite number of the run."""
    from dataclasses import replace

    sc = load_scenario(control_example_path("shift-low-od"))
    assert sc.shift_window is not None and sc.shift_window[0] > 0.2
    run = run_closed_loop(replace(sc, duration=0.2), params)
    m = run.metrics
    assert np.isnan(m["ratio_rate"]) and all(np.isnan(m["ratio_span"]))
    assert np.isfinite(m["slip_error"]) and np.isfinite(m["ratio_error"])
