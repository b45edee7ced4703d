"""``empact frf-estimate``: FRFs with coherence from a user's measured records."""
from __future__ import annotations

import click
import numpy as np

from ..identification import METHODS, estimate_frf
from ..identification.records import load_records, sample_rate
from . import InputError, echo_json, json_option, main


@main.command("frf-estimate")
@click.argument("data", type=click.Path(dir_okay=False))
@click.option("--input", "inputs", multiple=True, required=True,
              help="Input column (repeatable for simultaneous uncorrelated inputs).")
@click.option("--output", "outputs", multiple=True, required=True,
              help="Output column (repeatable).")
@click.option("--fs", type=float, default=None, help="Sample rate [Hz] (or give --time).")
@click.option("--time", "time_col", default=None, help="Time column [s], uniformly sampled.")
@click.option("--method", type=click.Choice(METHODS), default="H1", show_default=True)
@click.option("--nperseg", type=int, default=None, help="Welch segment length [samples].")
@json_option
@click.option("--plot", type=click.Path(dir_okay=False), default=None,
              help="Bode-plus-coherence figure (format from the suffix).")
def frf_estimate(data: str, inputs: tuple[str, ...], outputs: tuple[str, ...], fs: float | None,
                 time_col: str | None, method: str, nperseg: int | None, as_json: bool,
                 plot: str | None) -> None:
    """Estimate FRFs and coherence from the records in DATA (CSV with a header row)."""
    if (fs is None) == (time_col is None):
        raise InputError("give exactly one of --fs HZ and --time COLUMN")
    if fs is not None and not (np.isfinite(fs) and fs > 0):
        raise InputError(f"--fs {fs:g}: must be a positive sample rate [Hz]")
    cols = list(dict.fromkeys(list(inputs) + list(outputs) + ([time_col] if time_col else [])))
    rec = load_records(data, cols)
    if time_col:
        fs = sample_rate(rec[time_col], time_col)
    est = estimate_frf(np.column_stack([rec[c] for c in inputs]),
                       np.column_stack([rec[c] for c in outputs]), fs, method=method,
                       nperseg=nperseg, inputs=inputs, outputs=outputs)
    if plot:
        from ..plotting import save_single
        from ..plotting_identification import plot_frf_estimate
        save_single(plot_frf_estimate(est, title=str(data)), plot)
    if as_json:
        echo_json({"data": data, "fs_hz": fs, "method": est.method, "inputs": est.inputs,
                   "outputs": est.outputs, "n_averages": est.n_averages,
                   "frequencies_hz": est.frequencies_hz,
                   "H": np.stack([est.H.real, est.H.imag], axis=-1),
                   "magnitude_db": 20 * np.log10(np.abs(est.H) + 1e-300),
                   "coherence": est.coherence, "multiple_coherence": est.multiple_coherence})
    elif not plot:
        click.echo(f"{'f [Hz]':>10s} " + " ".join(f"{o + '/' + i + ' [dB]':>24s} {'coh':>5s}"
                                                  for i in est.inputs for o in est.outputs))
        for k, f in enumerate(est.frequencies_hz):
            cells = []
            for j in range(len(est.inputs)):
                for i in range(len(est.outputs)):
                    cells.append(f"{20 * np.log10(abs(est.H[i, j, k]) + 1e-300):24.3f} "
                                 f"{est.coherence[i, j, k]:5.3f}")
            click.echo(f"{f:10.4g} " + " ".join(cells))
