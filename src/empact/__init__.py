"""empact: dynamic analysis and simulation of electromechanically actuated pushbelt CVTs.

After "Dynamic analysis of the Empact CVT: ratio and slip dependent, non-minimum phase
dynamics".  SI units throughout (rad, m, kg, s, N); Hz, degrees and dB only for display.

Parameters and operating points
===============================
   load_params        -- a TOML parameter file over the shipped set
   default_params     -- the shipped, calibrated set
   save_params        -- write a parameter set (TOML)
   Params             -- a frozen, validated parameter set
   OperatingPoint     -- r_g, nu, F_s, omega_p (the ``[operating]`` table)
   ParameterError     -- the error of every bad value, file or option (one line)

Variator geometry and traction (eqs. 1, 4-6; Fig. 10)
=====================================================
   variator_state     -- radii, wrap angle, sheave translations, belt length at ratios
   belt_length        -- eq. 6
   ratio_range        -- the variator's geometric ratio range
   traction_from_params, load_traction, traction_curves
                      -- analytic and tabulated traction curves mu(nu, r_g)
   load_loss_map      -- a measured torque-loss map T_loss(r_g, omega_in, T_in, F_s), in
                         place of the analytic losses of ``[losses]``

Axial physics of the variator (the machine as built)
====================================================
   creep_damping, shift_rate
                      -- the creep law (Carbone et al. 2007; Ide et al.), its linearisation
   thrust_ratio_from_params, load_thrust_ratio, kappa_geo
                      -- the equilibrium thrust ratio kappa*(tau, r_g), analytic or tabulated

Linear models (Sec. 2.1, 2.2)
=============================
   actuation_model    -- servos, worm, epicyclic sets, screws, sheaves, belt (Fig. 3)
   driveline_model    -- the test-bench driveline (Fig. 7)
   LumpedModel        -- M, C, K from kinematic rows: modes, FRFs, state space
   calibrate          -- fit parameters to target eigenfrequencies

Slip dynamics (Sec. 2.2, Figs. 9-13)
====================================
   slip_model         -- the driveline with the linearised belt damper (eq. 3)
   belt_root_locus    -- poles over c_b (Fig. 9)
   pole_sweep         -- poles over an operating variable (Fig. 11)
   zero_locus         -- zeros of F_s -> nu over the ratio (Fig. 13)
   stability_map      -- stability over two operating variables

Nonlinear model (Secs. 2.3, 3)
==============================
   nonlinear_model    -- the whole CVT (compiled right-hand side)
   trim               -- steady operating points
   linearize, plant   -- exact linearisation; the plant (T_mp, T_ms; load T_l as the
                         disturbance) -> (r_g, nu, nu_r)
   nmp_analysis       -- non-minimum-phase zeros of T_mp -> nu or nu_r (Sec. 2.3)
   simulate, run_scenario, load_scenario
                      -- time simulation

Identification and experiments (Secs. 3, 4)
===========================================
   realize_steps      -- state-space realisation from step responses
   estimate_frf       -- H1/H2 FRFs with coherence from records
   identify_plant     -- Fig. 2 by realisation of the nonlinear model's steps
   run_rig, rig_frf   -- the virtual test rig (Fig. 14)

Control and sweeps (beyond the paper)
=====================================
   plant_family       -- trimmed, exactly linearised plants on a grid (LPV)
   design_pi, design_hinf
                      -- robust decentralised PI; mixed-sensitivity H-infinity (slycot)
   robustness_map     -- disk margins of a controller over a family
   run_closed_loop    -- a scenario with a [controller] on the nonlinear machine
   monte_carlo, load_spread
                      -- an analysis over a parameter spread (failures kept with reasons)
   SweepOptions       -- where a sweep runs: in process, a local Dask cluster, a scheduler

LTI tools
=========
   frequency_response -- C (jwI - A)^-1 B + D, vectorised
   transmission_zeros -- invariant zeros
   root_locus         -- eigenvalues along any parameter, continuous branches

The report (`empact.report.build_report`), the figures (`empact.plotting`) and the checked
claims (`empact.reproduction`) are subpackages.  Names are imported on first use, so
``import empact`` is fast.
"""
from __future__ import annotations

import importlib
from typing import Any

__version__ = "0.2.0"

#: public name -> module that defines it
_CATALOGUE = {
    "load_params": "params", "default_params": "params", "save_params": "params",
    "Params": "params", "OperatingPoint": "params", "ParameterError": "errors",
    "variator_state": "variator.geometry", "belt_length": "variator.geometry",
    "ratio_range": "variator.geometry",
    "traction_from_params": "variator.traction", "load_traction": "variator.traction",
    "traction_curves": "variator.traction", "load_loss_map": "variator.losses",
    "creep_damping": "variator.shift_law", "shift_rate": "variator.shift_law",
    "thrust_ratio_from_params": "variator.thrust_ratio",
    "load_thrust_ratio": "variator.thrust_ratio",
    "kappa_geo": "variator.thrust_ratio",
    "actuation_model": "linear.actuation", "driveline_model": "linear.driveline",
    "LumpedModel": "linear.lumped", "calibrate": "linear.calibration",
    "slip_model": "slip.model", "belt_root_locus": "slip.loci", "pole_sweep": "slip.loci",
    "zero_locus": "slip.loci", "stability_map": "slip.stability",
    "nonlinear_model": "nonlinear.model", "trim": "nonlinear.equilibrium",
    "linearize": "nonlinear.linearization", "plant": "nonlinear.linearization",
    "nmp_analysis": "nonlinear.nmp", "simulate": "nonlinear.simulation",
    "run_scenario": "nonlinear.simulation", "load_scenario": "nonlinear.scenario",
    "realize_steps": "identification.realization",
    "estimate_frf": "identification.frf_estimation",
    "identify_plant": "experiments.plant_id", "run_rig": "experiments.rig",
    "rig_frf": "experiments.rig",
    "plant_family": "control.family", "design_pi": "control.pi",
    "design_hinf": "control.hinf", "robustness_map": "control.robustness",
    "run_closed_loop": "control.closed_loop", "load_control_scenario": "control.closed_loop",
    "Plant": "nonlinear.linearization",
    "monte_carlo": "montecarlo.study", "load_spread": "montecarlo.spread",
    "SweepOptions": "sweep",
    "frequency_response": "lti", "transmission_zeros": "lti", "root_locus": "lti",
}

#: deprecated names: still importable (each warns, naming its replacement), not in ``__all__``
DEPRECATED_NAMES = ("load_control_scenario",)

__all__ = sorted(set(_CATALOGUE) - set(DEPRECATED_NAMES))

#: module paths of empact 0.1 kept for one release, removed in 0.3.0 (importing one warns,
#: naming the new one and the removal)
DEPRECATED_MODULES = {"empact.geometry": "empact.variator.geometry",
                      "empact.traction": "empact.variator.traction",
                      "empact.shift_law": "empact.variator.shift_law",
                      "empact.thrust_ratio": "empact.variator.thrust_ratio"}


#: subpackages and modules reached as attributes (``empact.plotting.plot_bode`` without an
#: ``import empact.plotting`` first), imported on first use
SUBMODULES = ("control", "experiments", "identification", "linear", "montecarlo", "nonlinear",
              "plotting", "report", "reproduction", "slip", "variator", "errors", "export",
              "lti", "paper", "params", "plausibility", "sweep")


def __getattr__(name: str) -> Any:
    if name in _CATALOGUE:
        value = getattr(importlib.import_module(f".{_CATALOGUE[name]}", __name__), name)
        globals()[name] = value
        return value
    if name in SUBMODULES:
        return importlib.import_module(f".{name}", __name__)
    raise AttributeError(f"module 'empact' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_CATALOGUE) | set(SUBMODULES))
