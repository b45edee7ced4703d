"""Progress bars on stderr: tqdm's redrawn bar on a terminal; on a pipe or a log file, whole
lines (at most one every 10 s, and the final state) with no carriage returns or escapes."""
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


def progress(iterable: Iterable[Any] | None = None, *, total: int | None = None, desc: str,
             unit: str, enabled: bool = True) -> tqdm:
    """A progress bar on stderr (disabled unless `enabled`).

    On a terminal the bar is redrawn in place and removed when done; elsewhere (captured,
    piped, redirected to a log) it is written as plain lines, at most one every 10 s, plus the
    final state.
    """
    stream = sys.stderr
    if getattr(stream, "isatty", lambda: False)():
        return tqdm(iterable, total=total, desc=desc, unit=unit, disable=not enabled,
                    file=stream, leave=False)
    return tqdm(iterable, total=total, desc=desc, unit=unit, disable=not enabled,
                file=_Lines(stream), leave=True, mininterval=10.0, ascii=True, ncols=80)
