"""Writing files and folders atomically, and reading input files through one guard (private).

Every output of empact is written to a temporary path beside its destination and moved into
place only when complete, so a failure or an interrupt never leaves a partial file.  Files are
created with the permissions of an ordinary file (``0666`` less the umask, usually ``0644``)
and folders likewise (``0777`` less the umask), not the ``0600`` / ``0700`` of `tempfile`.
A temporary name is never longer than the file system allows (`temp_prefix`), so a name that
fits fits its temporary too.

What a block of code wrote is known: `recording` collects the destination of every file that
one of these writers moves into place meanwhile (the command line's closing line names them).

Every input file is read through `check_input` (a regular file: not a folder, FIFO, device or
socket, which would hang or never end; not larger than its kind allows) and, for text,
`read_input_text` (UTF-8, no NUL bytes); `parse_json` and `parse_toml` refuse documents nested
deeper than `MAX_DEPTH`.  Each problem is one line naming the file (the caller's error type).
"""
from __future__ import annotations

import json
import os
import shutil
import stat
import tempfile
import tomllib
from contextlib import contextmanager
from pathlib import Path
from typing import Any, Callable, Iterator

from .errors import ParameterError

__all__ = ["atomic_write_text", "atomic_write_bytes", "atomic_file", "atomic_folder", "umask",
           "temp_prefix", "NAME_MAX", "check_input", "read_input_text", "parse_json",
           "parse_toml", "MAX_DEPTH", "MAX_TEXT_BYTES", "file_kind", "recording"]

#: longest file name (one path component) in bytes on the file systems empact writes to
NAME_MAX = 255
#: deepest nesting of tables and lists accepted in an input document (JSON, TOML)
MAX_DEPTH = 32
#: largest text input file (parameters, scenarios, tables, controllers, records) [bytes]
MAX_TEXT_BYTES = 256 * 2**20


def temp_prefix(name: str, room: int) -> str:
    """``"." + name``, shortened so that ``room`` more bytes (a random part and a suffix)
    still fit in `NAME_MAX`.

    Parameters
    ----------
    name : str
        The destination's file name.
    room : int
        Bytes the caller appends [bytes].

    Returns
    -------
    str
        The prefix of the temporary name.
    """
    raw = ("." + name).encode()[:max(1, NAME_MAX - room)]
    return raw.decode(errors="ignore")


def file_kind(mode: int) -> str:
    """What a non-regular file is, in words (``"a FIFO (named pipe)"``).

    Parameters
    ----------
    mode : int
        ``st_mode`` of `os.stat`.

    Returns
    -------
    str
        A FIFO, a character or block device, a socket or a folder.
    """
    if stat.S_ISFIFO(mode):
        return "a FIFO (named pipe)"
    if stat.S_ISCHR(mode) or stat.S_ISBLK(mode):
        return "a device"
    if stat.S_ISSOCK(mode):
        return "a socket"
    if stat.S_ISDIR(mode):
        return "a folder"
    return "not a regular file"


def check_input(path: str | os.PathLike[str], what: str, *,
                max_bytes: int = MAX_TEXT_BYTES,
                error: type[ParameterError] = ParameterError) -> Path:
    """Check an input file before it is opened: it exists, is a regular file (a FIFO or a
    device would block or never end) and holds at most `max_bytes`.

    Parameters
    ----------
    path : str or path-like
        The file.
    what : str
        What the file is, for the messages (``"parameter"`` -> "no such parameter file").
    max_bytes : int
        Largest accepted size [bytes].
    error : type
        The `ParameterError` subclass raised.

    Returns
    -------
    Path
        `path`.

    Raises
    ------
    ParameterError
        (`error`) one line naming the file: missing, a folder, a FIFO, device or socket, too
        large, or not readable (the system's reason: no permission, name too long, ...).
    """
    p = Path(path)
    if not str(path):
        raise error(f"no {what} file named (an empty name)")
    try:
        st = os.stat(p)
    except FileNotFoundError:
        raise error(f"{p}: no such {what} file") from None
    except OSError as exc:
        raise error(f"{p}: cannot be read ({(exc.strerror or 'error').lower()})") from None
    if stat.S_ISDIR(st.st_mode):
        raise error(f"{p}: is a folder, not a {what} file")
    if not stat.S_ISREG(st.st_mode):
        raise error(f"{p}: is {file_kind(st.st_mode)}, not a {what} file")
    if st.st_size > max_bytes:
        raise error(f"{p}: {st.st_size / 2**20:.0f} MiB; a {what} file may hold at most "
                    f"{max_bytes / 2**20:.0f} MiB")
    if not os.access(p, os.R_OK):
        raise error(f"{p}: cannot be read (permission denied)")
    return p


def read_input_text(path: str | os.PathLike[str], what: str, *,
                    max_bytes: int = MAX_TEXT_BYTES,
                    error: type[ParameterError] = ParameterError) -> str:
    """The text of an input file, read through `check_input`: UTF-8 (a byte-order mark is
    skipped), no NUL bytes.

    Parameters
    ----------
    path : str or path-like
        The file.
    what : str
        What the file is, for the messages.
    max_bytes : int
        Largest accepted size [bytes].
    error : type
        The `ParameterError` subclass raised.

    Returns
    -------
    str
        The file's text.

    Raises
    ------
    ParameterError
        (`error`) one line naming the file (see `check_input`; binary or not UTF-8).
    """
    p = check_input(path, what, max_bytes=max_bytes, error=error)
    try:
        data = p.read_bytes()
    except OSError as exc:
        raise error(f"{p}: cannot be read ({(exc.strerror or 'error').lower()})") from None
    if b"\x00" in data:
        raise error(f"{p}: a binary file, not a {what} file (UTF-8 text)")
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError:
        raise error(f"{p}: not a UTF-8 text file (a {what} file is UTF-8 text)") from None


def _depth(doc: Any) -> int:
    """Deepest nesting of dicts and lists in `doc` (iterative: any depth)."""
    deepest, stack = 0, [(doc, 0)]
    while stack:
        obj, d = stack.pop()
        if isinstance(obj, dict):
            stack.extend((v, d + 1) for v in obj.values())
        elif isinstance(obj, list):
            stack.extend((v, d + 1) for v in obj)
        else:
            continue
        deepest = max(deepest, d + 1)
    return deepest


def _check_depth(doc: Any, p: Path, what: str, error: type[ParameterError]) -> Any:
    if _depth(doc) > MAX_DEPTH:
        raise error(f"{p}: nested deeper than {MAX_DEPTH} levels; not a {what} file")
    return doc


def parse_json(path: str | os.PathLike[str], what: str, *,
               error: type[ParameterError] = ParameterError) -> Any:
    """The JSON document of an input file (`read_input_text`), nested at most `MAX_DEPTH`.

    Parameters
    ----------
    path : str or path-like
        The file.
    what : str
        What the file is, for the messages (``"controller"``).
    error : type
        The `ParameterError` subclass raised.

    Returns
    -------
    object
        The parsed document.

    Raises
    ------
    ParameterError
        (`error`) one line naming the file: unreadable, not JSON, or nested too deep.
    """
    p = Path(path)
    text = read_input_text(p, what, error=error)
    try:
        doc = json.loads(text)
    except json.JSONDecodeError:
        raise error(f"{p}: not a {what} file (not JSON text)") from None
    except RecursionError:
        raise error(f"{p}: nested deeper than {MAX_DEPTH} levels; not a {what} file") from None
    return _check_depth(doc, p, what, error)


def parse_toml(path: str | os.PathLike[str], what: str, *,
               error: type[ParameterError] = ParameterError) -> dict[str, Any]:
    """The TOML document of an input file (`read_input_text`), nested at most `MAX_DEPTH`.

    Parameters
    ----------
    path : str or path-like
        The file.
    what : str
        What the file is, for the messages (``"parameter"``).
    error : type
        The `ParameterError` subclass raised.

    Returns
    -------
    dict
        The parsed tables and values.

    Raises
    ------
    ParameterError
        (`error`) one line naming the file: unreadable, not TOML, or nested too deep.
    """
    p = Path(path)
    text = read_input_text(p, what, error=error)
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise error(f"{p}: not valid TOML ({exc})") from None
    except RecursionError:
        raise error(f"{p}: nested deeper than {MAX_DEPTH} levels; not a {what} file") from None
    return _check_depth(doc, p, what, error)

_UMASK: int | None = None

#: the open `recording` blocks (each a dict used as an ordered set of written paths)
_RECORDS: list[dict[Path, None]] = []


@contextmanager
def recording() -> Iterator[dict[Path, None]]:
    """Collect what is written while the block runs: the destination of every file an atomic
    writer of this module moves into place (`atomic_file` and the writers on it; every file
    of an `atomic_folder`), absolute, once each, in the order written.  Files written into a
    folder that `atomic_folder` later moves into place are recorded at their destination.

    Yields
    ------
    dict of pathlib.Path to None
        The written paths (its keys, an ordered set), filled as the block runs.
    """
    rec: dict[Path, None] = {}
    _RECORDS.append(rec)
    try:
        yield rec
    finally:
        _RECORDS.remove(rec)


def _record(paths: Iterator[Path] | list[Path], moved_from: Path | None = None) -> None:
    """Record `paths` (absolute) in every open `recording`; `moved_from`: a temporary folder
    whose recorded files are now at their destination (dropped from the records)."""
    for rec in _RECORDS:
        if moved_from is not None:
            for old in [k for k in rec if k.is_relative_to(moved_from)]:
                del rec[old]
        for path in paths:
            rec[path] = None


def umask() -> int:
    """The process umask (read once)."""
    global _UMASK
    if _UMASK is None:
        _UMASK = os.umask(0o022)
        os.umask(_UMASK)
    return _UMASK


@contextmanager
def atomic_file(path: str | os.PathLike[str]) -> Iterator[Path]:
    """Yield a temporary path beside `path`; on success it replaces `path`, else it is removed.

    The caller writes the temporary path (any library that takes a file name).
    """
    path = Path(path)
    suffix = ".tmp" + path.suffix
    fd, tmp = tempfile.mkstemp(dir=path.parent if str(path.parent) else ".",
                               prefix=temp_prefix(path.name, len(suffix.encode()) + 10) + ".",
                               suffix=suffix)
    os.close(fd)
    tmp_path = Path(tmp)
    try:
        yield tmp_path
        os.chmod(tmp_path, 0o666 & ~umask())
        os.replace(tmp_path, path)
        if _RECORDS:
            _record([path.absolute()])
    except BaseException:
        tmp_path.unlink(missing_ok=True)
        raise


def _write(path: str | os.PathLike[str], write: Callable[[Path], object]) -> Path:
    with atomic_file(path) as tmp:
        write(tmp)
    return Path(path)


def atomic_write_text(path: str | os.PathLike[str], text: str) -> Path:
    """Write `text` (UTF-8) to `path` atomically."""
    return _write(path, lambda p: p.write_text(text, encoding="utf-8"))


def atomic_write_bytes(path: str | os.PathLike[str], data: bytes) -> Path:
    """Write `data` to `path` atomically."""
    return _write(path, lambda p: p.write_bytes(data))


@contextmanager
def atomic_folder(dest: str | os.PathLike[str]) -> Iterator[Path]:
    """Yield a temporary folder beside `dest`; on success its files are moved into `dest`.

    `dest` is created if missing (with its parents).  A file of the temporary folder replaces
    the file of the same name in `dest`; other files in `dest` are left alone.  On failure the
    temporary folder is removed and `dest` is untouched (if it did not exist, it is not
    created).
    """
    dest = Path(dest).resolve()
    dest.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(dir=dest.parent,
                                prefix=temp_prefix(dest.name, 16) + ".tmp-"))
    try:
        yield tmp
        mode_file, mode_dir = 0o666 & ~umask(), 0o777 & ~umask()
        files = []
        for p in sorted(tmp.rglob("*")):
            os.chmod(p, mode_dir if p.is_dir() else mode_file)
            if not p.is_dir():
                files.append(dest / p.relative_to(tmp))
        if not dest.exists():
            os.chmod(tmp, mode_dir)
            tmp.rename(dest)
        else:
            for p in sorted(tmp.iterdir()):
                target = dest / p.name
                if target.is_dir() and not target.is_symlink():
                    shutil.rmtree(target)
                os.replace(p, target)
        if _RECORDS:
            _record(files, moved_from=tmp)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
