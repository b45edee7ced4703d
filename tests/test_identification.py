"""Tests for empact.identification (step-response realisation and FRF estimation)."""
from __future__ import annotations

import control
import numpy as np
import pytest
import scipy.signal as sg
from scipy.optimize import linear_sum_assignment

from empact.identification import FRFEstimate, RealizationResult, estimate_frf, realize_steps

FS_STEP = 500.0      # step-response sample rate [Hz]
N_STEP = 1500        # step-response samples (3 s)
FS = 1000.0          # FRF record sample rate [Hz]


# ----------------------------------------------------------------------------------- fixtures
def _modal_system(seed: int = 1) -> control.StateSpace:
    """Order-6, 2-in/2-out modal system; modes near 1.5, 8 and 40 Hz, zeta 2-8 %."""
    rng = np.random.default_rng(seed)
    w = 2 * np.pi * np.array([1.5, 8.0, 40.0]) * (1 + 0.1 * rng.uniform(-1, 1, 3))
    zeta = rng.uniform(0.02, 0.08, 3)
    A = np.zeros((6, 6))
    for k in range(3):
        A[2 * k:2 * k + 2, 2 * k:2 * k + 2] = [[0, 1], [-w[k] ** 2, -2 * zeta[k] * w[k]]]
    B = np.zeros((6, 2))
    B[1::2] = rng.normal(size=(3, 2))
    return control.ss(A, B, rng.normal(size=(2, 6)), 0.1 * rng.normal(size=(2, 2)))


@pytest.fixture(scope="module")
def modal_case():
    sys = _modal_system()
    t = np.arange(N_STEP) / FS_STEP
    # exact ZOH-sampled step responses: a step is piecewise constant, so c2d(zoh) is exact
    steps = control.step_response(control.c2d(sys, 1 / FS_STEP), t).outputs.transpose(2, 0, 1)
    return sys, t, steps, realize_steps(t, steps, inputs=["T_d", "T_l"], outputs=["w_p", "w_s"])


def _resonance(f0: float, zeta: float, gain: float = 1.0):
    """ZOH-discretised 2nd-order low-pass resonance (b, a) at FS."""
    w0 = 2 * np.pi * f0
    b, a, _ = sg.cont2discrete(([gain * w0 ** 2], [1, 2 * zeta * w0, w0 ** 2]), 1 / FS, "zoh")
    return b.ravel(), a


def _true_frf(ba, f):
    return sg.freqz(*ba, worN=f, fs=FS)[1]


# ------------------------------------------------------------------------------ realisation
def test_realize_recovers_order_poles_and_frf(modal_case):
    sys, _, steps, res = modal_case
    assert isinstance(res, RealizationResult)
    # exact: true order of the modal construction; noise-free Hankel has rank 6
    assert res.order == 6
    assert res.singular_values[6] < 1e-9 * res.singular_values[0]
    pt, pi = sys.poles(), res.sys.poles()
    cost = np.abs(pt[:, None] - pi[None, :]) / np.abs(pt)[:, None]
    rows, cols = linear_sum_assignment(cost)
    # tol 1 % (brief) on the relative pole error; reference: poles of the exact modal matrix
    assert cost[rows, cols].max() < 0.01
    f = np.logspace(np.log10(0.5), np.log10(60.0), 300)
    Gt, Gi = sys(2j * np.pi * f), res.sys(2j * np.pi * f)
    rel = np.linalg.norm(Gi - Gt, axis=(0, 1)) / np.linalg.norm(Gt, axis=(0, 1))
    # tol 2 % (brief) on the Frobenius-relative FRF error over 0.5-60 Hz (all modes inside);
    # reference: analytic continuous FRF of the true system
    assert rel.max() < 0.02
    # tol 1e-9 abs: D is h_0 = steps[0] exactly (reference: the true D)
    np.testing.assert_allclose(res.sys.D, sys.D, atol=1e-9)
    # tol 99.9 %: noise-free data of exact order must be reproduced (reference: input steps)
    assert np.all(res.fit > 99.9)
    np.testing.assert_allclose(res.step_model, steps, atol=1e-8)  # tol 1e-8 abs, same reason
    assert res.sys.input_labels == ["T_d", "T_l"] and res.sys.output_labels == ["w_p", "w_s"]
    # tol 1e-12 rel: the realisation's sample time is the records' (reference: 1 / FS_STEP)
    assert res.sys.state_labels[0] == "x0" and res.sys_discrete.dt == pytest.approx(1 / FS_STEP,
                                                                                    rel=1e-12)


def test_realize_fixed_order_and_hankel_size(modal_case):
    sys, t, steps, _ = modal_case
    res = realize_steps(t, steps, 6, n_block_rows=40, n_block_cols=200)
    pt, pi = sys.poles(), res.sys.poles()
    cost = np.abs(pt[:, None] - pi[None, :]) / np.abs(pt)[:, None]
    # tol 1 % (brief); reference: exact modal poles
    assert cost[linear_sum_assignment(cost)].max() < 0.01


def test_realize_noisy_steps_order_and_poles(modal_case):
    sys, t, steps, _ = modal_case
    noise = 1e-5 * np.abs(steps).max() * np.random.default_rng(7).normal(size=steps.shape)
    res = realize_steps(t, steps + noise)
    # exact: the threshold + largest-gap rule must see through a 1e-5 noise floor
    assert res.order == 6
    pt, pi = sys.poles(), res.sys.poles()
    cost = np.abs(pt[:, None] - pi[None, :]) / np.abs(pt)[:, None]
    # tol 1 % (brief); reference: exact modal poles
    assert cost[linear_sum_assignment(cost)].max() < 0.01
    # tol 99 %: noise is 1e-5 of the peak step, the fit is limited by it (reference: steps)
    assert np.all(res.fit > 99.0)


def test_realize_negative_real_eigenvalue_refused():
    t = np.arange(50) * 0.01
    # x[k+1] = -0.5 x[k] + u, y = x: A_d = -0.5 has no real matrix logarithm
    steps = np.concatenate([[0.0], np.cumsum((-0.5) ** np.arange(49))])[:, None, None]
    with pytest.raises(ValueError, match="negative real axis"):
        realize_steps(t, steps, 1)


@pytest.mark.parametrize("t, steps, kwargs, match", [
    (np.zeros((10, 2)), np.zeros((10, 1, 1)), {}, r"^t must be 1-D"),
    (np.r_[0.0, 0.1, 0.25, np.arange(3, 10) * 0.1], np.zeros((10, 1, 1)), {},
     r"^t must be increasing and uniformly spaced"),
    (np.arange(10.0), np.zeros((10, 1)), {}, r"^steps must have shape"),
    (np.arange(10.0), np.zeros((9, 1, 1)), {}, r"^steps must have shape"),
    (np.r_[np.arange(9.0), np.inf], np.zeros((10, 1, 1)), {}, r"^t must be finite"),
    (np.arange(10.0), np.full((10, 1, 1), np.nan), {}, r"^steps must be finite"),
    (np.arange(10.0), np.ones((10, 1, 1)), {"order": 0}, r"^order must be a positive integer"),
    (np.arange(10.0), np.ones((10, 1, 1)), {"order": 2.5}, r"^order must be a positive integer"),
    (np.arange(10.0), np.ones((10, 1, 1)), {"order": 8}, r"^order=8 exceeds the maximum"),
    (np.arange(10.0), np.ones((10, 1, 1)), {"n_block_rows": 8, "n_block_cols": 5},
     r"^too few samples"),
    (np.arange(10.0), np.ones((10, 1, 1)), {"sv_threshold": 2.0}, r"^sv_threshold must be"),
    (np.arange(10.0), np.ones((10, 1, 1)), {"inputs": ["a", "b"]}, r"^inputs must be"),
])
def test_realize_validation(t, steps, kwargs, match):
    with pytest.raises(ValueError, match=match):
        realize_steps(t, steps, **kwargs)


# --------------------------------------------------------------------------- FRF estimation
def test_frf_conventions_siso():
    rng = np.random.default_rng(3)
    u = rng.normal(size=4096)
    y = sg.lfilter(*_resonance(50.0, 0.1), u) + 0.1 * rng.normal(size=4096)
    kw = dict(fs=FS, nperseg=256)
    h1, h2 = estimate_frf(u, y, **kw), estimate_frf(u, y, method="H2", **kw)
    f, Suy = sg.csd(u, y, **kw)
    Syu, Suu, Syy = sg.csd(y, u, **kw)[1], sg.welch(u, **kw)[1], sg.welch(y, **kw)[1]
    # tol 1e-10 rel: identical arithmetic; reference: scipy.signal csd / welch / coherence
    np.testing.assert_allclose(h1.H[0, 0], Suy / Suu, rtol=1e-10)
    np.testing.assert_allclose(h2.H[0, 0], Syy / Syu, rtol=1e-10)
    np.testing.assert_allclose(h1.coherence[0, 0], sg.coherence(u, y, **kw)[1], rtol=1e-10)
    np.testing.assert_allclose(h1.multiple_coherence[0], h1.coherence[0, 0], rtol=1e-10)
    assert isinstance(h1, FRFEstimate) and h1.H.shape == (1, 1, f.size)
    assert h1.n_averages == 1 + (4096 - 256) // 128 and h1.inputs == ("u[0]",)


def test_frf_h1_output_noise_matches_truth():
    rng = np.random.default_rng(2)
    n_t = 2 ** 17
    ba = _resonance(60.0, 0.05)
    u = rng.normal(size=n_t)
    y0 = sg.lfilter(*ba, u)
    y = y0 + 0.2 * y0.std() * rng.normal(size=n_t)
    est = estimate_frf(u, y, FS)
    mask = est.coherence[0, 0] >= 0.9
    rel = np.abs(est.H[0, 0] - _true_frf(ba, est.frequencies_hz)) / np.abs(
        _true_frf(ba, est.frequencies_hz))
    assert mask.sum() > 50
    # tol 2 % median / 5 % 95th percentile (brief); reference: freqz of the exact filter
    assert np.median(rel[mask]) <= 0.02
    assert np.percentile(rel[mask], 95) <= 0.05


def test_frf_input_noise_h1_biased_h2_unbiased():
    rng = np.random.default_rng(4)
    n_t, sigma_n = 2 ** 18, 0.5
    ba = _resonance(60.0, 0.05)
    u = rng.normal(size=n_t)                     # white, variance 1
    y = sg.lfilter(*ba, u)
    u_meas = u + sigma_n * rng.normal(size=n_t)  # white input-measurement noise
    expected = 1.0 / (1.0 + sigma_n ** 2)        # S_uu / (S_uu + S_nn), both white: 0.8
    h1 = estimate_frf(u_meas, y, FS, nperseg=512)
    h2 = estimate_frf(u_meas, y, FS, method="H2", nperseg=512)
    Ht = _true_frf(ba, h1.frequencies_hz)
    ratio1 = np.abs(h1.H[0, 0]) / np.abs(Ht)
    # tol +-0.02 abs on the median gain ratio (the per-bin random error of |H| is about
    # sqrt(1-g2)/(g sqrt(2 n_d)) = 1.6 % for g2 = 0.8, n_d = 511, Bendat & Piersol 9.73);
    # reference: bias factor computed from the noise variance
    assert np.median(ratio1) == pytest.approx(expected, abs=0.02)
    rel2 = np.abs(h2.H[0, 0] - Ht) / np.abs(Ht)
    # tol +-0.02 on the median H2 gain ratio and 3 % on its median complex error (same
    # random-error estimate; H2 is unbiased by input noise); reference: freqz of the filter
    assert np.median(np.abs(h2.H[0, 0]) / np.abs(Ht)) == pytest.approx(1.0, abs=0.02)
    assert np.median(rel2) <= 0.03


def test_frf_mimo_h1_recovers_both_columns():
    rng = np.random.default_rng(5)
    n_t = 2 ** 17
    bas = [[_resonance(20.0, 0.05), _resonance(90.0, 0.03, 0.5)],
           [_resonance(45.0, 0.04, 0.7), _resonance(150.0, 0.05)]]
    u = rng.normal(size=(n_t, 2))                # two uncorrelated simultaneous inputs
    y = np.stack([sum(sg.lfilter(*bas[i][j], u[:, j]) for j in range(2)) for i in range(2)], 1)
    y += 0.05 * y.std(axis=0) * rng.normal(size=y.shape)
    est = estimate_frf(u, y, FS, inputs=["a", "b"], outputs=["c", "d"])
    f = est.frequencies_hz
    Ht = np.array([[_true_frf(bas[i][j], f) for j in range(2)] for i in range(2)])
    assert est.H.shape == (2, 2, f.size) and est.outputs == ("c", "d")
    # error of each element relative to the magnitude of its output row |H_i.| (an element
    # far below its row neighbour is buried in that neighbour's random error)
    rel = np.abs(est.H - Ht) / np.linalg.norm(Ht, axis=1, keepdims=True)
    for i in range(2):
        mask = est.multiple_coherence[i] >= 0.9
        for j in range(2):
            # tol 2 % median / 5 % 95th percentile (brief); reference: freqz of each filter
            assert np.median(rel[i, j, mask]) <= 0.02
            assert np.percentile(rel[i, j, mask], 95) <= 0.05


@pytest.mark.parametrize("u, y, kwargs, match", [
    (np.ones(64), np.ones(64), {"method": "H3"}, r"^method must be one of"),
    (np.ones(64), np.ones(64), {"fs": 0.0}, r"^fs must be a positive"),
    (np.ones(64), np.ones(63), {}, r"^u and y must have the same number of samples"),
    (np.ones((64, 1, 1)), np.ones(64), {}, r"^u must have shape"),
    (np.r_[np.ones(63), np.nan], np.ones(64), {}, r"^u must be finite"),
    (np.ones(64), np.ones(64), {"nperseg": 65}, r"^nperseg must be an integer in"),
    (np.ones(64), np.ones(64), {"nperseg": 32, "noverlap": 32}, r"^noverlap must be"),
    (np.ones((64, 2)), np.ones(64), {"method": "H2"}, r"^method='H2' needs n_out == n_in"),
    (np.ones(64), np.ones(64), {"detrend": "quadratic"}, r"^detrend must be"),
    (np.ones(64), np.ones(64), {"outputs": ["a", "b"]}, r"^outputs must be"),
])
def test_frf_validation(u, y, kwargs, match):
    kwargs.setdefault("fs", FS)
    with pytest.raises(ValueError, match=match):
        estimate_frf(u, y, **kwargs)


def test_realize_system_with_integrator():
    """Servo torque -> position plants integrate; the ZOH inverse must stay defined there.

    Truth: 1 / (s (s + 2)) in parallel with a 10 Hz, 5 % resonance; poles 0, -2 and the pair.
    """
    w0, z = 2 * np.pi * 10.0, 0.05
    sys = control.parallel(control.tf([1.0], [1.0, 2.0, 0.0]),
                           control.tf([w0**2], [1.0, 2 * z * w0, w0**2]))
    sys = control.ss(sys)
    t = np.arange(1000) / FS_STEP
    steps = control.step_response(control.c2d(sys, 1 / FS_STEP), t).outputs.reshape(-1, 1, 1)
    res = realize_steps(t, steps)
    assert res.order == 4  # exact: noise-free data of an order-4 system
    true = np.sort_complex(sys.poles())
    got = np.sort_complex(res.sys.poles())
    # integrator pole: |p| below 1e-6 rad/s (logm of an eigenvalue 1 to rounding)
    assert np.abs(got[np.argmin(np.abs(got))]) < 1e-6
    nz = np.abs(true) > 1e-9
    cost = np.abs(true[nz][:, None] - got[None, :]) / np.abs(true[nz])[:, None]
    r, c = linear_sum_assignment(cost)
    assert cost[r, c].max() < 0.01  # non-zero poles within 1 % (issue 5, item 6)
    w = 2 * np.pi * np.logspace(-1, 1.5, 30)
    H_true = control.frequency_response(sys, w).complex.ravel()
    H_id = control.frequency_response(res.sys, w).complex.ravel()
    assert np.max(np.abs(H_id - H_true) / np.abs(H_true)) < 0.02  # FRF within 2 %


def test_frf_unexcited_bins_are_nan_not_errors():
    """A multisine excites only its lines: the FRF is undefined (NaN) between them."""
    fs, period = 1000.0, 256
    k = np.arange(5, 40)
    spec = np.zeros(period // 2 + 1, complex)
    spec[k] = np.exp(2j * np.pi * np.random.default_rng(4).uniform(size=k.size))
    u = np.tile(np.fft.irfft(spec, period), 24)
    b, a = _resonance(30.0, 0.05)
    y = sg.lfilter(b, a, u)
    skip = 8 * period  # 2 s: the 30 Hz, 5 % transient decays by exp(-19)
    est = estimate_frf(u[skip:], y[skip:], fs, nperseg=period, noverlap=0, window="boxcar")
    lines = np.isin(np.arange(len(est.frequencies_hz)), k)
    assert np.all(np.isfinite(est.H[0, 0, lines]))
    assert np.all(np.isnan(est.H[0, 0, ~lines])) and np.all(np.isnan(est.coherence[0, 0, ~lines]))
    # periodic excitation, whole periods, steady state: exact at the lines up to rounding
    true = _true_frf((b, a), est.frequencies_hz[lines])
    assert np.max(np.abs(est.H[0, 0, lines] - true) / np.abs(true)) < 1e-6
    # an all-zero input is a dead channel, refused by name before any spectrum (issue 35)
    with pytest.raises(ValueError, match=r"input 'u\[0\]' is constant \(0 in every sample\)"):
        estimate_frf(np.zeros(512), y[:512], fs)
    # an input that moves only in samples no segment reads (5 segments of 100 cover 0..499)
    # carries no power at any frequency: refused, not an FRF of NaN
    u_late = np.zeros(512)
    u_late[-1] = 1.0
    with pytest.raises(ValueError, match="no power"):
        estimate_frf(u_late, y[:512], fs, nperseg=100, noverlap=0)


def test_records_convert_header_units_to_si(tmp_path):
    """`load_records`: ``[rpm]`` -> rad/s (2 pi / 60), ``[ms]`` -> s, ``[N m]`` unchanged; an
    unknown unit of a column read is refused, one of a column not read is ignored."""
    from empact.errors import DataError
    from empact.identification import load_records

    p = tmp_path / "r.csv"
    p.write_text("t [ms],w [rpm],T [N m],z [furlong]\n" + "".join(
        f"{i},{60 * i},{2 * i},1\n" for i in range(20)))
    rec = load_records(p, ["t", "w", "T"], quantities={"t": "time"})
    k = np.arange(20.0)
    np.testing.assert_allclose(rec["t"], k * 1e-3, rtol=1e-15, atol=0)
    np.testing.assert_allclose(rec["w"], k * 2 * np.pi, rtol=1e-15, atol=0)
    np.testing.assert_array_equal(rec["T"], 2 * k)
    with pytest.raises(DataError, match=r"column 'z' has unit \[furlong\], which empact does "
                                        r"not convert"):
        load_records(p, ["z"])
    with pytest.raises(DataError, match=r"column 'w' has unit \[rpm\], a unit of angular "
                                        r"speed; the column is a time"):
        load_records(p, ["w"], quantities={"w": "time"})
