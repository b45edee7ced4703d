"""Experiments on the nonlinear model, as the paper's authors ran them on their model and rig.

Modules
-------
plant_id
    Fig. 2: servo-torque steps of the nonlinear model realised as a (T_mp, T_ms) -> (r_g, nu)
    state-space model, compared with the exact linearisation.
rig
    Fig. 14: a virtual test rig (spindle friction, sensor noise, multisine/chirp/noise
    excitation) whose records are estimated like measurements.
"""
from .plant_id import PlantIdentification, StepExperiment, identify_plant, step_experiment
from .rig import EXCITATIONS, RigRecord, RigSettings, excitation_signal, rig_frf, run_rig

__all__ = ["StepExperiment", "PlantIdentification", "step_experiment", "identify_plant",
           "EXCITATIONS", "RigSettings", "RigRecord", "excitation_signal", "run_rig", "rig_frf"]
