"""Command-line interface: a thin layer over the public API.

``empact --help`` lists the commands.  Each command's module is imported only when that command
runs (a lazy click group), so ``empact --help`` and ``empact params show`` start in a fraction
of a second.  Errors in input (parameter files, options, data) print one line ``error: ...`` on
stderr and exit with status 2; nothing is written then.
"""
from __future__ import annotations

import sys

import click

from ._common import LazyGroup

__all__ = ["main", "COMMANDS"]

#: command name -> ("module:object", short help); the module is imported when the command runs
COMMANDS = {
    "params": ("empact.cli.params_cmd:params_group", "Show and validate parameter files."),
    "calibrate": ("empact.cli.linear:calibrate_cmd",
                  "Fit parameters to target eigenfrequencies."),
    "modes": ("empact.cli.linear:modes",
              "Eigenfrequencies, mode shapes and modal energy (Tables 1-2)."),
    "frf": ("empact.cli.linear:frf", "Damped frequency response of a linear model (Fig. 6)."),
    "slip": ("empact.cli.slip:slip_group",
             "Slip dynamics: traction, poles, root locus, FRFs, zeros, maps (Figs. 9-13)."),
    "simulate": ("empact.cli.nonlinear:simulate_cmd", "Simulate a scenario of the nonlinear "
                 "model."),
    "linearize": ("empact.cli.nonlinear:linearize_cmd",
                  "Exact linear plant at an operating point (JSON, .mat, .npz)."),
    "nmp": ("empact.cli.nonlinear:nmp_cmd", "Zeros of T_mp -> nu over the ratio (Sec. 2.3)."),
    "identify": ("empact.cli.experiments:identify",
                 "Identify the plant from step responses (Fig. 2)."),
    "rig": ("empact.cli.experiments:rig", "Virtual test rig records (Fig. 14)."),
    "frf-estimate": ("empact.cli.identification:frf_estimate",
                     "FRFs with coherence from measured records (CSV)."),
    "reproduce": ("empact.cli.report_cmd:reproduce",
                  "Reproduce every table and figure of the paper."),
    "plants": ("empact.cli.control:plants_cmd",
               "Plant family: the exact plant over a grid of operating points."),
    "control": ("empact.cli.control:control_group",
                "Slip and ratio control: design, robustness, closed loop."),
    "fmu": ("empact.cli.fmu:fmu_group",
            "The machine as an FMU (FMI 2.0 co-simulation): export."),
    "montecarlo": ("empact.cli.montecarlo:montecarlo_cmd",
                   "Monte Carlo over parameter spread (in process or on Dask)."),
    "efficiency": ("empact.cli.efficiency:efficiency_cmd",
                   "Variator and total efficiency by clamping strategy (steady state)."),
    "cycle": ("empact.cli.drive_cycle:cycle_cmd",
              "A drive cycle (WLTC 3b, NEDC, FTP-75, a trace): energy and fuel by strategy."),
}



@click.group("empact", cls=LazyGroup, lazy=COMMANDS,
             context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="empact")
def main() -> None:
    """empact: dynamic analysis of electromechanically actuated pushbelt CVTs."""

if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
