"""System identification from measured (or simulated) test-bench data.

Functions
---------
realize_steps
    Continuous state-space model from sampled step responses (Kung's shifted-Hankel
    realisation, order from the Hankel singular values, exact ZOH inverse).
estimate_frf
    Non-parametric H1 / H2 frequency-response estimate with ordinary and multiple coherence
    (Welch cross-spectra).

Classes
-------
RealizationResult
    Models, Hankel singular values, order, fit [%] and model step responses.
FRFEstimate
    Frequencies [Hz], FRF, coherence and averaging information.
"""
from .frf_estimation import METHODS, FRFEstimate, estimate_frf
from .realization import RealizationResult, realize_steps

__all__ = ["realize_steps", "RealizationResult", "estimate_frf", "FRFEstimate", "METHODS"]
