"""Slip dynamics of the variator coupling (paper Sec. 2.2 "Slip dynamics", eqs. 1-3,
Figs. 9-13), and where the coupling loses damping or becomes unstable.

Modules
-------
coupling
    Eqs. 1-3: slip, belt torque, and its linearisation (the belt as a slip-dependent damper).
model
    The driveline with the belt damper as a state-space model, single and batched.
loci
    Root locus over ``c_b`` (Fig. 9), poles over an operating variable (Fig. 11), ``F_s -> nu``
    responses (Fig. 12), zeros over the ratio (Fig. 13).
stability
    Stability maps over two operating variables.
"""
from .coupling import (
    VARIABLES,
    BeltLinearisation,
    belt_torque,
    linearise_belt,  # noqa: F401 (deprecated: importable, not in __all__)
    linearize_belt,
    slip,
)
from .loci import (
    BeltRootLocus,
    PoleSweep,
    ZeroLocus,
    belt_root_locus,
    coupled_limit,
    pole_sweep,
    slip_frequency_responses,
    zero_locus,
)
from .model import (
    INPUTS,
    N_STRUCTURAL_ZEROS,
    OUTPUTS,
    REDUCED_STATES,
    STATES,
    SlipModel,
    reduced_matrices,
    slip_model,
    slip_state_space,
    state_matrices,
)
from .stability import StabilityMap, dynamic_poles, stability_map, stability_measures

__all__ = [
    "STATES", "INPUTS", "OUTPUTS", "VARIABLES", "N_STRUCTURAL_ZEROS", "REDUCED_STATES",
    "BeltLinearisation", "SlipModel", "BeltRootLocus", "PoleSweep", "ZeroLocus", "StabilityMap",
    "slip", "belt_torque", "linearize_belt", "slip_model", "slip_state_space",
    "state_matrices",
    "reduced_matrices", "dynamic_poles", "stability_measures", "belt_root_locus",
    "coupled_limit", "pole_sweep", "slip_frequency_responses", "zero_locus", "stability_map",
]
