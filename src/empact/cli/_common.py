"""Shared pieces of the command line (private): the error-converting and lazy groups, JSON
output, common options."""
from __future__ import annotations

import importlib
import json
import math
from typing import Any

import click
import numpy as np

from .._validate import check_number
from ..errors import ParameterError
from ..geometry import check_ratio
from ..params import OperatingPoint, Params, load_params
from ..traction import traction_from_params

__all__ = ["InputError", "ErrorGroup", "LazyGroup", "to_jsonable", "echo_json",
           "params_option", "json_option", "get_params", "operating_point", "OPTION_VARIABLE"]

#: operating-point option -> variable (the same four options on every command)
OPTION_VARIABLE = {"ratio": "r_g", "slip": "nu", "clamp": "F_s", "speed": "omega_p"}


class InputError(click.ClickException):
    """Bad input: one line on stderr, exit status 2."""

    exit_code = 2

    def show(self, file: Any = None) -> None:
        click.echo(f"error: {self.format_message()}", err=True)


class ErrorGroup(click.Group):
    """A group that turns the library's validation errors into `InputError`."""

    def invoke(self, ctx: click.Context) -> Any:
        try:
            return super().invoke(ctx)
        except (ParameterError, ValueError) as exc:
            raise InputError(str(exc).splitlines()[0] if str(exc) else type(exc).__name__) \
                from None


class LazyGroup(ErrorGroup):
    """An `ErrorGroup` whose commands are imported when they run.

    `lazy` maps a command name to ``("module:object", short help)``; ``--help`` of the group
    uses the short help and imports nothing.
    """

    def __init__(self, *args: Any, lazy: dict[str, tuple[str, str]] | None = None,
                 **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.lazy = dict(lazy or {})

    def list_commands(self, ctx: click.Context) -> list[str]:
        return sorted(set(super().list_commands(ctx)) | set(self.lazy))

    def get_command(self, ctx: click.Context, name: str) -> click.Command | None:
        if name not in self.lazy:
            return super().get_command(ctx, name)
        module, attr = self.lazy[name][0].split(":")
        return getattr(importlib.import_module(module), attr)

    def format_commands(self, ctx: click.Context, formatter: click.HelpFormatter) -> None:
        rows = [(name, self.lazy[name][1]) for name in sorted(self.lazy)]
        if rows:
            with formatter.section("Commands"):
                formatter.write_dl(rows)


def to_jsonable(obj: Any) -> Any:
    """numpy arrays and scalars to lists and floats; complex to ``[re, im]``; NaN to None."""
    if isinstance(obj, dict):
        return {str(k): to_jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [to_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return to_jsonable(obj.tolist())
    if isinstance(obj, (complex, np.complexfloating)):
        return [to_jsonable(float(obj.real)), to_jsonable(float(obj.imag))]
    if isinstance(obj, (np.floating, float)):
        return float(obj) if math.isfinite(obj) else None
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, np.bool_):
        return bool(obj)
    return obj


def echo_json(data: Any) -> None:
    """Print `data` as JSON on stdout."""
    click.echo(json.dumps(to_jsonable(data), indent=1))


params_option = click.option("--params", "params_file", type=click.Path(dir_okay=False),
                             default=None, help="TOML parameter file (default: shipped set).")
json_option = click.option("--json", "as_json", is_flag=True, help="Print JSON on stdout.")


def get_params(path: str | None):
    """Load parameters (errors become `InputError` through the group)."""
    return load_params(path)



def operating_point(params: Params, *, trim: bool = False, **options: float | None) \
        -> OperatingPoint:
    """The ``[operating]`` point of `params` with the given options (``ratio``, ``slip``,
    ``clamp``, ``speed``; None keeps the file's value), each checked under its option name.

    With `trim` the point must be one the nonlinear model can be trimmed at: a slip inside the
    traction curve's valid range and a positive clamping force.
    """
    values = {}
    for opt, value in options.items():
        if value is None:
            continue
        name = f"--{opt}"
        if opt == "ratio":
            values["r_g"] = float(check_ratio(check_number(name, value), params.variator, name))
        elif opt == "slip":
            lo, hi = traction_from_params(params).nu_range if trim else (-1.0, 1.0)
            values["nu"] = check_number(name, value, lo, hi, lo_open=not trim,
                                        hi_open=not trim, note="a fraction: 0.01 is 1 %")
        elif opt == "clamp":
            values["F_s"] = check_number(name, value, 0.0, lo_open=trim, unit="N")
        elif opt == "speed":
            values["omega_p"] = check_number(name, value, 0.0, lo_open=True, unit="rad/s")
        else:
            raise KeyError(opt)
    return params.operating.replace(**values)
