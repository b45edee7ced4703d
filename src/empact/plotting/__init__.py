"""Figures drawn from result objects (the only part of empact that imports matplotlib).

Every function takes result objects, draws into the caller's axes (``ax=``: one Axes, or an
array of them) or a new figure (no pyplot state), with one style (`STYLE`), and returns a `Plot`
(figure, axes, artists); `save_figure` writes PNG / SVG / PDF atomically.

Modules
-------
linear
    Mode shapes, modal energy, Bode plots (Figs. 4-6, 8).
slip
    Root locus over c_b, traction curves, poles over slip, slip FRFs, zero locus, stability
    map (Figs. 9-13).
nonlinear
    NMP geometry and zeros, simulation time histories, exact plant magnitudes.
identification
    FRF estimates with coherence, identified plants (Figs. 2, 14).
control
    Plant families' poles and zeros, loop shapes, robustness maps, closed-loop runs.
variator
    The machine sheet: traction curves with their torque reserve, the ratio's static
    stability map.
"""
from ._common import FORMATS, STYLE, Plot, save_figure, save_plot, symbol
from .control import (
    plot_closed_loop,
    plot_family_poles,
    plot_loop_shapes,
    plot_robustness_maps,
    plot_shift_envelope,
)
from .identification import plot_frf_estimate, plot_identified_plant
from .linear import plot_bode, plot_modal_energy, plot_mode_shapes
from .nonlinear import plot_nmp, plot_plant_magnitude, plot_simulation
from .slip import (
    plot_belt_root_locus,
    plot_pole_sweep,
    plot_slip_bode,
    plot_stability_map,
    plot_traction,
    plot_zero_locus,
)
from .variator import plot_ratio_stability, plot_traction_reserve

__all__ = ["Plot", "STYLE", "FORMATS", "save_figure", "save_plot", "symbol", "plot_mode_shapes",
           "plot_modal_energy", "plot_bode", "plot_belt_root_locus", "plot_traction",
           "plot_pole_sweep", "plot_slip_bode", "plot_zero_locus", "plot_stability_map",
           "plot_nmp", "plot_simulation", "plot_plant_magnitude", "plot_frf_estimate",
           "plot_identified_plant", "plot_family_poles", "plot_loop_shapes",
           "plot_robustness_maps", "plot_closed_loop", "plot_shift_envelope",
           "plot_traction_reserve",
           "plot_ratio_stability"]
