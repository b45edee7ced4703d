"""``empact frf-estimate``: FRFs with coherence from measured records (`empact.identification`).

The experiments on the nonlinear model (``identify``, ``rig``) are in `empact.cli.experiments`:
this command loads no simulation."""
from __future__ import annotations

import click
import numpy as np

from .._validate import check_int, check_number
from ..identification import METHODS, estimate_frf
from ..identification.records import load_records, sample_rate
from ._common import (
    InputError,
    emit_json,
    force_option,
    json_options,
)
from .linear import plot_option


@click.command("frf-estimate")
@click.argument("data", type=click.Path(dir_okay=False))
@click.option("--input", "inputs", multiple=True, required=True,
              help="Input column (repeatable for simultaneous uncorrelated inputs).")
@click.option("--output", "outputs", multiple=True, required=True,
              help="Output column (repeatable).")
@click.option("--fs", type=float, default=None, help="Sample rate [Hz] (or give --time).")
@click.option("--time", "time_col", default=None,
              help="Time column, uniformly sampled ([s] or its header's unit: ms, us, min).")
@click.option("--method", type=click.Choice(METHODS), default="H1", show_default=True)
@click.option("--nperseg", type=int, default=None,
              help="Welch segment length [samples] (default: min(n, 1024, max(64, n / 8))).")
@json_options
@plot_option
@force_option
def frf_estimate(data: str, inputs: tuple[str, ...], outputs: tuple[str, ...], fs: float | None,
                 time_col: str | None, method: str, nperseg: int | None, as_json: bool,
                 json_out: str | None, plot: str | None, force: bool) -> None:
    """Estimate FRFs and coherence from the records in DATA (CSV with a header row)."""
    if (fs is None) == (time_col is None):
        raise InputError("give exactly one of --fs HZ and --time COLUMN")
    if fs is not None:
        fs = check_number("--fs", fs, 0.0, 1e9, lo_open=True, unit="Hz")
    named = [("--input", c) for c in inputs] + [("--output", c) for c in outputs] \
        + ([("--time", time_col)] if time_col else [])
    for k, (opt, col) in enumerate(named):
        first = next(o for o, c in named if c == col)
        if [c for _, c in named].index(col) < k:
            raise InputError(f"{opt} {col}: " + ("given twice" if first == opt else
                             f"the column is already the {first.lstrip('-')}") + "; each "
                             "column is one signal (an input, an output or the time)")
    cols = list(dict.fromkeys(list(inputs) + list(outputs) + ([time_col] if time_col else [])))
    rec = load_records(data, cols, quantities={time_col: "time"} if time_col else None)
    n = len(next(iter(rec.values())))
    if nperseg is not None:
        nperseg = check_int("--nperseg", nperseg, 8, n)
    if time_col:
        fs = sample_rate(rec[time_col], time_col)
    assert fs is not None  # --fs or --time, checked above
    est = estimate_frf(np.column_stack([rec[c] for c in inputs]),
                       np.column_stack([rec[c] for c in outputs]), fs, method=method,
                       nperseg=nperseg, inputs=inputs, outputs=outputs)
    if plot:
        from ..plotting import plot_frf_estimate

        plot_frf_estimate(est, title=str(data)).save(plot)
    if as_json or json_out:
        emit_json({"data": data, "fs_hz": fs, "method": est.method, "inputs": est.inputs,
                   "outputs": est.outputs, "n_averages": est.n_averages,
                   "frequencies_hz": est.frequencies_hz,
                   "H": np.stack([est.H.real, est.H.imag], axis=-1),
                   "magnitude_db": 20 * np.log10(np.abs(est.H) + 1e-300),
                   "coherence": est.coherence, "multiple_coherence": est.multiple_coherence},
                  "frf_estimate", json_out)
    elif not plot:
        click.echo(f"{'f [Hz]':>10s} " + " ".join(f"{o + '/' + i + ' [dB]':>24s} {'coh':>5s}"
                                                  for i in est.inputs for o in est.outputs))
        excited = np.isfinite(est.coherence).any(axis=(0, 1))
        for k, f in enumerate(est.frequencies_hz):
            if not excited[k]:
                continue
            cells = []
            for j in range(len(est.inputs)):
                for i in range(len(est.outputs)):
                    cells.append(f"{20 * np.log10(abs(est.H[i, j, k]) + 1e-300):24.3f} "
                                 f"{est.coherence[i, j, k]:5.3f}")
            click.echo(f"{f:10.4g} " + " ".join(cells))
        if not excited.all():
            skipped = est.frequencies_hz[~excited]
            click.echo(f"({skipped.size} frequencies where the inputs carry no power are left "
                       f"out, {skipped.min():.4g}-{skipped.max():.4g} Hz; --json gives every "
                       "frequency, null there)")
