"""Shared pieces of the command line (private): the error-converting and lazy groups, one-line
errors, output paths checked before work, JSON with schema and units, common options.

Exit status: 0 success; 2 bad input (one line ``error: ...`` on stderr, nothing written);
1 a computation that ran but did not succeed (a simulation that stopped early, a calibration
that misses its targets), with one line saying why; 130 interrupted (Ctrl-C: one line
``error: interrupted``, nothing written).

Every option and argument of every command the groups hand out is guarded while it is parsed
(`guard_params`, installed by `_checked`): an empty value is an error naming the option, and
the value of every path option goes through one check (`check_path`) that turns what the
system would refuse later (a name too long, a FIFO or device, a folder that cannot be
searched) into one line.  Output files are declared with the `OutputFile` type; before a
command's body runs, one check (`check_outputs`) refuses any of them that exists (a symbolic
link too, dangling or not) unless ``--force``, has the wrong suffix, is not a regular file,
cannot be created (no permission, a read-only or full file system), or names the same file as
another output of the command.  After the body, one closing line on stderr names every file
the command wrote (`closing_line`: ``written: sim/run.csv, sim/run.png``; what `empact._io`'s
atomic writers moved into place meanwhile, `empact._io.recording`), so no command names its
outputs itself.  A new command or option gets these checks and the closing line without a
line of its own (tests/test_cli.py and tests/test_speaking.py walk every registered command
and option).
"""
from __future__ import annotations

import functools
import importlib
import inspect
import json
import os
import stat
import sys
import tempfile
from dataclasses import replace
from pathlib import Path
from typing import Any, Callable, Mapping, Sequence

import click
import numpy as np

from .._io import NAME_MAX, atomic_write_text, file_kind, recording
from .._validate import check_choice, check_int, check_number, check_values
from ..errors import ParameterError
from ..export import jsonable as to_jsonable
from ..params import OperatingPoint, Params, check_clamping, check_one_slip, load_params
from ..variator.geometry import check_ratio
from ..variator.traction import traction_from_params

__all__ = ["sweep_options", "sweep_from_options",
           "InputError", "Failed", "ErrorGroup", "LazyGroup", "to_jsonable", "emit_json",
           "params_option", "json_options", "force_option", "get_params", "operating_point",
           "operating_values", "PLOT_SUFFIXES", "LINEAR_OPTIONS",
           "output_file", "output_folder", "OPTION_VARIABLE", "UNITS", "JSON_VERSION",
           "OutputFile", "check_outputs", "quiet_option", "Interrupted",
           "EXIT_INTERRUPTED", "parse_list", "formats_option", "parse_choices", "schema_version",
           "traction_option", "check_path", "compact_json", "closing_line", "written_line",
           "guard_params", "shown_path", "MIN_FREE_BYTES", "OPERATING_RANGES", "loss_map_option",
           "announce_compilation", "COMPILING"]

#: suffixes of ``--plot`` files (the figure's format)
PLOT_SUFFIXES = ("png", "svg", "pdf")

#: operating-point option -> variable (the same options on every command)
OPTION_VARIABLE = {"ratio": "r_g", "slip": "nu", "clamp": "F_s", "speed": "omega_p",
                   "tau": "tau", "load-torque": "T_l"}
#: the options of the linear slip model's commands (a point given by slip and clamping force)
LINEAR_OPTIONS = ("ratio", "slip", "clamp", "speed")
#: the range of each operating variable any command takes (`operating_values`, the grids of
#: `plants` and `control design`, `efficiency`, `control discretize --at`): beyond every
#: pushbelt CVT (19 000 rpm, 1 MN of clamping, 10 kN m of torque), so that a value outside is
#: a typing error, refused before any work; the model's own limits (the variator's ratios,
#: the traction curve's slip range) are checked besides
OPERATING_RANGES = {"r_g": (0.0, 10.0), "nu": (-0.5, 0.5), "tau": (-1.0, 1.0),
                    "F_s": (0.0, 1e6), "omega_p": (0.0, 2000.0), "T_l": (-1e4, 1e4)}

def _one_line(text: str) -> str:
    return " ".join(str(text).split())


class InputError(click.ClickException):
    """Bad input: one line on stderr, exit status 2."""

    exit_code = 2

    def show(self, file: Any = None) -> None:
        click.echo(f"error: {_one_line(self.format_message())}", err=True)


class Failed(click.ClickException):
    """A computation that ran but did not succeed: one line on stderr, exit status 1."""

    exit_code = 1

    def show(self, file: Any = None) -> None:
        click.echo(f"error: {_one_line(self.format_message())}", err=True)


#: exit status of an interrupted command (128 + SIGINT, as a shell reports it)
EXIT_INTERRUPTED = 130


class Interrupted(click.ClickException):
    """Ctrl-C (SIGINT): one line on stderr, exit status 130; nothing was written (every
    output is moved into place only when complete), except what `kept` names (a streamed
    study's completed shards, kept for ``--resume``)."""

    exit_code = EXIT_INTERRUPTED

    def __init__(self, kept: str = "") -> None:
        super().__init__("interrupted")
        self.kept = kept

    def show(self, file: Any = None) -> None:
        click.echo("error: interrupted" + (f"; {self.kept}" if self.kept else ""), err=True)


#: the line a first run prints when numba compiles the model (its cache is cold)
COMPILING = ("compiling the model (a first run: numba compiles it once, 10 to 30 s; later runs "
             "load it from the cache)")

#: the commands that run the compiled nonlinear model (by their last name)
MODEL_COMMANDS = {"simulate", "linearize", "nmp", "identify", "rig", "reproduce", "plants",
                  "montecarlo", "design", "efficiency"}

_announced: Any = None  # a flag shared with forked workers (they compile too)


def announce_compilation() -> None:
    """Print `COMPILING` on stderr, once (in this process and the processes it forks), when
    numba starts compiling a function of empact: numba compiles only on a cache miss (its
    ``numba:compile`` event), i.e. on a first run or after the code changed, and a progress
    bar's estimate means nothing meanwhile."""
    global _announced
    if _announced is not None:
        return
    import multiprocessing

    from numba.core import event
    from tqdm import tqdm

    _announced = multiprocessing.RawValue("b", 0)

    class _Notice(event.Listener):
        def on_start(self, ev: Any) -> None:
            fn = getattr(ev.data.get("dispatcher"), "py_func", None)
            module = getattr(fn, "__module__", None) or ""  # None for generated functions
            if module.startswith("empact.") and not _announced.value:
                _announced.value = 1
                tqdm.write(COMPILING, file=sys.stderr)  # (a bar on a terminal is redrawn)

        def on_end(self, ev: Any) -> None:
            pass

    event.register("numba:compile", _Notice())


def shown_path(value: str, most: int = 60) -> str:
    """`value` as an error line shows it: a long name shortened to its start and its length.

    Parameters
    ----------
    value : str
        A path as given.
    most : int
        Longest value shown whole [characters].

    Returns
    -------
    str
        `value`, or its first ``most / 2`` characters and its length.
    """
    return value if len(value) <= most else f"{value[:most // 2]}...({len(value)} characters)"


def _is_empty(value: Any) -> bool:
    if isinstance(value, str):
        return not value.strip()
    if isinstance(value, (tuple, list)):
        return any(isinstance(v, str) and not v.strip() for v in value)
    return False


def check_path(value: str, option: str) -> None:
    """One check for the value of every path option and argument, input or output, while the
    command line is parsed: refuse, in one line naming the option, a file name longer than the
    file system allows, a path the system cannot look at (a component that is a file, no
    permission to search a folder) and a FIFO, device or socket (reading one blocks or never
    ends, replacing one is never meant).  A missing file passes (the reader or
    `check_outputs` says what it needs).

    Parameters
    ----------
    value : str
        The path as given.
    option : str
        The option's name, for the message (``--out``); empty for an argument.
    """
    what = f"{option} {shown_path(value)}" if option else shown_path(value)
    for part in Path(value).parts:
        n = len(part.encode(errors="surrogateescape"))
        if n > NAME_MAX:
            raise InputError(f"{what}: a file name of {n} bytes; file names hold at most "
                             f"{NAME_MAX}")
    try:
        st = os.stat(value)
    except (FileNotFoundError, NotADirectoryError) as exc:
        if isinstance(exc, NotADirectoryError):
            raise InputError(f"{what}: a part of the path is a file, not a folder") from None
        return
    except OSError as exc:
        raise InputError(f"{what}: {(exc.strerror or 'cannot be used').lower()}") from None
    if not (stat.S_ISREG(st.st_mode) or stat.S_ISDIR(st.st_mode)):
        raise InputError(f"{what}: is {file_kind(st.st_mode)}, not a file; name a regular "
                         "file")


def guard_params(cmd: click.Command) -> click.Command:
    """Install the parse-time guards on every parameter of `cmd` (once): an empty value
    (``--out ''``) is an error naming the option, and every `click.Path` value goes through
    `check_path`; the parameter's own callback runs after them.

    Parameters
    ----------
    cmd : click.Command
        The command (its parameters are changed in place).

    Returns
    -------
    click.Command
        `cmd`.
    """
    for param in cmd.params:
        if getattr(param, "_guarded", False) or getattr(param, "is_flag", False):
            continue
        own = param.callback
        name = max(param.opts, key=len) if isinstance(param, click.Option) else \
            (param.name or "").upper()
        is_path = isinstance(param.type, click.Path)

        def guarded(ctx: click.Context, prm: click.Parameter, value: Any, *, _own: Any = own,
                    _name: str = name, _path: bool = is_path) -> Any:
            source = ctx.get_parameter_source(prm.name or "")
            given = source in (click.core.ParameterSource.COMMANDLINE,
                               click.core.ParameterSource.ENVIRONMENT)
            if given and _is_empty(value):
                raise InputError(f"{_name}: an empty value; give a value or leave the option "
                                 "out")
            if given and _path and value is not None:
                for v in value if isinstance(value, (tuple, list)) else (value,):
                    check_path(str(v), _name if isinstance(prm, click.Option) else "")
            return _own(ctx, prm, value) if _own is not None else value

        param.callback = guarded
        param._guarded = True  # type: ignore[attr-defined]
    return cmd


#: files of one folder a closing line names one by one; beyond, it counts them by suffix
MOST_NAMED = 6


def _shown(path: Path) -> str:
    """`path` as the closing line shows it: relative to the current folder when inside it."""
    rel = os.path.relpath(path)
    return path.as_posix() if rel.startswith("..") else Path(rel).as_posix()


def written_line(paths: Sequence[os.PathLike[str] | str]) -> str:
    """The closing line of a command that wrote `paths`: ``written: A, B, ...``, each file
    relative to the current folder when inside it, in the order written; a folder that holds
    more than `MOST_NAMED` of them is named once with its files counted by suffix (a file whose
    suffix is its own in that folder is still named): ``written: report/ (index.html,
    claims.json, 40 .csv files, 57 .png files)``.

    Parameters
    ----------
    paths : sequence of path-like
        The files written (absolute or relative to the current folder).

    Returns
    -------
    str
        The line (empty when `paths` is).
    """
    groups: dict[Path, list[Path]] = {}
    for path in dict.fromkeys(Path(p).absolute() for p in paths):
        groups.setdefault(path.parent, []).append(path)
    parts: list[str] = []
    for folder, files in groups.items():
        if len(files) <= MOST_NAMED:
            parts.extend(_shown(f) for f in files)
            continue
        by_suffix: dict[str, list[Path]] = {}
        for f in files:
            by_suffix.setdefault(f.suffix or "(no suffix)", []).append(f)
        items = [fs[0].name if len(fs) == 1 else f"{len(fs)} {suffix} files"
                 for suffix, fs in sorted(by_suffix.items(), key=lambda kv: len(kv[1]))]
        parts.append(f"{_shown(folder).rstrip('/')}/ ({', '.join(items)})")
    return f"written: {', '.join(parts)}" if parts else ""


def closing_line(paths: Sequence[os.PathLike[str] | str]) -> None:
    """After a command ran (done, or failed after writing: exit 1): one line on stderr naming
    every file it wrote (`written_line`; the commands record them through `empact._io`'s
    writers, `empact._io.recording`), nothing when it wrote nothing.  `_checked` prints it for
    every command, unless ``--quiet``.

    Parameters
    ----------
    paths : sequence of path-like
        The files written.
    """
    line = written_line(paths)
    if line:
        click.echo(line, err=True)


def _checked(cmd: click.Command | None) -> click.Command | None:
    """`cmd` with its parameters guarded (`guard_params`), `check_outputs` run before its
    body, and for a command of the model `announce_compilation` (installed once, on every
    command the groups hand out, so that no command can forget it)."""
    if cmd is not None:
        guard_params(cmd)
    if cmd is None or cmd.callback is None or getattr(cmd.callback, "_outputs_checked", False) \
            or isinstance(cmd, click.Group):  # (a group's callback only hands over)
        return cmd
    body = cmd.callback
    takes_quiet = "quiet" in inspect.signature(body).parameters
    if not any(p.name == "quiet" for p in cmd.params):  # --quiet on every command
        cmd.params.append(click.Option(["--quiet"], is_flag=True,
                                       help="Nothing on stderr but errors (no progress)."))

    @functools.wraps(body)
    def run(*args: Any, **kwargs: Any) -> Any:
        ctx = click.get_current_context()
        check_outputs(ctx)
        quiet = bool(kwargs.get("quiet")) if takes_quiet else bool(kwargs.pop("quiet", False))
        if ctx.command.name in MODEL_COMMANDS and not quiet:
            announce_compilation()
        from .._progress import working

        name = ctx.command_path.split(" ", 1)[-1]
        with recording() as written:
            try:
                with working(name, enabled=not quiet):  # until a bar of the command's own
                    result = body(*args, **kwargs)
            except Failed:  # ran, did not succeed: it may have written (with --strict)
                if not quiet:
                    closing_line(list(written))
                raise
        if not quiet:
            closing_line(list(written))
        return result

    run._outputs_checked = True  # type: ignore[attr-defined]
    cmd.callback = run
    return cmd


class ErrorGroup(click.Group):
    """A group that turns the library's validation errors into `InputError` and Ctrl-C into
    `Interrupted`; every command it hands out checks its output files first
    (`check_outputs`)."""

    def get_command(self, ctx: click.Context, name: str) -> click.Command | None:
        return _checked(super().get_command(ctx, name))

    def invoke(self, ctx: click.Context) -> Any:
        try:
            return super().invoke(ctx)
        except (ParameterError, ValueError) as exc:
            raise InputError(str(exc) or type(exc).__name__) from None
        except KeyboardInterrupt:
            raise Interrupted() from None
        except OSError as exc:  # the system refused mid-run (a disk that filled up, ...)
            where = f"{exc.filename}: " if exc.filename else ""
            raise Failed(f"{where}{(exc.strerror or 'system error').lower()}; nothing "
                         "written") from None


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
        return _checked(getattr(importlib.import_module(module), attr))

    def format_commands(self, ctx: click.Context, formatter: click.HelpFormatter) -> None:
        rows = [(name, self.lazy[name][1]) for name in sorted(self.lazy)]
        if rows:
            with formatter.section("Commands"):
                formatter.write_dl(rows)

    def main(self, args: Any = None, prog_name: str | None = None,
             complete_var: str | None = None, standalone_mode: bool = True,
             **extra: Any) -> Any:
        """Run; every error is one line ``error: ...`` on stderr (click's usage errors too)."""
        if not standalone_mode:
            return super().main(args, prog_name, complete_var, False, **extra)
        try:
            rv = super().main(args, prog_name, complete_var, False, **extra)
        except click.UsageError as exc:
            if isinstance(exc, click.exceptions.NoArgsIsHelpError) and exc.ctx is not None:
                click.echo(exc.ctx.get_help(), err=True)  # a group alone: its usage
                sys.exit(2)
            cmd = exc.ctx.command_path if exc.ctx is not None else "empact"
            msg = _one_line(exc.format_message()).rstrip(".")
            click.echo(f"error: {cmd}: {msg[:1].lower()}{msg[1:]} (see '{cmd} --help')",
                       err=True)
            sys.exit(2)
        except click.ClickException as exc:
            exc.show()
            sys.exit(exc.exit_code)
        except click.exceptions.Abort as exc:
            if isinstance(exc.__cause__, KeyboardInterrupt):  # Ctrl-C outside a command
                Interrupted().show()
                sys.exit(EXIT_INTERRUPTED)
            click.echo("error: aborted", err=True)
            sys.exit(1)
        sys.exit(rv if isinstance(rv, int) else 0)


#: Version of the JSON documents the commands print (``schema.version``), unless
#: `SCHEMA_VERSIONS` names another for a schema.
JSON_VERSION = 1

#: Schemas whose keys or units changed since version 1 (the README's interchange section says
#: what changed): ``control.simulate`` 2 and ``montecarlo`` 2, slips as fractions
#: (``slip_error``, ``peak_slip``, ``slip_setpoint`` [-] in place of ``slip_error_pp``
#: [percentage points], ``peak_slip_pp``, ``slip_setpoint_pp`` [%]); ``control.simulate`` 3,
#: the targets named as the metrics (``targets[].name`` ``peak_slip_error``, ``slip_error``
#: in place of ``peak_slip_error_pp``, ``slip_error_pp``).
SCHEMA_VERSIONS = {"control.simulate": 3, "montecarlo": 2}


def schema_version(schema: str) -> int:
    """The version of JSON schema ``empact.<schema>``."""
    return SCHEMA_VERSIONS.get(schema, JSON_VERSION)



#: Units of every quantity key that appears in the commands' JSON (SI; complex numbers are
#: ``[re, im]`` pairs; arrays keep the unit of their elements).
UNITS = {
    "r_g": "-", "nu": "-", "F_s": "N", "F_p": "N", "omega_p": "rad/s", "omega_s": "rad/s",
    "T_b": "N m", "T_d": "N m", "T_l": "N m", "T_mp": "N m", "T_ms": "N m", "mu": "-",
    "dmu": "-", "c_b": "N m s/rad", "c_s": "N m s/rad", "g_F": "m",
    "frequencies_hz": "Hz", "uncoupled_hz": "Hz", "coupled_hz": "Hz", "zeros_hz": "Hz",
    "fs_hz": "Hz", "magnitude_db": "dB (re 1 output unit per input unit)", "phase_deg": "deg",
    "H": "output unit per input unit, complex as [re, im]",
    "poles": "rad/s, complex as [re, im]", "poles_z": "- (z-plane), complex as [re, im]",
    "zeros": "rad/s, complex as [re, im]",
    "rhp_zeros": "rad/s, complex as [re, im]", "start": "rad/s, complex as [re, im]",
    "end": "rad/s, complex as [re, im]", "branches": "rad/s, complex as [re, im]",
    "max_real": "1/s", "min_damping": "-", "unstable_fraction": "-",
    "energy_fraction": "- (signed: the sign of the spring's elongation in the mode shape; the "
                       "magnitudes of a mode sum to 1)",
    "shapes": "SI of each coordinate (mass-normalised)", "normalised_shapes": "-",
    "mass_matrix": "kg, kg m^2", "stiffness_matrix": "N/m, N m/rad", "coherence": "-",
    "multiple_coherence": "-", "fit_percent": "%", "singular_values": "-",
    "delta_x": "m", "delta": "m", "dL_exact": "m", "dL_first_order": "m",
    "A": "SI (states, inputs and outputs in their units)", "B": "SI", "C": "SI", "D": "SI",
    "values": "unit of the swept variable", "mu_peak": "-", "nu_peak": "-", "nu_range": "-",
    "residual": "-", "coulomb_sp": "N m", "coulomb_ss": "N m", "coulomb_omega": "rad/s",
    "drive_bandwidth_hz": "Hz", "load_bandwidth_hz": "Hz", "ratio_bandwidth_hz": "Hz",
    "step": "N m", "tau": "-",
    "omega_p_fixed": "rad/s", "wall_time_s": "s", "max_real_pole": "1/s", "disk_margin": "-",
    "gain_margin_db": "dB", "phase_margin_deg": "deg", "kp": "N m per unit error",
    "ki": "N m/s per unit error", "wi_rad_s": "rad/s", "crossover_hz": "Hz", "roll_off_hz": "Hz",
    "kappa": "-", "bandwidth_scale": "-", "alpha_min": "-", "gamma": "-", "gamma_opt": "-",
    "bandwidth_hz": "Hz", "f_keep_hz": "Hz", "omega_peak": "rad/s",
    "captured": "-", "slip_error": "-", "peak_slip": "-", "slip_setpoint": "-",
    "peak_slip_error": "-", "slip_reserve": "-", "min_clamping_force": "N",
    "max_clamping_force": "N", "peak_T_mp": "N m", "peak_T_ms": "N m", "T_mp_max": "N m",
    "T_ms_max": "N m", "saturated": "-", "servo_capacity_force": "N",
    "torque_request_min": "N m", "torque_request_exceeded": "-", "torque_limited": "-",
    "torque_reduction": "N m", "torque_limited_time": "s",
    "ratio_error": "-", "ratio_rate": "1/s", "ratio_span": "-",
    "mean_clamping_force": "N", "mean_slip_power": "W", "mean_actuation_power": "W",
    "mean_losses": "W", "shape": "-", "points": "-", "trimmed": "-",
    "f_slow_hz": "Hz", "zeta_slow": "-", "n_rhp_zeros": "-", "rhp_zero_hz": "Hz", "runs": "-",
    "succeeded": "-", "failures": "-",
    "T_in": "N m", "omega_in": "rad/s", "P_in": "W", "P_out": "W", "losses": "W",
    "actuation": "W", "efficiency": "-", "total_efficiency": "-",
    "energy": "J (every term)", "energy_balance_residual": "- (relative to the input energy)",
    "duration": "s",
    "ms": "-", "ms_above_2": "-", "bandwidth_floor_hz": "Hz", "max_ms": "-",
    "multipliers": "-", "evaluations": "-",
    "distance_m": "m", "duration_s": "s", "wheel_energy_J": "J", "energy_J": "J (every term)",
    "engine_J": "J", "fuel_g": "g", "fuel_l_per_100km": "l/100 km",
    "saving": "- (fraction of the reference's fuel)", "variator_efficiency": "-",
    "transmission_efficiency": "-", "engine_short": "- (samples)",
    "speed_error_max_kmh": "km/h", "belt_slack": "-", "variator_loss_J": "J",
    "quasi_static_variator_loss_J": "J", "dynamic_J": "J (every term)",
    "quasi_static_J": "J (every term)", "v_launch_m_s": "m/s", "dynamic_duration_s": "s",
    "rate_hz": "Hz", "stretches": "s", "n_steps": "-",
}


def compact_json(doc: Any, indent: str = "") -> str:
    """JSON text with one key a line, but a list of numbers (or of ``[re, im]`` pairs, or
    strings) on one line: `json.dumps` with ``indent`` put every number on a line of its own
    (``slip poles --json``: 1992 lines).

    Parameters
    ----------
    doc : object
        A JSON-able document (`to_jsonable`).
    indent : str
        The indent of the line `doc` starts on.

    Returns
    -------
    str
        The JSON text (`json.loads` reads back `doc`).
    """
    inner = indent + " "
    if isinstance(doc, dict):
        if not doc:
            return "{}"
        items = (f"{inner}{json.dumps(str(k))}: {compact_json(v, inner)}"
                 for k, v in doc.items())
        return "{\n" + ",\n".join(items) + f"\n{indent}}}"
    if isinstance(doc, list):
        def flat(x: Any) -> bool:
            return not isinstance(x, (dict, list)) or (
                isinstance(x, list) and all(not isinstance(y, (dict, list)) for y in x))
        if all(flat(x) for x in doc):
            return json.dumps(doc, separators=(", ", ": "))
        return "[\n" + ",\n".join(inner + compact_json(x, inner) for x in doc) + f"\n{indent}]"
    return json.dumps(doc)


def emit_json(data: Mapping[str, Any], schema: str, json_out: str | None = None) -> None:
    """Print (or, with `json_out`, write atomically) one JSON object: ``schema`` (name and
    version), ``units`` of every quantity key present, then `data`."""
    keys: set[str] = set()

    def collect(o: Any) -> None:
        if isinstance(o, Mapping):
            for k, v in o.items():
                keys.add(str(k))
                collect(v)
        elif isinstance(o, (list, tuple)):
            for v in o:
                collect(v)

    collect(data)
    doc = {"schema": {"name": f"empact.{schema}", "version": schema_version(schema)},
           "units": {k: UNITS[k] for k in sorted(keys) if k in UNITS}, **data}
    text = compact_json(to_jsonable(doc))
    if json_out is None:
        click.echo(text)
    else:
        atomic_write_text(json_out, text + "\n")


params_option = click.option("--params", "params_file", type=click.Path(dir_okay=False),
                             default=None, help="TOML parameter file (default: shipped set).")
force_option = click.option("--force", is_flag=True,
                            help="Replace existing output (in a folder: only empact's own "
                                 "files).")
quiet_option = click.option("--quiet", is_flag=True, help="No progress bar on stderr.")


def _load_traction(ctx: click.Context, param: click.Parameter, value: str | None) -> Any:
    """``--traction FILE`` read while the options are parsed (before any work): a bad table is
    one line and exit 2."""
    if value is None:
        return None
    from ..variator.traction import load_traction

    try:
        return load_traction(value)
    except ParameterError as exc:
        raise InputError(f"--traction: {exc}") from None


#: ``--traction FILE``: measured traction curves for every command that builds a traction
#: model (the slip commands, the nonlinear model's); the value (``traction_table``) is a
#: `TabulatedTraction` or None
traction_option = click.option(
    "--traction", "traction_table", type=click.Path(dir_okay=False), default=None,
    callback=_load_traction,
    help="Measured traction curves mu(nu, r_g): .csv (columns r_g,nu,mu) or .toml "
         "([[curve]] tables); default: the analytic magic formula of [traction].")


def _load_loss_map(ctx: click.Context, param: click.Parameter, value: str | None) -> Any:
    """``--loss-map FILE`` read while the options are parsed (before any work): a bad map is
    one line and exit 2."""
    if value is None:
        return None
    from ..variator.losses import load_loss_map

    try:
        return load_loss_map(value)
    except ParameterError as exc:
        raise InputError(f"--loss-map: {exc}") from None


#: ``--loss-map FILE``: a measured torque-loss map for every command that builds the
#: nonlinear model (its trims, simulations, efficiency maps and drive cycles); the value
#: (``loss_map``) is a `LossMap` or None, applied to the parameter set (`get_params`)
loss_map_option = click.option(
    "--loss-map", "loss_map", type=click.Path(dir_okay=False), default=None,
    callback=_load_loss_map,
    help="Measured torque-loss map T_loss(r_g, omega_in, T_in, F_s): .csv (columns "
         "r_g,omega_in,T_in,F_s and T_loss [N m] or efficiency [-], a full grid); replaces "
         "the parameter file's [losses] terms (clamping, load, drag); default: those.")
formats_option = click.option(
    "--formats", default="png", show_default=True,
    help="Figure formats, comma-separated: png, svg, pdf (png,svg or png,pdf adds vector "
         "figures for print).")


def parse_choices(option: str, text: str, allowed: Sequence[str]) -> tuple[str, ...]:
    """The comma-separated choices of an option (``--formats png,svg``, ``--sections
    table1,fig9``), each once, in the order given; an unknown one is one line naming the
    option and what it allows."""
    return tuple(dict.fromkeys(check_choice(option, f.strip(), allowed)
                               for f in text.split(",")))


class OutputFile(click.Path):
    """The type of an option that names an output file: `check_outputs` checks it before the
    command runs.

    Parameters
    ----------
    suffixes : the allowed suffixes without the dot (None: any); the file's format follows
        its suffix
    format_param : the name of a ``--format`` parameter of the same command; when given, the
        suffix must be that format's
    """

    def __init__(self, suffixes: tuple[str, ...] | None = None,
                 format_param: str | None = None) -> None:
        super().__init__(dir_okay=False)
        self.suffixes = suffixes
        self.format_param = format_param


def check_outputs(ctx: click.Context) -> None:
    """Check every `OutputFile` option given to the command of `ctx` (`output_file`: suffix,
    folder, existence unless the command's ``--force``); refuse two options naming one file.
    Runs before the command's body (the groups install it, `ErrorGroup`)."""
    force = bool(ctx.params.get("force", False))
    seen: dict[str, str] = {}
    for param in ctx.command.params:
        value = ctx.params.get(param.name or "")
        if not isinstance(param.type, OutputFile) or value is None:
            continue
        option = max(param.opts, key=len)
        suffixes = param.type.suffixes
        fmt = ctx.params.get(param.type.format_param) if param.type.format_param else None
        if fmt is not None:
            suffix = Path(value).suffix.lstrip(".").lower()
            if suffix != fmt:
                shown = f".{suffix}" if suffix else "none"
                raise InputError(f"{option} {value}: file suffix {shown!r} does not match "
                                 f"--format {fmt} (name the file "
                                 f"{Path(value).with_suffix('.' + fmt).name}, or drop --format: "
                                 "the format follows the suffix)")
        output_file(value, option, force=force, suffixes=suffixes)
        key = os.path.realpath(value)
        if key in seen:
            raise InputError(f"{option} {value}: the same file as {seen[key]}; give each output "
                             "its own file")
        seen[key] = option


def json_options(fn: Callable) -> Callable:
    """``--json`` (print JSON on stdout) and ``--json-out FILE`` (write it atomically; a
    ``.json`` file, new unless ``--force``)."""
    fn = click.option("--json-out", "json_out", type=OutputFile(("json",)), default=None,
                      help="Write the JSON to FILE.json (atomically) instead of stdout; an "
                           "existing file only with --force.")(fn)
    return click.option("--json", "as_json", is_flag=True, help="Print JSON on stdout.")(fn)


def sweep_options(fn: Callable) -> Callable:
    """``--scheduler none|local|ADDRESS``, ``--workers N`` and ``--scheduler-timeout S``."""
    fn = click.option("--scheduler-timeout", "scheduler_timeout", type=float, default=10.0,
                      show_default=True, help="Seconds to wait for a scheduler ADDRESS.")(fn)
    fn = click.option("--workers", type=int, default=None,
                      help="Worker processes: forked on this machine (--scheduler none; 1 "
                           "computes in this process; 'slip map' uses this many threads) "
                           "or of --scheduler local; default: one per core.")(fn)
    fn = click.option("--scheduler", default="none", show_default=True,
                      metavar="none|local|ADDRESS",
                      help="Where the sweep runs: this machine (--workers forked "
                           "processes), a local Dask cluster, or a running Dask scheduler "
                           "(tcp://host:8786); Dask is the optional 'dask' extra.")(fn)
    return fn


def sweep_from_options(scheduler: str, workers: int | None, timeout: float,
                       progress: bool | None = None):
    """The `empact.sweep.SweepOptions` of the sweep options (each checked under its name);
    a progress bar on stderr unless `progress` is false (off a terminal the bar writes lines
    only once the sweep has run a second: `empact._progress`); on this machine
    (``--scheduler none``) the workers default to one forked process per core."""
    from ..sweep import SweepOptions

    if workers is not None:
        check_int("--workers", workers, 1, 256)
    check_number("--scheduler-timeout", timeout, 0.1, 3600.0, unit="s")
    if progress is None:
        progress = True
    if workers is None and scheduler.strip() == "none":  # parallel by default: forked workers
        workers = os.cpu_count() or 1
    return SweepOptions(scheduler=scheduler, workers=workers, timeout=timeout,
                        progress=progress)


def parse_list(text: str, option: str, *, most: int, example: str = "0.5,1,2") -> list[float]:
    """A comma-separated list of finite numbers (``--ratios 0.5,1,2``), as every command reads
    one: an empty item, a non-number or more than `most` values is one line naming the
    option."""
    items = text.split(",")
    if any(not x.strip() for x in items):
        raise InputError(f"{option} {text!r}: an empty item; give comma-separated numbers, "
                         f"e.g. {example}")
    try:
        values = [float(x) for x in items]
    except ValueError:
        raise InputError(f"{option} {text!r}: must be comma-separated numbers, e.g. "
                         f"{example}") from None
    if not all(np.isfinite(values)):
        raise InputError(f"{option} {text!r}: values must be finite")
    if len(values) > most:
        raise InputError(f"{option} {text!r}: {len(values)} values; give 1 to {most}")
    return values


def get_params(path: str | None, loss_map: Any = None) -> Params:
    """Load parameters and check their physical plausibility (`empact.plausibility`, imported
    here: it builds the linear models, which ``empact --help`` should not load); a measured
    `loss_map` (``--loss-map``) replaces the file's losses."""
    from ..plausibility import check_plausible

    params = check_plausible(load_params(path), str(path) if path else "default.toml")
    if loss_map is not None:
        params = replace(params, loss_map=loss_map, loss_map_file=loss_map.source)
    return params


#: least free space in an output's file system before a command starts [bytes]
MIN_FREE_BYTES = 2**20


def _probe(folder: Path, what: str) -> None:
    """Refuse unless a file can be created in `folder` and its file system has
    `MIN_FREE_BYTES` free."""
    try:
        fd, tmp = tempfile.mkstemp(dir=folder, prefix=".empact-probe-")
        os.close(fd)
        os.unlink(tmp)
        fs = os.statvfs(folder)
    except OSError as exc:
        raise InputError(f"{what}: cannot write in {folder} "
                         f"({(exc.strerror or 'error').lower()})") from None
    free = fs.f_bavail * fs.f_frsize
    if free < MIN_FREE_BYTES:
        raise InputError(f"{what}: the disk holding {folder} is full ({free // 1024} KiB "
                         "free)")


def output_file(path: str | None, option: str, *, force: bool = False,
                suffixes: tuple[str, ...] | None = None) -> Path | None:
    """Check an output file before any work: its suffix is one of `suffixes` (if given), its
    folder exists and is writable, it is not a folder, and it does not exist unless `force`."""
    if path is None:
        return None
    p = Path(path)
    check_path(path, option)
    what = f"{option} {shown_path(path)}"
    if suffixes is not None and p.suffix.lstrip(".").lower() not in suffixes:
        raise InputError(f"{what}: file suffix {p.suffix or 'none'!r} must be one of "
                         f"{', '.join('.' + s for s in suffixes)}")
    if p.is_dir():
        raise InputError(f"{what}: is a folder, not a file")
    if p.is_symlink() and not force:  # dangling or not: replacing it loses the link
        raise InputError(f"{what}: exists (a symbolic link); give --force to replace it")
    if p.exists() and not force:
        raise InputError(f"{what}: exists; give --force to replace it")
    parent = p.parent if str(p.parent) else Path(".")
    if not parent.is_dir():
        raise InputError(f"{what}: folder {parent} does not exist")
    _probe(parent, what)
    return p


def output_folder(path: str, option: str = "--out", *, force: bool = False) -> Path:
    """Check an output folder before any work: not the current folder or one of its parents,
    not a file, empty or new unless `force` (then only empact's own files are replaced), and
    in a writable place."""
    check_path(path, option)
    what = f"{option} {shown_path(path)}"
    if Path(path).is_symlink() and not Path(path).exists():
        raise InputError(f"{what}: a dangling symbolic link; remove it or name a new folder")
    p = Path(path).resolve()
    cwd = Path.cwd().resolve()
    if p == cwd or p in cwd.parents:
        raise InputError(f"{what}: the current folder and its parents are never output "
                         "folders; name a new folder")
    if p.exists() and not p.is_dir():
        raise InputError(f"{what}: is a file, not a folder")
    if p.is_dir() and any(p.iterdir()) and not force:
        raise InputError(f"{what}: folder exists and is not empty; give --force to replace "
                         "empact's own files in it")
    existing = p
    while not existing.exists():
        existing = existing.parent
    if not existing.is_dir():
        raise InputError(f"{what}: {existing} is a file")
    _probe(existing, what)
    return p



def operating_values(params: Params, option: str, values: Any, *, trim: bool = False,
                     traction: Any = None) -> np.ndarray:
    """Values of one operating-point option (``ratio``, ``slip``, ``clamp``, ``speed``,
    ``tau``, ``load-torque``), checked under the option's name (``--slip = 0.5: ...``).

    The slip must lie in the traction curve's valid range (`traction`, default the table
    `params` names, else its analytic curve); with `trim` (a point the nonlinear model is
    trimmed at) the clamping force must be positive.
    """
    name = f"--{option}"
    if option == "ratio":
        return check_ratio(check_values(name, values, 0.0, lo_open=True), params.variator, name)
    if option == "slip":
        tr = traction if traction is not None else params.traction_table \
            if params.traction_table is not None else traction_from_params(params)
        lo, hi = tr.nu_range
        return check_values(name, values, lo, hi,
                            note="a fraction: 0.01 is 1 %; the traction curve's valid range")
    if option == "clamp":
        v = check_clamping(name, values) if trim else check_values(name, values, 0.0,
                                                                   unit="N")
        return check_values(name, v, *OPERATING_RANGES["F_s"], unit="N")
    if option == "speed":
        return check_values(name, values, *OPERATING_RANGES["omega_p"], lo_open=True,
                            unit="rad/s", note="the slip of eq. 2 is undefined at standstill")
    if option == "tau":
        return check_values(name, values, *OPERATING_RANGES["tau"], note="the torque ratio "
                            "mu / mu_max; 1 is the traction limit, 0.9 an 11 % torque reserve")
    if option == "load-torque":
        return check_values(name, values, *OPERATING_RANGES["T_l"], unit="N m")
    raise KeyError(option)


#: the variables besides r_g and omega_p that fix an operating point (two of them)
_PAIR = ("nu", "tau", "F_s", "T_l")


def operating_point(params: Params, *, trim: bool = False, traction: Any = None,
                    **options: float | None) -> OperatingPoint:
    """The ``[operating]`` point of `params` with the given options (``ratio``, ``slip``,
    ``clamp``, ``speed``, ``tau``, ``load_torque``; None keeps the file's value), each
    checked by `operating_values` (a slip against `traction`, default the analytic curve).

    Two of ``--slip`` (or ``--tau``), ``--clamp``, ``--load-torque`` state the point; one of
    them changes that variable of the file's point (``--slip`` and ``--tau`` replace each
    other); one that the file's point does not give is an error naming the choice."""
    values: dict[str, float | None] = {
        OPTION_VARIABLE[opt.replace("_", "-")]: float(operating_values(
            params, opt.replace("_", "-"), v, trim=trim, traction=traction))
        for opt, v in options.items() if v is not None}
    given = [k for k in _PAIR if k in values]
    check_one_slip("nu" in given, "tau" in given, names=("--slip", "--tau"))
    base = params.operating
    if len(given) >= 3:
        raise InputError("give at most two of --slip (or --tau), --clamp, --load-torque")
    if len(given) == 2:
        values.update({k: None for k in _PAIR if k not in given})
    elif len(given) == 1:
        k = given[0]
        slip_like = k in ("nu", "tau")
        if not slip_like and getattr(base, k) is None:
            has = " and ".join(f"--{_OPTION[v]}" for v in base.given)
            raise InputError(f"--{_OPTION[k]} with the parameter file's point given by {has}: "
                             f"also give one of them, to say which --{_OPTION[k]} replaces")
    try:
        return base.replace(**values)
    except ParameterError as exc:
        raise InputError(str(exc)) from None


_OPTION = {v: k for k, v in OPTION_VARIABLE.items()}
