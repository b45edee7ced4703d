"""``empact plants`` and ``empact control``: plant families, controller design, robustness,
closed loop on the nonlinear machine (beyond the paper)."""
from __future__ import annotations

import time
from typing import Any, Mapping

import click
import numpy as np

from .._progress import progress as progress_bar
from .._validate import check_number
from ..control.designs import CONTROLLER_TYPES
from ..errors import ParameterError
from ..params import check_one_slip
from ._common import (
    OPERATING_RANGES,
    UNITS,
    ErrorGroup,
    Failed,
    InputError,
    OutputFile,
    emit_json,
    force_option,
    get_params,
    json_options,
    loss_map_option,
    operating_values,
    params_option,
    quiet_option,
    sweep_from_options,
    sweep_options,
    traction_option,
)
from .slip import parse_values

#: the grid options of `plants` and `control design`: option -> (variable, unit, help)
GRID = {"ratio": ("r_g", "-", "geometric ratio r_g"), "slip": ("nu", "-", "slip nu (0.01 is "
        "1 %)"), "tau": ("tau", "-", "torque ratio mu / mu_max in place of --slip (0.9: an "
        "11 % torque reserve)"), "clamp": ("F_s", "N", "clamping force F_s"),
        "speed": ("omega_p", "rad/s", "primary speed omega_p"),
        "load-torque": ("T_l", "N m", "load torque T_l")}
#: most grid points of one family from the command line
MAX_FAMILY = 200_000
#: allowed ranges of the grid options (every command's)
_RANGE = OPERATING_RANGES


def grid_options(fn):
    for opt, (var, unit, doc) in reversed(list(GRID.items())):
        fn = click.option(f"--{opt}", opt.replace("-", "_"), default=None,
                          metavar="VALUE|LIST|RANGE",
                          help=f"{doc} [{unit}]; a list or start:stop:count makes it an axis "
                               "(default: the parameter file's [operating]).")(fn)
    fn = click.option("--damping", type=click.Choice(["none", "moderate", "large"]),
                      default="moderate", show_default=True, help="Actuation damping.")(fn)
    fn = click.option("--kinematics", type=click.Choice(["equal-translation", "paper-sec2.1"]),
                      default="equal-translation", show_default=True,
                      help="Sheave kinematics (the machine, or the Sec. 2.1 rows).")(fn)
    fn = click.option("--shift-law", "shift_law", type=click.Choice(["carbone", "ide",
                                                                     "shafai"]),
                      default="carbone", show_default=True, help="The belt's shift "
                      "resistance.")(fn)
    fn = click.option("--drive", type=click.Choice(["torque", "speed"]), default="speed",
                      show_default=True, help="Drive motor torque- or speed-controlled (the "
                      "test bench: speed, as `empact linearize`).")(fn)
    fn = click.option("--load", "load_mode", type=LoadMode(), default="torque",
                      show_default=True, help="Load motor torque- or speed-controlled (the "
                      "load torque is --load-torque).")(fn)
    return traction_option(fn)


class LoadMode(click.Choice):
    """``--load torque|speed``; a number names the option that took it over."""

    def __init__(self) -> None:
        super().__init__(["torque", "speed"])

    def convert(self, value, param, ctx):
        try:
            float(value)
        except (TypeError, ValueError):
            return super().convert(value, param, ctx)
        self.fail(f"{value!r} is a number: the load torque is --load-torque now; --load is the "
                  "load motor's mode (torque or speed)", param, ctx)


def family_from_options(params, raw: dict, damping: str, kinematics: str, shift_law: str,
                        drive: str = "speed", load: str = "torque", sweep=None,
                        loop_outputs: bool = True, traction_table=None,
                        driveline: str = "bench", cruise: bool = False):
    """Parse the grid options (each checked under its name) and build the family (with the
    outputs the loop model needs, `empact.control.family.LOOP_FAMILY_OUTPUTS`) on the
    analytic traction curve or the measured one (`traction_table`, ``--traction``); on the
    car (``--driveline vehicle``: the engine and the road are torques, `drive` and `load`
    not used; ``--cruise``: the road load sets T_l)."""
    from ..control.family import LOOP_FAMILY_OUTPUTS, plant_family
    from ..variator.geometry import check_ratio

    values: dict[str, Any] = {}
    for opt, text in raw.items():
        v = text if isinstance(text, np.ndarray) else parse_values(text, opt)
        if v is None:
            continue
        var, unit, _ = GRID[opt]
        lo, hi = _RANGE[var]
        for x in v:
            check_number(f"--{opt}", x, lo, hi, lo_open=var in ("r_g", "F_s", "omega_p"),
                         unit=unit)
        if var == "nu":
            # within the traction curve's valid range
            operating_values(params, "slip", v, traction=traction_table)
        if var == "r_g":
            check_ratio(v, params.variator, "--ratio")
        values[var] = v if v.size > 1 else float(v[0])
    n = int(np.prod([np.size(v) for v in values.values()] or [1]))
    if n > MAX_FAMILY:
        raise InputError(f"{n} grid points; at most {MAX_FAMILY}")
    check_one_slip("nu" in values, "tau" in values, names=("--slip", "--tau"))
    if sum(k in values for k in ("nu", "tau", "F_s", "T_l")) > 2:
        raise InputError("give at most two of --slip (or --tau), --clamp, --load-torque (the "
                         "trim solves the third)")
    tables = {} if traction_table is None else {"traction": traction_table}
    if cruise and driveline != "vehicle":
        raise InputError("--cruise: the road load needs --driveline vehicle")
    if cruise and ("T_l" in values or sum(k in values for k in ("nu", "tau", "F_s")) > 1):
        raise InputError("--cruise: give at most one of --slip (or --tau), --clamp and no "
                         "--load-torque (the road load sets it)")
    car = ({"driveline": "vehicle", "drive": "torque", "load": "torque", "cruise": cruise}
           if driveline == "vehicle" else {"drive": drive, "load": load})
    return plant_family(params, damping=damping, kinematics=kinematics, shift_law=shift_law,
                        sweep=sweep, outputs=LOOP_FAMILY_OUTPUTS if loop_outputs else None,
                        **car, **tables, **values)


def _summary(fam) -> dict:
    return {"shape": list(fam.shape), "points": fam.size, "trimmed": int(fam.ok.sum()),
            "axes": {k: v.tolist() for k, v in fam.axes.items()}, "fixed": fam.fixed,
            "inputs": list(fam.inputs), "outputs": list(fam.outputs),
            "failures": sorted({str(r) for r in fam.reason.ravel() if r})}


driveline_option = click.option(
    "--driveline", type=click.Choice(["bench", "vehicle"]), default="bench",
    show_default=True, help="The machine on the test bench, or in the car ([engine] inertia "
    "torque-controlled, the [vehicle] reflected with its road load; --drive and --load do not "
    "apply: both are torques).")


@click.command("plants")
@grid_options
@driveline_option
@click.option("--cruise", is_flag=True, help="With --driveline vehicle: the car at steady "
              "cruise on a level road, the road load sets the load torque (give one of "
              "--slip, --tau, --clamp; default: the [operating] slip).")
@click.option("--out", "out", type=OutputFile(("npz", "json", "mat")), default=None,
              help="Write the family (.npz, which `empact control check` reads; .json or "
                   ".mat); an existing file only with --force.")
@sweep_options
@loss_map_option
@params_option
@json_options
@force_option
@quiet_option
def plants_cmd(ratio, slip, tau, clamp, speed, load_torque, damping, kinematics, shift_law,
               drive, load_mode, traction_table, driveline, cruise, out, scheduler, workers,
               scheduler_timeout, loss_map, params_file, as_json, json_out, force,
               quiet) -> None:
    """Trim and exactly linearise the machine over a grid of operating points (a plant
    family: T_mp, T_ms and the load -> r_g, nu, nu_r), for control design and LPV models."""
    from ..control.family import save_family

    ctx = click.get_current_context()
    for opt, name in (("drive", "--drive"), ("load_mode", "--load")):
        if driveline == "vehicle" and ctx.get_parameter_source(opt) is \
                click.core.ParameterSource.COMMANDLINE:
            raise InputError(f"{name}: not with --driveline vehicle (the engine and the road "
                             "are torques)")
    sweep = sweep_from_options(scheduler, workers, scheduler_timeout, progress=not quiet)
    params = get_params(params_file, loss_map)
    t0 = time.perf_counter()
    fam = family_from_options(params, {"ratio": ratio, "slip": slip, "tau": tau,
                                       "clamp": clamp, "speed": speed,
                                       "load-torque": load_torque}, damping, kinematics,
                              shift_law, drive, load_mode, sweep,
                              traction_table=traction_table, driveline=driveline,
                              cruise=cruise)
    wall = time.perf_counter() - t0
    if out:
        save_family(fam, out)
    data = {**_summary(fam), "wall_time_s": wall}
    if as_json or json_out:
        emit_json(data, "plants", json_out)
        return
    click.echo(f"{fam.size} points ({int(fam.ok.sum())} trimmed) on axes "
               f"{', '.join(f'{k} [{len(v)}]' for k, v in fam.axes.items()) or 'none'} in "
               f"{wall:.2f} s")
    for r in data["failures"]:
        click.echo(f"  not trimmed: {r}")


@click.group("control", cls=ErrorGroup)
def control_group() -> None:
    """Slip and ratio control: design, robustness across a family, closed loop."""


def _family_tables(family_file, traction_table, loss_map) -> None:
    """Refuse a measured table beside a family file (which records its own model)."""
    for option, table in (("--traction", traction_table), ("--loss-map", loss_map)):
        if family_file and table is not None:
            raise InputError(f"{option}: give it with the design family, not with --family (a "
                             "family file records its own model options)")


def _loop_from(scenario_file, params):
    """The loop a design or check uses: a closed-loop scenario's (its [controller],
    [sensors], [limits]), or the shipped loop (`empact.control.law.SHIPPED_LOOP`)."""
    from ..control.law import SHIPPED_LOOP, LoopConfig
    from ..nonlinear.scenario import load_scenario

    if scenario_file is None:
        return LoopConfig.of(params, **SHIPPED_LOOP)
    sc = load_scenario(scenario_file)
    if not sc.closed_loop:
        raise InputError(f"--loop-scenario {scenario_file}: no [controller] table (the loop "
                         "is a closed-loop scenario's)")
    return LoopConfig.for_scenario(sc, params)


loop_option = click.option(
    "--loop-scenario", "loop_scenario", type=click.Path(dir_okay=False), default=None,
    help="Take the loop (rate, feedforwards, sensors, servo limits) from this closed-loop "
         "scenario (default: the shipped loop, empact.control.law.SHIPPED_LOOP).")


@control_group.command("design")
@click.option("--method", type=click.Choice(list(CONTROLLER_TYPES)), default="pi",
              show_default=True, help="The controller type (empact.control.designs): "
              + "; ".join(f"{t.name}: {t.summary}" for t in CONTROLLER_TYPES.values()) + ".")
@click.option("--bandwidth", default=None, metavar="RATIO,SLIP",
              help="Loop bandwidths [Hz] (default: the design function's, the shipped "
                   "design's: design_pi 0.5,1; design_hinf 0.1,0.2).")
@click.option("--alpha-min", "alpha_min", type=float, default=None,
              help="Smallest multiloop disk margin at every grid point (default: the design "
                   "function's, 0.5, the shipped designs').")
@click.option("--schedule/--no-schedule", default=None,
              help="Gain-schedule the gains on the errors over the family's axes (r_g, tau, "
                   "F_s) (default: the design function's: scheduled, on the loop that "
                   "runs).")
@click.option("--slip-signal", "slip_signal",
              type=click.Choice(["nu", "nu_r", "ln_nu", "ln_nu_r"]), default="nu",
              show_default=True, help="The measured slip, or its logarithm (ln_: the slip's "
              "response to the clamping varies by orders of magnitude along the traction "
              "curve; the logarithm evens much of it out).")
@click.option("--nominal", default=None, metavar="I,J,...",
              help="Grid index of the nominal plant (default: the middle).")
@loop_option
@grid_options
@click.option("--out", "out", type=OutputFile(("json", "mat")), required=True,
              help="Controller file (.json or .mat; an existing file only with --force).")
@loss_map_option
@params_option
@json_options
@force_option
@quiet_option
def design_cmd(method, bandwidth, alpha_min, schedule, slip_signal, nominal, loop_scenario,
               ratio, slip, tau, clamp, speed, load_torque, damping, kinematics, shift_law,
               drive, load_mode, traction_table, out, loss_map, params_file, as_json, json_out,
               force, quiet) -> None:
    """Design a controller (T_mp, T_ms) from the errors of (r_g, slip) on a plant family
    (default: empact.control.family.DESIGN_GRID: r_g 0.43..2.25 (7, geometric) x torque
    ratio tau 0.8, 0.9, 0.95 x clamping force 3, 5, 8, 16, 32 kN at [operating]'s speed)."""
    from ..control.family import DESIGN_GRID

    kind = CONTROLLER_TYPES[method]
    # only what the user gives: the defaults are the design function's (one source)
    given: dict = {"slip": slip_signal}
    if bandwidth is not None:
        try:
            bw = tuple(float(x) for x in bandwidth.split(","))
        except ValueError:
            raise InputError(f"--bandwidth {bandwidth!r}: two numbers RATIO,SLIP [Hz]") from None
        if len(bw) != 2:
            raise InputError(f"--bandwidth {bandwidth!r}: two numbers RATIO,SLIP [Hz]")
        for b in bw:
            check_number("--bandwidth", b, 0.0, 50.0, lo_open=True, unit="Hz")
        given["bandwidth_hz"] = bw
    for option, name, value in (("--alpha-min", "alpha_min", alpha_min),
                                ("--schedule/--no-schedule", "schedule", schedule)):
        if value is None:
            continue
        if not kind.accepts(name):
            raise InputError(f"{option}: not an option of --method {method} "
                             f"({kind.function})")
        given[name] = value
    if alpha_min is not None:
        check_number("--alpha-min", alpha_min, 0.05, 1.9,
                     note="the multiloop disk margin each plant must keep")
    params = get_params(params_file, loss_map)
    loop = _loop_from(loop_scenario, params)
    defaults = not any(v is not None for v in (ratio, slip, tau, clamp, load_torque))
    raw = {"ratio": ratio if ratio is not None else DESIGN_GRID["r_g"],
           "slip": slip, "tau": tau if tau is not None else (None if slip
                                                              else DESIGN_GRID["tau"]),
           "clamp": clamp if clamp is not None else (DESIGN_GRID["F_s"] if defaults
                                                      else None),
           "speed": speed, "load-torque": load_torque}
    nom = None
    if nominal:
        try:
            nom = tuple(int(x) for x in nominal.split(","))
        except ValueError:
            raise InputError(f"--nominal {nominal!r}: grid indices I,J,...") from None
    with progress_bar(total=2, desc=f"control design ({method}): family, design",
                      unit="step", enabled=not quiet) as bar:
        fam = family_from_options(params, raw, damping, kinematics, shift_law, drive,
                                  load_mode, loop_outputs=True, traction_table=traction_table)
        bar.update(1)
        if not fam.ok.all():
            raise InputError(f"{int((~fam.ok).sum())} grid points do not trim ("
                             f"{sorted({str(r) for r in fam.reason.ravel() if r})[0]}); "
                             "narrow the grid")
        if nom is not None and (len(nom) != len(fam.shape)
                                or any(not 0 <= i < s for i, s in zip(nom, fam.shape))):
            raise InputError(f"--nominal {nominal!r}: indices in a grid of shape {fam.shape}")
        if kind.accepts("loop"):  # checked on the loop that runs
            given.update(loop=loop, params=params)
        ctrl = kind.design_function()(fam, nominal=nom, **given)
        bar.update(1)
    ctrl.save(out)
    if as_json or json_out:
        emit_json({"method": method, "n_states": ctrl.n, "design": dict(ctrl.design),
                   "file": str(out)}, "control.design", json_out)
        return
    w = ctrl.design["worst"]
    click.echo(f"{method}: {ctrl.n} states; over {fam.size} plants: all stable "
               f"{w['all_stable']}, worst disk margin {w['disk_margin']:.3f} "
               f"(+-{w['gain_margin_db']:.2f} dB, +-{w['phase_margin_deg']:.1f} deg)")


@control_group.command("check")
@click.argument("controller", type=click.Path(dir_okay=False))
@click.option("--family", "family_file", type=click.Path(dir_okay=False), default=None,
              help="Plant family (.npz from `empact plants`; default: the design family "
                   "on the parameter set).")
@loop_option
@driveline_option
@click.option("--min-disk-margin", "min_dm", type=float, default=None,
              help="With --strict: the smallest multiloop disk margin allowed (default: the "
                   "controller's own design margin, its design record's alpha_min, else its "
                   "worst disk_margin; none recorded: stability alone).")
@click.option("--strict", is_flag=True, help="Exit 1 when a plant is unstable or a disk "
              "margin is below --min-disk-margin or, without it, the controller's design "
              "margin (without --strict: report and exit 0).")
@click.option("--mu", is_flag=True, help="Also the structured singular value bound "
              "(slycot ab13md, continuous loop) over a parametric spread covering the family.")
@traction_option
@loss_map_option
@params_option
@json_options
@force_option
@quiet_option
def check_cmd(controller, family_file, loop_scenario, driveline, min_dm, strict, mu,
              traction_table, loss_map, params_file, as_json, json_out, force, quiet) -> None:
    """Closed-loop poles and disk margins of CONTROLLER (a controller file, or shipped:pi,
    shipped:hinf) on the loop that runs (sampled, with the loop's sensors and feedforwards;
    empact.control.loop) against every plant of a family."""
    from ..control.controller import load_controller
    from ..control.family import design_family, load_family
    from ..control.loop import family_loops
    from ..control.robustness import disk_gain_phase, mu_upper_bound

    if min_dm is not None:
        check_number("--min-disk-margin", min_dm, 0.0, 1.99)
    _family_tables(family_file, traction_table, loss_map)
    ctrl = load_controller(controller)
    gate, gate_source = ((min_dm, "--min-disk-margin") if min_dm is not None
                         else design_margin(ctrl.design))
    params = get_params(params_file, loss_map)
    loop = _loop_from(loop_scenario, params)
    tables = {} if traction_table is None else {"traction": traction_table}
    if family_file and driveline != "bench":
        raise InputError("--driveline: give it with the design family, not with --family (a "
                         "family file records its own model options)")
    car = {"driveline": "vehicle"} if driveline == "vehicle" else {}
    fam = load_family(family_file) if family_file else design_family(params, **tables, **car)
    for name in ctrl.measured:
        base = name[3:] if name.startswith("ln_") else name
        if base not in fam.outputs:
            raise InputError(f"{controller}: measures {name!r}, the family has "
                             f"{', '.join(fam.outputs)}")
    with progress_bar(total=2 if mu else 1, desc="control check: margins" + (", mu" if mu
                                                                           else ""),
                      unit="step", enabled=not quiet) as bar:
        lm = family_loops(fam, ctrl, loop, params)
        rho = lm.spectral_radius()
        dm = lm.disk_margins()
        bar.update(1)
        worst = float(dm["alpha"].min())
        gm, pm = disk_gain_phase(worst)
        data: dict[str, Any] = {
            "worst": {"disk_margin": worst, "gain_margin_db": float(gm),
                      "phase_margin_deg": float(pm),
                      "spectral_radius": float(rho.max()),
                      "all_stable": bool(np.all(rho < 1)),
                      "stable": int((rho < 1).sum()), "points": int(rho.size)},
            "spectral_radius": rho, "poles_z": lm.poles(), "disk_margin": dm["alpha"],
            "input_disk_margin": dm["input"], "output_disk_margin": dm["output"],
            "axes": {k: v for k, v in fam.axes.items()},
            "loop": {"rate_hz": loop.spec.rate, "feedforward": loop.spec.feedforward,
                     "sensors": loop.sensors is not None}}
        if mu:
            data["mu"] = mu_upper_bound(fam, ctrl.at(
                {k: float(np.median(v)) for k, v in fam.operating.items()})
                if ctrl.schedule is not None else ctrl, tuple(s // 2 for s in fam.shape))
            bar.update(1)
    data["gate"] = {"min_disk_margin": gate, "source": gate_source}
    ok = data["worst"]["all_stable"] and worst >= gate
    if as_json or json_out:
        emit_json({**data, "passed": ok}, "control.check", json_out)
    else:
        w = data["worst"]
        click.echo(f"{fam.size} plants: {w['stable']} closed-loop stable; worst disk margin "
                   f"{worst:.3f} (+-{w['gain_margin_db']:.2f} dB, +-{w['phase_margin_deg']:.1f}"
                   f" deg); largest |z| {w['spectral_radius']:.6f} (sampled at "
                   f"{loop.spec.rate:g} Hz)")
        if mu:
            click.echo(f"mu upper bound {data['mu']['mu_peak']:.3g} ({data['mu']['n_blocks']} "
                       "real blocks; < 1 certifies the box)")
    if strict and not ok:
        raise Failed(f"check failed: {fam.size - data['worst']['stable']} unstable plants, "
                     f"worst disk margin {worst:.3f} (required {gate:g}: {gate_source})")


@control_group.command("tune")
@click.argument("controller", type=click.Path(dir_okay=False))
@click.option("--family", "family_file", type=click.Path(dir_okay=False), default=None,
              help="Plant family (.npz from `empact plants`; default: the design family "
                   "on the parameter set, as `control check`).")
@loop_option
@driveline_option
@click.option("--out", "out", type=OutputFile(("json", "mat")), required=True,
              help="The tuned controller (.json or .mat; an existing file only with --force).")
@click.option("--parameters", "parameters", default=None, metavar="NAME,...",
              help="The multipliers tuned (default all: kp_ratio, ki_ratio, rolloff_ratio, "
                   "kp_slip, ki_slip, rolloff_slip; empact.control.tune.TUNABLE).")
@click.option("--min-disk-margin", "min_dm", type=float, default=0.6, show_default=True,
              help="The worst multiloop disk margin the result is judged against (exit 1 "
                   "with --strict when missed).")
@click.option("--max-ms", "max_ms", type=float, default=2.0, show_default=True,
              help="Sensitivity peak allowed per loop (loop at a time), a penalty of the "
                   "objective; 0: none.")
@click.option("--bandwidth-floor", "bw_floor", default=None, metavar="RATIO,SLIP",
              help="Lowest sensitivity bandwidth per loop over the family [Hz] (default: the "
                   "starting controller's).")
@click.option("--seed", type=int, default=0, show_default=True,
              help="Seed of the optimiser's initial simplex.")
@click.option("--maxiter", "maxiter", type=int, default=300, show_default=True,
              help="Most objective evaluations.")
@click.option("--strict", is_flag=True, help="Exit 1 when the tuned controller misses "
              "--min-disk-margin, --max-ms or the bandwidth floor (it is written either way).")
@traction_option
@loss_map_option
@params_option
@json_options
@force_option
@quiet_option
def tune_cmd(controller, family_file, loop_scenario, driveline, out, parameters, min_dm,
             max_ms, bw_floor, seed, maxiter, strict, traction_table, loss_map, params_file,
             as_json, json_out, force, quiet) -> None:
    """Tune CONTROLLER's PI structure (a controller file, or shipped:pi; gains, integral
    corners, roll-offs per loop, the schedule's shape kept) to maximise the worst multiloop
    disk margin over every plant of a family on the loop that runs, with an Ms penalty and a
    bandwidth floor (empact.control.tune)."""
    from ..control.controller import load_controller
    from ..control.family import design_family, load_family
    from ..control.tune import TuneOptions, check_pi, parse_parameters, tune_pi

    check_number("--min-disk-margin", min_dm, 0.0, 1.99)
    check_number("--max-ms", max_ms, 0.0, 100.0,
                 note="0 for none, else above 1: the sensitivity peak allowed")
    if 0 < max_ms <= 1:
        raise InputError(f"--max-ms {max_ms:g}: 0 for none, or above 1 (a sensitivity peak)")
    check_number("--seed", seed, 0, 2**32 - 1)
    check_number("--maxiter", maxiter, 1, 100_000)
    floor: tuple[float, float] | None = None
    if bw_floor is not None:
        try:
            values = [float(x) for x in bw_floor.split(",")]
        except ValueError:
            raise InputError(f"--bandwidth-floor {bw_floor!r}: two numbers RATIO,SLIP "
                             "[Hz]") from None
        if len(values) != 2:
            raise InputError(f"--bandwidth-floor {bw_floor!r}: two numbers RATIO,SLIP [Hz]")
        floor = (values[0], values[1])
        for b in floor:
            check_number("--bandwidth-floor", b, 0.0, 50.0, lo_open=True, unit="Hz")
    try:
        opts = TuneOptions(parameters=(parse_parameters(parameters) if parameters is not None
                                       else TuneOptions().parameters),
                           max_ms=max_ms or None, bandwidth_floor_hz=floor,
                           min_disk_margin=min_dm, seed=seed, max_evaluations=maxiter)
    except ParameterError as exc:
        raise InputError(str(exc).replace("parameters = ", "--parameters ", 1)) from None
    _family_tables(family_file, traction_table, loss_map)
    ctrl = load_controller(controller)
    try:
        check_pi(ctrl)
    except ParameterError as exc:
        raise InputError(f"{controller}: {exc}") from None
    params = get_params(params_file, loss_map)
    loop = _loop_from(loop_scenario, params)
    tables = {} if traction_table is None else {"traction": traction_table}
    if family_file and driveline != "bench":
        raise InputError("--driveline: give it with the design family, not with --family (a "
                         "family file records its own model options)")
    car = {"driveline": "vehicle"} if driveline == "vehicle" else {}
    fam = load_family(family_file) if family_file else design_family(params, **tables, **car)
    for name in ctrl.measured:
        base = name[3:] if name.startswith("ln_") else name
        if base not in fam.outputs:
            raise InputError(f"{controller}: measures {name!r}, the family has "
                             f"{', '.join(fam.outputs)}")
    with progress_bar(total=1, desc="control tune", unit="run", enabled=not quiet) as bar:
        tuned, result = tune_pi(ctrl, fam, loop, params, opts)
        bar.update(1)
    tuned.save(out)
    if as_json or json_out:
        emit_json({**result.to_dict(), "file": str(out)}, "control.tune", json_out)
    else:
        bef, aft = result.before, result.after
        click.echo(f"{fam.size} plants, {result.evaluations} evaluations in "
                   f"{result.wall_time_s:.1f} s: worst disk margin {bef['disk_margin']:.3f} -> "
                   f"{aft['disk_margin']:.3f} [-] (+-{aft['gain_margin_db']:.2f} dB, "
                   f"+-{aft['phase_margin_deg']:.1f} deg); Ms ratio {bef['ms']['ratio']:.2f} -> "
                   f"{aft['ms']['ratio']:.2f} [-], slip {bef['ms']['slip']:.2f} -> "
                   f"{aft['ms']['slip']:.2f} [-]")
        click.echo("multipliers [-]: " + ", ".join(f"{k} {v:.4g}"
                                                    for k, v in result.multipliers.items()))
    if strict and not result.met:
        raise Failed(f"tune: the tuned controller misses the targets (worst disk margin "
                     f"{result.after['disk_margin']:.3f}, required {min_dm:g}; Ms "
                     f"{max(result.after['ms'].values()):.2f}, allowed {max_ms:g})")


def design_margin(design: Mapping[str, Any]) -> tuple[float, str]:
    """The disk margin a controller's design record promises, and where it comes from: its
    ``alpha_min`` (the margin the design required of every plant), else its
    ``worst.disk_margin`` (the margin it reports); ``(0, "none recorded")`` without either
    (stability alone is judged)."""
    if isinstance(design.get("alpha_min"), (int, float)):
        return float(design["alpha_min"]), "the design's alpha_min"
    worst = design.get("worst")
    if isinstance(worst, dict) and isinstance(worst.get("disk_margin"), (int, float)):
        return float(worst["disk_margin"]), "the design's worst disk_margin"
    return 0.0, "no design margin recorded: stability alone"


@control_group.command("simulate")
@click.argument("scenario", required=False, type=click.Path(dir_okay=False))
@click.option("--example", default=None, help="A shipped closed-loop scenario.")
@click.option("--list-examples", "list_ex", is_flag=True, help="List them.")
@click.option("--controller", "controller", default=None, type=click.Path(dir_okay=False),
              help="Controller file replacing the scenario's.")
@click.option("--strict", is_flag=True, help="Exit 1 when a target of the scenario's "
              "[targets] is missed (without it: report and exit 0; a run that stops early "
              "exits 1 either way).")
@click.option("--out", "out", type=OutputFile(("csv",)), default=None,
              help="Write the time histories (.csv; an existing file only with --force).")
@traction_option
@loss_map_option
@params_option
@json_options
@force_option
@quiet_option
def simulate_cmd(scenario, example, list_ex, controller, strict, out, traction_table,
                 loss_map, params_file, as_json, json_out, force, quiet) -> None:
    """Closed loop on the nonlinear machine: print the scenario's metrics and its targets
    (exit 1 when the run stops early, or with --strict when a target is missed)."""
    from ..control.closed_loop import (
        check_targets,
        control_example_path,
        control_examples,
        run_closed_loop,
        shown_metric,
    )
    from ..efficiency import energy_summary
    from ..nonlinear.scenario import check_references, load_scenario
    from ..nonlinear.simulation import write_csv

    if list_ex:
        for name, desc in control_examples().items():
            click.echo(f"{name:24s} {desc}")
        return
    if (scenario is None) == (example is None):
        raise InputError("give exactly one of SCENARIO or --example NAME (see --list-examples)")
    params = get_params(params_file, loss_map)
    sc = load_scenario(control_example_path(example) if example else scenario,
                       params if traction_table is None else None)
    if loss_map is not None:  # the command line's map over the scenario's [model] loss_map
        sc = sc.with_options(loss_map=loss_map)
    if not sc.closed_loop:
        raise InputError(f"{scenario}: no [controller] table (an open-loop scenario: run it "
                         "with 'empact simulate')")
    if controller:
        sc = sc.with_controller(controller)
    if traction_table is not None:  # the references against the curve the run uses
        sc = sc.with_options(traction=traction_table)
        check_references(sc, params)
    run = run_closed_loop(sc, params, progress=not quiet)
    if out:
        write_csv(run.result, out)
    m = run.metrics
    checks = check_targets(m, sc.targets)
    if as_json or json_out:  # slips as fractions, as the API gives them
        emit_json({"scenario": sc.name, "metrics": m,
                   "targets": [{"name": c.name, "met": c.met, "target": c.describe()}
                               for c in checks],
                   **energy_summary(run.result, params, sc.options.kinematics)},
                  "control.simulate", json_out)
    else:  # for people: slips in % and percentage points; every number with its unit
        for k, v in m.items():
            v, unit = shown_metric(k, v)
            unit = {"pp": "percentage points"}.get(unit, unit) or UNITS.get(k, "")
            number = isinstance(v, (int, float)) and not isinstance(v, bool)
            shown = f"{v:.6g}" if isinstance(v, float) else str(v)
            click.echo(f"{k:22s} {shown} [{unit}]" if number else f"{k:22s} {shown}")
        for c in checks:
            click.echo(f"target: {c.describe()}")
    if not run.result.complete:
        raise Failed(f"closed loop stopped early: {run.result.message}")
    missed = [c for c in checks if not c.met]
    if strict and missed:
        raise Failed(f"{len(missed)} of {len(checks)} targets missed: "
                     + "; ".join(c.describe() for c in missed))


@control_group.command("discretize")
@click.argument("controller", type=click.Path(dir_okay=False))
@click.option("--rate", default=None, metavar="HZ", help="Sample rate [Hz] (with --at: the "
              "loop's, which is the default there).")
@click.option("--method", type=click.Choice(["tustin", "zoh", "foh", "bilinear"]),
              default="tustin", show_default=True, help="Discretisation (the formulas of "
              "scipy.signal.cont2discrete; with --at: tustin, as the loop law).")
@click.option("--at", "at", default=None, metavar="NAME=VALUE,...",
              help="Fold the schedule's gains at this operating point into B and D and add "
                   "the loop that runs there (loop_plant: servo torques -> errors), e.g. "
                   "r_g=1,tau=0.9,F_s=10000 (r_g, nu or tau, F_s, T_l, omega_p in SI; at "
                   "most two of nu/tau, F_s, T_l; what is not given comes from the "
                   "parameter file's [operating], as for `plants`).")
@loop_option
@click.option("--out", "out", type=OutputFile(("json", "mat")), required=True,
              help="The discrete controller (.json or .mat; an existing file only with "
                   "--force).")
@params_option
@force_option
def discretize_cmd(controller, rate, method, at, loop_scenario, out, params_file,
                   force) -> None:
    """Write CONTROLLER (a controller file, or shipped:pi, shipped:hinf) as a discrete-time
    state space at its sample rate (x[k+1] = A x[k] +
    B e[k], du[k] = C x[k] + D e[k]; a schedule's gains act on e as before, or, with --at,
    are folded in at that point, with the loop it closes there)."""
    from ..control.controller import load_controller

    if rate is not None:
        try:
            rate = float(rate)
        except ValueError:
            raise InputError(f"--rate {rate!r}: a sample rate in Hz") from None
        check_number("--rate", rate, 1.0, 1e5, unit="Hz")
    ctrl = load_controller(controller)
    if ctrl.dt:
        raise InputError(f"{controller}: already discrete (dt = {ctrl.dt:g} s)")
    if at is None:
        if rate is None:
            raise InputError("--rate: give the sample rate in Hz (or --at, at the loop's)")
        cd = ctrl.discretize(1.0 / rate, method)
        cd.save(out)
        click.echo(f"{ctrl.n}-state controller at {rate:g} Hz ({method})")
        return
    from ..control.loop import controller_at

    params = get_params(params_file)
    point = parse_point(at, params)
    loop = _loop_from(loop_scenario, params)
    if rate is not None and rate != loop.spec.rate:
        raise InputError(f"--rate {rate:g}: with --at the controller runs at the loop's rate "
                         f"({loop.spec.rate:g} Hz)")
    if method != "tustin":
        raise InputError(f"--method {method}: with --at the controller is discretised as the "
                         "loop law does (tustin)")
    cd = controller_at(ctrl, loop, params, point)
    cd.save(out)
    click.echo(f"{ctrl.n}-state controller at {loop.spec.rate:g} Hz (tustin) folded at "
               f"{at} (gains {', '.join(f'{g:.6g}' for g in cd.design['schedule_gains'])}), "
               f"with the loop there ({cd.design['loop_plant']['A'].shape[0]} states)")


#: the variables of ``--at`` and the operating-point option whose checks they take
AT_VARIABLES = {"r_g": "ratio", "nu": "slip", "tau": "tau", "F_s": "clamp", "omega_p": "speed",
                "T_l": "load-torque"}


def parse_point(text: str, params: Any = None) -> dict[str, float]:
    """``--at NAME=VALUE,...`` as a mapping, one error line naming what is wrong: an item
    that is not NAME=VALUE with a number, a name not of `AT_VARIABLES` or given twice, and
    (with `params`) a value outside what the option of that variable takes
    (`operating_values`: the variator's ratios, the traction curve's slips,
    `OPERATING_RANGES`), more than two of nu (or tau), F_s, T_l, or both nu and tau."""
    point: dict[str, float] = {}
    for item in text.split(","):
        name, eq, value = item.partition("=")
        name = name.strip()
        try:
            number = float(value)
        except ValueError:
            raise InputError(f"--at {text!r}: {item!r} is not NAME=VALUE with a number "
                             "(e.g. r_g=1,tau=0.9,F_s=10000)") from None
        if not eq or not name:
            raise InputError(f"--at {text!r}: {item!r} is not NAME=VALUE")
        if name not in AT_VARIABLES:
            raise InputError(f"--at {text!r}: {name!r} is not an operating variable; give "
                             f"r_g and two of nu (or tau), F_s, T_l ({', '.join(AT_VARIABLES)})")
        if name in point:
            raise InputError(f"--at {text!r}: {name} given twice")
        point[name] = number
    if params is not None:
        for key, v in point.items():
            try:
                operating_values(params, AT_VARIABLES[key], v, trim=True)
            except ParameterError as exc:
                raise InputError(f"--at {key}={v:g}: "
                                 f"{str(exc).partition(': ')[2] or exc}") from None
    if "nu" in point and "tau" in point:
        raise InputError(f"--at {text!r}: give nu or tau, not both (one slip set-point)")
    if sum(k in point for k in ("nu", "tau", "F_s", "T_l")) > 2:
        raise InputError(f"--at {text!r}: give at most two of nu (or tau), F_s, T_l (the trim "
                         "solves the third)")
    return point
