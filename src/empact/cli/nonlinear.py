"""``empact simulate``, ``empact linearize`` and ``empact nmp``: the nonlinear model."""
from __future__ import annotations

import json
import os
import shutil
import sys
import tempfile
from pathlib import Path

import click
import numpy as np

from .._validate import check_number
from ..geometry import check_ratio
from ._common import (InputError, echo_json, get_params, json_option, operating_point,
                      params_option, to_jsonable)


@click.command("simulate")
@click.argument("scenario", required=False, type=click.Path(dir_okay=False))
@click.option("--example", "example", default=None, help="Run a shipped example scenario.")
@click.option("--list-examples", "list_ex", is_flag=True, help="List the shipped scenarios.")
@click.option("--out", "out", default=".", show_default=True, type=click.Path(file_okay=False),
              help="Folder for NAME.csv and NAME.png / NAME.svg.")
@click.option("--duration", "duration", type=float, default=None,
              help="Override the scenario's end time [s].")
@click.option("--states", "states", is_flag=True, help="Also write the states to the CSV.")
@params_option
@click.option("--quiet", is_flag=True, help="No progress bar on stderr.")
def simulate_cmd(scenario: str | None, example: str | None, list_ex: bool, out: str,
                 duration: float | None, states: bool, params_file: str | None,
                 quiet: bool) -> None:
    """Simulate SCENARIO.toml (or --example NAME); write CSV (units in the header) and a figure.

    Exit status 1 when the run stopped early (the output is kept and marked incomplete).
    """
    from ..nonlinear.scenario import example_path, list_examples, load_scenario
    from ..nonlinear.simulate import csv_text, run_scenario

    if list_ex:
        for name, desc in list_examples().items():
            click.echo(f"{name:24s} {desc}")
        return
    if (scenario is None) == (example is None):
        raise InputError("give exactly one of SCENARIO or --example NAME (see --list-examples)")
    path = example_path(example) if example else scenario
    sc = load_scenario(path)
    if duration is not None:
        sc = sc.with_duration(check_number("--duration", duration, 0.0, 3600.0, lo_open=True,
                                           unit="s"))
    params = get_params(params_file)
    res = run_scenario(sc, params, progress=not quiet)
    from ..plotting import plot_simulation, save_figure

    dest = Path(out)
    dest.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(dir=dest, prefix=f".{sc.name}.tmp-"))
    try:
        (tmp / f"{sc.name}.csv").write_text(csv_text(res, states))
        save_figure(plot_simulation(res).figure, tmp / sc.name)
        for f in tmp.iterdir():
            os.replace(f, dest / f.name)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    click.echo(str(dest / f"{sc.name}.csv"))
    if not res.complete:
        click.echo(f"incomplete: {res.message}", err=True)
        sys.exit(1)


def _options(drive: str, load: str, damping: str, kinematics: str) -> dict:
    return {"drive": drive, "load": load, "damping": damping, "kinematics": kinematics}


model_options = [
    click.option("--damping", type=click.Choice(["none", "moderate", "large"]),
                 default="moderate", show_default=True, help="Actuation damping level."),
    click.option("--drive", type=click.Choice(["torque", "speed"]), default="torque",
                 show_default=True, help="Drive motor torque- or speed-controlled."),
    click.option("--load", type=click.Choice(["torque", "speed"]), default="torque",
                 show_default=True, help="Load motor torque- or speed-controlled."),
    click.option("--kinematics", type=click.Choice(["actuation", "equal-translation"]),
                 default="actuation", show_default=True,
                 help="Sense of the secondary sheave coordinate (see empact.nonlinear)."),
]


def _add(options):
    def deco(fn):
        for opt in reversed(options):
            fn = opt(fn)
        return fn
    return deco


@click.command("linearize")
@click.option("--ratio", "r_g", type=float, required=True, help="Geometric ratio r_g [-].")
@click.option("--slip", "nu", type=float, required=True, help="Slip nu [-] (0.004 is 0.4 %).")
@click.option("--clamp", "F_s", type=float, required=True, help="Clamping force F_s [N].")
@click.option("--speed", "omega_p", type=float, required=True,
              help="Primary speed omega_p [rad/s].")
@click.option("--format", "fmt", type=click.Choice(["json", "mat", "npz"]), default="json",
              show_default=True)
@click.option("--out", "out", type=click.Path(dir_okay=False), default=None,
              help="Output file (default: JSON on stdout; required for mat and npz).")
@click.option("--all-io", is_flag=True, help="All inputs and outputs, not only the plant's.")
@_add(model_options)
@params_option
def linearize_cmd(r_g, nu, F_s, omega_p, fmt, out, all_io, damping, drive, load, kinematics,
                  params_file) -> None:
    """Exact linear plant (T_mp, T_ms) -> (r_g, nu) at an operating point: A, B, C, D."""
    from ..nonlinear.linearize import PLANT_INPUTS, PLANT_OUTPUTS, linearize
    from ..nonlinear.model import nonlinear_model
    from ..nonlinear.trim import trim

    params = get_params(params_file)
    point = operating_point(params, trim=True, ratio=r_g, slip=nu, clamp=F_s, speed=omega_p)
    model = nonlinear_model(params, **_options(drive, load, damping, kinematics))
    op = trim(model, point.r_g, point.omega_p, nu=point.nu, F_s=point.F_s)
    sys_ = linearize(op, None if all_io else PLANT_INPUTS, None if all_io else PLANT_OUTPUTS)
    data = {"A": sys_.A, "B": sys_.B, "C": sys_.C, "D": sys_.D,
            "inputs": list(sys_.input_labels), "outputs": list(sys_.output_labels),
            "states": list(sys_.state_labels),
            "operating_point": {**op.as_dict(), "model_options": _options(drive, load, damping,
                                                                          kinematics)},
            "units": "SI (states: see empact.nonlinear)"}
    if fmt == "json":
        text = json.dumps(to_jsonable(data), indent=1)
        if out is None:
            click.echo(text)
            return
        from .._io import atomic_write_text

        atomic_write_text(out, text + "\n")
    else:
        if out is None:
            raise InputError(f"--format {fmt} needs --out FILE")
        path = Path(out)
        fd, tmp = tempfile.mkstemp(dir=path.parent.resolve() if str(path.parent) else ".",
                                   prefix=f".{path.name}.", suffix=f".{fmt}")
        os.close(fd)
        flat = {k: np.asarray(data[k]) for k in "ABCD"}
        op_names = list(op.as_dict())
        op_vals = np.array([op.as_dict()[k] for k in op_names])
        try:
            if fmt == "mat":
                from scipy.io import savemat
                savemat(tmp, {**{k: flat[k] for k in "ABCD"},
                              "inputs": np.array(data["inputs"], dtype=object),
                              "outputs": np.array(data["outputs"], dtype=object),
                              "states": np.array(data["states"], dtype=object),
                              "operating_point_names": np.array(op_names, dtype=object),
                              "operating_point": op_vals})
            else:
                with open(tmp, "wb") as fh:
                    np.savez(fh, **{k: flat[k] for k in "ABCD"},
                             inputs=np.array(data["inputs"]), outputs=np.array(data["outputs"]),
                             states=np.array(data["states"]),
                             operating_point_names=np.array(op_names),
                             operating_point=op_vals)
            os.replace(tmp, path)
        except BaseException:
            Path(tmp).unlink(missing_ok=True)
            raise
    click.echo(str(out), err=True)


@click.command("nmp")
@click.option("--ratios", "ratios", default="0.5,1,2", show_default=True,
              help="Comma-separated ratios r_g.")
@click.option("--slip", "nu", type=float, default=0.004, show_default=True, help="Slip [-].")
@click.option("--clamp", "F_s", type=float, default=10e3, show_default=True,
              help="Clamping force [N].")
@click.option("--speed", "omega_p", type=float, default=300.0, show_default=True,
              help="Primary speed [rad/s].")
@click.option("--fmax", "f_max", type=float, default=200.0, show_default=True,
              help="Largest zero frequency reported [Hz].")
@click.option("--slip-signal", "slip_signal", type=click.Choice(["eq2", "speed"]), default="eq2",
              show_default=True, help="Slip of eq. 2, or from the shaft speeds at the "
              "operating ratio (see empact.nonlinear.nmp).")
@click.option("--plot", "plot", type=click.Path(dir_okay=False), default=None,
              help="Write the figure (format from the suffix).")
@_add(model_options)
@params_option
@json_option
def nmp_cmd(ratios, nu, F_s, omega_p, f_max, slip_signal, plot, damping, drive, load,
            kinematics, params_file, as_json) -> None:
    """Delta_x, belt-length change and the zeros of T_mp -> nu over the ratio (Sec 2.3)."""
    from ..nonlinear.nmp import nmp_analysis

    try:
        r = [float(x) for x in ratios.split(",") if x.strip()]
    except ValueError:
        raise InputError(f"--ratios {ratios!r}: must be comma-separated numbers") from None
    if not r:
        raise InputError("--ratios: give at least one ratio")
    params = get_params(params_file)
    base = operating_point(params, trim=True, slip=nu, clamp=F_s, speed=omega_p)
    check_ratio(r, params.variator, "--ratios")
    check_number("--fmax", f_max, 0.0, lo_open=True, unit="Hz")
    res = nmp_analysis(params, r, base=base, f_max=f_max, slip=slip_signal,
                       **_options(drive, load, damping, kinematics))
    if plot:
        from ..plotting import plot_nmp

        plot_nmp(res).save(plot)
    g = res.geometry
    if as_json:
        echo_json({"ratios": res.r_g, "delta_x_m": g.delta_x, "delta_m": g.delta,
                   "dL_exact_m": g.dL_exact, "dL_first_order_m": g.dL_first_order,
                   "zeros_hz": [z / (2 * np.pi) for z in res.zeros],
                   "rhp_zeros_hz": [z / (2 * np.pi) for z in res.rhp_zeros],
                   "n_rhp": res.n_rhp, "n_rhp_real": res.n_rhp_real,
                   "slip_signal": res.slip, "operating_point": res.operating})
        return
    click.echo(f"{'r_g':>6s} {'Delta_x [mm]':>13s} {'dL/delta exact':>15s} {'4 phi/tan(b)':>13s}"
               f"  RHP zeros of T_mp -> nu [Hz]")
    for k, rg in enumerate(res.r_g):
        z = ", ".join(f"{v.real / 2 / np.pi:+.3g}{v.imag / 2 / np.pi:+.3g}j"
                      for v in res.rhp_zeros[k]) or "none"
        click.echo(f"{rg:6.3g} {1e3 * g.delta_x[k]:13.4f} {g.dL_exact[k] / g.delta:15.4f} "
                   f"{g.dL_first_order[k] / g.delta:13.4f}  {z}")
