"""One sweep layer for embarrassingly parallel work: in process, in forked workers, or on Dask.

A sweep is a list of *chunks*, each a picklable argument of a module-level function; the
results come back in chunk order.  Schedulers:

``"none"`` (default)
    This machine, no Dask: with ``workers`` of 1 (the default of `SweepOptions`), in process,
    one chunk after another; with ``workers`` N > 1 (the CLI's default: one per core), N
    forked worker processes (`empact._parallel.run_forked`).  The first chunk runs in this
    process before the fork, so that the workers inherit what it loaded (imports, numba's
    compiled code, lazy tables) and start computing at once: no start-up tax (a 200-run
    closed-loop Monte Carlo on two workers: ``bench/bench_sweep.py``).  Chunks of about a
    second (a streamed study's) are planned with `taper_chunks`: that first chunk is one
    item, and the chunks shrink towards the end so that the workers finish together.
``"local"``
    A `distributed.LocalCluster` with ``workers`` single-threaded worker *processes*, started
    for the sweep and closed after it (about 3 s to start).
an address (``"tcp://host:8786"`` or ``"host:8786"``)
    A running scheduler (``dask-scheduler`` + ``dask-worker``, or dask-jobqueue on
    SLURM / PBS); a scheduler that cannot be reached within ``timeout`` is a one-line
    `SweepError`.

Every chunk runs with one BLAS thread (threadpoolctl), in process and on workers alike, so
that a sweep's results are bitwise equal whatever the scheduler or the number of workers (the
callers' chunk functions compute each point independently of its chunk).  A worker that dies
mid-sweep is survived: Dask reschedules its chunks (and retries a chunk up to ``retries``
times); a chunk that raises is reported with its index.  Size chunks for >= 50 ms of compute
(`chunk_count`): a Dask task costs about 5 ms of overhead.  A Ctrl-C stops a sweep at once:
the workers of a local cluster ignore SIGINT and are killed, not waited for, and a Ctrl-C
while the cluster starts is delivered once it is up (`empact._parallel`).

Dask is an optional extra (``pip install empact[dask]``); this module imports it only when a
sweep uses it.
"""
from __future__ import annotations

import asyncio
import importlib
import math
import os
import re
import shutil
import sys
import tempfile
from dataclasses import dataclass
from typing import Any, Callable, Sequence

from threadpoolctl import ThreadpoolController

from ._parallel import run_forked, sigint_held
from ._progress import progress as progress_bar
from ._validate import check_int, check_number
from .errors import ParameterError

__all__ = ["SweepError", "SweepOptions", "run_chunks", "plan_chunks", "chunk_count",
           "chunk_slices", "taper_chunks", "check_address"]


class SweepError(ParameterError):
    """A sweep that cannot run: unknown scheduler, unreachable address, Dask missing."""


@dataclass(frozen=True)
class SweepOptions:
    """Where and how a sweep runs.

    Attributes
    ----------
    scheduler : "none", "local" or a scheduler address
    workers : int, optional
        Worker processes: forked ones on this machine (``"none"``; default 1, in process), or
        those of a local cluster (``"local"``; default one per CPU core).
    timeout : float
        Seconds to wait for a remote scheduler.
    retries : int
        Extra attempts of a chunk that fails on a worker.
    progress : bool
        A progress bar on stderr while chunks complete.
    """

    scheduler: str = "none"
    workers: int | None = None
    timeout: float = 10.0
    retries: int = 2
    progress: bool = False

    def __post_init__(self) -> None:
        s = str(self.scheduler).strip()
        if not s:
            raise SweepError("--scheduler '': give none, local or a scheduler address")
        object.__setattr__(self, "scheduler", s)
        if s not in ("none", "local"):
            check_address(s)
        if self.workers is not None:
            object.__setattr__(self, "workers", check_int("workers", self.workers, 1, 256))
        object.__setattr__(self, "timeout", check_number("timeout", self.timeout, 0.1, 3600.0,
                                                         unit="s"))
        object.__setattr__(self, "retries", check_int("retries", self.retries, 0, 20))

    @property
    def parallelism(self) -> int:
        """Chunks that run at once: `workers` (``"none"``: default 1, in process; a local
        cluster: default one per core)."""
        if self.scheduler == "none":
            return self.workers or 1
        return self.workers or os.cpu_count() or 1


#: a scheduler address: an optional protocol, a host name or [IPv6] address, a port
_ADDRESS = re.compile(r"^(?:(?P<proto>[a-z][a-z0-9+.-]*)://)?(?P<host>\[[0-9A-Fa-f:.]+\]|"
                      r"[A-Za-z0-9_.-]+):(?P<port>[0-9]{1,5})$")


def check_address(address: str) -> str:
    """A Dask scheduler address, ``[tcp://]host:port`` (``tls://``, ``ucx://`` and an
    ``[IPv6]`` host too), checked before any connection: one line otherwise.

    Parameters
    ----------
    address : str
        The address as given to ``--scheduler``.

    Returns
    -------
    str
        `address`.

    Raises
    ------
    SweepError
        When `address` is not of that form or its port is not 1 to 65535.
    """
    m = _ADDRESS.match(address)
    if m is None or not 1 <= int(m["port"]) <= 65535:
        raise SweepError(f"--scheduler {address}: give none, local or a scheduler address "
                         "HOST:PORT (tcp://host:8786, a port from 1 to 65535)")
    return address


def _per_chunk(seconds_per_item: float, target: float) -> int:
    """Items of a chunk of about `target` seconds (at least one)."""
    return max(1, int(math.ceil(target / max(seconds_per_item, 1e-9))))


def chunk_count(n_items: int, seconds_per_item: float, workers: int = 1,
                target: float = 0.05) -> int:
    """Number of chunks for `n_items` items of `seconds_per_item` each: chunks of about
    `target` seconds (>= 50 ms: Dask's per-task overhead is about 5 ms), and at least two per
    worker when the work allows it.

    Parameters
    ----------
    n_items : int
        Number of items (points) of the sweep.
    seconds_per_item : float
        Estimated compute time of one item [s].
    workers : int
        Chunks that run at once (`SweepOptions.parallelism`).
    target : float
        Wanted compute time of one chunk [s].

    Returns
    -------
    int
        The number of chunks, between 1 and `n_items` (1 when there are no items).
    """
    per = _per_chunk(seconds_per_item, target)
    n = max(1, int(math.ceil(n_items / per)))
    return max(1, min(n_items, max(n, 2 * workers if n_items * seconds_per_item
                                   > 4 * target * workers else n)))


def chunk_slices(n_items: int, n_chunks: int) -> list[slice]:
    """`n_chunks` contiguous slices covering ``range(n_items)``, sizes differing by one.

    Parameters
    ----------
    n_items : int
        Number of items.
    n_chunks : int
        Wanted number of chunks (clipped to ``[1, n_items]``).

    Returns
    -------
    list of slice
        The slices in order, none empty (an empty list when there are no items).
    """
    n_chunks = max(1, min(n_chunks, n_items))
    edges = [round(k * n_items / n_chunks) for k in range(n_chunks + 1)]
    return [slice(a, b) for a, b in zip(edges, edges[1:]) if b > a]


def plan_chunks(n_items: int, seconds_per_item: float,
                options: SweepOptions | None = None, target: float = 0.05,
                taper: bool = False) -> list[slice]:
    """Contiguous chunks of ``range(n_items)`` sized by `chunk_count` for `options`'
    parallelism (in process by default).

    Parameters
    ----------
    n_items : int
        Number of items of the sweep.
    seconds_per_item : float
        Estimated compute time of one item [s].
    options : SweepOptions, optional
        The scheduler whose parallelism sizes the chunks (default: in process).
    target : float
        Wanted compute time of one chunk [s] (`chunk_count`; a streamed study's chunks,
        written to a shard each, are about a second: `empact.shards`).
    taper : bool
        With more than one worker, `taper_chunks` instead: a first chunk of one item and
        chunks that shrink towards the end (for chunks of about a second; default False).

    Returns
    -------
    list of slice
        Contiguous slices covering ``range(n_items)``, in order (`chunk_slices`).
    """
    workers = (options or SweepOptions()).parallelism
    if taper and workers > 1:
        return taper_chunks(n_items, _per_chunk(seconds_per_item, target), workers)
    return chunk_slices(n_items, chunk_count(n_items, seconds_per_item, workers, target))


def taper_chunks(n_items: int, per: int, workers: int) -> list[slice]:
    """Chunks of at most `per` items for `workers` workers that start at once and end
    together: a first chunk of one item, then chunks of ``ceil(left / (2 workers))`` items
    (``left`` the items not yet in a chunk), at most `per` and at least ``ceil(per / 4)``.

    The first chunk runs in this process before the workers fork (`run_chunks`): with one
    item it loads what they inherit (numba's code, a law's references) while the other
    cores wait for a run, not for a whole chunk.  The shrinking tail (guided scheduling)
    leaves the workers within about a small chunk of each other at the end, where equal
    chunks of a second each left one worker a whole chunk alone (a 200-run closed-loop study
    on two workers: 16 chunks of 12-13 runs, one in this process, 8 on one worker and 7 on
    the other).

    Parameters
    ----------
    n_items : int
        Number of items.
    per : int
        Items of a full chunk (>= 1).
    workers : int
        Chunks that run at once.

    Returns
    -------
    list of slice
        Contiguous slices covering ``range(n_items)``, in order, none empty.
    """
    least = -(-per // 4)
    edges = [0, min(1, n_items)]
    while edges[-1] < n_items:
        left = n_items - edges[-1]
        edges.append(edges[-1] + min(left, per, max(least, -(-left // (2 * workers)))))
    return [slice(a, b) for a, b in zip(edges, edges[1:]) if b > a]


#: the process's thread pools and the number of modules loaded when they were scanned
_POOLS: list[Any] = [None, -1]


def _thread_pools() -> ThreadpoolController:
    """The loaded BLAS and OpenMP pools (threadpoolctl), scanned again only after a module was
    imported since the last scan (a library arrives with a module; a scan of the loaded
    libraries costs ~0.9 ms, a chunk of a small family not much more)."""
    if _POOLS[1] != len(sys.modules):
        _POOLS[:] = [ThreadpoolController(), len(sys.modules)]
    return _POOLS[0]


def _one_thread(fn: Callable[[Any], Any], arg: Any) -> Any:
    """Run a chunk with one BLAS thread (the same arithmetic everywhere)."""
    with _thread_pools().limit(limits=1):
        return fn(arg)


def run_chunks(fn: Callable[[Any], Any], chunks: Sequence[Any],
               options: SweepOptions | None = None, desc: str = "sweep",
               done: Callable[[int, Any], None] | None = None) -> list[Any]:
    """``[fn(c) for c in chunks]`` on the chosen scheduler, results in chunk order.

    With `done`, the results are streamed instead: ``done(k, fn(chunks[k]))`` is called in
    this process as each chunk completes (in completion order, whatever the scheduler) and
    the result is not kept (the list returned holds None), so that memory does not grow with
    the number of chunks (a study writing a shard per chunk: `empact.shards`).

    `fn` must be a module-level function and the chunks picklable for Dask schedulers.

    Parameters
    ----------
    fn : callable
        The chunk function, called with one chunk (with one BLAS thread).
    chunks : sequence
        The chunks, each `fn`'s argument.
    options : SweepOptions, optional
        Where and how the sweep runs (default: in process, no progress bar).
    desc : str
        Label of the progress bar.
    done : callable, optional
        ``done(index, result)``, called in this process as each chunk completes; an
        exception from it stops the sweep (the workers are terminated).

    Returns
    -------
    list
        ``fn(c)`` for every chunk ``c``, in chunk order (None each with `done`).

    Raises
    ------
    SweepError
        When Dask is missing, the scheduler cannot be reached, or a chunk fails on a worker
        (the message names the chunk's index).
    """
    opts = options or SweepOptions()
    chunks = list(chunks)
    out: list[Any] = [None] * len(chunks)

    def store(k: int, result: Any) -> None:
        if done is None:
            out[k] = result
        else:
            done(k, result)

    if opts.scheduler == "none":
        _run_here(fn, chunks, opts.parallelism, opts.progress, desc, store)
    else:
        _run_dask(fn, chunks, opts, desc, store)
    return out


def _run_here(fn: Callable[[Any], Any], chunks: list[Any], workers: int, progress: bool,
              desc: str, store: Callable[[int, Any], None]) -> None:
    """The chunks on this machine: in process, or the first one here and the rest in
    `workers` forked processes (they inherit what the first one loaded); `store(k, result)`
    as each completes."""
    with progress_bar(total=len(chunks), desc=desc, unit="chunk", enabled=progress) as bar:
        for k, c in enumerate(chunks if workers <= 1 else chunks[:1]):
            store(k, _one_thread(fn, c))
            bar.update(1)
        if workers > 1 and len(chunks) > 1:
            def done(index: int, result: Any) -> None:
                store(index + 1, result)
                bar.update(1)

            run_forked(_one_thread, [(fn, c) for c in chunks[1:]],
                       min(workers, len(chunks) - 1), done=done, keep=False)


#: Dask settings of the clusters `run_chunks` starts itself (``"local"``): a batch sweep needs
#: no statistical profiler, a 20 ms health tick or work stealing between equal workers; with
#: them a worker computes a pure-Python closed-loop run about 15 % slower (measured in
#: ``bench/bench_sweep.py``; a remote cluster takes the same keys from its own config, e.g.
#: ``DASK_DISTRIBUTED__WORKER__PROFILE__ENABLED=False``).
LOCAL_CONFIG = {"distributed.worker.profile.enabled": False,
                "distributed.admin.tick.interval": "1s",
                "distributed.admin.system-monitor.interval": "5s",
                "distributed.worker.memory.monitor-interval": "5s",
                "distributed.scheduler.work-stealing": False}


def _distributed(opts: SweepOptions):
    """The optional `distributed` module (the ``dask`` extra), imported on first use."""
    try:
        return importlib.import_module("distributed")
    except ImportError:
        raise SweepError(f"--scheduler {opts.scheduler}: Dask is not installed (pip install "
                         "'empact[dask]')") from None


def _client(opts: SweepOptions):
    """A Dask client (and the local cluster it owns, or None)."""
    distributed = _distributed(opts)
    if opts.scheduler == "local":
        workers = opts.parallelism
        cluster = None
        # Dask's scratch space (worker folders, its lock files) goes into a folder of this
        # run, removed when the cluster closes (`_run_dask`): nothing is left in the system's
        # temporary folder (Dask's default leaves dask-scratch-space/*.lock there)
        scratch = tempfile.mkdtemp(prefix="empact-dask-")
        try:
            # the worker processes ignore Ctrl-C, which at a terminal reaches them too (each
            # would print a traceback): this process stops the sweep and closes the cluster
            with importlib.import_module("dask").config.set(
                    {**LOCAL_CONFIG, "temporary-directory": scratch}), sigint_held():
                cluster = distributed.LocalCluster(
                    n_workers=workers, threads_per_worker=1, processes=True,
                    dashboard_address=":0", silence_logs=50, preload=["empact._parallel"],
                    local_directory=scratch)
        except BaseException:
            if cluster is not None:  # a Ctrl-C while it started: delivered once it is up
                cluster.close()
            shutil.rmtree(scratch, ignore_errors=True)
            raise
        cluster._empact_scratch = scratch
        try:
            return distributed.Client(cluster), cluster
        except BaseException:
            _close_cluster(cluster)
            raise
    address = opts.scheduler if "://" in opts.scheduler else f"tcp://{opts.scheduler}"
    try:
        return distributed.Client(address, timeout=f"{opts.timeout}s"), None
    except (OSError, TimeoutError) as exc:
        reason = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise SweepError(f"--scheduler {opts.scheduler}: cannot reach the scheduler within "
                         f"{opts.timeout:g} s ({reason[:120]})") from None


def _run_dask(fn, chunks, opts: SweepOptions, desc: str,
              store: Callable[[int, Any], None]) -> None:
    distributed = _distributed(opts)
    client, cluster = _client(opts)
    try:
        futures = client.map(_one_thread, [fn] * len(chunks), chunks, pure=False,
                             retries=opts.retries)
        index = {f.key: k for k, f in enumerate(futures)}
        with progress_bar(total=len(chunks), desc=desc, unit="chunk",
                          enabled=opts.progress) as bar:
            for fut in distributed.as_completed(futures):
                k = index[fut.key]
                if fut.status == "error":
                    exc = fut.exception()
                    raise SweepError(f"sweep chunk {k} failed on a worker: "
                                     f"{type(exc).__name__}: {exc}") from None
                store(k, fut.result())
                bar.update(1)
    except BaseException:
        if cluster is not None:  # interrupted or failed: do not wait for running chunks
            _stop_workers(cluster)
        raise
    finally:
        client.close()
        if cluster is not None:
            _close_cluster(cluster)


def _close_cluster(cluster: Any) -> None:
    """Close a local cluster `_client` started and remove its scratch folder."""
    scratch = getattr(cluster, "_empact_scratch", None)
    try:
        cluster.close()
    finally:
        if scratch:
            shutil.rmtree(scratch, ignore_errors=True)


async def _close_all(workers: list[Any], timeout: float) -> None:
    await asyncio.gather(*(w.close(timeout=timeout) for w in workers), return_exceptions=True)


def _stop_workers(cluster: Any, timeout: float = 0.5) -> None:
    """Close the worker processes of a local cluster within about `timeout` seconds (a
    Ctrl-C, a failed chunk): a worker that is computing a chunk is killed, not waited for
    (a graceful close waits up to 4 s for it)."""
    try:
        cluster.sync(_close_all, list(cluster.workers.values()), timeout)
    except Exception:  # noqa: BLE001 - cluster.close() follows and closes what is left
        pass
