"""``empact identify`` and ``empact rig``: experiments on the nonlinear model
(`empact.experiments`): the plant realised from step responses (Fig. 2) and the virtual test
rig's records (Fig. 14)."""
from __future__ import annotations

from typing import Any, Literal, cast

import click
import numpy as np

from .._progress import progress as progress_bar
from .._validate import check_int, check_number
from ..experiments.rig import EXCITATIONS
from ..variator.geometry import check_ratio
from ._common import (
    InputError,
    OutputFile,
    emit_json,
    force_option,
    get_params,
    json_options,
    loss_map_option,
    operating_point,
    output_folder,
    params_option,
    parse_list,
    quiet_option,
    to_jsonable,
    traction_option,
)
from .linear import plot_option

#: Most samples of a virtual rig record (duration x sample rate).
MAX_RIG_SAMPLES = 2_000_000


def _ratios(text: str) -> list[float]:
    return parse_list(text, "--ratios", most=50)


@click.command("identify")
@click.option("--ratios", default="0.5,1,2", show_default=True,
              help="Comma-separated geometric ratios.")
@click.option("--slip", "nu", type=float, default=None,
              help="Slip (fraction: 0.004 is 0.4 %; default: the parameter file's "
                   "[operating]).")
@click.option("--clamp", "F_s", type=float, default=None, help="F_s [N].")
@click.option("--speed", "omega_p", type=float, default=None, help="Primary speed [rad/s].")
@click.option("--order", type=int, default=None, help="Model order (default: by fit).")
@click.option("--step", "step", type=float, default=1e-4, show_default=True,
              help="Servo torque step size [N m].")
@traction_option
@loss_map_option
@params_option
@json_options
@click.option("--out", type=click.Path(file_okay=False), default=None,
              help="Folder for the step responses (CSV) and models (JSON); new or empty "
                   "unless --force.")
@plot_option
@force_option
@quiet_option
def identify(ratios: str, nu: float | None, F_s: float | None, omega_p: float | None,
             order: int | None, step: float, traction_table: Any, loss_map: Any,
             params_file: str | None, as_json: bool,
             json_out: str | None, out: str | None, plot: str | None, force: bool,
             quiet: bool) -> None:
    """Identify (T_mp, T_ms) -> (r_g, nu) from step responses of the nonlinear model (Fig 2)."""
    from .._io import atomic_folder
    from ..experiments.plant_id import identify_plant
    from ..nonlinear.model import nonlinear_model

    if order is not None:
        order = check_int("--order", order, 1, 200)
    step = check_number("--step", step, -1.0, 1.0, unit="N m")
    if step == 0:
        raise InputError("--step = 0: must be a non-zero torque step in [-1, 1] [N m]")
    r_list = _ratios(ratios)
    dest = None if out is None else output_folder(out, "--out", force=force)
    params = get_params(params_file, loss_map)
    base = operating_point(params, trim=True, traction=traction_table, slip=nu, clamp=F_s,
                           speed=omega_p)
    check_ratio(r_list, params.variator, "--ratios")
    machine = None if traction_table is None else nonlinear_model(params,
                                                                  traction=traction_table)
    results = [identify_plant(params, base.replace(r_g=r), order=order, amplitudes=(step, step),
                              model=machine)
               for r in progress_bar(r_list, desc="identify", unit="ratio", enabled=not quiet)]
    models = [{"r_g": res.r_g, "operating_point": res.experiment.op.to_dict(),
               "order": res.realization.order, "fit_percent": res.realization.fit,
               "singular_values": res.realization.singular_values[:40],
               "A": res.realization.A, "B": res.realization.B,
               "C": res.realization.C, "D": res.realization.D,
               "inputs": ["T_mp", "T_ms"], "outputs": ["r_g", "nu"]} for res in results]
    data = {"operating_point": base.to_dict(), "step": step, "models": models}
    if dest is not None:
        import json

        with atomic_folder(dest) as tmp:
            for res in results:
                e = res.experiment
                cols = np.column_stack([e.t, e.steps.reshape(len(e.t), -1)])
                np.savetxt(tmp / f"steps_rg_{res.r_g:g}.csv", cols, delimiter=",", comments="",
                           header="time [s],r_g/T_mp [1/(N m)],r_g/T_ms [1/(N m)],"
                                  "nu/T_mp [1/(N m)],nu/T_ms [1/(N m)]")
            (tmp / "models.json").write_text(json.dumps(to_jsonable(
                {"schema": {"name": "empact.identify", "version": 1}, **data}), indent=1))
    if plot:  # the figure only when asked (matplotlib and its drawing are most of the wait)
        from ..plotting import plot_identified_plant

        plot_identified_plant(results, np.logspace(-1, np.log10(200), 400)).save(plot)
    if as_json or json_out:
        emit_json(data, "identify", json_out)
    else:
        for d in models:
            fit = np.asarray(d["fit_percent"])
            click.echo(f"r_g = {d['r_g']:g}: order {d['order']}, step fits "
                       f"{', '.join(f'{v:.2f}' for v in fit.ravel())} %")


@click.command("rig")
@click.option("--excite", type=click.Choice(["T_mp", "T_ms"]), default="T_mp",
              show_default=True, help="The servo torque to excite.")
@click.option("--excitation", type=click.Choice(EXCITATIONS), default="multisine",
              show_default=True)
@click.option("--ratio", "r_g", type=float, default=0.5, show_default=True)
@click.option("--slip", "nu", type=float, default=0.0, show_default=True, help="Slip fraction.")
@click.option("--clamp", "F_s", type=float, default=10e3, show_default=True, help="F_s [N].")
@click.option("--speed", "omega_p", type=float, default=300.0, show_default=True,
              help="Primary speed [rad/s].")
@click.option("--rms", type=float, default=0.05, show_default=True,
              help="Excitation RMS [N m].")
@click.option("--band", default="0.5:100", show_default=True, help="Excited band LO:HI [Hz].")
@click.option("--duration", type=float, default=16.384, show_default=True, help="[s]")
@click.option("--fs", "fs", type=float, default=1000.0, show_default=True,
              help="Sample rate [Hz].")
@click.option("--friction", type=float, default=0.2, show_default=True,
              help="Spindle Coulomb friction torque [N m] (both spindles).")
@click.option("--seed", type=int, default=1, show_default=True)
@traction_option
@loss_map_option
@params_option
@click.option("--out", required=True, type=OutputFile(("csv",)),
              help="CSV records (time, T_mp, T_ms, theta_mp, theta_ms, nu; units in the "
                   "header); an existing file only with --force.")
@force_option
@click.option("--quiet", is_flag=True, help="No progress bar on stderr.")
def rig(excite: str, excitation: str, r_g: float, nu: float, F_s: float, omega_p: float,
        rms: float, band: str, duration: float, fs: float, friction: float, seed: int,
        traction_table: Any, loss_map: Any, params_file: str | None, out: str, force: bool,
        quiet: bool) -> None:
    """Virtual test rig: excite a servo torque of the nonlinear model (Fig 14).

    The model has spindle Coulomb friction and sensor noise; the records it writes are what
    `empact frf-estimate` reads."""
    from .._io import atomic_write_text
    from ..experiments.rig import RigSettings, run_rig

    try:
        lo, hi = (float(v) for v in band.split(":"))
    except ValueError:
        raise InputError(f"--band {band!r}: give LO:HI in Hz, e.g. 0.5:100") from None
    fs = check_number("--fs", fs, 0.0, 1e5, lo_open=True, unit="Hz")
    duration = check_number("--duration", duration, 0.0, 3600.0, lo_open=True, unit="s")
    if duration * fs > MAX_RIG_SAMPLES:
        raise InputError(f"--duration x --fs = {duration:g} s x {fs:g} Hz = "
                         f"{duration * fs:.3g} samples; at most {MAX_RIG_SAMPLES}")
    if duration * fs < 64:
        raise InputError(f"--duration x --fs = {duration:g} s x {fs:g} Hz = "
                         f"{duration * fs:.3g} samples; at least 64 (an FRF needs records)")
    lo = check_number("--band (low end)", lo, 0.0, fs / 2, lo_open=True, hi_open=True,
                      unit="Hz", note="below half the sample rate")
    hi = check_number("--band (high end)", hi, lo, fs / 2, lo_open=True, hi_open=True,
                      unit="Hz", note="above the low end, below half the sample rate")
    rms = check_number("--rms", rms, 0.0, 100.0, lo_open=True, unit="N m")
    friction = check_number("--friction", friction, 0.0, 100.0, unit="N m")
    seed = check_int("--seed", seed, 0, 2**32 - 1)
    params = get_params(params_file, loss_map)
    op = operating_point(params, trim=True, traction=traction_table, ratio=r_g, slip=nu,
                         clamp=F_s, speed=omega_p).resolve(params, traction_table)
    settings = RigSettings(r_g=op.r_g, nu=op.nu, F_s=op.F_s, omega_p=op.omega_p,
                           excite=cast(Literal["T_mp", "T_ms"], excite),
                           excitation=excitation, band_hz=(lo, hi), rms=rms, duration=duration,
                           sample_rate=fs, coulomb=(friction, friction), seed=seed,
                           period=min(2048, int(duration * fs)),
                           settle=0.0)  # the records are written whole
    rec = run_rig(params, settings, progress=not quiet, traction=traction_table)
    if not rec.complete:
        raise InputError(f"rig simulation incomplete, nothing written: {rec.message}")
    atomic_write_text(out, rec.to_csv())
