"""``empact fmu export``: the nonlinear machine as an FMI 2.0 co-simulation unit."""
from __future__ import annotations

from typing import Any

import click

from .._validate import check_number
from ..variator.traction import DEFAULT_TRACTION_LAW
from ._common import (
    ErrorGroup,
    InputError,
    OutputFile,
    force_option,
    get_params,
    operating_point,
    params_option,
)
from .nonlinear import _add, _options, model_options_for

__all__ = ["fmu_group"]


@click.group("fmu", cls=ErrorGroup)
def fmu_group() -> None:
    """The machine as an FMU (FMI 2.0 co-simulation) for Simulink, Modelica tools, FMPy."""


@fmu_group.command("export")
@click.option("--out", "out", type=OutputFile(("fmu",)), required=True,
              help="The FMU file (.fmu; an existing file only with --force).")
@click.option("--controller", "controller", type=click.Path(dir_okay=False), default=None,
              help="Controller JSON file (empact control design; or shipped:pi): the sampled "
                   "loop law goes inside (inputs r_g_ref, tau_ref and the drive and load "
                   "inputs; outputs also the servo torques T_mp, T_ms).")
@click.option("--rate", type=float, default=1000.0, show_default=True,
              help="The loop law's sample rate [Hz] (with --controller).")
@click.option("--duration", type=float, default=60.0, show_default=True,
              help="With --controller: the longest run [s] (the loop law's tables).")
@click.option("--ratio", "r_g", type=float, default=None,
              help="Starting ratio r_g [-] (default: the parameter file's [operating]).")
@click.option("--slip", "nu", type=float, default=None, help="Starting slip nu [-].")
@click.option("--tau", "tau", type=float, default=None,
              help="Starting torque ratio mu / mu_max [-] in place of --slip.")
@click.option("--clamp", "F_s", type=float, default=None, help="Starting clamping force [N].")
@click.option("--load-torque", "T_l", type=float, default=None,
              help="Starting load torque T_l [N m].")
@click.option("--speed", "omega_p", type=float, default=None,
              help="Starting primary speed omega_p [rad/s].")
@click.option("--method", type=click.Choice(["rodas4", "rodas5p", "ros2"]), default="rodas4",
              show_default=True, help="The integrator inside (empact simulate's).")
@click.option("--rtol", type=float, default=1e-4, show_default=True,
              help="The integrator's relative tolerance [-].")
@click.option("--max-step", "max_step", type=float, default=0.01, show_default=True,
              help="The integrator's largest step [s].")
@_add(model_options_for("speed"))
@params_option
@force_option
def export_cmd(out: str, controller: str | None, rate: float, duration: float, r_g: float | None,
               nu: float | None, tau: float | None, F_s: float | None, T_l: float | None,
               omega_p: float | None, method: str, rtol: float, max_step: float, damping: str,
               drive: str, load: str, kinematics: str, shift_law: str, thrust_ratio: str | None,
               creep_map: str | None, traction_table: Any, loss_map: Any, traction_law: str,
               params_file: str | None, force: bool) -> None:
    """Write an FMI 2.0 co-simulation FMU of the nonlinear machine, started at an operating
    point (trimmed at initialisation), with empact's integrator inside (any communication
    step). Inputs T_mp, T_ms and the drive and load inputs (held over each step); outputs
    every model output (r_g, nu, nu_r, F_s, speeds, powers); parameters the physical ones
    with units and ranges. The target machine needs Python with empact installed.
    """
    from ..fmu import export_fmu

    # the API's ranges (`empact.fmu.FmuConfig`), checked under the options' names
    check_number("--rate", rate, 1.0, 1e5, unit="Hz")
    check_number("--duration", duration, 0.0, 3600.0, lo_open=True, unit="s")
    check_number("--rtol", rtol, 1e-12, 0.1)
    check_number("--max-step", max_step, 0.0, 10.0, lo_open=True, unit="s")
    params = get_params(params_file)
    point = operating_point(params, trim=True, traction=traction_table, ratio=r_g, slip=nu,
                            tau=tau, clamp=F_s, load_torque=T_l, speed=omega_p)
    if traction_law != DEFAULT_TRACTION_LAW:  # (a law the FMU's model options do not carry)
        raise InputError(f"--traction-law {traction_law}: an FMU is exported with the default "
                         f"analytic law ({DEFAULT_TRACTION_LAW}) or measured curves (--traction)")
    options = _options(drive, load, damping, kinematics, shift_law, thrust_ratio, creep_map,
                       traction_table, loss_map=loss_map)
    export_fmu(out, params, options=options, point=point, controller=controller,
               rate=rate, method=method, rtol=rtol, max_step=max_step, duration=duration)
