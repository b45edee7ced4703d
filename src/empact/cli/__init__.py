"""Command-line interface: a thin layer over the public API.

``empact --help`` lists the commands.  Errors in input (parameter files, options, data) print
one line ``error: ...`` on stderr and exit with status 2; nothing is written then.
"""
from __future__ import annotations

import json
import math
import sys
from typing import Any

import click
import numpy as np

from ..params import ParameterError, load_params

__all__ = ["main"]


class InputError(click.ClickException):
    """Bad input: one line on stderr, exit status 2."""

    exit_code = 2

    def show(self, file: Any = None) -> None:
        click.echo(f"error: {self.format_message()}", err=True)


class _Group(click.Group):
    """Turns the library's validation errors into `InputError`."""

    def invoke(self, ctx: click.Context) -> Any:
        try:
            return super().invoke(ctx)
        except (ParameterError, ValueError) as exc:
            raise InputError(str(exc).splitlines()[0] if str(exc) else type(exc).__name__) \
                from None


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


@click.group(cls=_Group, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="empact")
def main() -> None:
    """empact: dynamic analysis of electromechanically actuated pushbelt CVTs."""


def _register() -> None:
    from . import linear, nonlinear, params_cmd, report_cmd, slip  # noqa: F401
    from . import identification  # noqa: F401


_register()

if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
