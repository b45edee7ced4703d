"""Writing linear systems for other tools: JSON, MATLAB ``.mat`` and numpy ``.npz``.

`save_system` writes a named state-space model (A, B, C, D with the input, output and state
names and units) and its metadata (operating point, options) atomically.  In MATLAB::

    s = load('plant.mat');
    sys = ss(s.A, s.B, s.C, s.D, 'InputName', cellstr(s.inputs), ...
             'OutputName', cellstr(s.outputs), 'StateName', cellstr(s.states));

JSON documents carry ``schema`` (name and version) and ``units``.
"""
from __future__ import annotations

import json
import os
import zipfile
import zlib
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np

from ._io import atomic_file, atomic_write_text, check_input
from ._lazy import lazy_module
from ._validate import check_choice
from .errors import ParameterError

sio = lazy_module("scipy.io")

__all__ = ["FORMATS", "system_dict", "save_system", "format_of", "jsonable", "read_npz"]

#: largest ``.npz`` archive read (`read_npz`) [bytes]
MAX_ARCHIVE_BYTES = 4 * 2**30

#: File formats of `save_system`.
FORMATS = ("json", "mat", "npz")


def jsonable(obj: Any) -> Any:
    """numpy arrays and scalars to lists and floats; complex to ``[re, im]``; NaN to None.

    Parameters
    ----------
    obj : object
        A value to write as JSON: mappings (keys become strings), lists and tuples are
        converted entry by entry; other objects (strings, ints, None) pass unchanged.

    Returns
    -------
    object
        The same structure with only JSON types: numpy arrays as nested lists, numpy
        scalars as int, float or bool, complex numbers as ``[re, im]``, non-finite floats
        (NaN, inf) as None.
    """
    if isinstance(obj, Mapping):
        return {str(k): jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return jsonable(obj.tolist())
    if isinstance(obj, (complex, np.complexfloating)):
        return [jsonable(float(obj.real)), jsonable(float(obj.imag))]
    if isinstance(obj, (float, np.floating)):
        return float(obj) if np.isfinite(obj) else None
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, np.bool_):
        return bool(obj)
    return obj


def format_of(path: str | os.PathLike[str], fmt: str | None = None) -> str:
    """The format named, or the one of the file's suffix.

    Parameters
    ----------
    path : str or path-like
        The file; its suffix (case-insensitive) gives the format when `fmt` is None.
    fmt : {"json", "mat", "npz"}, optional
        The format named explicitly (overrides the suffix).

    Returns
    -------
    str
        One of `FORMATS`.

    Raises
    ------
    ParameterError
        When `fmt`, or without it the suffix, is not one of `FORMATS`.
    """
    if fmt is not None:
        return check_choice("format", fmt, FORMATS)
    return check_choice(f"{path}: file suffix", Path(path).suffix.lstrip(".").lower(), FORMATS)


def system_dict(sys, units: Mapping[str, Sequence[str]] | None = None,
                metadata: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """A named state-space model as a plain dictionary (A, B, C, D, names, units).

    Parameters
    ----------
    sys : control.StateSpace or empact.nonlinear.linearization.Plant
        The system, n states, m inputs, p outputs (``A, B, C, D`` and the names
        ``input_labels``, ``output_labels``, ``state_labels``).
    units : dict str -> sequence of str, optional
        Units per signal, e.g. ``{"inputs": [...], "outputs": [...], "states": [...]}``;
        each entry becomes ``<key>_units``.
    metadata : dict, optional
        Extra entries, added as they are (after the others, so they may override them).

    Returns
    -------
    dict
        ``A``, ``B``, ``C``, ``D`` (ndarrays, shapes (n, n), (n, m), (p, n), (p, m)),
        ``inputs``, ``outputs``, ``states`` (lists of names), the ``<key>_units`` lists and
        the `metadata` entries.
    """
    d: dict[str, Any] = {"A": np.asarray(sys.A), "B": np.asarray(sys.B),
                         "C": np.asarray(sys.C), "D": np.asarray(sys.D),
                         "inputs": list(sys.input_labels), "outputs": list(sys.output_labels),
                         "states": list(sys.state_labels)}
    if units:
        d.update({f"{k}_units": list(v) for k, v in units.items()})
    d.update(metadata or {})
    return d


def save_system(sys, path: str | os.PathLike[str], *, fmt: str | None = None,
                schema: str = "empact.system", units: Mapping[str, Sequence[str]] | None = None,
                metadata: Mapping[str, Any] | None = None) -> Path:
    """Write a named state-space model atomically as JSON, ``.mat`` or ``.npz``.

    Parameters
    ----------
    sys : control.StateSpace or empact.nonlinear.linearization.Plant (as `system_dict`)
    path : destination file
    fmt : "json", "mat" or "npz" (default: from the suffix)
    schema : JSON schema name (version 1)
    units : ``{"inputs": [...], "outputs": [...], "states": [...]}`` units per signal
    metadata : extra entries: numbers, strings, flat dictionaries of numbers (a dictionary
        becomes ``<key>_names`` / ``<key>`` arrays in ``.mat`` and ``.npz``)

    Returns
    -------
    Path
        The file written (`path`).
    """
    fmt = format_of(path, fmt)
    data = system_dict(sys, units, metadata)
    if fmt == "json":
        doc = {"schema": {"name": schema, "version": 1}, **data}
        atomic_write_text(path, json.dumps(jsonable(doc), indent=1) + "\n")
        return Path(path)
    flat: dict[str, Any] = {}
    for k, v in data.items():
        if isinstance(v, Mapping):
            names = [n for n in v if not isinstance(v[n], (Mapping, str))]
            flat[f"{k}_names"] = np.array(names, dtype=object if fmt == "mat" else str)
            flat[k] = np.array([float(v[n]) for n in names])
            for n in v:
                if isinstance(v[n], str):
                    flat[f"{k}_{n}"] = v[n]
        elif isinstance(v, (list, tuple)) and v and isinstance(v[0], str):
            flat[k] = np.array(v, dtype=object if fmt == "mat" else str)
        else:
            flat[k] = np.asarray(v)
    return write_arrays(path, flat, fmt)


def write_arrays(path: str | os.PathLike[str], arrays: Mapping[str, Any], fmt: str) -> Path:
    """Write named arrays atomically as MATLAB ``.mat`` (fmt "mat") or numpy ``.npz``."""
    with atomic_file(path) as tmp:
        if fmt == "mat":
            sio.savemat(tmp, dict(arrays))
        else:
            with open(tmp, "wb") as fh:
                np.savez(fh, **arrays)
    return Path(path)


def read_npz(path: str | os.PathLike[str], what: str, required: Sequence[str],
             hint: str = "") -> dict[str, np.ndarray]:
    """Every array of a numpy ``.npz`` archive written by empact, read whole.

    One-line `ParameterError` naming the file and `what` it should be (and `hint`, how to
    write one) for a missing file, a file that is not an ``.npz`` archive (text, truncated,
    damaged), a pickled (object) array, or a missing array of `required`.

    Parameters
    ----------
    path : str or path-like
        The ``.npz`` archive.
    what : str
        What the file should be, for the messages (e.g. ``"plant family"``).
    required : sequence of str
        Names of the arrays the archive must hold.
    hint : str
        How to write such a file, appended to the messages (default: nothing).

    Returns
    -------
    dict str -> ndarray
        Every array of the archive by name (not only `required`).

    Raises
    ------
    ParameterError
        For a missing file, a folder, an unreadable archive or a missing required array.
    """
    p = Path(path)
    how = f"; {hint}" if hint else ""
    check_input(p, what, max_bytes=MAX_ARCHIVE_BYTES)
    try:
        with np.load(p, allow_pickle=False) as z:
            arrays = {name: z[name] for name in z.files}
    except (zipfile.BadZipFile, zlib.error, EOFError, OSError, ValueError, KeyError):
        # a text or truncated file, a damaged member, a pickled (object) array
        raise ParameterError(f"{p}: not a {what} (not a readable .npz archive{how})") from None
    missing = [name for name in required if name not in arrays]
    if missing:
        raise ParameterError(f"{p}: not a {what} (no {', '.join(missing)} in the archive"
                             f"{how})")
    return arrays
