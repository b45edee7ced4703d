"""One result contract (private): every public result class has `to_dict` (JSON-safe, SI)
and, where it is a table, `to_pandas` (pandas optional).

`Result` is the mixin: its `to_dict` takes the dataclass fields (without the private ones
and those a class lists in ``_not_data``: models, laws, caches), turns nested results into
their own `to_dict` and writes every value as the commands' JSON does
(`empact.export.jsonable`: arrays as lists, complex as ``[re, im]``, NaN and inf as None).
A table (`TableResult`) also defines ``_columns`` (column name -> 1-D array, SI);
`to_pandas` makes the frame of it, and its other writers (``to_csv``) are built on the same
columns.
"""
from __future__ import annotations

import dataclasses
import importlib
import os
from typing import Any, ClassVar, Mapping

import numpy as np

from .export import jsonable

__all__ = ["Result", "TableResult", "plain", "frame"]


def plain(obj: Any) -> Any:
    """`obj` with nested results as their `to_dict` and every value JSON-safe.

    Parameters
    ----------
    obj : object
        A result (or any object with ``to_dict``), a dataclass (its public fields), a
        mapping, sequence, array or scalar.

    Returns
    -------
    object
        Only JSON types (`empact.export.jsonable`): dicts with string keys, lists, str,
        int, float (finite), bool and None.

    Raises
    ------
    TypeError
        For a value that is none of these and has no ``to_dict`` (one line naming its type).
    """
    if hasattr(obj, "to_dict") and not isinstance(obj, type):
        return plain(obj.to_dict())
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):  # a settings record
        return {f.name: plain(getattr(obj, f.name)) for f in dataclasses.fields(obj)
                if not f.name.startswith("_")}
    if isinstance(obj, Mapping):
        return {str(k): plain(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [plain(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return jsonable(obj.tolist()) if obj.dtype != object else [plain(v) for v in obj.tolist()]
    if isinstance(obj, os.PathLike):
        return os.fspath(obj)
    if obj is None or isinstance(obj, (str, bool, int, float, complex, np.generic)):
        return jsonable(obj)
    raise TypeError(f"{type(obj).__name__} has no JSON form (give it a to_dict)")


def frame(columns: Mapping[str, Any], owner: str) -> Any:
    """A pandas DataFrame of named 1-D columns (pandas imported here: it is optional).

    Parameters
    ----------
    columns : dict str -> array, each shape (n,)
        The columns, in order (SI; a name carries its unit as ``name [unit]`` where the
        writer's header does).
    owner : str
        The class asking (for the error message).

    Returns
    -------
    pandas.DataFrame

    Raises
    ------
    ImportError
        Without pandas (one line: how to install it).
    """
    try:  # optional: imported when a table is asked for
        pd = importlib.import_module("pandas")
    except ImportError:  # pragma: no cover - depends on the environment
        raise ImportError(f"{owner}.to_pandas needs pandas (pip install pandas); to_dict "
                          "gives the same data without it") from None
    return pd.DataFrame({k: np.asarray(v) for k, v in columns.items()})


class Result:
    """The result contract: `to_dict` (JSON-safe, SI) of the dataclass fields."""

    #: fields left out of `to_dict` (objects that are not data: models, laws, caches)
    _not_data: ClassVar[tuple[str, ...]] = ()

    def _data(self) -> dict[str, Any]:
        """The fields `to_dict` writes, as they are (arrays, nested results)."""
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(self)  # type: ignore[arg-type]
                if not f.name.startswith("_") and f.name not in self._not_data}

    def to_dict(self) -> dict[str, Any]:
        """The result as plain JSON types (SI; arrays as nested lists, complex numbers as
        ``[re, im]`` pairs, NaN as None; nested results as their own `to_dict`).

        Returns
        -------
        dict
            Field name -> value, ready for ``json.dumps(..., allow_nan=False)``.
        """
        return plain(self._data())


class TableResult(Result):
    """A result that is a table: `to_dict` and `to_pandas` (one column per quantity, SI),
    both of ``_columns``."""

    def _columns(self) -> dict[str, Any]:
        """Column name -> 1-D array (SI), in order."""
        raise NotImplementedError

    def to_pandas(self) -> Any:
        """The result as a table: a pandas.DataFrame, one column per quantity (SI).

        Returns
        -------
        pandas.DataFrame

        Raises
        ------
        ImportError
            Without pandas (it is optional).
        """
        return frame(self._columns(), type(self).__name__)
