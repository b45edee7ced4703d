"""The linear lumped-parameter models of the paper's Sec. 2.1 and 2.2.

Modules
-------
lumped
    The engine: M, K, C from kinematic rows; undamped modes with modal energy; frequency
    responses from the second-order form; named state space.
actuation
    The actuation model of Fig. 3 (servos, worm, epicyclic sets, screws, sheaves, belt).
driveline
    The test-bench driveline of Fig. 7.
calibration
    Fitting parameters to target eigenfrequencies.
"""
from .actuation import actuation_model
from .calibration import CalibrationResult, Target, calibrate, load_targets, model_frequencies
from .driveline import driveline_model, uncoupled_frequencies
from .lumped import LumpedModel, Modes, element_matrix

__all__ = ["LumpedModel", "Modes", "element_matrix", "actuation_model", "driveline_model",
           "uncoupled_frequencies", "Target", "CalibrationResult", "calibrate", "load_targets",
           "model_frequencies"]
