"""``empact simulate``, ``empact linearize`` and ``empact nmp``: the nonlinear model."""
from __future__ import annotations

from typing import Any

import click
import numpy as np

from .._validate import check_number
from ..variator.geometry import check_ratio
from ..variator.traction import DEFAULT_TRACTION_LAW, TRACTION_LAWS
from ._common import (
    PLOT_SUFFIXES,
    UNITS,
    Failed,
    InputError,
    OutputFile,
    emit_json,
    force_option,
    formats_option,
    get_params,
    json_options,
    loss_map_option,
    operating_point,
    output_folder,
    params_option,
    parse_choices,
    parse_list,
    traction_option,
)
from .linear import plot_option

#: Most output samples (duration x sample rate) one simulation may write.
MAX_SAMPLES = 5_000_000


@click.command("simulate")
@click.argument("scenario", required=False, type=click.Path(dir_okay=False))
@click.option("--example", "example", default=None, help="Run a shipped example scenario.")
@click.option("--list-examples", "list_ex", is_flag=True, help="List the shipped scenarios.")
@click.option("--out", "out", default=None, type=click.Path(file_okay=False),
              help="Output folder for NAME.csv and the figure NAME.png (default: sim-NAME); "
                   "new or empty unless --force.")
@formats_option
@click.option("--duration", "duration", type=float, default=None,
              help="Override the scenario's end time [s].")
@click.option("--states", "states", is_flag=True, help="Also write the states to the CSV.")
@click.option("--keep-partial", is_flag=True,
              help="When the run stops early, write what was computed (marked INCOMPLETE).")
@traction_option
@loss_map_option
@params_option
@json_options
@force_option
@click.option("--quiet", is_flag=True, help="No progress bar on stderr.")
def simulate_cmd(scenario: str | None, example: str | None, list_ex: bool, out: str | None,
                 formats: str, duration: float | None, states: bool, keep_partial: bool,
                 traction_table: Any, loss_map: Any, params_file: str | None, as_json: bool,
                 json_out: str | None, force: bool, quiet: bool) -> None:
    """Simulate SCENARIO.toml (or --example NAME); write CSV (units in the header) and a figure
    (PNG; --formats png,svg adds the vector figure).  With --json (or --json-out) a summary
    of the run instead (its energy balance: energies by term [J] under ``energy`` and
    ``energy_balance_residual`` [-], relative to the input energy), and the files only with
    --out.

    Exit status: 0 complete; 1 the run stopped early (nothing written, or with --keep-partial
    the partial result, marked INCOMPLETE); 2 bad input.
    """
    from .._io import atomic_folder
    from .._progress import progress as progress_bar
    from ..control.closed_loop import run_closed_loop
    from ..efficiency import energy_summary
    from ..nonlinear.scenario import check_references, example_path, list_examples, load_scenario
    from ..nonlinear.simulation import csv_text, run_scenario
    from ..plotting import plot_simulation, save_figure

    if list_ex:
        for name, desc in list_examples().items():
            click.echo(f"{name:24s} {desc}")
        return
    if (scenario is None) == (example is None):
        raise InputError("give exactly one of SCENARIO or --example NAME (see --list-examples)")
    fmts = parse_choices("--formats", formats, PLOT_SUFFIXES)
    params = get_params(params_file, loss_map)
    sc = load_scenario(example_path(example) if example else str(scenario),
                       params if traction_table is None else None)
    if loss_map is not None:  # the command line's map over the scenario's [model] loss_map
        sc = sc.with_options(loss_map=loss_map)
    if traction_table is not None:  # the references against the curve the run uses
        sc = sc.with_options(traction=traction_table)
        check_references(sc, params)
    if duration is not None:
        sc = sc.with_duration(check_number("--duration", duration, 0.0, 3600.0, lo_open=True,
                                           unit="s"))
    n_samples = sc.duration * sc.sample_rate
    if n_samples > MAX_SAMPLES:
        raise InputError(f"duration x sample rate = {sc.duration:g} s x {sc.sample_rate:g} Hz "
                         f"= {n_samples:.3g} output samples; at most {MAX_SAMPLES}")
    summary = as_json or json_out
    dest = output_folder(out or f"sim-{sc.name}", "--out", force=force) \
        if out or not summary else None
    if sc.closed_loop:
        res = run_closed_loop(sc, params, progress=not quiet).result
    else:
        res = run_scenario(sc, params, progress=not quiet)
    if not res.complete and not keep_partial:
        raise Failed(f"simulation stopped early, nothing written (--keep-partial keeps it): "
                     f"{res.message}")
    if dest is not None:
        with atomic_folder(dest) as tmp, progress_bar(total=2, desc=f"writing {sc.name}",
                                                      unit="file", enabled=not quiet) as bar:
            (tmp / f"{sc.name}.csv").write_text(csv_text(res, states))
            bar.update(1)
            save_figure(plot_simulation(res).figure, tmp / sc.name, fmts)
            bar.update(1)
    if summary:
        emit_json({"scenario": sc.name, "complete": res.complete, "message": res.message,
                   "duration": float(res.t[-1]), "stats": dict(res.stats),
                   **energy_summary(res, params, sc.options.kinematics),
                   "files": [] if dest is None else [str(dest / f"{sc.name}.csv")]},
                  "simulate", json_out)
    if not res.complete:
        raise Failed(f"incomplete: {res.message}")


def _options(drive: str, load: str, damping: str, kinematics: str, shift_law: str,
             thrust_ratio: str | None, creep_map: str | None = None,
             traction_table: Any = None, traction_law: str = DEFAULT_TRACTION_LAW,
             loss_map: Any = None) -> dict:
    opts: dict[str, Any] = {"drive": drive, "load": load, "damping": damping,
                            "kinematics": kinematics, "shift_law": shift_law}
    if loss_map is not None:
        opts["loss_map"] = loss_map
    if traction_law != DEFAULT_TRACTION_LAW:  # (the default: the JSON as before)
        opts["traction_law"] = traction_law
    if traction_table is not None:
        opts["traction"] = traction_table
    if thrust_ratio:
        from ..variator.thrust_ratio import load_thrust_ratio

        opts["thrust_ratio"] = load_thrust_ratio(thrust_ratio)
    if creep_map:
        from ..variator.shift_law import load_creep_map

        opts["creep_map"] = load_creep_map(creep_map)
    return opts


_TABLES = ("thrust_ratio", "creep_map", "traction", "loss_map")


def _described(opts: dict) -> dict:
    """The model options for JSON / metadata (a tabulated map by its source)."""
    return {k: (v.source if k in _TABLES and v is not None else v)
            for k, v in opts.items()
            if not (k in _TABLES + ("reference_ratio",) and v is None)}


def model_options_for(drive: str = "torque") -> list:
    """The model-option flags (`ModelOptions`), with the drive motor's default: ``"speed"``
    for the plant commands (the test bench, as `empact plants`), ``"torque"`` for the
    analyses of the bare machine (`empact nmp`, as `empact.nmp_analysis`)."""
    return [
        click.option("--damping", type=click.Choice(["none", "moderate", "large"]),
                     default="moderate", show_default=True, help="Actuation damping level."),
        click.option("--drive", type=click.Choice(["torque", "speed"]), default=drive,
                     show_default=True, help="Drive motor torque- or speed-controlled."),
        click.option("--load", type=click.Choice(["torque", "speed"]), default="torque",
                     show_default=True, help="Load motor torque- or speed-controlled."),
        click.option("--kinematics", type=click.Choice(["equal-translation", "paper-sec2.1"]),
                     default="equal-translation", show_default=True,
                     help="The machine's sheave kinematics, or the paper's Sec. 2.1 rows (a "
                          "named variant)."),
        click.option("--shift-law", "shift_law",
                     type=click.Choice(["carbone", "ide", "shafai"]), default="carbone",
                     show_default=True, help="The belt's shift resistance "
                     "(empact.variator.shift_law)."),
        click.option("--thrust-ratio", "thrust_ratio", type=click.Path(dir_okay=False),
                     default=None, help="Measured thrust-ratio map kappa*(tau, r_g), .csv "
                     "(r_g,tau,kappa) or .toml (default: the analytic [thrust_ratio])."),
        click.option("--creep-map", "creep_map", type=click.Path(dir_okay=False),
                     default=None, help="Measured shift-speed map K_c(r_g, F_s), .csv "
                     "(r_g,F_s,K_c) or .toml (default: the analytic creep law of [shift])."),
        traction_option,
        loss_map_option,
        click.option("--traction-law", "traction_law", type=click.Choice(list(TRACTION_LAWS)),
                     default=DEFAULT_TRACTION_LAW, show_default=True,
                     help="The analytic traction law of [traction] (the registry "
                          "empact.variator._laws.TRACTION_LAWS), unless --traction gives "
                          "measured curves."),
    ]


def _add(options):
    def deco(fn):
        for opt in reversed(options):
            fn = opt(fn)
        return fn
    return deco


@click.command("linearize")
@click.option("--ratio", "r_g", type=float, default=None,
              help="Geometric ratio r_g [-] (default: the parameter file's [operating]).")
@click.option("--slip", "nu", type=float, default=None, help="Slip nu [-] (0.004 is 0.4 %).")
@click.option("--tau", "tau", type=float, default=None,
              help="Torque ratio mu / mu_max [-] in place of --slip (0.9: an 11 % torque "
                   "reserve).")
@click.option("--clamp", "F_s", type=float, default=None, help="Clamping force F_s [N].")
@click.option("--load-torque", "T_l", type=float, default=None, help="Load torque T_l [N m].")
@click.option("--speed", "omega_p", type=float, default=None,
              help="Primary speed omega_p [rad/s].")
@click.option("--format", "fmt", type=click.Choice(["json", "mat", "npz"]), default=None,
              help="File format (default: from the --out suffix, which must match it; JSON on "
                   "stdout without --out).")
@click.option("--out", "out", type=OutputFile(("json", "mat", "npz"), format_param="fmt"),
              default=None, help="Output file (.json, .mat or .npz; an existing file only with "
                                 "--force).")
@click.option("--all-io", is_flag=True, help="All inputs and outputs, not only the plant's.")
@click.option("--json", "as_json", is_flag=True,
              help="Print the plant as JSON on stdout (default without --out: a summary).")
@_add(model_options_for("speed"))
@params_option
@force_option
def linearize_cmd(r_g, nu, tau, F_s, T_l, omega_p, fmt, out, all_io, as_json, damping, drive,
                  load, kinematics, shift_law, thrust_ratio, creep_map, traction_table,
                  loss_map, traction_law, params_file, force) -> None:
    """Exact linear plant at an operating point: A, B, C, D.

    Inputs T_mp, T_ms (control) and the load T_l (or omega_l_ref with --load speed) as the
    disturbance; outputs r_g, nu (eq. 2) and nu_r (slip at the operating ratio).  By default
    the test bench (drive motor speed-controlled, load motor torque-controlled), as
    `empact plants`: a family's point equals this plant.
    """
    from ..export import format_of, save_system, system_dict
    from ..nonlinear.equilibrium import trim
    from ..nonlinear.linearization import (
        PLANT_INPUTS,
        PLANT_OUTPUTS,
        disturbance_input,
        linearized_plant,
    )
    from ..nonlinear.model import INPUT_UNITS, OUTPUT_UNITS, STATE_UNITS, nonlinear_model

    if out is None and fmt not in (None, "json"):
        raise InputError(f"--format {fmt} needs --out FILE")
    if out is not None and as_json:
        raise InputError("--json prints the plant, --out writes it: give one of them")
    params = get_params(params_file)
    point = operating_point(params, trim=True, traction=traction_table, ratio=r_g, slip=nu,
                            tau=tau, clamp=F_s, load_torque=T_l, speed=omega_p)
    opts = _options(drive, load, damping, kinematics, shift_law, thrust_ratio, creep_map,
                    traction_table, traction_law, loss_map)
    model = nonlinear_model(params, **opts)
    op = trim(model, point)
    dist = disturbance_input(model)
    # the matrices and names, without python-control (~1.5 s of start-up for a container)
    sys_ = linearized_plant(op, None if all_io else PLANT_INPUTS + (dist,),
                            None if all_io else PLANT_OUTPUTS)
    units = {"inputs": [INPUT_UNITS[n] for n in sys_.inputs],
             "outputs": [OUTPUT_UNITS[n] for n in sys_.outputs],
             "states": [STATE_UNITS[n] for n in sys_.states]}
    meta = {"operating_point": op.to_dict(), "model_options": _described(opts),
            "control_inputs": list(PLANT_INPUTS), "disturbance_inputs": [dist]}
    if out is None and (as_json or fmt == "json"):
        emit_json(system_dict(sys_, units, meta), "linearize")
        return
    if out is None:
        click.echo(_plant_summary(sys_, units, op.to_dict()))
        return
    save_system(sys_, out, fmt=format_of(out, fmt), schema="empact.linearize", units=units,
                metadata=meta)


def _plant_summary(sys_: Any, units: dict[str, list[str]], point: dict[str, Any]) -> str:
    """A linear plant in a few lines of text: the point, the states, inputs and outputs with
    their units, the poles [rad/s] (a complex pair once, with its frequency [Hz] and damping
    ratio [-])."""
    def named(names: Any, us: list[str]) -> str:
        return ", ".join(f"{n} [{u}]" for n, u in zip(names, us))

    at = ", ".join(f"{k} = {float(v):.5g} {UNITS[k]}" for k, v in point.items()
                   if k in ("r_g", "nu", "F_s", "omega_p", "T_l", "tau")
                   and isinstance(v, (int, float)))
    poles = np.linalg.eigvals(np.asarray(sys_.A, dtype=float))
    rows = []
    for p in sorted(poles, key=lambda z: (-z.real, abs(z.imag))):
        if p.imag < 0:
            continue  # (its conjugate is shown)
        if p.imag > 0:
            w = abs(p)
            rows.append(f"  {p.real:12.5g} +/- {p.imag:.5g}j rad/s  (f = {w / (2 * np.pi):.4g} "
                        f"Hz, zeta = {-p.real / w:.3g})")
        else:
            rows.append(f"  {p.real:12.5g} rad/s")
    n_rhp = int(np.sum(poles.real > 0))
    return "\n".join([
        f"linear plant at {at}",
        f"states ({len(sys_.states)}): {named(sys_.states, units['states'])}",
        f"inputs ({len(sys_.inputs)}): {named(sys_.inputs, units['inputs'])}",
        f"outputs ({len(sys_.outputs)}): {named(sys_.outputs, units['outputs'])}",
        f"poles ({len(poles)}, {n_rhp} in the right half-plane), slowest first:", *rows,
        "(--json prints A, B, C, D; --out FILE.json|.mat|.npz writes them)"])


@click.command("nmp")
@click.option("--ratios", "ratios", default="0.5,1,2", show_default=True,
              help="Comma-separated ratios r_g.")
@click.option("--slip", "nu", type=float, default=None,
              help="Slip [-] (default: the parameter file's [operating]).")
@click.option("--tau", "tau", type=float, default=None,
              help="Torque ratio mu / mu_max [-] in place of --slip.")
@click.option("--clamp", "F_s", type=float, default=None, help="Clamping force [N].")
@click.option("--load-torque", "T_l", type=float, default=None, help="Load torque T_l [N m].")
@click.option("--speed", "omega_p", type=float, default=None, help="Primary speed [rad/s].")
@click.option("--fmax", "f_max", type=float, default=200.0, show_default=True,
              help="Largest zero frequency reported [Hz].")
@click.option("--slip-signal", "slip_signal", type=click.Choice(["nu", "nu_r"]), default="nu",
              show_default=True, help="Slip nu of eq. 2 on the current radii, or nu_r at the "
              "operating ratio (see empact.nonlinear.nmp).")
@plot_option
@_add(model_options_for("torque"))
@params_option
@json_options
@force_option
def nmp_cmd(ratios, nu, tau, F_s, T_l, omega_p, f_max, slip_signal, plot, damping, drive, load,
            kinematics, shift_law, thrust_ratio, creep_map, traction_table, loss_map,
            traction_law, params_file, as_json, json_out, force) -> None:
    """Delta_x, belt-length change and the zeros of T_mp -> nu over the ratio (Sec 2.3)."""
    from ..nonlinear.nmp import nmp_analysis

    r = parse_list(ratios, "--ratios", most=200)
    f_max = check_number("--fmax", f_max, 0.0, 1e5, lo_open=True, unit="Hz")
    params = get_params(params_file)
    base = operating_point(params, trim=True, traction=traction_table, slip=nu, tau=tau,
                           clamp=F_s, load_torque=T_l, speed=omega_p)
    check_ratio(r, params.variator, "--ratios")
    res = nmp_analysis(params, r, base=base, f_max_hz=f_max, slip=slip_signal,
                       **_options(drive, load, damping, kinematics, shift_law, thrust_ratio,
                                  creep_map, traction_table, traction_law, loss_map))
    if plot:
        from ..plotting import plot_nmp

        plot_nmp(res).save(plot)
    g = res.geometry
    if as_json or json_out:
        emit_json({"r_g": res.r_g, "delta_x": g.delta_x, "delta": g.delta,
                   "dL_exact": g.dL_exact, "dL_first_order": g.dL_first_order,
                   "zeros": list(res.zeros), "rhp_zeros": list(res.rhp_zeros),
                   "n_rhp": res.n_rhp, "n_rhp_real": res.n_rhp_real,
                   "slip_signal": res.slip, "operating_point": base.to_dict(),
                   "model_options": _described(res.operating["options"])}, "nmp", json_out)
        return
    click.echo(f"{'r_g':>6s} {'Delta_x [mm]':>13s} {'dL/delta exact':>15s} {'4 phi/tan(b)':>13s}"
               f"  RHP zeros of T_mp -> {res.slip} [Hz]")
    for k, rg in enumerate(res.r_g):
        z = ", ".join(f"{v.real / 2 / np.pi:+.3g}{v.imag / 2 / np.pi:+.3g}j"
                      for v in res.rhp_zeros[k]) or "none"
        click.echo(f"{rg:6.3g} {1e3 * g.delta_x[k]:13.4f} {g.dL_exact[k] / g.delta:15.4f} "
                   f"{g.dL_first_order[k] / g.delta:13.4f}  {z}")
