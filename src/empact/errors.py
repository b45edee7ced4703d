"""The project's error types.

Every error that a user can cause with a bad value, file or option is a `ParameterError` (a
`ValueError`) whose message is one line: what is wrong, the value, and what is allowed.  The
command line prints it as ``error: <message>`` and exits with status 2.
"""
from __future__ import annotations

__all__ = ["ParameterError", "TrimError", "DataError"]


class ParameterError(ValueError):
    """A parameter value, key, option or file is not acceptable (one-line message)."""


class TrimError(ParameterError):
    """No steady operating point exists for a request (the message names the request)."""


class DataError(ParameterError):
    """A data file (CSV records, traction table) cannot be used (names the file and place)."""
