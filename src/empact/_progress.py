"""Progress bars on stderr: tqdm's redrawn bar on a terminal; on a pipe or a log file, whole
lines (at most one every 10 s, and the final state) with no carriage returns or escapes.  A bar
left by an exception (a Ctrl-C, an error) writes no final state: the error line is the last
word."""
from __future__ import annotations

import sys
from typing import Any, Iterable

from tqdm import tqdm

__all__ = ["progress"]


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


def progress(iterable: Iterable[Any] | None = None, *, total: int | None = None, desc: str,
             unit: str, enabled: bool = True) -> tqdm:
    """A progress bar on stderr (disabled unless `enabled`).

    On a terminal the bar is redrawn in place and removed when done; elsewhere (captured,
    piped, redirected to a log) it is written as plain lines, at most one every 10 s, plus the
    final state.
    """
    stream = sys.stderr
    if getattr(stream, "isatty", lambda: False)():
        return _Bar(iterable, total=total, desc=desc, unit=unit, disable=not enabled,
                    file=stream, leave=False)
    return _Bar(iterable, total=total, desc=desc, unit=unit, disable=not enabled,
                file=_Lines(stream), leave=True, mininterval=10.0, ascii=True, ncols=80)
