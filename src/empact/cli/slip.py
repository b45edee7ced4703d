"""``empact slip ...``: slip dynamics of the variator coupling (paper Sec. 2.2, Figs. 9-13).

Operating point options (SI, slip as a fraction): ``--ratio`` r_g [-], ``--slip`` nu [-]
(0.04 is 4 %), ``--clamp`` F_s [N], ``--speed`` omega_p [rad/s]; unset options take the
``[operating]`` point of the parameter file.  Where a command sweeps, an option takes a list
``a,b,c`` or a range ``start:stop:count`` (``count >= 2`` points, ends included; at most
`MAX_SWEEP` values per option and `MAX_MAP` points per map).  ``--traction FILE`` replaces
the analytic traction curve by a tabulated one (CSV ``r_g,nu,mu`` or TOML ``[[curve]]``).
JSON output has ``schema`` and ``units``; poles and zeros are ``[re, im]`` pairs in rad/s.
"""
from __future__ import annotations

from typing import Callable

import click
import numpy as np

from .._validate import check_int, check_number
from ..params import OperatingPoint, Params
from ..slip import (
    INPUTS,
    OUTPUTS,
    VARIABLES,
    belt_root_locus,
    pole_sweep,
    slip_frequency_responses,
    slip_model,
    stability_map,
    zero_locus,
)
from ..variator.traction import TractionModel, traction_curves, traction_from_params
from ._common import (
    LINEAR_OPTIONS,
    OPTION_VARIABLE,
    ErrorGroup,
    InputError,
    emit_json,
    force_option,
    get_params,
    json_options,
    operating_values,
    params_option,
    quiet_option,
    sweep_from_options,
    sweep_options,
    traction_option,
)
from .linear import frequency_grid, plot_option

VARIABLE_OPTION = {OPTION_VARIABLE[k]: k for k in LINEAR_OPTIONS}
#: Most values one option may sweep (poles, responses, zeros are computed per value).
MAX_SWEEP = 10_000
#: Most points of a stability map (about 0.1 s per 40 000 points on two cores).
MAX_MAP = 4_000_000


def parse_values(text: str | None, option: str, limit: int = MAX_SWEEP) -> np.ndarray | None:
    """``"a"`` -> [a]; ``"a,b,c"`` -> list; ``"start:stop:count"`` -> ``linspace``.

    Raises `InputError` (one line, exit 2) for anything else, or more than `limit` values.
    """
    if text is None:
        return None
    hint = "give a value, a list a,b,c or a range start:stop:count"
    s = text.strip()
    if ":" in s:
        parts = s.split(":")
        if len(parts) != 3:
            raise InputError(f"--{option} {text!r}: a range is start:stop:count")
        try:
            a, b = float(parts[0]), float(parts[1])
        except ValueError:
            raise InputError(f"--{option} {text!r}: start and stop must be numbers") from None
        try:
            n = int(parts[2])
        except ValueError:
            raise InputError(f"--{option} {text!r}: count must be a whole number in "
                             f"[2, {limit}]") from None
        if not 2 <= n <= limit:
            raise InputError(f"--{option} {text!r}: count {n} must be in [2, {limit}]")
        if not (np.isfinite(a) and np.isfinite(b)) or a == b:
            raise InputError(f"--{option} {text!r}: start and stop must be finite and differ")
        return np.linspace(a, b, n)
    try:
        values = np.array([float(p) for p in s.split(",")])
    except ValueError:
        raise InputError(f"--{option} {text!r}: not a number; {hint}") from None
    if not np.all(np.isfinite(values)):
        raise InputError(f"--{option} {text!r}: values must be finite")
    if values.size > limit:
        raise InputError(f"--{option}: {values.size} values; at most {limit}")
    return values


def op_options(fn: Callable) -> Callable:
    """The four operating-point options, ``--traction`` and ``--params``."""
    for name, var in reversed([(k, OPTION_VARIABLE[k]) for k in LINEAR_OPTIONS]):
        unit, doc = VARIABLES[var]
        fn = click.option(f"--{name}", name, default=None, metavar="VALUE|LIST|RANGE",
                          help=f"{doc} [{unit}] ({var}); default from the parameter file.")(fn)
    fn = traction_option(fn)
    return params_option(fn)


def _setup(params_file: str | None, traction_table: TractionModel | None) \
        -> tuple[Params, TractionModel]:
    params = get_params(params_file)
    tr = traction_table if traction_table is not None \
        else params.traction_table if params.traction_table is not None \
        else traction_from_params(params)
    return params, tr


def _grid(params: Params, tr: TractionModel, raw: dict[str, str | None], *, max_sweeps: int,
          exact: int | None = None, limit: int = MAX_SWEEP) \
        -> tuple[OperatingPoint, dict[str, np.ndarray]]:
    """Base operating point and the swept variables ``{variable: values}``, every value
    checked under its option's name."""
    values = {}
    for opt, text in raw.items():
        v = parse_values(text, opt, limit)
        if v is not None:
            values[OPTION_VARIABLE[opt]] = operating_values(params, opt, v, traction=tr)
    sweeps = {v: a for v, a in values.items() if a.size > 1}
    names = ", ".join("--" + VARIABLE_OPTION[v] for v in sweeps) or "none"
    if exact is not None and len(sweeps) != exact:
        raise InputError(f"give exactly {exact} of --ratio/--slip/--clamp/--speed as lists or "
                         f"ranges (got {len(sweeps)}: {names})")
    if len(sweeps) > max_sweeps:
        raise InputError(f"give at most {max_sweeps} of --ratio/--slip/--clamp/--speed as a list "
                         f"or range (got {names})")
    fixed = {v: float(a[0]) for v, a in values.items() if a.size == 1}
    return params.operating.resolve(params, tr).replace(**fixed), sweeps


def _pairs(z: np.ndarray) -> list[list[float]]:
    return [[float(c.real), float(c.imag)] for c in np.asarray(z, complex).ravel()]


@click.group("slip", cls=ErrorGroup)
def slip_group() -> None:
    """Slip dynamics: traction, poles, root locus, FRFs, zeros, stability map (Figs. 9-13)."""


# --------------------------------------------------------------------------------------------
@slip_group.command("statespace")
@op_options
@json_options
@force_option
def statespace(ratio, slip, clamp, speed, traction_table, params_file, as_json,
               json_out, force) -> None:
    """The linearised slip model at one operating point (A, B, C, D with names)."""
    params, tr = _setup(params_file, traction_table)
    base, _ = _grid(params, tr, dict(ratio=ratio, slip=slip, clamp=clamp, speed=speed),
                    max_sweeps=0)
    m = slip_model(params, base, tr)
    if as_json or json_out:
        emit_json({"operating_point": base.to_dict(), "c_b": m.belt.c_b, "c_s": m.belt.c_s,
                   "g_F": m.belt.g_F, "mu": m.belt.mu, "dmu": m.belt.dmu, "A": m.A, "B": m.B,
                   "C": m.C, "D": m.D, "inputs": m.inputs, "outputs": m.outputs,
                   "states": m.states}, "slip.statespace", json_out)
        return
    b = m.belt
    click.echo(f"slip model at r_g = {base.r_g:g}, nu = {base.nu:g}, F_s = {base.F_s:g} N, "
               f"omega_p = {base.omega_p:g} rad/s")
    click.echo(f"mu = {b.mu:.5g}, mu' = {b.dmu:.5g}, c_b = {b.c_b:.5g} N m s/rad (paper eq. 3), "
               f"c_s = {b.c_s:.5g} N m s/rad, g_F = {b.g_F:.5g} m")
    for name, mat, rows, cols in (("A", m.A, m.states, m.states), ("B", m.B, m.states, m.inputs),
                                  ("C", m.C, m.outputs, m.states),
                                  ("D", m.D, m.outputs, m.inputs)):
        click.echo(f"{name}:" + "".join(f"{c:>13s}" for c in cols))
        for r, row in zip(rows, mat):
            click.echo(f"{r:>13s}" + "".join(f"{x:13.5g}" for x in row))


# --------------------------------------------------------------------------------------------
@slip_group.command("poles")
@op_options
@json_options
@plot_option
@force_option
def poles(ratio, slip, clamp, speed, traction_table, params_file, as_json, json_out, plot,
          force) -> None:
    """Poles at one operating point, or over one swept variable (Fig. 11: --slip range)."""
    params, tr = _setup(params_file, traction_table)
    base, sweeps = _grid(params, tr, dict(ratio=ratio, slip=slip, clamp=clamp, speed=speed),
                         max_sweeps=1)
    name, values = next(iter(sweeps.items())) if sweeps else ("nu", np.array([base.nu]))
    sw = pole_sweep(params, name, values, base, tr)  # type: ignore[arg-type]
    points = []
    for k, v in enumerate(values):
        op = base.replace(**{name: float(v)})
        m = slip_model(params, op, tr)
        max_re = float(sw.max_real[k])
        points.append({"operating_point": op.to_dict(), "mu": m.belt.mu, "dmu": m.belt.dmu,
                       "c_b": m.belt.c_b, "poles": _pairs(m.poles()),
                       "max_real": max_re, "min_damping": float(sw.min_damping[k]),
                       "stable": bool(max_re <= 1e-6)})
    if plot:
        from ..plotting import plot_pole_sweep

        plot_pole_sweep(sw).save(plot)
    if as_json or json_out:
        emit_json({"operating_point": base.to_dict(), "variable": name if sweeps else None,
                   "values": values, "points": points,
                   "note": "poles: all 8 eigenvalues, including the three structural zeros; "
                           "max_real and min_damping leave those out"}, "slip.poles", json_out)
        return
    if plot:
        return
    click.echo(f"{name:>10s} {'c_b':>10s}  oscillatory poles: f [Hz] / damping [-]"
               f"{'':8s}{'max Re [1/s]':>13s}")
    for k, p in enumerate(points):
        f, z = sw.oscillatory(k)
        osc = "  ".join(f"{fi:7.3f}/{zi:+.4f}" for fi, zi in zip(f, z))
        click.echo(f"{values[k]:10.4g} {p['c_b']:10.4g}  {osc:38s} {p['max_real']:+13.4g}"
                   + ("" if p["stable"] else "  UNSTABLE"))


# --------------------------------------------------------------------------------------------
@slip_group.command("rootlocus")
@click.option("--ratio", "ratio", type=float, default=1.0, show_default=True,
              help="Geometric ratio r_g [-].")
@click.option("--slip", "slip", type=float, default=0.0, show_default=True,
              help="Slip nu0 [-] of the kinematic ratio r_g (1 - nu0).")
@click.option("--cb-min", type=float, default=1e-3, show_default=True,
              help="Smallest c_b of the computed locus [N m s/rad] (c_b = 0 is added exactly).")
@click.option("--cb-max", type=float, default=1e4, show_default=True,
              help="Largest c_b [N m s/rad] (c_b -> inf is added exactly).")
@params_option
@json_options
@plot_option
@force_option
def rootlocus(ratio, slip, cb_min, cb_max, params_file, as_json, json_out, plot,
              force) -> None:
    """Root locus over the belt damping c_b from 0 to infinity (Fig. 9)."""
    params = get_params(params_file)
    ratio = float(operating_values(params, "ratio", ratio))
    slip = float(operating_values(params, "slip", slip))  # as every command reads a slip
    cb_min = check_number("--cb-min", cb_min, 0.0, lo_open=True, unit="N m s/rad")
    cb_max = check_number("--cb-max", cb_max, cb_min, 1e12, lo_open=True, unit="N m s/rad",
                          note="above --cb-min")
    rl = belt_root_locus(params, ratio, slip, c_b_range=(cb_min, cb_max))
    if plot:
        from ..plotting import plot_belt_root_locus

        plot_belt_root_locus(rl).save(plot)
    if as_json or json_out:
        emit_json({"r_g": ratio, "nu": slip, "c_b": rl.locus.parameter,
                   "branches": np.stack([rl.locus.poles.real, rl.locus.poles.imag], axis=-1),
                   "start": _pairs(rl.start), "end": _pairs(rl.stop),
                   "end_note": "c_b -> inf: seven finite poles; the eighth goes to -inf",
                   "uncoupled_hz": rl.uncoupled_hz, "coupled_hz": rl.coupled_hz},
                  "slip.rootlocus", json_out)
        return
    if plot:
        return
    click.echo(f"root locus over c_b at r_g = {ratio:g}: {len(rl.locus.parameter)} points, "
               f"c_b from {cb_min:g} to {cb_max:g} N m s/rad")
    click.echo("c_b = 0   (uncoupled): " + ", ".join(f"{f:.3f}" for f in rl.uncoupled_hz)
               + " Hz")
    click.echo("c_b -> inf (coupled):  " + ", ".join(f"{f:.3f}" for f in rl.coupled_hz)
               + " Hz (one real pole -> -inf)")


# --------------------------------------------------------------------------------------------
@slip_group.command("frf")
@op_options
@click.option("--input", "inp", type=click.Choice(INPUTS), default="F_s", show_default=True)
@click.option("--output", "out", type=click.Choice(OUTPUTS), default="nu", show_default=True)
@click.option("--fmin", type=float, default=0.1, show_default=True, help="[Hz]")
@click.option("--fmax", type=float, default=300.0, show_default=True, help="[Hz]")
@click.option("--n", "n", type=int, default=400, show_default=True, help="Number of frequencies.")
@json_options
@plot_option
@force_option
def frf(ratio, slip, clamp, speed, traction_table, params_file, inp, out, fmin, fmax, n,
        as_json, json_out, plot, force) -> None:
    """Frequency response (default F_s -> nu) at one or several points (Fig. 12)."""
    params, tr = _setup(params_file, traction_table)
    f = frequency_grid(fmin, fmax, n)
    base, sweeps = _grid(params, tr, dict(ratio=ratio, slip=slip, clamp=clamp, speed=speed),
                         max_sweeps=1, limit=max(2, min(MAX_SWEEP, 10_000_000 // len(f))))
    if sweeps:
        name, values = next(iter(sweeps.items()))
        ops = [base.replace(**{name: float(v)}) for v in values]
    else:
        ops = [base]
    resp = slip_frequency_responses(params, ops, 2 * np.pi * f, traction=tr, input=inp,
                                    output=out)
    if plot:
        from ..plotting import plot_slip_bode

        plot_slip_bode(resp, title=f"{inp} -> {out}").save(plot)
    if as_json or json_out:
        emit_json({"operating_point": base.to_dict(), "input": inp, "output": out,
                   "frequencies_hz": f,
                   "responses": [{"operating_point": op.to_dict(),
                                  "magnitude_db": r.magnitude_db()[0, 0],
                                  "phase_deg": r.phase_deg()[0, 0]}
                                 for op, r in zip(ops, resp)]}, "slip.frf", json_out)
        return
    if plot:
        return
    click.echo(f"{'f [Hz]':>10s} " + " ".join(f"{r.label:>26s}" for r in resp)
               + f"  |{out}/{inp}| [dB]")
    for k in range(len(f)):
        click.echo(f"{f[k]:10.4g} " + " ".join(f"{r.magnitude_db()[0, 0, k]:26.3f}"
                                               for r in resp))


# --------------------------------------------------------------------------------------------
@slip_group.command("zeros")
@op_options
@json_options
@plot_option
@force_option
def zeros(ratio, slip, clamp, speed, traction_table, params_file, as_json, json_out, plot,
          force) -> None:
    """Zeros of F_s -> nu at one ratio or over a --ratio list/range (Fig. 13)."""
    params, tr = _setup(params_file, traction_table)
    raw = dict(ratio=ratio, slip=slip, clamp=clamp, speed=speed)
    base, sweeps = _grid(params, tr, raw, max_sweeps=1)
    if sweeps and "r_g" not in sweeps:
        raise InputError("zeros: only --ratio may be a list or range (the zeros of F_s -> nu do "
                         "not depend on --clamp or --speed, and on --slip only through "
                         "r_g (1 - nu))")
    ratios = sweeps.get("r_g", np.array([base.r_g]))
    zl = zero_locus(params, ratios, base, tr)
    if plot:
        from ..plotting import plot_zero_locus

        plot_zero_locus(zl).save(plot)
    coupled_hz = np.sort(np.abs(zl.coupled), axis=1)[:, ::2] / (2 * np.pi)
    if as_json or json_out:
        emit_json({"operating_point": base.to_dict(), "r_g": ratios,
                   "zeros": [_pairs(z[np.isfinite(z)]) for z in zl.zeros],
                   "zeros_at_origin": zl.n_origin, "zeros_hz": zl.zero_hz,
                   "coupled_hz": coupled_hz,
                   "note": "zeros away from the origin; they equal the poles of the coupled "
                           "driveline (c_b -> inf)"}, "slip.zeros", json_out)
        return
    if plot:
        return
    click.echo(f"{'r_g':>8s}  zeros of F_s -> nu [Hz] (|z| / 2 pi)   coupled poles [Hz]  "
               "(+ zeros at the origin)")
    for k, r in enumerate(ratios):
        click.echo(f"{r:8.4g}  {', '.join(f'{x:8.3f}' for x in zl.zero_hz[k]):30s}"
                   f"   {', '.join(f'{x:8.3f}' for x in coupled_hz[k]):18s}  (+{zl.n_origin[k]})")


# --------------------------------------------------------------------------------------------
@slip_group.command("map")
@op_options
@click.option("--method", type=click.Choice(["reduced", "full"]), default="reduced",
              show_default=True, help="Stacked 5x5 reduced matrices or the full 8x8 ones.")
@click.option("--chunk", "chunk", type=int, default=4096, show_default=True,
              help="Points per batched eigenvalue call (bounds memory).")
@sweep_options
@json_options
@plot_option
@force_option
@quiet_option
def map_cmd(ratio, slip, clamp, speed, traction_table, params_file, method, chunk, scheduler,
            workers, scheduler_timeout, as_json, json_out, plot, force, quiet) -> None:
    """Stability map over two ranges (--slip 0.001:0.06:200 --ratio 0.5:2.2:200)."""
    params, tr = _setup(params_file, traction_table)
    raw = dict(ratio=ratio, slip=slip, clamp=clamp, speed=speed)
    base, sweeps = _grid(params, tr, raw, max_sweeps=2, exact=2, limit=MAX_MAP // 2)
    order = ["nu", "F_s", "omega_p", "r_g"]  # x axis: the first of these that is swept
    (x_name, x), (y_name, y) = sorted(sweeps.items(), key=lambda kv: order.index(kv[0]))
    if x.size * y.size > MAX_MAP:
        raise InputError(f"--{VARIABLE_OPTION[x_name]} x --{VARIABLE_OPTION[y_name]}: "
                         f"{x.size} x {y.size} = {x.size * y.size} points; at most {MAX_MAP}")
    sweep = sweep_from_options(scheduler, workers, scheduler_timeout, progress=not quiet)
    sm = stability_map(params, x_name, x, y_name, y, base=base,  # type: ignore[arg-type]
                       traction=tr, method=method, chunk_size=check_int("--chunk", chunk, 1),
                       workers=workers, sweep=sweep)
    if plot:
        from ..plotting import plot_stability_map

        plot_stability_map(sm).save(plot)
    if as_json or json_out:
        emit_json({"operating_point": base.to_dict(), "x": {"name": x_name, "values": x},
                   "y": {"name": y_name, "values": y}, "max_real": sm.max_real,
                   "min_damping": sm.min_damping, "unstable": sm.unstable,
                   "unstable_fraction": sm.unstable_fraction,
                   "note": "arrays have shape (len(y), len(x))"}, "slip.map", json_out)
        return
    click.echo(f"stability map over {x_name} ({len(x)}) x {y_name} ({len(y)}): "
               f"{100 * sm.unstable_fraction:.1f} % of the points unstable; largest real part "
               f"{sm.max_real.max():.4g} 1/s, smallest damping ratio of the stable points "
               f"{np.min(sm.min_damping[~sm.unstable], initial=np.inf):.4g}")


# --------------------------------------------------------------------------------------------
@slip_group.command("traction")
@click.option("--ratio", "ratio", default="0.43,1,2.25", show_default=True,
              metavar="LIST|RANGE", help="Ratios r_g [-].")
@click.option("--slip", "slip", default="0:0.1:101", show_default=True, metavar="LIST|RANGE",
              help="Slips nu [-] (0.01 is 1 %).")
@traction_option
@params_option
@json_options
@plot_option
@force_option
def traction(ratio, slip, traction_table, params_file, as_json, json_out, plot, force) -> None:
    """Traction coefficient mu and slope mu' over slip at some ratios (Fig. 10)."""
    params, tr = _setup(params_file, traction_table)
    r = operating_values(params, "ratio", parse_values(ratio, "ratio"))
    nu = operating_values(params, "slip", parse_values(slip, "slip"), traction=tr)
    curves = traction_curves(tr, r, nu, label="(tabulated)" if traction_table is not None else "")
    if plot:
        from ..plotting import plot_traction

        plot_traction(curves).save(plot)
    nu_pk, mu_pk = curves.peak()
    if as_json or json_out:
        emit_json({"r_g": r, "nu": nu, "mu": curves.mu, "dmu": curves.dmu,
                   "nu_range": tr.nu_range, "nu_peak": nu_pk, "mu_peak": mu_pk},
                  "slip.traction", json_out)
        return
    if plot:
        return
    click.echo(f"{'nu':>8s} " + " ".join(f"{'mu(' + format(x, 'g') + ')':>12s} "
                                         f"{'dmu(' + format(x, 'g') + ')':>12s}" for x in r))
    for k in range(len(nu)):
        click.echo(f"{nu[k]:8.4g} " + " ".join(f"{curves.mu[j, k]:12.5g} {curves.dmu[j, k]:12.5g}"
                                               for j in range(len(r))))
