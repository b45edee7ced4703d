"""The nonlinear model of the whole Empact CVT, its operating points, linearisation and
simulation (the paper's ref. [4], used in its Secs. 2.3 and 3).

Modules
-------
model
    Options, the model object and its compiled right-hand side (`_kernel`).
equilibrium
    Steady operating points (`trim`).
linearization
    Exact (forward-mode) linearisation; the (T_mp, T_ms) -> (r_g, nu) plant.
nmp
    Non-minimum-phase analysis of Sec. 2.3: belt geometry and the zeros of T_mp -> nu.
scenario
    Simulation scenarios (TOML) and the shipped examples.
simulation
    The simulator (`simulate`, `run_scenario`) and its result.
"""
from .equilibrium import TrimResult, traction_peak, trim
from .linearization import PLANT_INPUTS, PLANT_OUTPUTS, linearize, plant, trim_point  # noqa: F401 (deprecated)
from .model import (
    BASE_STATES,
    DISSIPATION_TERMS,
    OUTPUTS,
    VARIATOR_LOSSES,
    EmpactModel,
    ModelOptions,
    nonlinear_model,
    rhs,
    shift_inertia,
)
from .nmp import BeltLengthChange, NmpResult, belt_length_change, nmp_analysis
from .scenario import Scenario, example_path, list_examples, load_scenario
from .simulation import SimulationResult, run_scenario, simulate, write_csv

__all__ = ["ModelOptions", "EmpactModel", "nonlinear_model", "rhs", "shift_inertia",
           "BASE_STATES", "OUTPUTS", "VARIATOR_LOSSES", "DISSIPATION_TERMS", "TrimResult",
           "trim", "traction_peak", "linearize", "plant",
           "PLANT_INPUTS", "PLANT_OUTPUTS", "BeltLengthChange", "NmpResult",
           "belt_length_change", "nmp_analysis", "Scenario", "load_scenario", "list_examples",
           "example_path", "SimulationResult", "simulate", "run_scenario", "write_csv"]
