"""``empact montecarlo``: an analysis over a parameter spread, in process or on Dask."""
from __future__ import annotations

import os

import click

from ._common import (
    Failed,
    InputError,
    Interrupted,
    emit_json,
    force_option,
    get_params,
    json_options,
    loss_map_option,
    output_folder,
    params_option,
    quiet_option,
    sweep_from_options,
    sweep_options,
    traction_option,
)


@click.command("montecarlo")
@click.option("--spread", "spread_file", type=click.Path(dir_okay=False), default=None,
              help="TOML file of parameter distributions (see --example-spread).")
@click.option("--example-spread", "example_spread", is_flag=False, flag_value="example",
              default=None, type=click.Choice(["example", "wide"]),
              help="Print a shipped spread file and exit: 'example' (the default, a few "
                   "percent) or 'wide' (traction shape at all three ratios, clamping level, "
                   "load step; for --analysis closed-loop).")
@click.option("--runs", type=int, default=100, show_default=True, help="Number of runs.")
@click.option("--analysis", type=click.Choice(["plant", "slip", "closed-loop"]),
              default="plant", show_default=True,
              help="What each run evaluates: the plant at the operating point, the slip "
                   "model's stability, or a closed-loop scenario's metrics.")
@click.option("--scenario", "scenario", type=click.Path(dir_okay=False), default=None,
              help="Closed-loop scenario file (closed-loop analysis).")
@click.option("--example", default=None,
              help="A shipped closed-loop scenario (see 'empact control simulate "
                   "--list-examples').")
@click.option("--controller", default=None, type=click.Path(dir_okay=False),
              help="Controller file (or shipped:pi, shipped:hinf) replacing the scenario's.")
@click.option("--seed", type=int, default=0, show_default=True,
              help="Seed of the study (run i draws from its own stream of it).")
@click.option("--out", "out", type=click.Path(file_okay=False), default=None,
              help="Folder for runs.csv, runs.json and summary.json; the runs stream into "
                   "its shards/ (a chunk of about a second each) and manifest.json as they "
                   "complete.")
@click.option("--resume", is_flag=True,
              help="Continue the killed study in --out from its shards (the same spread, "
                   "seed, runs, analysis and parameters).")
@click.option("--strict", is_flag=True,
              help="Closed loop: exit 1 when any run missed a scenario target (or failed).")
@sweep_options
@traction_option
@loss_map_option
@params_option
@json_options
@force_option
@quiet_option
def montecarlo_cmd(spread_file, example_spread, runs, analysis, scenario, example, controller,
                   seed, out, resume, strict, scheduler, workers, scheduler_timeout,
                   traction_table, loss_map,
                   params_file, as_json, json_out, force, quiet) -> None:
    """Monte Carlo over parameter spread: each run draws the spread's parameters, evaluates
    the analysis and is recorded (a failed run with its reason); prints the summary
    (quantiles, failure count).

    Closed loop: each run's scenario targets are judged (met / missed by name, columns
    ``met.NAME``), with its macro slip and belt slack; the summary counts the runs missing
    each target (a run that failed to simulate misses every target).

    Exit status: 0 when at least one run succeeded (with --strict: and no run missed a
    target); 1 when every run failed (nothing written), or with --strict when a run missed
    a target; 2 bad input (a spread none of whose values a parameter may take, ...)."""
    from importlib import resources
    from pathlib import Path

    from .._validate import check_int
    from ..montecarlo import load_spread, monte_carlo, save_montecarlo

    if example_spread:
        click.echo(resources.files("empact.data").joinpath(
            "montecarlo", f"{example_spread}-spread.toml").read_text(), nl=False)
        return
    if spread_file is None:
        raise InputError("--spread: give a spread file (--example-spread prints one)")
    runs = check_int("--runs", runs, 1, 1_000_000)
    seed = check_int("--seed", seed, 0, 2**63 - 1)
    closed = analysis == "closed-loop"
    if traction_table is not None and analysis == "slip":
        raise InputError("--traction: the slip analysis draws the analytic curve's "
                         "coefficients; a measured table serves --analysis plant and "
                         "closed-loop")
    if loss_map is not None and analysis == "slip":
        raise InputError("--loss-map: the slip analysis's linear slip model has no torque "
                         "loss; a measured map serves --analysis plant and closed-loop")
    if not closed and (scenario or example or controller):
        raise InputError(f"--analysis {analysis}: --scenario, --example and --controller "
                         "belong to --analysis closed-loop")
    if closed and (scenario is None) == (example is None):
        raise InputError("--analysis closed-loop: give exactly one of --scenario FILE or "
                         "--example NAME")
    if strict and not closed:
        raise InputError(f"--strict: judges the scenario targets of --analysis closed-loop, "
                         f"not --analysis {analysis}")
    if resume and not out:
        raise InputError("--resume: give the study's folder with --out DIR")
    if resume:
        from ..shards import MANIFEST

        if not (Path(out) / MANIFEST).is_file():
            raise InputError(f"--resume {out}: not a study folder (no {MANIFEST}); start the "
                             "study with --out alone")
    elif out:
        output_folder(out, "--out", force=force)
    sweep = sweep_from_options(scheduler, workers, scheduler_timeout, progress=not quiet)
    params = get_params(params_file, loss_map)
    sc = ctrl = None
    if closed:
        from ..control.closed_loop import control_example_path, resolve_controller
        from ..nonlinear.scenario import check_references, load_scenario

        sc = load_scenario(control_example_path(example) if example else scenario,
                           params if traction_table is None else None)
        if not sc.closed_loop:
            raise InputError(f"--scenario {scenario}: no [controller] table (the closed-loop "
                             "analysis needs a closed-loop scenario)")
        if traction_table is not None:  # the references against the curve the run uses
            sc = sc.with_options(traction=traction_table)
            check_references(sc, params)
        if loss_map is not None:  # the command line's map over the scenario's
            sc = sc.with_options(loss_map=loss_map)
        assert sc.controller is not None  # closed_loop
        ctrl = resolve_controller(controller or sc.controller.file)
    spread = load_spread(spread_file, params, sc)
    existed = bool(out) and os.path.lexists(out)
    try:
        result = monte_carlo(params, spread, runs, analysis, seed=seed, scenario=sc,
                             controller=ctrl, sweep=sweep, traction=traction_table,
                             store=out, resume=resume)
    except KeyboardInterrupt:
        if not out:
            raise
        raise Interrupted(_interrupted_study(out, resume or existed)) from None
    if result.failures == result.runs:
        kind, f = next(iter(result.summary()["failure_reasons"].items()))
        raise Failed(f"every one of the {result.runs} runs failed ({f['count']} x {kind}, "
                     f"e.g. {f['example'].partition(': ')[2]}); "
                     + (f"no table written (the shards stay in {out})" if out
                        else "nothing written"))
    if out:
        save_montecarlo(result, out)
    summary = result.summary()
    verdicts = summary.get("verdicts")
    if as_json or json_out:
        emit_json(summary, "montecarlo", json_out)
    else:
        _echo_summary(result, summary, analysis, seed)
    if strict and verdicts and verdicts["runs_missing_any"]:
        missed = ", ".join(f"{t} {v['missed']}" for t, v in verdicts["targets"].items()
                           if v["missed"])
        raise Failed(f"--strict: {verdicts['runs_missing_any']} of {result.runs} runs missed "
                     f"a scenario target ({missed}; {result.failures} failed to simulate)")


def _echo_summary(result, summary, analysis, seed) -> None:
    click.echo(f"{result.runs} runs of the {analysis} analysis (seed {seed}): "
               f"{result.failures} failed")
    for kind, f in summary["failure_reasons"].items():
        click.echo(f"  {f['count']} x {kind}, e.g. {f['example']}")
    v = summary.get("verdicts")
    if v:
        click.echo(f"without macro slip or belt slack: {v['clean']} of {result.runs} "
                   f"({100 * v['clean_fraction']:.1f} %); macro slip {v['macro_slip']}, "
                   f"belt slack {v['belt_slack']}, other failures {v['failed_other']}")
        click.echo(f"runs missing a target: {v['runs_missing_any']} of {result.runs}")
        for t, c in v["targets"].items():
            click.echo(f"  {t:22s} missed by {c['missed']:5d} runs"
                       + (f" ({c['missed_failed']} failed to simulate)"
                          if c["missed_failed"] else ""))
    click.echo(f"{'output':22s} {'unit':18s} {'n':>6s} {'q05':>11s} {'median':>11s} "
               f"{'q95':>11s}")
    for name, s in summary["outputs"].items():
        if s["n"]:
            click.echo(f"{name:22s} {s['unit']:18s} {s['n']:6d} {s['q05']:11.4g} "
                       f"{s['q50']:11.4g} {s['q95']:11.4g}")
        else:
            click.echo(f"{name:22s} {s['unit']:18s} {0:6d}   (no finite value)")


def _interrupted_study(out: str, existed: bool) -> str:
    """What an interrupted streamed study leaves in `out`: its completed shards stay, for
    ``--resume`` (the text of the ``error: interrupted`` line); a study that completed no
    chunk removes the manifest and shards folder it made, and the folder if it made it
    (nothing written)."""
    import json
    from pathlib import Path

    from ..shards import MANIFEST, SHARDS

    folder = Path(out)
    try:
        doc = json.loads((folder / MANIFEST).read_text())
        done, chunks = len(doc["completed"]), len(doc["chunks"])
        kept = sum(b - a for k, (a, b) in enumerate(doc["chunks"]) if k in set(doc["completed"]))
        runs = int(doc["runs"])
    except (OSError, ValueError, KeyError, TypeError):
        done = 0
    if done:
        return (f"{done} of {chunks} chunks ({kept} of {runs} runs) kept in {out}: continue "
                "with --resume")
    if not existed:  # only what this run made
        (folder / MANIFEST).unlink(missing_ok=True)
        for path in ((folder / SHARDS), folder):
            try:
                path.rmdir()
            except OSError:
                pass
    return ""
