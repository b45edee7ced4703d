"""Experiments on the nonlinear model (`empact.experiments`): Fig. 2 and the virtual rig.

The truth here is the exact linearisation of the same nonlinear model at the same point.
"""
import numpy as np
import pytest

from empact.experiments.plant_id import identify_plant
from empact.experiments.rig import RigSettings, excitation_signal, rig_frf, run_rig
from empact.lti import channel_zeros, system_response
from empact.nonlinear.linearization import linearize


@pytest.fixture(scope="module")
def plant_r1(params):
    return identify_plant(params, params.operating.replace(r_g=1.0))


def test_identified_plant_matches_exact_linearisation(plant_r1):
    R = plant_r1.realization
    assert np.nanmin(R.fit) >= 98.0  # the order rule's own target (worst channel, percent)
    w = 2 * np.pi * np.logspace(np.log10(0.2), 2, 200)
    Hi = system_response(R.sys, w).H
    He = system_response(plant_r1.exact, w).H
    err = np.median(np.abs(Hi - He) / np.abs(He), axis=-1)
    # 5 % median per channel between 0.2 and 100 Hz: the steps are 1e-5 N m (3e-5 N m already
    # gives up to 7 %: the slip responds nonlinearly near the traction peak), 6 s at 500 Hz
    assert err.max() <= 0.05, err


def test_identified_rhp_zero_matches_exact(plant_r1):
    """The real right-half-plane zero of T_mp -> nu_r (the slip at the operating ratio) is
    found in the identified model as in the exact one."""
    z_id = channel_zeros(plant_r1.realization.sys, "T_mp", "nu_r", max_abs=1e7)
    z_ex = channel_zeros(plant_r1.exact, "T_mp", "nu_r", max_abs=1e7)
    # real right-half-plane zeros; below 0.05 Hz they cancel the driveline's pole at the origin
    real_rhp = lambda z: z[(z.real > 2 * np.pi * 0.05)  # noqa: E731
                           & (np.abs(z.imag) < 1e-6 * np.abs(z))].real
    slow_ex = real_rhp(z_ex).min()
    slow_id = real_rhp(z_id).min()
    # the slowest real right-half-plane zero (about 1.7 Hz) recovered within 5 %
    assert abs(slow_id / slow_ex - 1) < 0.05


@pytest.mark.parametrize("kind", ["multisine", "chirp", "noise"])
def test_excitation_rms_and_band(kind):
    fs, n = 1000.0, 8192
    x = excitation_signal(kind, n, fs, (5.0, 50.0), 0.3, seed=3)
    assert np.sqrt(np.mean(x**2)) == pytest.approx(0.3, rel=1e-12)  # scaled exactly
    X = np.abs(np.fft.rfft(x)) ** 2
    f = np.fft.rfftfreq(n, 1 / fs)
    inside = X[(f >= 4) & (f <= 60)].sum() / X.sum()
    assert inside > 0.95  # >= 95 % of the power in (slightly widened) band
    assert np.array_equal(x, excitation_signal(kind, n, fs, (5.0, 50.0), 0.3, seed=3))


def test_rig_without_friction_matches_linear_model(params):
    s = RigSettings(excite="T_ms", coulomb=(0.0, 0.0), band_hz=(2.0, 100.0), duration=20.48,
                    noise={"theta_mp": 1e-5, "theta_ms": 1e-5, "nu": 1e-8})
    rec = run_rig(params, s)
    assert rec.complete
    est = rig_frf(rec, outputs=("theta_ms",))
    lin = linearize(rec.op, ["T_ms"], ["theta_ms"])
    f = est.frequencies_hz
    sel = (f >= 2) & (f <= 100) & (est.coherence[0, 0] >= 0.9)
    # the simulator interpolates the sampled excitation linearly (first-order hold), so the
    # true response from the samples is H(j w) times the hold's sinc^2(f / fs) (2.7 % at 90 Hz)
    H = system_response(lin, 2 * np.pi * f[sel]).H[0, 0] * np.sinc(f[sel] / s.sample_rate) ** 2
    err = np.abs(est.H[0, 0, sel] - H) / np.abs(H)
    assert sel.sum() > 100
    # known truth (the exact linearisation), coherence >= 0.9: median 2 %, 95th pct 5 %
    # (issue 5 item 6): periodic multisine, whole periods after the transient, no leakage
    assert np.median(err) <= 0.02 and np.percentile(err, 95) <= 0.05


def test_rig_is_seeded(params):
    s = RigSettings(excite="T_mp", duration=1.024, period=512, settle=0.0)
    a, b = run_rig(params, s), run_rig(params, s)
    for name in a.signals:
        assert np.array_equal(a.signals[name], b.signals[name])
