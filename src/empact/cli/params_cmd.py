"""``empact params`` and ``empact calibrate``."""
from __future__ import annotations

import click

from ..calibration import calibrate, load_targets
from ..params import Params, dumps_params, save_params
from . import get_params, main, params_option


@main.group("params")
def params_group() -> None:
    """Show and validate parameter files."""


@params_group.command("show")
@click.argument("file", required=False, type=click.Path(dir_okay=False))
@click.option("--describe", is_flag=True, help="List every key with unit, range and meaning.")
def show(file: str | None, describe: bool) -> None:
    """Print the complete parameter set of FILE (default: the shipped set) as TOML."""
    params = get_params(file)
    if describe:
        for name, section in params.to_dict().items():
            kind = type(getattr(params, name))
            if hasattr(kind, "describe"):
                for key, unit, rng, doc in kind.describe():
                    click.echo(f"{name}.{key:10s} [{unit}] {rng}: {doc}")
        return
    click.echo(dumps_params(params), nl=False)


@params_group.command("validate")
@click.argument("file", type=click.Path(dir_okay=False))
def validate(file: str) -> None:
    """Check FILE; exit 0 and print 'ok' if every value is acceptable."""
    get_params(file)
    click.echo(f"{file}: ok")


@main.command("calibrate")
@click.argument("targets", type=click.Path(dir_okay=False))
@params_option
@click.option("--out", "out", required=True, type=click.Path(dir_okay=False),
              help="Where to write the calibrated parameter file (TOML).")
def calibrate_cmd(targets: str, params_file: str | None, out: str) -> None:
    """Fit the free parameters named in TARGETS to its target eigenfrequencies."""
    params: Params = get_params(params_file)
    tgts, free = load_targets(targets)
    res = calibrate(params, tgts, free)
    click.echo(f"{'target':34s} {'target [Hz]':>11s} {'model [Hz]':>11s} {'error':>9s}", err=True)
    for t, f, e in zip(res.targets, res.achieved_hz, res.relative_error):
        click.echo(f"{t.label:34s} {t.frequency_hz:11.4g} {f:11.4g} {100 * e:+8.3f}%", err=True)
    for name, a, b in zip(res.free, res.initial, res.final):
        click.echo(f"  {name:22s} {a:12.5g} -> {b:12.5g}", err=True)
    click.echo(f"optimiser: {res.message}", err=True)
    header = (f"Calibrated by `empact calibrate {targets}` (max |error| "
              f"{100 * abs(res.relative_error).max():.3f} %).")
    save_params(res.params, out, header=header)
    click.echo(out)
