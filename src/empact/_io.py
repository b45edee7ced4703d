"""Writing files and folders atomically (private).

Every output of empact is written to a temporary path beside its destination and moved into
place only when complete, so a failure or an interrupt never leaves a partial file.  Files are
created with the permissions of an ordinary file (``0666`` less the umask, usually ``0644``)
and folders likewise (``0777`` less the umask), not the ``0600`` / ``0700`` of `tempfile`.
"""
from __future__ import annotations

import os
import shutil
import tempfile
from contextlib import contextmanager
from pathlib import Path
from typing import Callable, Iterator

__all__ = ["atomic_write_text", "atomic_write_bytes", "atomic_file", "atomic_folder", "umask"]

_UMASK: int | None = None


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
    fd, tmp = tempfile.mkstemp(dir=path.parent if str(path.parent) else ".",
                               prefix=f".{path.name}.", suffix=".tmp" + path.suffix)
    os.close(fd)
    tmp_path = Path(tmp)
    try:
        yield tmp_path
        os.chmod(tmp_path, 0o666 & ~umask())
        os.replace(tmp_path, path)
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
    tmp = Path(tempfile.mkdtemp(dir=dest.parent, prefix=f".{dest.name}.tmp-"))
    try:
        yield tmp
        mode_file, mode_dir = 0o666 & ~umask(), 0o777 & ~umask()
        for p in tmp.rglob("*"):
            os.chmod(p, mode_dir if p.is_dir() else mode_file)
        if not dest.exists():
            os.chmod(tmp, mode_dir)
            tmp.rename(dest)
            return
        for p in sorted(tmp.iterdir()):
            target = dest / p.name
            if target.is_dir() and not target.is_symlink():
                shutil.rmtree(target)
            os.replace(p, target)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
