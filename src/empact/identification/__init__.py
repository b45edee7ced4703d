"""System identification from measured (or simulated) records: model-agnostic algorithms.

Modules
-------
realization
    `realize_steps`: continuous state-space model from sampled step responses (Kung's
    shifted-Hankel realisation, order from the Hankel singular values or a fit target, exact
    ZOH inverse).
frf_estimation
    `estimate_frf`: non-parametric H1 / H2 frequency-response estimate with ordinary and
    multiple coherence (Welch cross-spectra).
records
    `load_records`: named numeric columns from CSV files, with the sample rate.

The experiments that feed them from the nonlinear model (Fig. 2, the virtual rig of Fig. 14)
are in `empact.experiments`.
"""
from .frf_estimation import METHODS, FRFEstimate, estimate_frf
from .realization import RealizationResult, realize_steps
from .records import load_records, sample_rate

__all__ = ["realize_steps", "RealizationResult", "estimate_frf", "FRFEstimate", "METHODS",
           "load_records", "sample_rate"]
