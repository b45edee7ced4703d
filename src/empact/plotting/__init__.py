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
efficiency
    Efficiency maps of the clamping strategies, efficiency over clamping force.
drive_cycle
    A quasi-static drive cycle: trace, ratio, clamping, cumulative losses.

Each submodule is imported when one of its names is first used (``from empact.plotting import
plot_bode`` loads the Bode plot's module, not the control plots' simulation stack).
"""
from __future__ import annotations

import importlib
from typing import Any

#: public name -> the submodule that defines it
_CATALOGUE = {
    "Plot": "_common", "STYLE": "_common", "FORMATS": "_common", "save_figure": "_common",
    "save_plot": "_common", "symbol": "_common",
    "plot_mode_shapes": "linear", "plot_modal_energy": "linear", "plot_bode": "linear",
    "plot_belt_root_locus": "slip", "plot_traction": "slip", "plot_pole_sweep": "slip",
    "plot_slip_bode": "slip", "plot_zero_locus": "slip", "plot_stability_map": "slip",
    "plot_nmp": "nonlinear", "plot_simulation": "nonlinear",
    "plot_plant_magnitude": "nonlinear",
    "plot_frf_estimate": "identification", "plot_identified_plant": "identification",
    "plot_family_poles": "control", "plot_loop_shapes": "control",
    "plot_robustness_maps": "control", "plot_closed_loop": "control",
    "plot_shift_envelope": "control",
    "plot_traction_reserve": "variator", "plot_ratio_stability": "variator",
    "plot_efficiency_map": "efficiency", "plot_drive_cycle": "drive_cycle",
    "plot_dynamic_cycle": "drive_cycle",
}

__all__ = list(_CATALOGUE)


def __getattr__(name: str) -> Any:
    if name not in _CATALOGUE:
        raise AttributeError(f"module 'empact.plotting' has no attribute {name!r}")
    value = getattr(importlib.import_module(f".{_CATALOGUE[name]}", __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_CATALOGUE))
