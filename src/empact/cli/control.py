"""``empact plants`` and ``empact control``: plant families, controller design, robustness,
closed loop on the nonlinear machine (beyond the paper)."""
from __future__ import annotations

import time

import click
import numpy as np

from .._progress import progress as progress_bar
from .._validate import check_number
from ._common import (UNITS, ErrorGroup, Failed, InputError, OutputFile, check_references,
                      emit_json, force_option, fraction_metrics, get_params, json_options,
                      operating_values, params_option, quiet_option, sweep_from_options,
                      sweep_options)
from .slip import parse_values

#: the grid options of `plants` and `control design`: option -> (variable, unit, help)
GRID = {"ratio": ("r_g", "-", "geometric ratio r_g"), "slip": ("nu", "-", "slip nu (0.01 is "
        "1 %)"), "tau": ("tau", "-", "torque ratio mu / mu_max in place of --slip (0.9: an "
        "11 % torque reserve)"), "clamp": ("F_s", "N", "clamping force F_s"),
        "speed": ("omega_p", "rad/s", "primary speed omega_p"),
        "load-torque": ("T_l", "N m", "load torque T_l")}
#: most grid points of one family from the command line
MAX_FAMILY = 200_000
#: allowed ranges of the grid options
_RANGE = {"r_g": (0.0, 10.0), "nu": (-0.5, 0.5), "tau": (-1.0, 1.0), "F_s": (0.0, 1e6),
          "omega_p": (0.0, 2000.0), "T_l": (-1e4, 1e4)}


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
    return fn


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
                        drive: str = "speed", load: str = "torque", sweep=None):
    """Parse the grid options (each checked under its name) and build the family."""
    from ..control.family import plant_family
    from ..variator.geometry import check_ratio

    values = {}
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
            operating_values(params, "slip", v)  # within the traction curve's valid range
        if var == "r_g":
            check_ratio(v, params.variator, "--ratio")
        values[var] = v if v.size > 1 else float(v[0])
    n = int(np.prod([np.size(v) for v in values.values()] or [1]))
    if n > MAX_FAMILY:
        raise InputError(f"{n} grid points; at most {MAX_FAMILY}")
    if "nu" in values and "tau" in values:
        raise InputError("give --slip or --tau, not both")
    if sum(k in values for k in ("nu", "tau", "F_s", "T_l")) > 2:
        raise InputError("give at most two of --slip (or --tau), --clamp, --load-torque (the "
                         "trim solves the third)")
    return plant_family(params, damping=damping, kinematics=kinematics, shift_law=shift_law,
                        drive=drive, load=load, sweep=sweep, **values)


def _summary(fam) -> dict:
    return {"shape": list(fam.shape), "points": fam.size, "trimmed": int(fam.ok.sum()),
            "axes": {k: v.tolist() for k, v in fam.axes.items()}, "fixed": fam.fixed,
            "inputs": list(fam.inputs), "outputs": list(fam.outputs),
            "failures": sorted({str(r) for r in fam.reason.ravel() if r})}


@click.command("plants")
@grid_options
@click.option("--out", "out", type=OutputFile(("npz", "json", "mat")), default=None,
              help="Write the family (.npz, which `empact control check` reads; .json or "
                   ".mat); an existing file only with --force.")
@sweep_options
@params_option
@json_options
@force_option
@quiet_option
def plants_cmd(ratio, slip, tau, clamp, speed, load_torque, damping, kinematics, shift_law,
               drive, load_mode, out, scheduler, workers, scheduler_timeout, params_file,
               as_json, json_out, force, quiet) -> None:
    """Trim and exactly linearise the machine over a grid of operating points (a plant
    family: T_mp, T_ms and the load -> r_g, nu, nu_r), for control design and LPV models."""
    from ..control.family import save_family

    sweep = sweep_from_options(scheduler, workers, scheduler_timeout, progress=not quiet)
    params = get_params(params_file)
    t0 = time.perf_counter()
    fam = family_from_options(params, {"ratio": ratio, "slip": slip, "tau": tau,
                                       "clamp": clamp, "speed": speed,
                                       "load-torque": load_torque}, damping, kinematics,
                              shift_law, drive, load_mode, sweep)
    wall = time.perf_counter() - t0
    if out:
        save_family(fam, out)
    data = {**_summary(fam), "wall_time_s": wall}
    if as_json or json_out:
        emit_json(data, "plants", json_out)
        return
    click.echo(f"{fam.size} points ({int(fam.ok.sum())} trimmed) on axes "
               f"{', '.join(f'{k} [{len(v)}]' for k, v in fam.axes.items()) or 'none'} in "
               f"{wall:.2f} s" + (f"; written to {out}" if out else ""))
    for r in data["failures"]:
        click.echo(f"  not trimmed: {r}")


@click.group("control", cls=ErrorGroup)
def control_group() -> None:
    """Slip and ratio control: design, robustness across a family, closed loop."""


@control_group.command("design")
@click.option("--method", type=click.Choice(["pi", "hinf"]), default="pi", show_default=True,
              help="Decentralised PI for the family, or H-infinity mixed sensitivity.")
@click.option("--bandwidth", default=None, metavar="RATIO,SLIP",
              help="Loop bandwidths [Hz] (default 0.1,0.05: the shipped designs).")
@click.option("--alpha-min", "alpha_min", type=float, default=0.2, show_default=True,
              help="PI: smallest multiloop disk margin at every grid point.")
@click.option("--slip-signal", "slip_signal", type=click.Choice(["nu", "nu_r"]), default="nu",
              show_default=True, help="The measured slip.")
@click.option("--nominal", default=None, metavar="I,J,...",
              help="Grid index of the nominal plant (default: the middle).")
@grid_options
@click.option("--out", "out", type=OutputFile(("json", "mat")), required=True,
              help="Controller file (.json or .mat; an existing file only with --force).")
@params_option
@json_options
@force_option
@quiet_option
def design_cmd(method, bandwidth, alpha_min, slip_signal, nominal, ratio, slip, tau, clamp,
               speed, load_torque, damping, kinematics, shift_law, drive, load_mode, out,
               params_file, as_json, json_out, force, quiet) -> None:
    """Design a controller (T_mp, T_ms) from the errors of (r_g, slip) on a plant family
    (default family: r_g 0.5..2 (7, geometric), torque ratio tau 0.8..0.95 (4) at
    [operating]'s clamping force and speed; empact.control.family.DESIGN_GRID)."""
    from ..control.hinf import design_hinf
    from ..control.pi import design_pi

    bw_text = bandwidth or "0.1,0.05"
    try:
        bw = tuple(float(x) for x in bw_text.split(","))
    except ValueError:
        raise InputError(f"--bandwidth {bw_text!r}: two numbers RATIO,SLIP [Hz]") from None
    if len(bw) != 2:
        raise InputError(f"--bandwidth {bw_text!r}: two numbers RATIO,SLIP [Hz]")
    for b in bw:
        check_number("--bandwidth", b, 0.0, 50.0, lo_open=True, unit="Hz")
    if method == "pi":
        check_number("--alpha-min", alpha_min, 0.05, 1.9,
                     note="the multiloop disk margin each plant must keep")
    params = get_params(params_file)
    from ..control.family import DESIGN_GRID

    raw = {"ratio": ratio or DESIGN_GRID["r_g"],
           "slip": slip, "tau": tau or (None if slip else DESIGN_GRID["tau"]),
           "clamp": clamp, "speed": speed, "load-torque": load_torque}
    nom = None
    if nominal:
        try:
            nom = tuple(int(x) for x in nominal.split(","))
        except ValueError:
            raise InputError(f"--nominal {nominal!r}: grid indices I,J,...") from None
    with progress_bar(total=2, desc=f"control design ({method}): family, design",
                      unit="step", enabled=not quiet) as bar:
        fam = family_from_options(params, raw, damping, kinematics, shift_law, drive,
                                  load_mode)
        bar.update(1)
        if not fam.ok.all():
            raise InputError(f"{int((~fam.ok).sum())} grid points do not trim ("
                             f"{sorted({str(r) for r in fam.reason.ravel() if r})[0]}); "
                             "narrow the grid")
        if nom is not None and (len(nom) != len(fam.shape)
                                or any(not 0 <= i < s for i, s in zip(nom, fam.shape))):
            raise InputError(f"--nominal {nominal!r}: indices in a grid of shape {fam.shape}")
        if method == "pi":
            ctrl = design_pi(fam, bw, alpha_min=alpha_min, slip=slip_signal, nominal=nom)
        else:
            ctrl = design_hinf(fam, bw, slip=slip_signal, nominal=nom)
        bar.update(1)
    ctrl.save(out)
    if as_json or json_out:
        emit_json({"method": method, "n_states": ctrl.n, "design": dict(ctrl.design),
                   "file": str(out)}, "control.design", json_out)
        return
    w = ctrl.design["worst"]
    click.echo(f"{method}: {ctrl.n} states; over {fam.size} plants: all stable "
               f"{w['all_stable']}, worst disk margin {w['disk_margin']:.3f} "
               f"(+-{w['gain_margin_db']:.2f} dB, +-{w['phase_margin_deg']:.1f} deg); "
               f"written to {out}")


@control_group.command("check")
@click.argument("controller", type=click.Path(dir_okay=False))
@click.option("--family", "family_file", type=click.Path(dir_okay=False), required=True,
              help="Plant family (.npz from `empact plants`).")
@click.option("--mu", is_flag=True, help="Also the structured singular value bound "
              "(slycot ab13md) over a parametric spread covering the family.")
@json_options
@force_option
@quiet_option
def check_cmd(controller, family_file, mu, as_json, json_out, force, quiet) -> None:
    """Closed-loop poles and disk margins of CONTROLLER against every plant of a family."""
    from ..control.controller import load_controller
    from ..control.family import load_family
    from ..control.robustness import mu_upper_bound, robustness_map

    ctrl = load_controller(controller)
    fam = load_family(family_file)
    for name in ctrl.measured:
        base = name[3:] if name.startswith("ln_") else name
        if base not in fam.outputs:
            raise InputError(f"{controller}: measures {name!r}, the family has "
                             f"{', '.join(fam.outputs)}")
    with progress_bar(total=2 if mu else 1, desc="control check: margins" + (", mu" if mu
                                                                           else ""),
                      unit="step", enabled=not quiet) as bar:
        rm = robustness_map(fam, ctrl)
        bar.update(1)
        data = {"worst": rm.worst(), "max_real_pole": rm.max_real_pole,
                "disk_margin": rm.disk_margin, "axes": {k: v for k, v in fam.axes.items()}}
        if mu:
            data["mu"] = mu_upper_bound(fam, ctrl, tuple(s // 2 for s in fam.shape))
            bar.update(1)
    if as_json or json_out:
        emit_json(data, "control.check", json_out)
        return
    w = rm.worst()
    click.echo(f"{fam.size} plants: {int(rm.stable.sum())} closed-loop stable; worst disk "
               f"margin {w['disk_margin']:.3f} (+-{w['gain_margin_db']:.2f} dB, "
               f"+-{w['phase_margin_deg']:.1f} deg); largest pole real part "
               f"{w['max_real_pole']:.4g} 1/s")
    if mu:
        click.echo(f"mu upper bound {data['mu']['mu_peak']:.3g} ({data['mu']['n_blocks']} real "
                   f"blocks; < 1 certifies the box)")


@control_group.command("simulate")
@click.argument("scenario", required=False, type=click.Path(dir_okay=False))
@click.option("--example", default=None, help="A shipped closed-loop scenario.")
@click.option("--list-examples", "list_ex", is_flag=True, help="List them.")
@click.option("--controller", "controller", default=None, type=click.Path(dir_okay=False),
              help="Controller file replacing the scenario's.")
@click.option("--out", "out", type=OutputFile(("csv",)), default=None,
              help="Write the time histories (.csv; an existing file only with --force).")
@params_option
@json_options
@force_option
@quiet_option
def simulate_cmd(scenario, example, list_ex, controller, out, params_file, as_json, json_out,
                 force, quiet) -> None:
    """Closed loop on the nonlinear machine: print the scenario's metrics against its
    targets (exit 1 when the run stops early)."""
    from ..control.closed_loop import control_example_path, control_examples, run_closed_loop
    from ..nonlinear.scenario import load_scenario
    from ..nonlinear.simulation import write_csv

    if list_ex:
        for name, desc in control_examples().items():
            click.echo(f"{name:24s} {desc}")
        return
    if (scenario is None) == (example is None):
        raise InputError("give exactly one of SCENARIO or --example NAME (see --list-examples)")
    sc = load_scenario(control_example_path(example) if example else scenario)
    if not sc.closed_loop:
        raise InputError(f"{scenario}: no [controller] table (an open-loop scenario: run it "
                         "with 'empact simulate')")
    if controller:
        sc = sc.with_controller(controller)
    params = get_params(params_file)
    check_references(sc, params)
    run = run_closed_loop(sc, params, progress=not quiet)
    if out:
        write_csv(run.result, out)
    m = run.metrics
    if as_json or json_out:  # slips as fractions (schema version 2)
        emit_json({"scenario": sc.name, "metrics": fraction_metrics(m)}, "control.simulate",
                  json_out)
    else:  # for people: slips in % and percentage points
        for k, v in m.items():
            name, unit = (k[:-3], "percentage points" if "error" in k else "%") \
                if k.endswith("_pp") else (k, UNITS.get(k, ""))
            shown = f"{v:.6g}" if isinstance(v, float) else str(v)
            click.echo(f"{name:22s} {shown} {unit if unit != '-' else ''}".rstrip())
    if not run.result.complete:
        raise Failed(f"closed loop stopped early: {run.result.message}")
