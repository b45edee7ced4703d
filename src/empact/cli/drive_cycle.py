"""``empact cycle``: a drive cycle, quasi-static (`empact.drive_cycle`), by clamping strategy:
energy by loss term and phase, efficiencies, fuel and the saving against hydraulic-sf1.3."""
from __future__ import annotations

import click

from .._validate import check_number
from ..cycles import CYCLES, load_cycle, read_trace
from ..drive_cycle import (
    DEFAULT_STRATEGIES,
    REFERENCE,
    STRATEGIES,
    TERMS,
    check_trace,
    quasi_static_cycle,
)
from ..errors import ParameterError
from ._common import (
    InputError,
    emit_json,
    force_option,
    get_params,
    json_options,
    loss_map_option,
    output_folder,
    params_option,
    parse_choices,
    shown_path,
)
from .linear import plot_option


@click.command("cycle")
@click.option("--cycle", "cycle", required=True,
              help="A shipped cycle (" + ", ".join(CYCLES) + ") or a CSV trace FILE "
                   "('time [s]', 'speed [km/h]' or 'speed [m/s]').")
@click.option("--strategies", "strategies", default=",".join(DEFAULT_STRATEGIES),
              show_default=True,
              help="Comma-separated clamping strategies (" + ", ".join(STRATEGIES) + ").")
@click.option("--out", "out", default=None, type=click.Path(file_okay=False),
              help="Output folder for cycle.json and samples.csv; new or empty unless "
                   "--force.")
@click.option("--dynamic", is_flag=True,
              help="Also run the cycle forward on the nonlinear vehicle driveline with the "
                   "loop law and a driver (empact.dynamic_cycle; minutes: about a minute "
                   "per strategy on WLTC 3b), the quasi-static model below the launch "
                   "speed and at rest.")
@click.option("--rate", "rate", type=float, default=1000.0, show_default=True,
              help="With --dynamic: the loop law's and the driver's rate [Hz].")
@click.option("--output-rate", "output_rate", type=float, default=100.0, show_default=True,
              help="With --dynamic: output samples per second [Hz] (the energies' "
                   "quadrature).")
@plot_option
@loss_map_option
@params_option
@json_options
@force_option
def cycle_cmd(cycle, strategies, out, dynamic, rate, output_rate, plot, loss_map, params_file,
              as_json, json_out, force) -> None:
    """A drive cycle, quasi-static (backward): the variator trimmed at every sample of the
    trace on the operating line, its losses and actuation, the engine's fuel, by strategy
    (energies [J], fuel [g] and [l/100 km], saving against hydraulic-sf1.3); with
    --dynamic, forward on the nonlinear car with the loop law and a driver (speed error,
    macro slip, belt slack)."""
    from .._io import atomic_folder

    chosen = parse_choices("--strategies", strategies, tuple(STRATEGIES))
    if not dynamic:
        for name, src in (("--rate", "rate"), ("--output-rate", "output_rate")):
            if click.get_current_context().get_parameter_source(src) is \
                    click.core.ParameterSource.COMMANDLINE:
                raise InputError(f"{name}: only with --dynamic")
    check_number("--rate", rate, 100.0, 1e4, unit="Hz")
    check_number("--output-rate", output_rate, 1.0, 1e3, unit="Hz")
    params = get_params(params_file, loss_map)
    if cycle in CYCLES:
        trace = load_cycle(cycle)
    else:
        try:
            trace = read_trace(cycle)
        except ParameterError as exc:
            raise InputError(f"--cycle {shown_path(cycle)!r}: not a shipped cycle "
                             f"({', '.join(CYCLES)}), and as a trace file: "
                             f"{str(exc).replace(cycle, shown_path(cycle))}") from None
    check_trace(params, trace)
    dest = output_folder(out, "--out", force=force) if out else None
    res = quasi_static_cycle(params, trace, strategies=chosen)
    if dynamic:
        _dynamic(params, trace, res, chosen, rate, output_rate, plot, dest, as_json, json_out)
        return
    doc = res.to_dict()
    if plot:
        from ..plotting import plot_drive_cycle

        plot_drive_cycle(res).save(plot)
    if dest is not None:
        with atomic_folder(dest) as tmp:
            emit_json(doc, "cycle", str(tmp / "cycle.json"))  # with schema and units
            (tmp / "samples.csv").write_text(_samples_csv(res))
    if as_json or json_out:
        emit_json(doc, "cycle", json_out)
        return
    click.echo(f"{doc['cycle']}: {doc['distance_m'] / 1e3:.3f} km in {doc['duration_s']:g} s, "
               f"traction at the wheels {doc['wheel_energy_J'] / 1e6:.3f} MJ")
    head = " ".join(f"{k:>8s}" for k in TERMS)
    click.echo(f"{'strategy':16s} {head} {'var.eff':>7s} {'trans.':>7s} {'fuel':>7s} "
               f"{'fuel':>9s} {'saving':>7s}")
    units = " ".join(f"{'[kJ]':>8s}" for _ in TERMS)
    click.echo(f"{'':16s} {units} {'[%]':>7s} {'[%]':>7s} {'[g]':>7s} {'[l/100km]':>9s} "
               f"{'[%]':>7s}")
    def pct(x: float | None, width: int = 7) -> str:  # (none: nothing transmitted)
        return f"{'-':>{width}s}" if x is None else f"{100 * x:{width}.2f}"

    for s, d in doc["strategies"].items():
        e = " ".join(f"{d['energy_J'][k] / 1e3:8.1f}" for k in TERMS)
        per_100 = d["fuel_l_per_100km"]
        click.echo(f"{s:16s} {e} {pct(d['variator_efficiency'])} "
                   f"{pct(d['transmission_efficiency'])} {d['fuel_g']:7.1f} "
                   f"{'-' if per_100 is None else format(per_100, '.2f'):>9s} "
                   f"{'' if d['saving'] is None else pct(d['saving'])}")
    for s, d in doc["strategies"].items():
        if d["engine_short"]:
            click.echo(f"{s}: the engine cannot follow the trace at {d['engine_short']} "
                       "samples (beyond full load or its highest speed; computed as asked)")
    if REFERENCE not in doc["strategies"]:
        click.echo(f"(no saving: {REFERENCE}, the reference, was not run)")


def _dynamic(params, trace, qs, chosen, rate, output_rate, plot, dest, as_json,
             json_out) -> None:
    """``empact cycle --dynamic``: the dynamic cycle on the quasi-static one `qs`."""
    from .._io import atomic_folder
    from ..dynamic_cycle import dynamic_cycle

    res = dynamic_cycle(params, trace, strategies=chosen, quasi_static=qs, rate=rate,
                        output_rate=output_rate)
    doc = res.to_dict()
    if plot:
        from ..plotting import plot_dynamic_cycle

        plot_dynamic_cycle(res).save(plot)
    if dest is not None:
        with atomic_folder(dest) as tmp:
            emit_json(doc, "cycle", str(tmp / "cycle.json"))
            (tmp / "samples.csv").write_text(_samples_csv(qs))
    if as_json or json_out:
        emit_json(doc, "cycle", json_out)
        return
    click.echo(f"{doc['cycle']}: {doc['distance_m'] / 1e3:.3f} km in {doc['duration_s']:g} s, "
               f"traction at the wheels {doc['wheel_energy_J'] / 1e6:.3f} MJ; dynamic "
               f"{doc['dynamic_duration_s']:g} s at and above {3.6 * doc['v_launch_m_s']:.1f} "
               f"km/h (law at {rate:g} Hz), the quasi-static model below")
    head = " ".join(f"{k:>8s}" for k in TERMS + ("brakes",))
    click.echo(f"{'strategy':16s} {head} {'fuel':>7s} {'l/100km':>7s} {'saving':>7s} "
               f"{'dv max':>7s} {'macro':>6s} {'slack':>6s} {'var.loss dyn/qs':>16s}")
    units = " ".join(f"{'[kJ]':>8s}" for _ in TERMS + ("brakes",))
    click.echo(f"{'':16s} {units} {'[g]':>7s} {'':>7s} {'[%]':>7s} {'[km/h]':>7s} "
               f"{'':>6s} {'':>6s} {'[kJ]':>16s}")
    for s, d in doc["strategies"].items():
        e = " ".join(f"{d['energy_J'][k] / 1e3:8.1f}" for k in TERMS + ("brakes",))
        saving = "" if d["saving"] is None else f"{100 * d['saving']:7.2f}"
        var = f"{d['variator_loss_J'] / 1e3:.1f}/{d['quasi_static_variator_loss_J'] / 1e3:.1f}"
        click.echo(f"{s:16s} {e} {d['fuel_g']:7.1f} {d['fuel_l_per_100km']:7.2f} "
                   f"{saving:>7s} {d['speed_error_max_kmh']:7.2f} {str(d['macro_slip']):>6s} "
                   f"{str(d['belt_slack']):>6s} {var:>16s}")
    for s, d in doc["strategies"].items():
        if not d["complete"]:
            bad = [m for m in d["messages"] if not m.startswith("completed")]
            click.echo(f"{s}: a stretch stopped early: {bad[0]}")


def _samples_csv(res) -> str:
    """The per-sample table: time, speed, wheel power, and by strategy ratio, engine speed,
    clamping, engine power and fuel rate (SI)."""
    cols = ["time [s]", "speed [m/s]", "P_wheel [W]"]
    data = [res.t, res.v, res.P_wheel]
    for s in res.strategies:
        cols += [f"{s} r_g [-]", f"{s} omega_e [rad/s]", f"{s} F_s [N]", f"{s} P_e [W]",
                 f"{s} fuel [kg/s]"]
        data += [res.r_g[s], res.omega_e[s], res.F_s[s], res.power[s]["engine"],
                 res.fuel_rate[s]]
    lines = [f"# empact cycle {res.cycle.name}: quasi-static, by strategy", ",".join(cols)]
    lines += [",".join(repr(float(c[k])) for c in data) for k in range(res.t.size)]
    return "\n".join(lines) + "\n"
