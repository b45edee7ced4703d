"""A virtual test rig: the nonlinear model excited like the paper's prototype (Sec. 4, Fig. 14).

The rig trims the nonlinear model at an operating point, adds smooth Coulomb friction in the
spindles (the measured FRFs of the paper are "strongly influenced by the friction in the CVT,
mainly in the spindles"), excites one servo torque with a chosen signal around its holding
torque, and records the servo torques and the measured signals with seeded sensor noise.
The records have the same form as a user's measurements (`RigRecord.to_csv` writes what
``empact frf-estimate`` reads), so the same estimator serves both.

Excitations (`excitation_signal`): ``"multisine"`` (random-phase, flat amplitude spectrum on
the frequency lines of one period inside the band, repeated), ``"chirp"`` (logarithmic sweep
over the record) and ``"noise"`` (Gaussian noise, band-pass filtered with a zero-phase 4th-order
Butterworth filter).  Each is scaled to the requested RMS value.
"""
from __future__ import annotations

import csv
import io
from dataclasses import InitVar, dataclass, field
from typing import Any, Literal, Mapping

import numpy as np

from .._deprecate import warn_renamed
from .._lazy import lazy_module
from .._results import TableResult
from .._validate import check_choice, check_int, check_number
from ..errors import ParameterError
from ..identification.frf_estimation import FRFEstimate, estimate_frf
from ..identification.records import header_cell
from ..nonlinear.equilibrium import TrimResult, trim
from ..nonlinear.model import INPUT_UNITS, OUTPUT_UNITS, STATE_UNITS, nonlinear_model
from ..nonlinear.simulation import METHODS, simulate
from ..params import OperatingPoint

sig = lazy_module("scipy.signal")

__all__ = ["EXCITATIONS", "RigSettings", "RigRecord", "excitation_signal", "run_rig", "rig_frf"]

EXCITATIONS = ("multisine", "chirp", "noise")
MEASURED = ("theta_mp", "theta_ms", "nu")

#: units of the recorded signals (the servo torques and the measured signals)
RECORD_UNITS = {**{n: INPUT_UNITS[n] for n in ("T_mp", "T_ms")},
                **{n: {**STATE_UNITS, **OUTPUT_UNITS}[n] for n in MEASURED}}


def excitation_signal(kind: str, n: int, fs: float, band_hz: tuple[float, float], rms: float,
                      seed: int = 0, period: int = 2048) -> np.ndarray:
    """An excitation of `n` samples at `fs` [Hz] with content in `band_hz` [Hz], scaled to
    `rms`.

    Parameters
    ----------
    kind : {"multisine", "chirp", "noise"}
    n : number of samples
    fs : sample rate [Hz]
    band_hz : (f_lo, f_hi) [Hz], 0 < f_lo < f_hi < fs / 2
    rms : RMS value of the result (input units)
    seed : seed of the random phases / noise
    period : multisine period [samples]

    Returns
    -------
    ndarray, shape (n,)
        The excitation at sample times ``arange(n) / fs``, RMS `rms` (input units): a
        random-phase multisine on the period's frequency lines in the band (repeated every
        `period` samples), a logarithmic chirp from f_lo to f_hi, or band-pass filtered
        white noise.

    Raises
    ------
    ParameterError
        For an unknown `kind`, a band outside ``0 < f_lo < f_hi < fs / 2``, a non-positive
        `rms`, or a band holding no multisine line.
    """
    check_choice("excitation", kind, EXCITATIONS)
    f_lo, f_hi = band_hz
    if not 0 < f_lo < f_hi < fs / 2:
        raise ParameterError(f"band = ({f_lo:g}, {f_hi:g}) Hz: need 0 < f_lo < f_hi < fs/2 = "
                             f"{fs / 2:g} Hz")
    check_number("rms", rms, 0.0, lo_open=True)
    rng = np.random.default_rng(seed)
    t = np.arange(n) / fs
    if kind == "multisine":
        k = np.arange(1, period // 2)
        k = k[(k * fs / period >= f_lo) & (k * fs / period <= f_hi)]
        if k.size == 0:
            raise ParameterError(f"band = ({f_lo:g}, {f_hi:g}) Hz holds no frequency line of the "
                                 f"{period}-sample multisine period (lines every "
                                 f"{fs / period:g} Hz): widen the band or lengthen the record")
        spec = np.zeros(period // 2 + 1, complex)
        spec[k] = np.exp(2j * np.pi * rng.uniform(size=k.size))
        one = np.fft.irfft(spec, period)
        x = np.resize(one, n)
    elif kind == "chirp":
        x = sig.chirp(t, f0=f_lo, t1=t[-1], f1=f_hi, method="logarithmic", phi=-90)
    else:
        sos = sig.butter(4, [f_lo, f_hi], btype="bandpass", fs=fs, output="sos")
        x = sig.sosfiltfilt(sos, rng.standard_normal(n))
    return x * (rms / np.sqrt(np.mean(x**2)))


@dataclass(frozen=True)
class RigSettings:
    """Settings of a virtual rig experiment (SI; defaults: the paper's Fig. 14 point).

    Attributes
    ----------
    r_g, nu, F_s, omega_p : operating point: ratio [-], slip [-], clamping force [N], primary
        speed [rad/s] (Fig. 14: r_g = 0.5, nu0 = 0)
    excite : the servo torque excited, "T_mp" or "T_ms"
    excitation : "multisine", "chirp" or "noise"
    band_hz : excited band (lo, hi) [Hz] (``band``: deprecated name)
    rms : RMS of the excitation [N m]
    duration : record length [s]
    sample_rate : [Hz]
    period : multisine period [samples]; also the FRF segment length
    settle : initial part of the record left out of the FRF estimate [s] (transients)
    coulomb : Coulomb friction torque in the primary and secondary spindle [N m]
    noise : sensor noise standard deviation per measured signal (theta_mp, theta_ms [rad],
        nu [-]); the slip default 1e-7 is optimistic for a rig: the slip response at nu0 = 0 is
        about 1e-5 per N m, so a realistic resolution of 1e-5 hides it (as in the paper)
    seed : seed of the excitation and the noise
    method : the simulator's integrator (`empact.nonlinear.simulation.METHODS`); Rodas5P by
        default: the records' input kink every sample caps every method's steps at the sample
        period, where the order-5 method is both faster and far more accurate than the
        order-2 one (``bench/RESULTS.md``, the integrators)
    """

    r_g: float = 0.5
    nu: float = 0.0
    F_s: float = 10e3
    omega_p: float = 300.0
    excite: Literal["T_mp", "T_ms"] = "T_mp"
    excitation: str = "multisine"
    band_hz: tuple[float, float] = (0.5, 100.0)
    rms: float = 0.05
    duration: float = 16.384
    sample_rate: float = 1000.0
    period: int = 2048
    settle: float = 4.096
    coulomb: tuple[float, float] = (0.2, 0.2)
    noise: Mapping[str, float] = field(default_factory=lambda: {
        "theta_mp": 1e-4, "theta_ms": 1e-4, "nu": 1e-7})
    seed: int = 1
    band: InitVar[tuple[float, float] | None] = None
    method: str = "rodas5p"

    def __post_init__(self, band: tuple[float, float] | None = None) -> None:
        if band is not None:
            warn_renamed("RigSettings.band", "band_hz [Hz]", stacklevel=3)
            object.__setattr__(self, "band_hz", tuple(band))
        check_choice("method", self.method, METHODS)
        check_choice("excite", self.excite, ("T_mp", "T_ms"))
        check_choice("excitation", self.excitation, EXCITATIONS)
        check_number("duration", self.duration, 0.0, lo_open=True, unit="s")
        check_number("sample_rate", self.sample_rate, 0.0, lo_open=True, unit="Hz")
        check_number("settle", self.settle, 0.0, self.duration, hi_open=True, unit="s")
        check_int("period", self.period, 16, int(self.duration * self.sample_rate))
        for k, c in enumerate(self.coulomb):
            check_number(f"coulomb[{k}]", c, 0.0, unit="N m")
        for name, std in self.noise.items():
            check_choice("noise signal", name, MEASURED)
            check_number(f"noise[{name!r}]", std, 0.0)


@dataclass(frozen=True, eq=False)
class RigRecord(TableResult):
    """Records of one rig experiment.

    Attributes
    ----------
    t : sample times [s], shape (n_t,)
    signals : name -> samples, shape (n_t,): servo torques T_mp, T_ms [N m] and the measured
        theta_mp, theta_ms [rad], nu [-] (deviations from the operating point, with noise)
    settings : the `RigSettings`
    op : the trimmed operating point
    complete : False if the simulation stopped early (`message` says why)
    message : the simulator's message
    """

    t: np.ndarray
    signals: dict[str, np.ndarray]
    settings: RigSettings
    op: TrimResult
    complete: bool
    message: str

    def _columns(self) -> dict[str, np.ndarray]:
        """``t`` [s], then the signals (`to_csv`'s columns)."""
        return {"t": self.t, **self.signals}

    def to_csv(self) -> str:
        """CSV text: a ``#`` comment line (the experiment), a header of names with units in
        brackets (``theta_ms [rad]``, as `empact simulate` writes them), one row per
        sample; `empact.identification.load_records` reads it."""
        s = self.settings
        buf = io.StringIO()
        buf.write(f"# empact rig: {s.excitation} on {s.excite} at r_g = {s.r_g:g}, nu = "
                  f"{s.nu:g}, F_s = {s.F_s:g} N, omega_p = {s.omega_p:g} rad/s; signals are "
                  "deviations from the operating point\n")
        w = csv.writer(buf, lineterminator="\n")
        columns = self._columns()
        w.writerow([header_cell("time", "s")] + [header_cell(n, RECORD_UNITS[n])
                                                  for n in list(columns)[1:]])
        data = np.column_stack(list(columns.values()))
        w.writerows([f"{v:.9g}" for v in row] for row in data)
        return buf.getvalue()


def run_rig(params, settings: RigSettings | None = None, *, progress: bool = False,
            traction: Any = None) -> RigRecord:
    """Run one virtual rig experiment (nonlinear model, Coulomb friction, sensor noise).

    Parameters
    ----------
    params : Params
    settings : RigSettings, optional
        Ratio, slip, clamping force, speed, the excited servo, the excitation and its band
        [Hz] and rms [N m], duration [s], sample rate [Hz], friction, noise, seed, integrator
        (default `RigSettings()`).
    progress : bool
        A progress bar on stderr.
    traction : TabulatedTraction, optional
        Measured traction curves for the machine (`empact.variator.traction.load_traction`);
        default the analytic curve of ``params.traction``.

    Returns
    -------
    RigRecord
        ``t`` [s], shape (n_t,), and ``signals`` by name (``T_mp, T_ms`` [N m], ``theta_mp,
        theta_ms`` [rad], ``nu`` [-]; deviations from the operating point), the settings, the
        trimmed point; ``to_csv()`` writes it as a measurement.
    """
    s = settings or RigSettings()
    model = nonlinear_model(params, coulomb_sp=float(s.coulomb[0]),
                            coulomb_ss=float(s.coulomb[1]), traction=traction)
    op = trim(model, OperatingPoint(r_g=s.r_g, nu=s.nu, F_s=s.F_s, omega_p=s.omega_p))
    n = int(round(s.duration * s.sample_rate))
    t = np.arange(n) / s.sample_rate
    x = excitation_signal(s.excitation, n, s.sample_rate, s.band_hz, s.rms, seed=s.seed,
                          period=s.period)
    j = model.inputs.index(s.excite)
    res = simulate(model, op.x, {s.excite: np.column_stack([t, op.u[j] + x])}, t[-1],
                   u0=op.u, sample_rate=s.sample_rate, method=s.method, progress=progress,
                   name=f"rig {s.excite}")
    k = len(res.t)
    rng = np.random.default_rng(s.seed + 1000)
    signals = {name: res.output(name) - op.u[model.inputs.index(name)]
               for name in ("T_mp", "T_ms")}
    for name in MEASURED:
        ref = getattr(op, "nu") if name == "nu" else op.x[model.states.index(name)]
        signals[name] = res.output(name) - ref + s.noise.get(name, 0.0) * rng.standard_normal(k)
    return RigRecord(t=res.t, signals=signals, settings=s, op=op, complete=res.complete,
                     message=res.message)


def rig_frf(record: RigRecord, outputs=MEASURED, method: str = "H1") -> FRFEstimate:
    """FRF estimate (with coherence) from the excited servo torque to the measured signals.

    The first ``settings.settle`` seconds are left out.  A periodic multisine is analysed with
    a rectangular window over whole periods (no leakage at its lines); the other excitations
    with Hann-windowed, half-overlapping segments of ``settings.period`` samples.

    Parameters
    ----------
    record : RigRecord
    outputs : sequence of str
        The measured signals [their units].
    method : {"H1", "H2"}
        The estimator.

    Returns
    -------
    FRFEstimate
        ``H`` (n_out, 1, n_f), ``coherence`` (n_out, 1, n_f) [-] at ``omega`` [rad/s].
    """
    s = record.settings
    k0 = int(round(s.settle * s.sample_rate))
    y = np.column_stack([record.signals[o][k0:] for o in outputs])
    u = record.signals[s.excite][k0:]
    periodic = s.excitation == "multisine"
    return estimate_frf(u, y, s.sample_rate, method=method, nperseg=s.period,
                        window="boxcar" if periodic else "hann",
                        noverlap=0 if periodic else s.period // 2,
                        inputs=[s.excite], outputs=list(outputs))
