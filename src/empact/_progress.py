"""Progress bars on stderr: tqdm's redrawn bar on a terminal; on a pipe or a log file, whole
lines (the first after 1 s, then at most one every 10 s, and the final state) with no
carriage returns or escapes: work that ends within a second writes none.  A bar
left by an exception (a Ctrl-C, an error) writes no final state: the error line is the last
word.

`working` is the indicator of work that has no steps to count (a command without a bar of its
own): ``linearize: working, 00:03 elapsed``, by the same rules (after a second, then every
10 s as lines; redrawn each second on a terminal), ended by the first real bar."""
from __future__ import annotations

import sys
import threading
import time
from contextlib import contextmanager
from typing import Any, Iterable, Iterator

from tqdm import tqdm

__all__ = ["progress", "working", "WORKING_FORMAT"]

#: the line of `working` (``desc: working, 00:03 elapsed``)
WORKING_FORMAT = "{desc}: working, {elapsed} elapsed"


class _Lines:
    """A text stream for tqdm that writes each redraw of the bar as one line."""

    def __init__(self, stream: Any) -> None:
        self.stream = stream

    def write(self, text: str) -> None:
        text = text.replace("\r", "").rstrip()
        if text:  # tqdm's clearing writes (blanks, a lone newline) are dropped
            self.stream.write(text + "\n")

    def flush(self) -> None:
        self.stream.flush()


class _Bar(tqdm):
    """tqdm that, left by an exception (as a context manager, or an iteration that an
    exception ends), closes without writing its final state."""

    def __exit__(self, exc_type: Any, exc_value: Any, traceback: Any) -> Any:
        if exc_type is not None:
            self.leave = False
        return super().__exit__(exc_type, exc_value, traceback)

    def close(self) -> None:
        if sys.exc_info()[0] is not None:  # in a finally: an exception (or GeneratorExit)
            self.leave = False
        super().close()


class _LineBar(_Bar):
    """A bar written as lines that shows itself only once it has run `delay` seconds: a timer
    writes its first state then (tqdm's own ``delay`` waits for the next update, which a long
    step does not give), so work that ends sooner (a quick run, bad input found at once)
    leaves no progress lines beside its result or its one error line."""

    def __init__(self, *args: Any, delay: float = 0.0, **kwargs: Any) -> None:
        super().__init__(*args, delay=delay, **kwargs)
        self._timer = None
        self._once = threading.Lock()
        if delay > 0 and not self.disable:
            self._timer = threading.Timer(delay, self.show)
            self._timer.daemon = True
            self._timer.start()

    def show(self) -> None:
        """Write the current state now (the timer's call after `delay`)."""
        with self._once:
            if not self.disable and not getattr(self, "_closed", False):
                self.delay = 0  # shown: later updates and the final state are written
                self.refresh()
                self.last_print_t, self.last_print_n = self._time(), self.n

    def close(self) -> None:
        timer, once = getattr(self, "_timer", None), getattr(self, "_once", None)
        if timer is not None:
            timer.cancel()
        if once is not None:
            with once:
                self._closed = True
        super().close()


class _Off:
    """A disabled bar: iterates, counts and closes, and writes nothing."""

    def __init__(self, iterable: Iterable[Any] | None) -> None:
        self.n: float = 0
        self.iterable, self.disable = iterable, True

    def __iter__(self) -> Any:
        return iter(self.iterable if self.iterable is not None else ())

    def __enter__(self) -> "_Off":
        return self

    def __exit__(self, *exc: Any) -> None:
        return None

    def update(self, n: float = 1) -> None:
        """Count `n` more steps."""
        self.n += n

    def refresh(self) -> None:
        """Nothing to draw."""

    def show(self) -> None:
        """Nothing to draw."""

    def close(self) -> None:
        """Nothing to close."""


#: seconds a bar written as lines waits before its first line
LINE_DELAY = 1.0


def progress(iterable: Iterable[Any] | None = None, *, total: int | None = None, desc: str,
             unit: str, enabled: bool = True, delay: float = LINE_DELAY) -> tqdm:
    """A progress bar on stderr (disabled unless `enabled`).

    On a terminal the bar is redrawn in place and removed when done; elsewhere (captured,
    piped, redirected to a log) it is written as plain lines once it has run `delay` seconds
    (its state then, at most one line every 10 s, and the final state).
    """
    if not enabled:  # no tqdm at all: it would make a multiprocessing lock (a semaphore
        return _Off(iterable)  # that a worker killed by a Ctrl-C leaves to the tracker)
    _end_working()  # a bar of the work's own replaces the indicator
    stream = sys.stderr
    if getattr(stream, "isatty", lambda: False)():
        return _Bar(iterable, total=total, desc=desc, unit=unit, disable=not enabled,
                    file=stream, leave=False)
    return _LineBar(iterable, total=total, desc=desc, unit=unit, disable=not enabled,
                    file=_Lines(stream), leave=True, mininterval=10.0, ascii=True, ncols=80,
                    delay=delay)



class _Working:
    """The ticker of `working`: a thread that waits `delay`, then makes the bar (only then:
    tqdm's multiprocessing lock is not made for work that ends sooner) and redraws it every
    `every` seconds until `end`."""

    def __init__(self, desc: str, tty: bool, delay: float) -> None:
        self.desc, self.tty, self.delay = desc, tty, delay
        self.every = 1.0 if tty else 10.0
        self.t0 = time.time()
        self.lock, self.stop = threading.Lock(), threading.Event()
        self.bar: Any = None
        self.thread = threading.Thread(target=self.run, daemon=True)
        self.thread.start()

    def run(self) -> None:
        if self.stop.wait(self.delay):
            return
        with self.lock:
            if self.stop.is_set():
                return
            file = sys.stderr if self.tty else _Lines(sys.stderr)
            # (a delay that never passes: tqdm draws only when told, by refresh)
            self.bar = _Bar(total=None, desc=self.desc, file=file, leave=False,
                            bar_format=WORKING_FORMAT, ascii=not self.tty, delay=1e9)
            self.bar.start_t = self.t0  # elapsed since the work began
            self.bar.refresh()
        while not self.stop.wait(self.every):
            with self.lock:
                if self.stop.is_set():
                    return
                self.bar.refresh()

    def end(self) -> None:
        with self.lock:
            self.stop.set()
            if self.bar is not None:
                self.bar.leave = False  # the indicator leaves no final line
                self.bar.close()


#: the `working` indicator now running (at most one)
_WORKING: list[_Working] = []


def _end_working() -> None:
    while _WORKING:
        _WORKING.pop().end()


@contextmanager
def working(desc: str, *, enabled: bool = True, delay: float = LINE_DELAY) -> Iterator[None]:
    """Show that work is going on, on stderr, while the block runs: nothing for work that ends
    within `delay` seconds; then ``desc: working, MM:SS elapsed`` (as lines off a terminal:
    the first after `delay`, then one every 10 s; redrawn each second on a terminal, and only
    when stdout is not that terminal too, whose output it would garble).  A `progress` bar
    started inside the block ends the indicator; it leaves no final line.

    Parameters
    ----------
    desc : str
        What works (the command's name).
    enabled : bool
        False: show nothing (``--quiet``).
    delay : float
        Seconds before the first line [s].

    Yields
    ------
    None
    """
    tty = getattr(sys.stderr, "isatty", lambda: False)()
    if not enabled or _WORKING or (tty and getattr(sys.stdout, "isatty", lambda: False)()):
        yield
        return
    w = _Working(desc, tty, delay)
    _WORKING.append(w)
    try:
        yield
    finally:
        if w in _WORKING:
            _WORKING.remove(w)
        w.end()
