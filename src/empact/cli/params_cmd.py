"""``empact params show`` and ``empact params validate``."""
from __future__ import annotations

import click

from ..params import describe_parameters, dumps_params, load_params
from ._common import ErrorGroup, get_params


@click.group("params", cls=ErrorGroup)
def params_group() -> None:
    """Show and validate parameter files."""


@params_group.command("show")
@click.argument("file", required=False, type=click.Path(dir_okay=False))
@click.option("--describe", is_flag=True, help="List every key with its unit, allowed range, "
              "meaning, value, plausible band and source.")
def show(file: str | None, describe: bool) -> None:
    """Print the complete parameter set of FILE (default: the shipped set) as TOML.

    FILE's values are range-checked; ``empact params validate FILE`` also checks the models
    they define."""
    params = load_params(file)
    if describe:
        for p in describe_parameters(params):
            value = "not set" if p.value is None else f"{p.value:.6g}"
            band = "" if p.band[0] != p.band[0] else f"; plausible [{p.band[0]:g}, " \
                f"{p.band[1]:g}]"
            click.echo(f"{p.name} [{p.unit}] = {value}{band}; allowed {p.allowed}: {p.doc}"
                       + (f" (source: {p.source})" if p.source else ""))
        return
    click.echo(dumps_params(params), nl=False)


@params_group.command("validate")
@click.argument("file", type=click.Path(dir_okay=False))
def validate(file: str) -> None:
    """Check FILE as every command does (values, ranges and the models they define); exit 0
    and print 'FILE: ok' if it is acceptable, else one line and exit 2.  A value outside its
    plausible band (``params show --describe``) is accepted and listed, each by its dotted
    name with what it is for (``driveline.k_belt`` is not ``actuation.k_belt``)."""
    params = get_params(file)
    odd = [p for p in describe_parameters(params)
           if p.value is not None and p.band[0] == p.band[0]
           and not p.band[0] <= p.value <= p.band[1]]
    click.echo(f"{file}: ok" + (f" ({len(odd)} value{'s' * (len(odd) > 1)} outside the "
                                "plausible band, below)" if odd else ""))
    for p in odd:
        click.echo(f"  {p.name} = {p.value:.6g} [{p.unit}]: outside the plausible band "
                   f"[{p.band[0]:g}, {p.band[1]:g}] [{p.unit}]; {p.doc}")
