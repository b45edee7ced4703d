"""Forked worker processes that stop at once on Ctrl-C (private).

`run_forked` computes independent items in forked processes (they start with everything the
parent imported), each on one BLAS thread: the workers share the cores, and OpenBLAS's
default of a thread per core in each made ``empact reproduce`` 1.12x slower on two cores
(`bench/RESULTS.md`; the items are small matrices).  The workers ignore SIGINT:
a Ctrl-C at a terminal reaches the whole process group, and the workers would each print a
traceback and carry on with the next item; the parent alone handles it and, on any exception
(KeyboardInterrupt included), terminates the workers instead of waiting for the items they
have started and queued.

The module is also the Dask preload of the local clusters `empact.sweep` starts
(`dask_setup`): their worker processes ignore SIGINT likewise.
"""
from __future__ import annotations

import multiprocessing
import signal
import threading
from contextlib import contextmanager
from typing import Any, Callable, Iterator, Sequence

from threadpoolctl import threadpool_limits

__all__ = ["run_forked", "ignore_sigint", "sigint_held", "dask_setup"]


def ignore_sigint() -> None:
    """Ignore SIGINT in this process (a worker's initializer: its parent handles Ctrl-C)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def _worker_init() -> None:
    """A forked worker's start: SIGINT ignored, one BLAS thread (the workers share the cores)."""
    ignore_sigint()
    threadpool_limits(1)


def dask_setup(worker: Any = None) -> None:
    """Dask preload hook (``preload=["empact._parallel"]``): the worker process ignores
    SIGINT (it runs in the worker's main thread, after asyncio installed its own handler)."""
    ignore_sigint()


@contextmanager
def sigint_held() -> Iterator[None]:
    """Hold Ctrl-C back while the block starts processes and raise it (KeyboardInterrupt)
    when the block ends (at once if the block fails).

    A local Dask cluster interrupted half-started cannot be closed (Dask's exit handler then
    fails with a traceback), one that has started closes at once; a forked worker inherits
    the holding handler until its initializer ignores SIGINT (no traceback from a worker
    interrupted while it starts).  Outside the main thread the block runs as it is."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    held: list[int] = []
    handler = signal.signal(signal.SIGINT, lambda signum, frame: held.append(signum))
    try:
        yield
    except BaseException:
        if held:  # e.g. a worker that the same Ctrl-C stopped while it started
            raise KeyboardInterrupt from None
        raise
    finally:
        signal.signal(signal.SIGINT, handler)
    if held:
        raise KeyboardInterrupt


#: the function and calls of the running `run_forked`, inherited by its forked workers: a
#: task sends only its index (nothing is pickled on the way out, only results come back)
_FORKED: list[tuple[Callable[..., Any], Sequence[tuple[Any, ...]]]] = []


def _call(index: int) -> tuple[int, Any]:
    fn, calls = _FORKED[-1]
    return index, fn(*calls[index])


def run_forked(fn: Callable[..., Any], calls: Sequence[tuple[Any, ...]], workers: int,
               done: Callable[[int, Any], None] | None = None, keep: bool = True) -> list[Any]:
    """``[fn(*args) for args in calls]`` in `workers` forked processes, started in the order
    given; `done(index, result)` is called in this process as each completes (with `keep`
    false the results are only handed to `done`: the list returned holds None).  The workers
    inherit `fn` and `calls` (forked after they are set): neither needs to be picklable, only
    the results travel back.

    An exception in a call is raised here; an exception here (a Ctrl-C, one from `done`)
    terminates the workers at once.
    """
    results: list[Any] = [None] * len(calls)
    pool = None
    _FORKED.append((fn, [tuple(args) for args in calls]))
    try:
        with sigint_held():
            pool = multiprocessing.get_context("fork").Pool(workers, initializer=_worker_init)
        for index, result in pool.imap_unordered(_call, range(len(calls)), chunksize=1):
            if keep:
                results[index] = result
            if done is not None:
                done(index, result)
        pool.close()
    except BaseException:
        if pool is not None:
            pool.terminate()
        raise
    finally:
        if pool is not None:
            pool.join()
        _FORKED.pop()
    return results
