"""The H-infinity design on the loop that runs (`empact.control.hinf`, issue 33 item 6): the
structured controller, its objective and gradient against independent computations, the
design's search on a small family, and the shipped ``hinf.json`` on the design family."""
import json

import numpy as np
import pytest
from click.testing import CliRunner

from empact.cli import main
from empact.control import hinf as H
from empact.control.controller import Controller, Schedule
from empact.control.family import LOOP_FAMILY_OUTPUTS, design_family, plant_family
from empact.control.law import SHIPPED_LOOP, LoopConfig
from empact.control.loop import default_omega, family_loops
from empact.control.robustness import _mu_2x2, frequency_responses
from empact.errors import ParameterError
from empact.reproduction.control import SHIPPED_DESIGNS, shipped_controller

MEASURED, OUTPUTS = ("r_g", "nu"), ("T_mp", "T_ms")
BW = (0.1, 0.2)
#: a point of the structure away from its start (off-diagonal gains, lead-lag, damping)
THETA = np.concatenate([[1.0, 0.1, -0.2, 1.0],
                        [np.log(0.25 * 2 * np.pi * BW[0]), 0.05, 0.3,
                         np.log(0.25 * 2 * np.pi * BW[1])],
                        np.log(5 * 2 * np.pi * np.array(BW)), [0.1, -0.2],
                        np.log(2 * np.pi * np.array(BW)), np.log(2 * np.pi * np.array(BW)) + 0.3])


@pytest.fixture(scope="module")
def small(params):
    """Four plants of the design family's range (r_g 0.7, 1.3 x F_s 5, 16 kN at tau 0.9), the
    shipped loop, the loop model of an unscheduled structured controller, and the scheduled
    problem the design searches on (the schedule of the loop's own gains at `BW`)."""
    fam = plant_family(params, r_g=np.array([0.7, 1.3]), tau=0.9, F_s=np.array([5e3, 16e3]),
                       outputs=LOOP_FAMILY_OUTPUTS)
    loop = LoopConfig.of(params, **SHIPPED_LOOP)
    start = Controller(*H.structure_state_space(THETA), MEASURED, OUTPUTS, 0.0, "hinf")
    lm0 = family_loops(fam, start, loop, params)
    gains, _ = H._loop_gains(lm0, BW, (0, 0), True)
    sched = Controller(start.A, start.B, start.C, start.D, MEASURED, OUTPUTS,
                       schedule=Schedule(axes=dict(fam.axes), gains=gains))
    applied = H.applied_gains(sched, fam, loop, params)
    problem = H._LoopProblem(lm0, applied, H.design_grid(lm0.dt, 1), BW, (3.0, 15.0), 0.5)
    return fam, loop, sched, problem


def test_structure_state_space_is_its_response():
    """The 8-state realisation's frequency response equals the structure's closed form
    (``diag(R_j Lambda_j) (K_p + K_i / s)``) to 1e-12 relative, 0.001-100 Hz."""
    w = 2 * np.pi * np.logspace(-3, 2, 200)
    A, B, C, D = H.structure_state_space(THETA)
    ss = frequency_responses(A, B, C, D, w)
    closed = H.structure_response(THETA, 1j * w)
    assert np.abs(ss - closed).max() <= 1e-12 * np.abs(closed).max()


def test_mu_in_closed_form_equals_the_golden_section():
    """``mu`` of two complex scalar blocks in closed form (`_mu`) against the golden section
    on the D-scaling of `empact.control.robustness` (200 seeded random 2 x 2 matrices, 1e-9
    relative), and between the largest diagonal magnitude and the largest singular value."""
    rng = np.random.default_rng(4)
    M = rng.standard_normal((200, 2, 2)) + 1j * rng.standard_normal((200, 2, 2))
    mu = H._mu(M)
    np.testing.assert_allclose(mu, _mu_2x2(M), rtol=1e-9)
    assert np.all(mu >= np.abs(np.diagonal(M, axis1=1, axis2=2)).max(-1) * (1 - 1e-12))
    assert np.all(mu <= np.linalg.norm(M, 2, axis=(1, 2)) * (1 + 1e-12))


def test_the_search_sees_the_loop_control_check_sees(params, small):
    """The design's problem (the unscheduled loop model, its errors times the gains the law
    applies; ``K`` at Tustin's warped frequency) against `family_loops` of the scheduled
    controller, rebuilt: the augmented plant's response to 1e-5 relative (the pre-processing
    is linearised by central differences, whose rounding floor differs between the two
    builds; the spectral radius, near 1, moves by 2e-10 with it: 1e-8), the controller's
    response to 1e-10 and the disk margins (closed-form ``mu`` against the golden section)
    to 1e-6."""
    fam, loop, sched, pb = small
    lm = family_loops(fam, sched, loop, params)
    G = lm.plant_response(pb.omega)
    assert np.abs(pb.G - G.reshape(pb.G.shape)).max() <= 1e-5 * np.abs(G).max()
    K = lm.controller_response(pb.omega)
    assert np.abs(H.structure_response(THETA, pb.s) - K).max() <= 1e-10 * np.abs(K).max()
    np.testing.assert_allclose(pb.spectral_radius(THETA), lm.spectral_radius(), rtol=1e-8)
    pk = pb.peaks(THETA)
    alpha = 1 / np.maximum(pk["mu_output"], pk["mu_input"]).max(axis=1)
    np.testing.assert_allclose(alpha, lm.disk_margins(pb.omega)["alpha"].ravel(), rtol=1e-6)


def test_gradient_equals_central_differences(small):
    """The objective's (sub)gradient (``d sbar = Re(u^H dM v)`` at the peak, ``mu``'s in
    closed form) against central differences (step 1e-6, agreement 1e-6 relative to the
    largest component) in every free parameter, with the disk-margin penalty active and
    not; zero in the fixed ones (`FIXED`)."""
    *_, pb = small
    free = [k not in H.FIXED for k in H.STRUCTURE]
    for alpha in (0.5, 1.0):  # 0.34 is this point's margin: 1.0 makes the penalty act
        pb.alpha = alpha
        f, g, _ = pb(THETA)
        fd = np.empty_like(g)
        for i in range(len(THETA)):
            e = np.zeros_like(THETA)
            e[i] = 1e-6
            fd[i] = (pb(THETA + e)[0] - pb(THETA - e)[0]) / 2e-6
        assert np.abs(g - fd)[free].max() <= 1e-6 * np.abs(fd).max(), (alpha, g, fd)
        assert not np.any(g[np.logical_not(free)])
    pb.alpha = 0.5 + H.ALPHA_RESERVE


def test_outside_the_box_or_unstable_is_infinite(small):
    """A parameter outside its box, or a controller that destabilises a plant (100 times the
    gains): an infinite objective, no gradient."""
    *_, pb = small
    out = THETA.copy()
    out[8] = 20.0  # a roll-off corner far above the Nyquist frequency
    assert pb(out)[0] == np.inf
    loud = THETA.copy()
    loud[:4] *= 100.0
    loud[4], loud[7] = loud[4] + np.log(100), loud[7] + np.log(100)
    assert np.any(pb.spectral_radius(loud) >= 1)
    assert pb(loud)[0] == np.inf and pb(loud)[1] is None


def test_design_on_a_small_family_improves_and_is_deterministic(params, small):
    """On four plants, 12 iterations: every plant stable with the disk margin required, the
    norm below the start's, the record's figures equal to a rebuilt loop's (`family_loops`,
    `loop_mixed_sensitivity`: 1e-9), and the same design twice, bit for bit."""
    fam, loop, *_ = small
    k = H.design_hinf(fam, BW, loop=loop, params=params, alpha_min=0.4, max_iterations=12)
    d = k.design
    assert d["worst"]["all_stable"] and d["worst"]["disk_margin"] >= 0.4
    assert d["gamma"] < d["gamma_start"]
    assert k.n == 8 and k.schedule is not None
    # 12 iterations on the design's grid, a quarter of them in each round with peaks added
    assert 1 <= len(d["rounds"]) <= H.REFINE_ROUNDS
    assert d["iterations"] == sum(r["iterations"] for r in d["rounds"])
    assert d["iterations"] <= 12 + (H.REFINE_ROUNDS - 1) * 3
    lm = family_loops(fam, k, loop, params)
    assert np.all(lm.spectral_radius() < 1)
    assert lm.disk_margins()["alpha"].min() == pytest.approx(d["worst"]["disk_margin"],
                                                             rel=1e-9)
    norm = H.loop_mixed_sensitivity(lm, H.applied_gains(k, fam, loop, params), BW,
                                    (params.servo.T_mp_max, params.servo.T_ms_max))
    assert norm["gamma"] == pytest.approx(d["gamma"], rel=1e-9)
    again = H.design_hinf(fam, BW, loop=loop, params=params, alpha_min=0.4, max_iterations=12)
    assert again.design["parameters"] == d["parameters"]
    np.testing.assert_array_equal(again.A, k.A)
    np.testing.assert_array_equal(again.schedule.gains, k.schedule.gains)
    A, B, C, D = H.structure_state_space(np.array(list(d["parameters"].values())))
    np.testing.assert_array_equal(k.A, A)
    np.testing.assert_array_equal(k.B, B)


@pytest.mark.parametrize("kwargs, message", [
    ({"alpha_min": 0.01}, "alpha_min = 0.01"),
    ({"bandwidth_hz": (0.1, 0.2, 0.3)}, "two values RATIO,SLIP"),
    ({"max_iterations": 0}, "max_iterations = 0"),
    ({"slip": "r_g"}, "slip = 'r_g'"),
    ({"params": None}, "needs params"),
])
def test_bad_options_are_one_line(params, small, kwargs, message):
    fam, loop, *_ = small
    opts = {"loop": loop, "params": params, **kwargs}
    with pytest.raises(ParameterError, match=message):
        H.design_hinf(fam, opts.pop("bandwidth_hz", BW), **opts)


def test_a_schedule_without_the_loop_is_refused(small):
    fam, *_ = small
    with pytest.raises(ParameterError, match="schedule = True needs the loop"):
        H.design_hinf(fam, BW, schedule=True)


@pytest.fixture(scope="module")
def shipped_check(params):
    """``empact control check hinf.json --strict --min-disk-margin 0.5 --json`` on the design
    family and the shipped loop (the command's defaults), and the design family."""
    from importlib import resources

    path = str(resources.files("empact.data").joinpath("control", "hinf.json"))
    res = CliRunner().invoke(main, ["control", "check", path, "--strict",
                                    "--min-disk-margin", "0.5", "--json", "--quiet"])
    return res, design_family(params)


def test_shipped_hinf_is_stable_with_margin_on_the_loop_that_runs(shipped_check):
    """Issue 33 item 6: the shipped H-infinity controller on every plant of the design family
    (105) on the loop that runs: stable, multiloop disk margin >= 0.5, ``control check
    --strict`` passes; its design record's ``worst`` is that loop's (to 1e-9)."""
    res, fam = shipped_check
    assert res.exit_code == 0, res.output
    out = json.loads(res.output)
    w = out["worst"]
    assert out["passed"] and w["all_stable"] and w["stable"] == w["points"] == 105
    assert w["disk_margin"] >= 0.5
    rec = shipped_controller("hinf").design["worst"]
    assert rec["disk_margin"] == pytest.approx(w["disk_margin"], rel=1e-9)
    assert rec["spectral_radius"] == pytest.approx(w["spectral_radius"], rel=1e-12)
    assert rec["all_stable"] is True


def test_regression_shipped_hinf_is_the_documented_design(params, shipped_check):
    """Regression guard (data/control/hinf.json): its matrices are the structure at its
    recorded parameters (1e-12), its schedule the loop's own gains at its recorded bandwidths
    on the design family (`_loop_gains`, 1e-6 relative: the loop's pre-processing is
    linearised by central differences), its recipe the shipped one (`SHIPPED_DESIGNS`), and
    its recorded norm the one its loop gives (`loop_mixed_sensitivity` on the design's grid,
    1e-6)."""
    _, fam = shipped_check
    c = shipped_controller("hinf")
    d = c.design
    theta = np.array([d["parameters"][k] for k in H.STRUCTURE])
    for got, want in zip((c.A, c.B, c.C, c.D), H.structure_state_space(theta)):
        np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12 * np.abs(want).max())
    assert tuple(d["bandwidth_hz"]) == SHIPPED_DESIGNS["hinf"]["bandwidth_hz"]
    assert d["alpha_min"] == SHIPPED_DESIGNS["hinf"]["alpha_min"] and d["scheduled"]
    loop = LoopConfig.of(params, **SHIPPED_LOOP)
    lm = family_loops(fam, c, loop, params)
    unscheduled = family_loops(fam, Controller(c.A, c.B, c.C, c.D, MEASURED, OUTPUTS), loop,
                               params)
    nominal = tuple(s // 2 for s in fam.shape)
    gains, _ = H._loop_gains(unscheduled, d["bandwidth_hz"], nominal, True)
    np.testing.assert_allclose(c.schedule.gains, gains, rtol=1e-6)
    norm = H.loop_mixed_sensitivity(lm, H.applied_gains(c, fam, loop, params),
                                    d["bandwidth_hz"], d["weights"]["servo_limits_nm"])
    assert norm["gamma"] == pytest.approx(d["gamma"], rel=1e-6)
    assert len(default_omega(lm.dt)) * H.GRID_REFINE - H.GRID_REFINE + 1 == norm["frequencies"]


def test_shipped_hinf_between_the_grid_points(params):
    """The shipped H-infinity controller at the 48 cell centres of the design family (r_g and
    F_s geometric, tau arithmetic midpoints), where the schedule interpolates: every plant
    stable with a multiloop disk margin of at least 0.5 (0.547 measured) on the loop that
    runs."""
    from empact.control.family import DESIGN_GRID

    mid = {k: (np.sqrt(v[1:] * v[:-1]) if k != "tau" else 0.5 * (v[1:] + v[:-1]))
           for k, v in DESIGN_GRID.items()}
    fam = plant_family(params, **mid, outputs=LOOP_FAMILY_OUTPUTS)
    assert fam.ok.all() and fam.size == 48
    lm = family_loops(fam, shipped_controller("hinf"), LoopConfig.of(params, **SHIPPED_LOOP),
                      params)
    assert np.all(lm.spectral_radius() < 1)
    assert lm.disk_margins()["alpha"].min() >= 0.5


def test_the_grid_peak_is_slycots_norm(params):
    """The design's frequency grid against a discrete norm computation: the largest singular
    value of the sensitivities at the errors and at the servo torques, ``(I + G K)^-1`` and
    ``(I + K G)^-1``, of the shipped controller on the loop that runs, over the design's grid
    (`design_grid`), against ``control.linfnorm`` (slycot ab13dd, tol 1e-10) of the same
    closed loops built from the loop model's matrices, at the four plants where the shipped
    design's margin and norm bind (r_g 0.567 and 2.25 x tau 0.8 and 0.95 at 3 kN): never
    above it, at most 1e-4 below it (4e-5 measured)."""
    import control

    c = shipped_controller("hinf")
    fam = plant_family(params, r_g=np.array([0.566570727769269, 2.25]),
                       tau=np.array([0.8, 0.95]), F_s=3000.0, outputs=LOOP_FAMILY_OUTPUTS)
    lm = family_loops(fam, c, LoopConfig.of(params, **SHIPPED_LOOP), params)
    w = H.design_grid(lm.dt)
    G = lm.plant_response(w).reshape(-1, len(w), 2, 2)
    K = lm.controller_response(w)
    k = lm.controller
    Kss = control.ss(k.A, k.B, k.C, k.D, lm.dt)
    eye = control.ss([], [], [], np.eye(2), lm.dt)
    for i, idx in enumerate(np.ndindex(*fam.shape)):
        P = control.ss(lm.Aa[idx], lm.Bu[idx] * lm.mask, lm.Ce[idx], np.zeros((2, 2)), lm.dt)
        for loop_tf, grid in ((control.feedback(eye, P * Kss, sign=1),
                               np.linalg.inv(np.eye(2) + G[i] @ K)),
                              (control.feedback(eye, Kss * P, sign=1),
                               np.linalg.inv(np.eye(2) + K @ G[i]))):
            norm = control.linfnorm(loop_tf)[0]
            peak = np.linalg.norm(grid, 2, axis=(1, 2)).max()
            assert norm * (1 - 1e-4) <= peak <= norm * (1 + 1e-9), (idx, peak, norm)
