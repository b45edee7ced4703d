"""Non-parametric frequency-response (FRF) estimation from input/output records (Welch).

Spectral convention (that of `scipy.signal.csd`): ``S_ab(f) = E[conj(A(f)) B(f)]``. With
``Y = H U`` (``H`` of shape (n_out, n_in)):

* H1: ``S_uy = S_uu H^T``, so ``H^T = S_uu^-1 S_uy`` -- unbiased by output noise, biased low by
  input noise (factor ``S_uu / (S_uu + S_nn)``);
* H2: ``S_yy = S_yu H^T``, so ``H^T = S_yu^-1 S_yy`` (square systems only) -- unbiased by input
  noise, biased high by output noise.

For SISO, H1 ``= csd(u, y) / welch(u)`` and H2 ``= welch(y) / csd(y, u)``.
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .._lazy import lazy_module
from .._results import TableResult
from ..errors import ParameterError

sig = lazy_module("scipy.signal")

__all__ = ["FRFEstimate", "estimate_frf"]

METHODS = ("H1", "H2")

#: relative input power below which a frequency counts as not excited
UNEXCITED = 1e-10


@dataclass(frozen=True)
class FRFEstimate(TableResult):
    """Result of `estimate_frf`.

    Attributes
    ----------
    omega : numpy.ndarray
        Frequencies [rad/s], shape (n_f,), 0 .. pi fs (`frequencies_hz` in Hz).
    H : numpy.ndarray
        Complex FRF [output units / input units], shape (n_out, n_in, n_f).
    coherence : numpy.ndarray
        Ordinary coherence between input j and output i at ``[i, j]`` [-], shape
        (n_out, n_in, n_f).
    multiple_coherence : numpy.ndarray
        Multiple coherence of each output with all inputs together [-], shape (n_out, n_f);
        equals `coherence` for a single input.
    method : str
        ``"H1"`` or ``"H2"``.
    inputs, outputs : tuple of str
        Channel names.
    n_averages : int
        Number of Welch segments averaged.
    """

    omega: np.ndarray
    H: np.ndarray
    coherence: np.ndarray
    multiple_coherence: np.ndarray
    method: str
    inputs: tuple[str, ...]
    outputs: tuple[str, ...]
    n_averages: int

    def _columns(self) -> dict[str, np.ndarray]:
        """``omega`` [rad/s], then ``H[output/input]`` (complex) and
        ``coherence[output/input]`` per channel, ``multiple_coherence[output]`` per output."""
        pairs = [(a, o, b, i) for a, o in enumerate(self.outputs)
                 for b, i in enumerate(self.inputs)]
        return {"omega": self.omega,
                **{f"H[{o}/{i}]": self.H[a, b] for a, o, b, i in pairs},
                **{f"coherence[{o}/{i}]": self.coherence[a, b] for a, o, b, i in pairs},
                **{f"multiple_coherence[{o}]": self.multiple_coherence[a]
                   for a, o in enumerate(self.outputs)}}

    @property
    def frequencies_hz(self) -> np.ndarray:
        """Frequencies [Hz], shape (n_f,)."""
        return self.omega / (2 * np.pi)


def _as_2d(name: str, x) -> np.ndarray:
    x = np.asarray(x, dtype=float)
    if x.ndim == 1:
        x = x[:, None]
    if x.ndim != 2 or x.shape[0] < 2 or x.shape[1] < 1:
        raise ValueError(f"{name} must have shape (n_t,) or (n_t, n_channels) with n_t >= 2, "
                         f"got shape {x.shape}")
    if not np.all(np.isfinite(x)):
        raise ValueError(f"{name} must be finite, found NaN or inf")
    return x


def _names(name: str, names, count: int, prefix: str) -> tuple[str, ...]:
    if names is None:
        return tuple(f"{prefix}[{i}]" for i in range(count))
    if isinstance(names, str) or len(names) != count:
        raise ValueError(f"{name} must be a sequence of {count} names, got {names!r}")
    return tuple(str(s) for s in names)


def _ratio(num: np.ndarray, den: np.ndarray) -> np.ndarray:
    """``num / den`` with 0 where ``den == 0``."""
    out = np.zeros(np.broadcast_shapes(num.shape, den.shape))
    return np.divide(num, den, out=out, where=den > 0)


def estimate_frf(u, y, fs: float, method: str = "H1", nperseg: int | None = None,
                 window="hann", noverlap: int | None = None, detrend="constant",
                 inputs: Sequence[str] | None = None,
                 outputs: Sequence[str] | None = None) -> FRFEstimate:
    """Estimate the frequency response from input/output records with Welch averaging.

    Parameters
    ----------
    u : array_like
        Input records, shape (n_t,) or (n_t, n_in) [any units].
    y : array_like
        Output records, shape (n_t,) or (n_t, n_out) [any units].
    fs : float
        Sample rate [Hz], > 0.
    method : {"H1", "H2"}, optional
        Estimator (see the module docstring). H2 needs ``n_out == n_in``.
    nperseg : int, optional
        Segment length [samples], ``<= n_t``. Default ``min(n_t, 1024, max(64, n_t // 8))``
        (the length of `window` if that is an array).
    window : str, tuple or array_like, optional
        Window, as for `scipy.signal.get_window`.
    noverlap : int, optional
        Overlap [samples], ``0 <= noverlap < nperseg``; default ``nperseg // 2``.
    detrend : {"constant", "linear", False} or callable, optional
        Per-segment detrending, as for `scipy.signal.csd`.
    inputs, outputs : sequence of str, optional
        Channel names (default ``u[j]``, ``y[i]``).

    Returns
    -------
    FRFEstimate
        Frequencies [Hz], FRF, ordinary and multiple coherence, number of averages.

    Raises
    ------
    ValueError
        For malformed arguments, an unknown `method`, H2 on a non-square system, inputs
        without power at every frequency, or a singular output-input spectral matrix (H2).

    Notes
    -----
    Frequencies where the inputs carry no power (the smallest eigenvalue of the input
    spectral matrix below ``UNEXCITED`` times its largest value over all frequencies), such as
    the bins between the lines of a multisine, get NaN in `H` and in the coherences: the FRF is
    not defined there.
    """
    if method not in METHODS:
        raise ValueError(f"method must be one of {METHODS}, got {method!r}")
    u, y = _as_2d("u", u), _as_2d("y", y)
    if u.shape[0] != y.shape[0]:
        raise ValueError(f"u and y must have the same number of samples, got shapes {u.shape} "
                         f"and {y.shape}")
    if not (np.isfinite(fs) and fs > 0):
        raise ValueError(f"fs must be a positive finite sample rate [Hz], got {fs!r}")
    (n_t, m), p = u.shape, y.shape[1]
    if method == "H2" and p != m:
        raise ValueError(f"method='H2' needs n_out == n_in, got n_out={p}, n_in={m}; use 'H1'")
    if isinstance(detrend, str) and detrend not in ("constant", "linear"):
        raise ValueError(f"detrend must be 'constant', 'linear', False or a callable, got "
                         f"{detrend!r}")
    if nperseg is None:
        nperseg = (np.size(window) if isinstance(window, np.ndarray)
                   else min(n_t, 1024, max(64, n_t // 8)))
    if isinstance(nperseg, bool) or int(nperseg) != nperseg or not 1 <= nperseg <= n_t:
        raise ValueError(f"nperseg must be an integer in [1, n_t={n_t}], got {nperseg!r}")
    nperseg = int(nperseg)
    noverlap = nperseg // 2 if noverlap is None else noverlap
    if isinstance(noverlap, bool) or int(noverlap) != noverlap or not 0 <= noverlap < nperseg:
        raise ValueError(f"noverlap must be an integer in [0, nperseg={nperseg}), got "
                         f"{noverlap!r}")
    noverlap = int(noverlap)
    in_names = _names("inputs", inputs, m, "u")
    out_names = _names("outputs", outputs, p, "y")
    for kind, names, data, why in (("input", in_names, u, "excites nothing"),
                                   ("output", out_names, y, "carries no response")):
        for k, name in enumerate(names):
            if np.ptp(data[:, k]) == 0:
                raise ParameterError(f"{kind} {name!r} is constant ({data[0, k]:g} in every "
                                     f"sample): a dead channel {why}; check the record")

    z = np.concatenate([u, y], axis=1).T                           # (n_c, n_t)
    f, P = sig.csd(z[:, None, :], z[None, :, :], fs=fs, window=window, nperseg=nperseg,
                   noverlap=noverlap, detrend=detrend, axis=-1)    # P[a, b] = E[conj(Z_a) Z_b]
    auto = np.einsum("aaf->af", P).real                             # (n_c, n_f)
    Suu, Suy = P[:m, :m].transpose(2, 0, 1), P[:m, m:].transpose(2, 0, 1)
    # frequencies the inputs do not excite (between the lines of a multisine, outside a band):
    # the input spectral matrix is singular there and the FRF is undefined -> NaN
    lam = np.linalg.eigvalsh(Suu)                                   # (n_f, n_in), ascending
    excited = lam[:, 0] > UNEXCITED * lam[:, -1].max()
    if not excited.any():
        raise ValueError("the inputs carry no power at any frequency (all zero?)")
    H1t = np.full((len(f), m, p), np.nan, complex)
    H1t[excited] = np.linalg.solve(Suu[excited], Suy[excited])      # (n_f, n_in, n_out)
    Ht = H1t
    if method == "H2":
        Syu = P[m:, :m].transpose(2, 0, 1)
        ok = excited & (np.abs(np.linalg.det(Syu)) > 0)
        Ht = np.full_like(H1t, np.nan)
        try:
            Ht[ok] = np.linalg.solve(Syu[ok], P[m:, m:].transpose(2, 0, 1)[ok])
        except np.linalg.LinAlgError:
            raise ValueError("singular spectral matrix S_yu at some excited frequency") from None

    coherence = _ratio(np.abs(P[:m, m:]) ** 2, auto[:m, None] * auto[None, m:]).transpose(1, 0, 2)
    coherence[:, :, ~excited] = np.nan
    coherent = np.einsum("fji,fji->if", H1t.conj(), Suy).real     # S_yu S_uu^-1 S_uy
    multiple = _ratio(coherent, auto[m:])
    n_avg = 1 + (n_t - nperseg) // (nperseg - noverlap)
    return FRFEstimate(omega=2 * np.pi * f, H=Ht.transpose(2, 1, 0), coherence=coherence,
                       multiple_coherence=multiple, method=method, inputs=in_names,
                       outputs=out_names, n_averages=int(n_avg))
