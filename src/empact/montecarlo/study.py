"""A Monte Carlo study: runs over a parameter spread, their table and its summary.

`monte_carlo` draws run ``i``'s parameters from its own random stream (`Spread.sample`),
evaluates the analysis (`empact.montecarlo.analyses`) and records the outputs, or, when the run
fails (a parameter out of its allowed range, a trim that does not converge, a solver that
stops), the reason: a failed run is never dropped and never stops the others.  The runs are
computed in chunks by the sweep layer (`empact.sweep`), in process or on Dask; as each run
depends only on the seed and its index, the table is the same whatever the scheduler and the
number of workers.

With a ``store`` folder a study streams: its chunks (about a second of work each; on several
workers the first is one run and the last shrink, `empact.sweep.taper_chunks`) are written
to shards as they complete (`empact.shards`), the parent process keeps none of them while the
study runs, a killed study resumes from its shards (``resume=True``) and the table is then
assembled from the shards in run order, bitwise the table of the same study in memory.
"""
from __future__ import annotations

import csv
import hashlib
import io
import json
import os
import pickle
from collections import Counter
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Iterable, Iterator, Sequence, TextIO

import numpy as np
from numpy.typing import NDArray

from .._io import atomic_folder
from .._results import TableResult
from .._validate import check_int
from ..control.closed_loop import resolve_controller
from ..errors import ParameterError, TrimError
from ..export import jsonable
from ..params import Params
from ..shards import ShardStore
from ..sweep import SweepOptions, plan_chunks, run_chunks
from .analyses import (
    SECONDS_PER_RUN,
    TARGET_PREFIX,
    AnalysisContext,
    RunFailed,
    evaluate,
    output_units,
    prepare,
)
from .spread import PEAK_SLIP_VARIABLES, SCENARIO_VARIABLES, Spread

__all__ = ["MonteCarloResult", "monte_carlo", "save_montecarlo", "failure_kind", "QUANTILES",
           "MAX_RUNS", "study_spec", "CHUNK_SECONDS"]

#: quantiles of the summary
QUANTILES = (0.05, 0.25, 0.5, 0.75, 0.95)

#: most runs of one study
MAX_RUNS = 1_000_000

#: version of the saved study's JSON (2: closed-loop slips as fractions, failure kinds)
SCHEMA_VERSION = 2

#: files of a saved study (the folder's own files, replaced by ``--force``)
FILES = ("runs.csv", "runs.json", "summary.json")

#: compute time of one chunk of a streamed study, each chunk a shard [s]
CHUNK_SECONDS = 1.0


@dataclass(frozen=True, eq=False)
class MonteCarloResult(TableResult):
    """The runs of a study.

    Attributes
    ----------
    analysis : the analysis evaluated ("plant", "slip", "closed-loop")
    seed : the study's seed
    spread : the parameter distributions
    samples : parameter values, shape (runs, n_parameters), columns `spread.names`
    outputs : output names (`OUTPUTS`)
    units : output and parameter name -> unit
    values : outputs, shape (runs, n_outputs); NaN for a failed run (and where an output does
        not exist, e.g. no right-half-plane zero)
    ok : run succeeded, shape (runs,)
    reasons : why each run failed ("" for a run that succeeded): ``kind: message`` with the
        kind of `failure_kind`
    """

    analysis: str
    seed: int
    spread: Spread
    samples: NDArray[np.float64]
    outputs: tuple[str, ...]
    units: dict[str, str]
    values: NDArray[np.float64]
    ok: NDArray[np.bool_]
    reasons: tuple[str, ...]

    @property
    def runs(self) -> int:
        """Number of runs."""
        return int(self.ok.size)

    @property
    def failures(self) -> int:
        """Number of failed runs."""
        return int(np.count_nonzero(~self.ok))

    def summary(self, quantiles: Sequence[float] = QUANTILES) -> dict[str, Any]:
        """Failure count (by kind, `failure_kind`, with the first run's reason) and, per
        output, the statistics of the successful runs where it is finite: ``n``, ``mean``,
        ``std``, ``min``, quantiles ``q05`` ..., ``max``.

        Parameters
        ----------
        quantiles : sequence of float, optional
            Probabilities in [0, 1] (default 0.05, 0.25, 0.5, 0.75, 0.95); each gives a key
            ``qNN`` (percent, two digits).
        """
        stats: dict[str, Any] = {}
        for j, name in enumerate(self.outputs):
            v = self.values[self.ok, j]
            v = v[np.isfinite(v)]
            s: dict[str, Any] = {"unit": self.units[name], "n": int(v.size)}
            if v.size:
                qs = np.quantile(v, quantiles)
                s.update(mean=float(v.mean()), std=float(v.std(ddof=1)) if v.size > 1 else 0.0,
                         min=float(v.min()))
                s.update({f"q{round(100 * q):02d}": float(x) for q, x in zip(quantiles, qs)})
                s["max"] = float(v.max())
            stats[name] = s
        failed = [r for r, ok in zip(self.reasons, self.ok) if not ok]
        kinds = Counter(r.split(":")[0] for r in failed)
        reasons = {k: {"count": n, "example": next(r for r in failed if r.startswith(k + ":"))}
                   for k, n in sorted(kinds.items(), key=lambda kv: (-kv[1], kv[0]))}
        out = {"analysis": self.analysis, "seed": self.seed, "runs": self.runs,
               "succeeded": self.runs - self.failures, "failures": self.failures,
               "failure_reasons": reasons}
        if self.analysis == "closed-loop":
            out["verdicts"] = self.verdicts()
        return {**out,
                "spread": {d.name: d.describe() for d in self.spread.distributions},
                "outputs": stats}

    @property
    def targets(self) -> tuple[str, ...]:
        """The scenario targets judged per run (closed loop; outputs ``met.NAME``)."""
        return tuple(n[len(TARGET_PREFIX):] for n in self.outputs
                     if n.startswith(TARGET_PREFIX))

    def missed(self) -> NDArray[np.bool_]:
        """Which runs missed which target, shape (runs, len(`targets`)); a failed run (no
        result) misses every target."""
        cols = [self.outputs.index(TARGET_PREFIX + t) for t in self.targets]
        return ~self.ok[:, None] | (self.values[:, cols] != 1.0)

    def verdicts(self) -> dict[str, Any]:
        """The closed-loop runs against their scenario's targets and the two failure modes:

        * ``targets``: per target, ``missed`` (runs that missed it, failed runs included)
          and ``missed_failed`` (of those, runs that failed to simulate);
        * ``runs_missing_any``: runs that missed at least one target (failed runs included);
        * ``macro_slip``, ``belt_slack``: runs with macro slip, with a slack belt (a run
          stopped by ``clamping force F_s fell to zero`` counts as slack);
        * ``failed_other``: runs that failed for another reason (by `failure_kind`);
        * ``clean``, ``clean_fraction``: runs that completed without macro slip or belt
          slack, and their share of all runs.
        """
        miss = self.missed()
        slack_stop = np.array([not ok and "belt slack" in r
                               for ok, r in zip(self.ok, self.reasons)], dtype=bool)
        col = {n: self.values[:, self.outputs.index(n)] for n in ("macro_slip", "belt_slack")}
        macro = self.ok & (col["macro_slip"] == 1.0)
        slack = (self.ok & (col["belt_slack"] == 1.0)) | slack_stop
        clean = self.ok & ~macro & ~slack
        return {"targets": {t: {"missed": int(miss[:, j].sum()),
                                "missed_failed": int((miss[:, j] & ~self.ok).sum())}
                            for j, t in enumerate(self.targets)},
                "runs_missing_any": int(miss.any(axis=1).sum()),
                "macro_slip": int(macro.sum()), "belt_slack": int(slack.sum()),
                "failed_other": int((~self.ok & ~slack_stop).sum()),
                "clean": int(clean.sum()), "clean_fraction": float(clean.mean())}

    def _columns(self) -> dict[str, NDArray]:
        """`table` by column: ``run``, ``status``, the parameters, the outputs, ``reason``."""
        rows = self.table()
        names = ["run", "status", *self.spread.names, *self.outputs, "reason"]
        return {n: np.array([r[n] for r in rows]) for n in names}

    def rows(self) -> Iterator[dict[str, Any]]:
        """`table`'s dicts one at a time (a writer holds one run's row, not the table's).

        Yields
        ------
        dict
            Run ``i``'s ``run``, ``status``, parameters, outputs and ``reason``, in run order.
        """
        for i in range(self.runs):
            row: dict[str, Any] = {"run": i, "status": "ok" if self.ok[i] else "failed"}
            row.update({n: float(x) for n, x in zip(self.spread.names, self.samples[i])})
            row.update({n: float(x) for n, x in zip(self.outputs, self.values[i])})
            row["reason"] = self.reasons[i]
            yield row

    def table(self) -> list[dict[str, Any]]:
        """One dict per run: ``run``, ``status``, the parameters, the outputs, ``reason``."""
        return list(self.rows())

    def write_csv(self, out: TextIO) -> None:
        """Write `to_csv`'s text to `out` a row at a time (its memory independent of the
        number of runs).

        Parameters
        ----------
        out : text file
            Where the CSV is written (opened with ``newline=""`` for a file on disk).

        Returns
        -------
        None
        """
        out.write(f"# empact Monte Carlo: analysis {self.analysis}, seed {self.seed}, "
                  f"{self.runs} runs, {self.failures} failed\n")
        for d in self.spread.distributions:
            out.write(f"# {d.name}: {d.describe()}\n")
        w = csv.writer(out, lineterminator="\n")
        names = list(self.spread.names) + list(self.outputs)
        w.writerow(["run", "status"] + [f"{n} [{self.units[n]}]" if self.units[n] else n
                                        for n in names] + ["reason"])
        for row in self.rows():
            w.writerow([row["run"], row["status"]]
                       + ["" if not np.isfinite(row[n]) else repr(row[n]) for n in names]
                       + [row["reason"]])

    def to_csv(self) -> str:
        """The table as CSV: ``#`` comment lines, then a header with units in brackets
        (readable by `empact.identification.records`' conventions); empty cells for NaN."""
        buf = io.StringIO()
        self.write_csv(buf)
        return buf.getvalue()


def _run_chunk(task) -> tuple[NDArray, NDArray, NDArray, list[str]]:
    """Runs ``start:stop`` of a study (a sweep chunk; module level, picklable)."""
    params, spread, context, seed, start, stop = task
    samples = spread.sample(seed, np.arange(start, stop))
    outputs = tuple(output_units(context))
    values = np.full((stop - start, len(outputs)), np.nan)
    ok = np.zeros(stop - start, dtype=bool)
    reasons = [""] * (stop - start)
    for k, row in enumerate(samples):
        try:
            p, ctx = prepare(params, spread, row, context)
            out = evaluate(p, ctx)
            values[k] = [out[n] for n in outputs]
            ok[k] = True
        except Exception as exc:  # noqa: BLE001 - recorded with its reason, never dropped
            text = " ".join(str(exc).split()) or "no message"
            reasons[k] = f"{failure_kind(exc)}: {text}"[:500]
    return samples, values, ok, reasons


def failure_kind(exc: BaseException) -> str:
    """What kind of failure an exception of a run is (the reasons' first word, by which the
    summary counts them): ``parameters`` (a value out of its range), ``trim`` (no steady
    point), ``stopped`` (the simulation stopped early), ``error`` (anything else).

    Parameters
    ----------
    exc : BaseException
        The exception a run raised.

    Returns
    -------
    {"trim", "parameters", "stopped", "error"}
        The kind (`TrimError` is ``trim``, any other `ParameterError` ``parameters``,
        `RunFailed` ``stopped``).
    """
    if isinstance(exc, TrimError):
        return "trim"
    if isinstance(exc, ParameterError):
        return "parameters"
    if isinstance(exc, RunFailed):
        return "stopped"
    return "error"


def monte_carlo(params: Params, spread: Spread, runs: int, analysis: str = "plant", *,
                seed: int = 0, scenario: Any = None, controller: Any = None,
                sweep: SweepOptions | None = None, traction: Any = None,
                store: str | os.PathLike[str] | None = None, resume: bool = False,
                chunk_seconds: float = CHUNK_SECONDS) -> MonteCarloResult:
    """Evaluate an analysis over `runs` parameter sets drawn from `spread`.

    Parameters
    ----------
    params : the nominal parameter set (the spread's parameters replace its values)
    spread : `Spread` (see `load_spread`)
    runs : number of runs (1 ... `MAX_RUNS`)
    analysis : "plant", "slip" or "closed-loop" (`empact.montecarlo.analyses`)
    seed : the study's seed (>= 0); run ``i`` draws from ``SeedSequence(seed, spawn_key=(i,))``
    scenario, controller : the closed-loop scenario (a `Scenario` with a [controller] table)
        and controller
        (`Controller`, default the scenario's own)
    sweep : where the runs are computed (`empact.sweep.SweepOptions`; default in process)
    traction : measured traction curves of the machine (a
        `empact.variator.traction.TabulatedTraction`; the plant and closed-loop analyses;
        default the table the parameter file names, `Params.traction_table`, else the
        analytic curve of each run's ``[traction]``, which a spread may vary; the table is not
        varied)
    store : a study folder: the runs stream to its shards as their chunks complete (chunks of
        about `chunk_seconds` of work, `empact.shards`); default None: in memory
    resume : continue the study in `store` (its completed chunks are read, not rerun); a
        `empact.shards.StudyMismatch` when the folder holds no study or another one (its
        analysis, seed, runs, spread, parameters or context differ)
    chunk_seconds : estimated compute time of a stored study's chunk [s] (fixed in its
        manifest when the study starts)

    Returns
    -------
    MonteCarloResult
        ``samples`` (runs, n_parameters), ``values`` (runs, n_outputs; NaN where a run
        failed), ``ok`` and ``reasons`` per run; ``summary()`` and ``table()``.

    Examples
    --------
    >>> from importlib.resources import files
    >>> import empact
    >>> params = empact.load_params()
    >>> spread = empact.load_spread(files("empact.data") / "montecarlo" / "example-spread.toml",
    ...                             params)
    >>> study = empact.monte_carlo(params, spread, 8, "plant", seed=1)
    >>> study.values.shape, int(study.ok.sum())
    ((8, 8), 8)
    """
    runs = check_int("runs", runs, 1, MAX_RUNS)
    seed = check_int("seed", seed, 0, 2**63 - 1)
    if analysis == "closed-loop" and controller is None and scenario is not None:
        controller = resolve_controller(scenario.controller.file)
    # the controller knows the nominal machine; each run's differs
    traction = traction if traction is not None else params.traction_table  # the file's
    if traction is not None and scenario is not None:
        scenario = scenario.with_options(traction=traction)
    context = AnalysisContext(analysis, scenario, controller,
                              params if analysis == "closed-loop" else None, traction)
    desc = f"monte carlo ({analysis})"
    if store is None:
        tasks = [(params, spread, context, seed, s.start, s.stop)
                 for s in plan_chunks(runs, SECONDS_PER_RUN[analysis], sweep)]
        parts = run_chunks(_run_chunk, tasks, sweep, desc=desc)
    else:
        shards = _study_store(store, resume, params, spread, context, runs, seed, sweep,
                              chunk_seconds)
        pending = shards.pending

        def done(k: int, part: tuple[NDArray, NDArray, NDArray, list[str]]) -> None:
            shards.write(pending[k], {"samples": part[0], "values": part[1], "ok": part[2],
                                      "reasons": np.array(part[3], dtype=str)})

        run_chunks(_run_chunk, [(params, spread, context, seed, *shards.chunks[k])
                                for k in pending], sweep, desc=desc, done=done)
        parts = [(a["samples"], a["values"], a["ok"], [str(r) for r in a["reasons"]])
                 for _, a in shards.iter_shards()]
    samples = np.concatenate([p[0] for p in parts]).reshape(runs, len(spread.names))
    out_units = output_units(context)
    outputs = tuple(out_units)
    units = {**{n: SCENARIO_VARIABLES.get(n) or ("-" if n in PEAK_SLIP_VARIABLES else
                                                params.unit(n)) for n in spread.names},
             **out_units}
    return MonteCarloResult(analysis=analysis, seed=seed, spread=spread, samples=samples,
                            outputs=outputs, units=units,
                            values=np.concatenate([p[1] for p in parts]),
                            ok=np.concatenate([p[2] for p in parts]),
                            reasons=tuple(r for p in parts for r in p[3]))


def study_spec(params: Params, spread: Spread, context: AnalysisContext, runs: int,
               seed: int) -> dict[str, Any]:
    """What identifies a stored study (its manifest's ``spec``): the analysis, seed and run
    count, and SHA-256 hashes of the parameters (`Params.to_dict`), the spread (each
    distribution's name and description) and the analysis' context (scenario, controller,
    nominal parameters and traction table, pickled).

    Parameters
    ----------
    params : Params
        The nominal parameter set.
    spread : Spread
        The study's spread.
    context : AnalysisContext
        The analysis and its context.
    runs : int
        Number of runs.
    seed : int
        The study's seed.

    Returns
    -------
    dict
        The manifest's ``spec`` (JSON-safe).
    """
    def digest(data: bytes) -> str:
        return hashlib.sha256(data).hexdigest()

    return {"analysis": context.kind, "seed": seed, "runs": runs,
            "parameters": digest(json.dumps(jsonable(params.to_dict()), sort_keys=True,
                                            default=str).encode()),
            "spread": digest(json.dumps([[d.name, d.describe()] for d in spread.distributions]
                                        ).encode()),
            "context": digest(pickle.dumps(context, protocol=4))}


def _study_store(store: str | os.PathLike[str], resume: bool, params: Params, spread: Spread,
                 context: AnalysisContext, runs: int, seed: int, sweep: SweepOptions | None,
                 chunk_seconds: float) -> ShardStore:
    """The shard store of a streamed study: opened (`resume`) or started with its chunks."""
    spec = study_spec(params, spread, context, runs, seed)
    if resume:
        return ShardStore.open(store, spec)
    chunks = [(s.start, s.stop) for s in plan_chunks(runs, SECONDS_PER_RUN[context.kind], sweep,
                                                     target=chunk_seconds, taper=True)]
    return ShardStore.create(store, spec, chunks)


def _write_runs_json(out: TextIO, head: dict[str, Any],
                     rows: Iterable[dict[str, Any]]) -> None:
    """Write ``json.dumps(jsonable({**head, "runs": list(rows)}), indent=1)`` and a newline to
    `out`, one row at a time (the same text: each row is dumped alone and indented to its
    depth, 2 spaces; a row holds no newline of its own, JSON escapes them).

    Parameters
    ----------
    out : text file
        Where the document is written.
    head : dict
        The document's other keys (before ``runs``).
    rows : iterable of dict
        The runs' rows (at least one).

    Returns
    -------
    None
    """
    encoder = json.JSONEncoder(indent=1)  # json.dumps(x, indent=1), made once
    text = encoder.encode(jsonable(head))
    out.write(text[:-2] + ',\n "runs": [')  # the head without its closing "\n}"
    sep = "\n  "
    for row in rows:
        out.write(sep + encoder.encode(jsonable(row)).replace("\n", "\n  "))
        sep = ",\n  "
    out.write("\n ]\n}\n" if sep != "\n  " else "]\n}\n")


def save_montecarlo(result: MonteCarloResult, folder: str | os.PathLike[str]) -> Path:
    """Write ``runs.csv``, ``runs.json`` (the table; null for NaN) and ``summary.json`` into
    `folder`, all or nothing (a temporary folder moved into place).  The tables are written
    a run at a time: the memory this takes does not grow with the number of runs (built
    whole, the two texts held about 8 kB a run: 74 MiB for 10 000 runs, `bench/RESULTS.md`).

    Parameters
    ----------
    result : MonteCarloResult
        The study to write.
    folder : str or path-like
        The folder written (created with its parents if missing; other files in it are
        left alone, files of the same name replaced).

    Returns
    -------
    Path
        `folder`.
    """
    with atomic_folder(folder) as tmp:
        with open(tmp / "runs.csv", "w", newline="") as f:
            result.write_csv(f)
        head = {"schema": {"name": "empact.montecarlo.runs", "version": SCHEMA_VERSION},
                "analysis": result.analysis, "seed": result.seed, "units": result.units,
                "parameters": list(result.spread.names), "outputs": list(result.outputs)}
        with open(tmp / "runs.json", "w") as f:
            _write_runs_json(f, head, result.rows())
        summary = {"schema": {"name": "empact.montecarlo", "version": SCHEMA_VERSION},
                   **result.summary()}
        (tmp / "summary.json").write_text(json.dumps(jsonable(summary), indent=1) + "\n")
    return Path(folder)
