"""``empact efficiency``: steady-state efficiency of the variator and its actuation by clamping
strategy (`empact.efficiency`), over input torque x input speed x ratio, or over clamping force
at one point (``--clamp A:B:N``).
"""
from __future__ import annotations

import click
import numpy as np

from .._validate import check_number
from ..efficiency import STRATEGIES, efficiency_map
from ..variator.geometry import check_ratio
from ._common import (
    OPERATING_RANGES,
    Failed,
    InputError,
    emit_json,
    force_option,
    get_params,
    json_options,
    loss_map_option,
    params_option,
    parse_choices,
)
from .linear import plot_option
from .slip import parse_values

#: most points of one map (each a trim, about 2 ms of one core)
MAX_POINTS = 20_000


def _values(text: str, option: str, unit: str, variable: str) -> np.ndarray:
    """A positive list or range of an option (`parse_values`) within the command line's range
    of its `variable` (`OPERATING_RANGES`), one line on error."""
    v = parse_values(text, option)
    assert v is not None
    hi = OPERATING_RANGES[variable][1]
    for x in v:
        check_number(f"--{option}", float(x), 0.0, hi, lo_open=True, unit=unit)
    return np.asarray(v, float)


@click.command("efficiency")
@click.option("--torque", "torque", default="50,100,150", show_default=True,
              help="Input torques T_in at the primary [N m]: a value, a list a,b,c or a range "
                   "start:stop:count.")
@click.option("--speed", "speed", default="300", show_default=True,
              help="Input (primary) speeds omega_in [rad/s]: a value, list or range.")
@click.option("--ratio", "ratio", default="0.5,1,2", show_default=True,
              help="Ratios r_g: a value, list or range.")
@click.option("--strategy", "strategy", default=",".join(STRATEGIES), show_default=True,
              help="Comma-separated clamping strategies (" + ", ".join(STRATEGIES) + ").")
@click.option("--clamp", "clamp", default=None,
              help="A:B:N: efficiency over the clamping force F_s [N] from A to B (N points) at "
                   "one torque, speed and ratio (the sweep's clamping replaces the "
                   "strategy's).")
@click.option("--tau", "tau", type=float, default=None,
              help="The slip strategy's torque ratio set-point [-] (default: the parameter "
                   "file's [operating] tau).")
@plot_option
@loss_map_option
@params_option
@json_options
@force_option
def efficiency_cmd(torque, speed, ratio, strategy, clamp, tau, plot, loss_map, params_file,
                   as_json, json_out, force) -> None:
    """Variator and total efficiency by clamping strategy (steady-state trims).

    Exit status: 0 done (a point that does not trim is listed with its reason); 1 when no
    point trims (nothing written); 2 bad input."""
    T = _values(torque, "torque", "N m", "T_l")
    w = _values(speed, "speed", "rad/s", "omega_p")
    r = _values(ratio, "ratio", "-", "r_g")
    strategies = parse_choices("--strategy", strategy, STRATEGIES)
    params = get_params(params_file, loss_map)
    check_ratio(r, params.variator, "--ratio")
    F = None
    if clamp is not None:
        if clamp.count(":") != 2:
            raise InputError(f"--clamp {clamp!r}: a clamping sweep is A:B:N (forces in N)")
        F = _values(clamp, "clamp", "N", "F_s")
        if T.size != 1 or w.size != 1 or r.size != 1:
            raise InputError("--clamp: give one --torque, one --speed and one --ratio")
    if tau is not None:
        tau = check_number("--tau", tau, 0.0, 1.0, lo_open=True, hi_open=True)
    n = len(strategies) * T.size * w.size * r.size * (1 if F is None else F.size)
    if n > MAX_POINTS:
        raise InputError(f"{n} points: at most {MAX_POINTS} per map (fewer torques, speeds, "
                         "ratios or strategies)")
    res = efficiency_map(params, T, w, r, strategies=strategies, F_s=F, tau=tau)
    points = res.points()
    if not any(p["ok"] for p in points):  # a map of nothing: not a result (exit 1)
        raise Failed(f"none of the {len(points)} points trims (e.g. {points[0]['strategy']} "
                     f"at r_g = {points[0]['r_g']:g}, T_in = {points[0]['T_in']:g} N m: "
                     f"{points[0]['reason']}); nothing written")
    if plot:
        from ..plotting import plot_efficiency_map

        plot_efficiency_map(res).save(plot)
    if as_json or json_out:
        emit_json(res.to_dict(), "efficiency", json_out)
        return
    click.echo(f"{'strategy':12s} {'r_g':>5s} {'T_in':>6s} {'omega':>7s} {'F_s':>7s} "
               f"{'tau':>6s} {'P_in':>8s} {'loss':>7s} {'act.':>7s} {'eff.':>6s} "
               f"{'total':>6s}")
    click.echo(f"{'':12s} {'[-]':>5s} {'[N m]':>6s} {'[rad/s]':>7s} {'[kN]':>7s} {'[-]':>6s} "
               f"{'[kW]':>8s} {'[W]':>7s} {'[W]':>7s} {'[%]':>6s} {'[%]':>6s}")
    for p in points:
        if not p["ok"]:
            click.echo(f"{p['strategy']:12s} {p['r_g']:5.3g} {p['T_in']:6.4g} "
                       f"{p['omega_in']:7.4g}  not trimmed: {p['reason']}")
            continue
        loss = sum(p["losses"].values())
        act = sum(p["actuation"].values())
        click.echo(f"{p['strategy']:12s} {p['r_g']:5.3g} {p['T_in']:6.4g} "
                   f"{p['omega_in']:7.4g} {p['F_s'] / 1e3:7.2f} {p['tau']:6.3f} "
                   f"{p['P_in'] / 1e3:8.3f} {loss:7.1f} {act:7.1f} "
                   f"{100 * p['efficiency']:6.2f} {100 * p['total_efficiency']:6.2f}")
