"""A study streamed to shards: one ``.npz`` file per completed chunk and a manifest.

A long study (`empact.montecarlo.monte_carlo` with a ``store`` folder) writes each chunk's
results as soon as the chunk completes, into ``shards/chunk-NNNNNN.npz`` of its folder, and
records the chunk as done in ``manifest.json``; both are written atomically (a temporary file
renamed into place), so a study that is killed leaves whole shards and a manifest that lists
only whole shards: it loses at most the chunks that were running.  The manifest holds what
identifies the study (`spec`: analysis, seed, run count and the hashes of the parameters, the
spread and the analysis' context; `spec_hash` over them), the chunks' run ranges (fixed when
the study starts, so that a resume on another number of workers computes the same chunks) and
the completed chunks.  `ShardStore.open` refuses, in one line, a folder whose study differs.

A shard holds whatever arrays the chunk function returns (named), so a record grows new
columns without a change here.
"""
from __future__ import annotations

import hashlib
import io
import json
import os
import zipfile
from pathlib import Path
from typing import Any, Iterator, Mapping, Sequence

import numpy as np

from ._io import atomic_write_bytes, atomic_write_text, parse_json
from .errors import ParameterError

__all__ = ["ShardStore", "StudyMismatch", "spec_hash", "MANIFEST", "SHARDS"]

#: the manifest's file name in a study folder
MANIFEST = "manifest.json"
#: the folder of the shards in a study folder
SHARDS = "shards"
#: the manifest's schema
SCHEMA = {"name": "empact.study.manifest", "version": 1}


class StudyMismatch(ParameterError):
    """A study folder that is not a study, or whose study differs from the one resumed."""


def _manifest(doc: Any, where: str) -> tuple[list[tuple[int, int]], set[int], dict]:
    """The chunks, completed chunks and spec of a manifest document, checked: one line
    (`StudyMismatch`) naming `where` (the option and the folder) and what is wrong."""
    def bad(what: str) -> StudyMismatch:
        return StudyMismatch(f"{where}: not a study folder ({MANIFEST}: {what}); start it "
                             "with --out alone")

    def whole(x: Any) -> bool:
        return isinstance(x, int) and not isinstance(x, bool)

    if not isinstance(doc, dict) or not isinstance(doc.get("schema"), dict) \
            or doc["schema"].get("name") != SCHEMA["name"]:
        raise bad(f"schema {SCHEMA['name']!r} expected")
    version = doc["schema"].get("version")
    if not whole(version) or version < 1:
        raise bad(f"schema version {version!r}: must be a whole number >= 1")
    if version > SCHEMA["version"]:
        raise StudyMismatch(f"{where}: {MANIFEST}: schema version {version} is newer than "
                            f"this empact reads (up to {SCHEMA['version']}); update empact")
    raw, done, spec = doc.get("chunks"), doc.get("completed"), doc.get("spec")
    if not isinstance(spec, dict):
        raise bad("no spec table")
    if not isinstance(raw, list) or not raw or not all(
            isinstance(c, list) and len(c) == 2 and all(whole(x) for x in c) for c in raw):
        raise bad("chunks must be a list of [start, stop] run pairs")
    chunks = [(int(a), int(b)) for a, b in raw]
    if chunks[0][0] != 0 or any(a >= b for a, b in chunks) or any(
            chunks[k][0] != chunks[k - 1][1] for k in range(1, len(chunks))):
        raise bad("chunks must cover the runs from 0, in order, each non-empty")
    if not isinstance(done, list) or not all(whole(k) and 0 <= k < len(chunks) for k in done):
        raise bad(f"completed must list chunk indices 0 to {len(chunks) - 1}")
    return chunks, set(done), dict(spec)


def spec_hash(spec: Mapping[str, Any]) -> str:
    """SHA-256 (hex) of `spec` as canonical JSON (sorted keys).

    Parameters
    ----------
    spec : mapping
        JSON-serialisable description of a study.

    Returns
    -------
    str
        64 hexadecimal digits.
    """
    text = json.dumps(spec, sort_keys=True, separators=(",", ":"), default=str)
    return hashlib.sha256(text.encode()).hexdigest()


class ShardStore:
    """The shards and manifest of one study in a folder (`create` or `open` it).

    Attributes
    ----------
    folder : Path
        The study folder.
    spec : dict
        What identifies the study (JSON).
    chunks : list of (int, int)
        Run range ``[start, stop)`` of each chunk, in run order.
    completed : set of int
        Indices of the chunks whose shard is written.
    """

    def __init__(self, folder: Path, spec: dict[str, Any], chunks: list[tuple[int, int]],
                 completed: set[int]) -> None:
        self.folder = folder
        self.spec = spec
        self.chunks = chunks
        self.completed = completed

    @classmethod
    def create(cls, folder: str | os.PathLike[str], spec: Mapping[str, Any],
               chunks: Sequence[tuple[int, int]]) -> "ShardStore":
        """Start a study in `folder` (created if missing): an empty ``shards`` folder and the
        manifest (any shards of an earlier study there are removed).

        Parameters
        ----------
        folder : path
            The study's folder.
        spec : mapping
            What identifies the study (`empact.montecarlo.study.study_spec`).
        chunks : sequence of (int, int)
            Each chunk's run range ``(start, stop)``.

        Returns
        -------
        ShardStore
            The new store, its manifest written.
        """
        path = Path(folder)
        (path / SHARDS).mkdir(parents=True, exist_ok=True)
        for old in (path / SHARDS).glob("chunk-*.npz"):
            old.unlink()
        store = cls(path, dict(spec), [(int(a), int(b)) for a, b in chunks], set())
        store._write_manifest()
        return store

    @classmethod
    def open(cls, folder: str | os.PathLike[str], spec: Mapping[str, Any],
             option: str = "--resume") -> "ShardStore":
        """The study in `folder`, to be resumed with `spec`.

        Parameters
        ----------
        folder : path
            The study's folder.
        spec : mapping
            The resuming study's spec; it must equal the manifest's.
        option : str
            The option named in a refusal.

        Returns
        -------
        ShardStore
            The store with its completed chunks.

        Raises
        ------
        StudyMismatch
            When `folder` has no manifest one can read (through `empact._io.parse_json`: a
            regular UTF-8 file, JSON, nested at most 32 levels) and trust (the schema, a
            version this empact reads, chunks that cover the runs from 0 in order, completed
            chunks among them, a shard of a completed chunk that is an archive), or its
            study's spec differs from `spec` (the message names the fields that differ).
        """
        path = Path(folder)
        try:
            doc = parse_json(path / MANIFEST, "study manifest", error=StudyMismatch)
        except StudyMismatch as exc:
            raise StudyMismatch(f"{option} {folder}: not a study folder ({exc}); start it "
                                "with --out alone") from None
        chunks, completed, old = _manifest(doc, f"{option} {folder}")
        if spec_hash(old) != spec_hash(spec):
            diff = sorted(k for k in set(old) | set(spec) if old.get(k) != spec.get(k))
            shown = ", ".join(f"{k} {old.get(k)!s:.16} there, {spec.get(k)!s:.16} here"
                              for k in diff)
            raise StudyMismatch(f"{option} {folder}: the study there differs ({shown}); "
                                "resume with the same spread, seed, runs, analysis and "
                                "parameters, or start a new folder")
        completed = {k for k in completed if (path / SHARDS / cls._name(k)).is_file()}
        for k in sorted(completed):
            shard = path / SHARDS / cls._name(k)
            if not zipfile.is_zipfile(shard):
                raise StudyMismatch(f"{option} {folder}: {SHARDS}/{shard.name} is damaged "
                                    "(not an .npz archive); delete it and --resume computes "
                                    "its chunk again")
        return cls(path, dict(spec), chunks, completed)

    @staticmethod
    def _name(index: int) -> str:
        return f"chunk-{index:06d}.npz"

    def _write_manifest(self) -> None:
        doc = {"schema": SCHEMA, "spec_hash": spec_hash(self.spec), "spec": self.spec,
               "runs": self.chunks[-1][1] if self.chunks else 0,
               "chunk_size": max((b - a for a, b in self.chunks), default=0),
               "chunks": [list(c) for c in self.chunks], "completed": sorted(self.completed)}
        atomic_write_text(self.folder / MANIFEST, json.dumps(doc) + "\n")

    @property
    def pending(self) -> list[int]:
        """Indices of the chunks still to compute, in run order."""
        return [k for k in range(len(self.chunks)) if k not in self.completed]

    def write(self, index: int, arrays: Mapping[str, np.ndarray]) -> None:
        """Write chunk `index`'s shard (the named arrays), then mark it done in the
        manifest (each atomically).

        Parameters
        ----------
        index : int
            The chunk's index.
        arrays : mapping of str to ndarray
            The chunk's named results.

        Returns
        -------
        None
        """
        buf = io.BytesIO()
        savez: Any = np.savez  # (its stubs type a keyword as allow_pickle's bool)
        savez(buf, **{k: np.asarray(v) for k, v in arrays.items()})
        atomic_write_bytes(self.folder / SHARDS / self._name(index), buf.getvalue())
        self.completed.add(index)
        self._write_manifest()

    def read(self, index: int) -> dict[str, np.ndarray]:
        """The arrays of chunk `index`'s shard.

        Parameters
        ----------
        index : int
            The chunk's index.

        Returns
        -------
        dict of str to ndarray
            The chunk's named results.
        """
        shard = self.folder / SHARDS / self._name(index)
        try:
            with np.load(shard, allow_pickle=False) as z:
                return {k: z[k] for k in z.files}
        except (OSError, ValueError, EOFError, zipfile.BadZipFile):
            raise StudyMismatch(f"{shard}: damaged (not a readable .npz archive); delete it "
                                "and --resume computes its chunk again") from None

    def iter_shards(self) -> Iterator[tuple[tuple[int, int], dict[str, np.ndarray]]]:
        """``((start, stop), arrays)`` of every chunk in run order (all must be complete)."""
        for k, rng in enumerate(self.chunks):
            yield rng, self.read(k)
