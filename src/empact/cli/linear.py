"""``empact modes``, ``empact frf`` and ``empact calibrate``: the linear models of
Sec. 2.1-2.2."""
from __future__ import annotations

import click
import numpy as np

from .._validate import check_int, check_number
from ..linear.actuation import actuation_model
from ..linear.calibration import calibrate, load_targets
from ..linear.driveline import driveline_model, uncoupled_frequencies
from ..params import DAMPING_LEVELS, save_params
from ..variator.geometry import check_ratio
from ._common import (
    PLOT_SUFFIXES,
    Failed,
    InputError,
    OutputFile,
    emit_json,
    force_option,
    get_params,
    json_options,
    params_option,
)

MODELS = {"actuation": actuation_model, "driveline": driveline_model}
#: Most frequencies one response may have.
MAX_FREQUENCIES = 100_000


def plot_option(fn):
    """``--plot FILE`` (format from the suffix)."""
    return click.option("--plot", "plot", type=OutputFile(PLOT_SUFFIXES), default=None,
                        help="Write the figure (format from the suffix: .png, .svg, .pdf); an "
                             "existing file only with --force.")(fn)


def kinematics_option(fn):
    """``--kinematics`` (actuation model rows)."""
    return click.option("--kinematics", type=click.Choice(["equal-translation", "paper-sec2.1"]),
                        default="equal-translation", show_default=True,
                        help="Actuation rows: the machine, or the paper's Sec. 2.1 rows "
                             "(stiffnesses [paper_sec21]).")(fn)


def ratio_option(default: float):
    """``--ratio`` (r_g)."""
    return click.option("--ratio", "r_g", type=float, default=default, show_default=True,
                        help="Geometric ratio r_g [-].")


@click.command("modes")
@click.argument("model", type=click.Choice(list(MODELS)))
@ratio_option(1.0)
@kinematics_option
@params_option
@json_options
@force_option
def modes(model: str, r_g: float, kinematics: str, params_file: str | None, as_json: bool,
          json_out: str | None, force: bool) -> None:
    """Undamped eigenfrequencies, mode shapes and modal energy of MODEL at a ratio."""
    params = get_params(params_file)
    r_g = float(check_ratio(check_number("--ratio", r_g), params.variator, "--ratio"))
    lm = actuation_model(params, r_g, kinematics=kinematics) if model == "actuation" \
        else driveline_model(params, r_g)
    m = lm.modes()
    if as_json or json_out:
        data = {"model": model, "r_g": r_g, "coordinates": m.coordinates, "springs": m.springs,
                "spring_parameters": m.spring_parameters,
                "frequencies_hz": m.frequencies_hz, "energy_fraction": m.energy_fraction,
                "shapes": m.shapes, "normalised_shapes": m.normalised_shapes,
                "mass_matrix": m.mass_matrix, "stiffness_matrix": m.stiffness_matrix}
        if model == "driveline":
            data["uncoupled_hz"] = uncoupled_frequencies(params)
        else:
            data["kinematics"] = kinematics
        emit_json(data, "modes", json_out)
        return
    click.echo(f"{lm.name}")
    click.echo("spring stiffnesses: " + ", ".join(
        f"{s} = {p}" for s, p in zip(m.springs, m.spring_parameters)))
    click.echo(f"{'mode':>4s} {'f [Hz]':>10s}  signed energy fraction per spring "
               f"({', '.join(m.springs)}): sign of the spring's elongation in the mode, "
               "magnitudes sum to 1")
    for j, f in enumerate(m.frequencies_hz):
        e = " ".join(f"{x:+6.3f}" for x in m.energy_fraction[j])
        click.echo(f"{j + 1:4d} {f:10.3f}  {e}")
    if model == "driveline":
        u = uncoupled_frequencies(params)
        click.echo(f"uncoupled (belt removed): primary {u['primary']:.3f} Hz, "
                   f"secondary {u['secondary']:.3f} Hz")


def frequency_grid(fmin: float, fmax: float, n: int) -> np.ndarray:
    """Log-spaced frequencies [Hz] from ``--fmin``, ``--fmax``, ``--n`` (checked)."""
    fmin = check_number("--fmin", fmin, 0.0, 1e6, lo_open=True, unit="Hz")
    fmax = check_number("--fmax", fmax, fmin, 1e6, lo_open=True, unit="Hz",
                        note="above --fmin")
    n = check_int("--n", n, 2, MAX_FREQUENCIES)
    return np.logspace(np.log10(fmin), np.log10(fmax), n)


@click.command("frf")
@click.argument("model", type=click.Choice(list(MODELS)))
@click.option("--input", "inputs", multiple=True, default=None,
              help="Input name (repeatable; default all), e.g. T_mp.")
@click.option("--output", "outputs", multiple=True, default=None,
              help="Output name (repeatable; default all coordinates), e.g. theta_mp; "
                   "append _dot for a velocity.")
@click.option("--damping", type=click.Choice(DAMPING_LEVELS), default="moderate",
              show_default=True, help="Damping level (actuation model).")
@click.option("--pulley-damping", "pulley_damping", type=click.Choice(["shafai", "creep"]),
              default="shafai", show_default=True,
              help="Actuation pulley damping: Shafai's at the damping level, or the creep law "
                   "linearised at --speed and --clamp.")
@click.option("--speed", "omega_p", type=float, default=None,
              help="Primary speed for the pulley damping [rad/s] (default: [damping] "
                   "omega_pulley).")
@click.option("--clamp", "F_s", type=float, default=None,
              help="Clamping force for the creep law [N] (default: [operating] F_s).")
@kinematics_option
@ratio_option(1.0)
@click.option("--fmin", type=float, default=0.1, show_default=True, help="[Hz]")
@click.option("--fmax", type=float, default=1000.0, show_default=True, help="[Hz]")
@click.option("--n", "n", type=int, default=400, show_default=True,
              help=f"Number of frequencies (2 to {MAX_FREQUENCIES}).")
@params_option
@json_options
@plot_option
@force_option
def frf(model: str, inputs: tuple[str, ...], outputs: tuple[str, ...], damping: str,
        pulley_damping: str, omega_p: float | None, F_s: float | None, kinematics: str,
        r_g: float, fmin: float, fmax: float, n: int, params_file: str | None, as_json: bool,
        json_out: str | None, plot: str | None, force: bool) -> None:
    """Damped frequency response of MODEL, computed directly from M, C and K."""
    for opt, names in (("--input", inputs), ("--output", outputs)):
        twice = sorted({x for x in names if names.count(x) > 1})
        if twice:
            raise InputError(f"{opt} {twice[0]}: given twice; name each signal once")
    params = get_params(params_file)
    f = frequency_grid(fmin, fmax, n)
    r_g = float(check_ratio(check_number("--ratio", r_g), params.variator, "--ratio"))
    if omega_p is not None:
        omega_p = check_number("--speed", omega_p, 0.0, 2000.0, lo_open=True, unit="rad/s")
    if F_s is not None:
        F_s = check_number("--clamp", F_s, 0.0, 1e6, lo_open=True, unit="N")
    lm = actuation_model(params, r_g, damping, omega_p, kinematics=kinematics,
                         pulley_damping=pulley_damping, F_s=F_s) if model == "actuation" \
        else driveline_model(params, r_g)
    try:
        resp = lm.frequency_response(2 * np.pi * f, list(inputs) or None, list(outputs) or None,
                                     label=f"{damping} damping" if model == "actuation" else "")
    except ValueError as exc:
        raise InputError(f"--input / --output: {exc}") from None
    if plot:
        from ..plotting import plot_bode

        pairs = [(o, i) for i in resp.inputs for o in resp.outputs]
        plot_bode([resp], pairs, title=f"{lm.name}").save(plot)
    if as_json or json_out:
        emit_json({"model": model, "r_g": r_g, "damping": damping,
                   **({"kinematics": kinematics, "pulley_damping": pulley_damping}
                      if model == "actuation" else {}), "inputs": resp.inputs,
                   "outputs": resp.outputs, "frequencies_hz": resp.frequencies_hz,
                   "magnitude_db": resp.magnitude_db(), "phase_deg": resp.phase_deg(),
                   "H": np.stack([resp.H.real, resp.H.imag], axis=-1)}, "frf", json_out)
        return
    if not plot:
        mag = resp.magnitude_db()
        click.echo(f"{'f [Hz]':>10s} " + " ".join(f"{o + '/' + i:>22s}" for i in resp.inputs
                                                  for o in resp.outputs) + "  [dB]")
        for k in range(len(f)):
            click.echo(f"{f[k]:10.4g} " + " ".join(f"{mag[a, b, k]:22.3f}"
                                                   for b in range(len(resp.inputs))
                                                   for a in range(len(resp.outputs))))


@click.command("calibrate")
@click.argument("targets", type=click.Path(dir_okay=False))
@params_option
@click.option("--out", "out", required=True, type=OutputFile(("toml",)),
              help="Where to write the calibrated parameter file (.toml).")
@click.option("--tolerance", type=float, default=1.0, show_default=True,
              help="Largest relative miss of any target [%]; beyond it nothing is written "
                   "and the exit status is 1.")
@click.option("--kinematics", type=click.Choice(["equal-translation", "paper-sec2.1"]),
              default=None, help="Actuation rows for targets that do not name theirs "
              "(default: the file's, else equal-translation).")
@click.option("--tie", "tie", multiple=True, metavar="DEPENDENT=FREE",
              help="Hold a parameter equal to a free one, e.g. actuation.k_ts=actuation.k_tp "
                   "(repeatable; adds to the file's [ties]).")
@force_option
def calibrate_cmd(targets: str, params_file: str | None, out: str, tolerance: float,
                  kinematics: str | None, tie: tuple[str, ...], force: bool) -> None:
    """Fit the free parameters named in TARGETS to its target eigenfrequencies.

    Exit status 0 when every target is met within --tolerance (the file is written), 1 when
    not (nothing written), 2 for bad input.
    """
    tol = check_number("--tolerance", tolerance, 0.0, 100.0, lo_open=True, unit="%")
    ties = {}
    for item in tie:
        dep, eq, src = item.partition("=")
        if not eq or not dep.strip() or not src.strip():
            raise InputError(f"--tie {item!r}: expected DEPENDENT=FREE, e.g. "
                             "actuation.k_ts=actuation.k_tp")
        ties[dep.strip()] = src.strip()
    params = get_params(params_file)
    tgts, free, ties = load_targets(targets, kinematics=kinematics, ties=ties)
    res = calibrate(params, tgts, free, ties)
    click.echo(f"{'target':44s} {'target [Hz]':>11s} {'model [Hz]':>11s} {'error':>9s}", err=True)
    for t, f, e in zip(res.targets, res.achieved_hz, res.relative_error):
        click.echo(f"{t.label:44s} {t.frequency_hz:11.4g} {f:11.4g} {100 * e:+8.3f}%", err=True)
    for name, a, b in zip(res.free, res.initial, res.final):
        click.echo(f"  {name:22s} {a:12.5g} -> {b:12.5g}", err=True)
    for dep, src in res.ties.items():
        click.echo(f"  {dep:22s} tied to {src}", err=True)
    click.echo(f"optimiser: {res.message}", err=True)
    worst = int(np.argmax(np.abs(res.relative_error)))
    miss = 100 * abs(res.relative_error[worst])
    if not miss <= tol:
        raise Failed(f"calibration misses {res.targets[worst].label} by {miss:.3g} % "
                     f"(--tolerance {tol:g} %); nothing written")
    header = (f"Calibrated by `empact calibrate {targets}` (max |error| {miss:.3f} %).")
    save_params(res.params, out, header=header)
