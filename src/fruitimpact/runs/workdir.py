"""The work folder of a run: what fruitimpact may delete, what it can trust.

* **Ownership.**  A folder fruitimpact creates (or adopts, when it is empty)
  gets a marker file, ``.fruitimpact-workdir``, that also records whether the
  folder itself was created.  A folder without the marker is never written in
  nor deleted from: an existing folder that is not empty and has no marker is
  refused.  Cleanup deletes only the files a run writes (parts, summaries,
  manifest, marker, lock, temporaries, recognised by their exact names), and the
  folder only if fruitimpact created it and it is then empty.
* **Manifest.**  ``manifest.jsonl`` is an append-only log: a header line with the
  job's fingerprint, then one line per completed chunk, appended by the driver
  once the chunk's files are in place: its row range, its status counts, and
  the size and SHA-256 of its part file and summary file.  A torn last line
  (a kill while appending) is ignored, so that chunk is simply computed again.
* **Verification.**  A chunk counts as complete only if its files have the
  recorded size and SHA-256; the bytes are hashed again whenever they are read.
  A part replaced, truncated or with flipped bytes is recomputed, never used.

Part files are Arrow IPC files (no compression: writing and reading them costs
little next to evaluation); summaries are a stream of NumPy ``.npy`` records.  Both are
written under a temporary name and renamed.  They are not fsync'ed: a power
loss may cost a chunk, which the hash check then finds and recomputes.
"""

from __future__ import annotations

import hashlib
import io
import json
import os
import re
from pathlib import Path

import numpy as np

from fruitimpact.impact.outputs import temporary_path
from fruitimpact.runs.abandon import slices
from fruitimpact.runs.locking import RunLock
from fruitimpact.runs.plan import WORK_FORMAT, RunError

MARKER = ".fruitimpact-workdir"
MANIFEST = "manifest.jsonl"
LOCK = ".fruitimpact-lock"
#: Files of a work folder that fruitimpact wrote: parts, summaries and their temporaries.
_OWN = re.compile(r"^\.?part-\d{7}\.(arrow|summary\.npy)(\.fruitimpact-tmp-\d+-[0-9a-f]{8})?$")


def part_name(index: int) -> str:
    return f"part-{index:07d}.arrow"


def summary_name(index: int) -> str:
    return f"part-{index:07d}.summary.npy"


class _HashingFile:
    """A write-only file that hashes what passes through it (pyarrow writes straight into it)."""

    closed = False

    def __init__(self, handle):
        self.handle = handle
        self.digest = hashlib.sha256()
        self.size = 0

    def write(self, data) -> int:
        self.digest.update(data)
        self.size += len(data)
        return self.handle.write(data)

    def writable(self) -> bool:
        return True

    def flush(self) -> None:
        self.handle.flush()

    def close(self) -> None:
        self.closed = True


def _write_file(path: Path, write) -> dict:
    """``write(file)`` into a temporary beside ``path``, renamed into place; returns the
    file's name, size and SHA-256 (hashed as written)."""
    tmp = temporary_path(path)
    try:
        with open(tmp, "wb") as handle:
            sink = _HashingFile(handle)
            write(sink)
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()
    return {"name": path.name, "bytes": sink.size, "sha256": sink.digest.hexdigest()}


def manifest_lines(folder) -> list[dict]:
    """The readable lines of the manifest in ``folder`` (a torn or garbled line is skipped; none without one)."""
    try:
        text = (Path(folder) / MANIFEST).read_text(errors="replace")
    except OSError:
        return []
    lines = []
    for line in text.splitlines():
        try:
            lines.append(json.loads(line))
        except ValueError:
            continue
    return lines


def recorded_chunks(folder) -> dict[int, dict]:
    """The completed chunks the manifest in ``folder`` records, by index (the last record of a chunk wins)."""
    return {line["chunk"]: line for line in manifest_lines(folder)[1:] if isinstance(line.get("chunk"), int)}


def write_part(workdir, index: int, table) -> dict:
    """Write chunk ``index``'s rows (a pyarrow Table) as its part file; returns its file entry."""
    import pyarrow as pa

    # LZ4: half the bytes to write and hash (a pyarrow built without it writes them plain; both read back alike)
    options = pa.ipc.IpcWriteOptions(compression="lz4" if pa.Codec.is_available("lz4") else None)

    def write(sink):
        with pa.ipc.new_file(sink, table.schema, options=options) as writer:
            for part in slices(table):  # an interrupted run's writer stops between slices (``runs.abandon``)
                writer.write_table(part)

    return _write_file(Path(workdir) / part_name(index), write)


def write_summary(workdir, index: int, arrays: dict) -> dict:
    """Write chunk ``index``'s summary arrays into its summary file, hashed as written: the
    arrays' names (one JSON line), then each array as a ``.npy`` record, in that order (a
    stream: nothing is built in memory first)."""
    names = list(arrays)

    def write(sink):
        sink.write((json.dumps(names) + "\n").encode())
        for name in names:
            np.lib.format.write_array(sink, np.asarray(arrays[name]), allow_pickle=False)

    return _write_file(Path(workdir) / summary_name(index), write)


def read_verified(workdir, entry: dict) -> bytes | None:
    """The bytes of the file of ``entry`` if they have its recorded size and SHA-256, else None."""
    try:
        data = (Path(workdir) / entry["name"]).read_bytes()
    except OSError:
        return None
    if len(data) != entry["bytes"] or hashlib.sha256(data).hexdigest() != entry["sha256"]:
        return None
    return data


def read_part(workdir, entry: dict):
    """The rows of a part file (pyarrow Table), verified; ``RunError`` if it changed since written."""
    import pyarrow as pa

    data = read_verified(workdir, entry)
    if data is None:
        _discard(Path(workdir) / entry["name"])
        raise RunError(f"{Path(workdir) / entry['name']} changed after it was written (size or SHA-256 differs); "
                       f"it was removed: run the same command again to compute it anew")
    return pa.ipc.open_file(pa.py_buffer(data)).read_all()


def read_summary(workdir, entry: dict) -> dict | None:
    """The arrays of a summary file, verified; None if it is missing or changed."""
    data = read_verified(workdir, entry)
    if data is None:
        return None
    stream = io.BytesIO(data)
    names = json.loads(stream.readline())
    return {name: np.lib.format.read_array(stream, allow_pickle=False) for name in names}


def _discard(path: Path) -> None:
    try:
        path.unlink()
    except FileNotFoundError:
        pass


def _visible(folder: Path, spare) -> list[Path]:
    """Entries of ``folder`` other than the files of the output (``spare``: the output's path)."""
    entries = []
    for entry in folder.iterdir():
        if spare is not None and entry.parent.resolve() == Path(spare).parent.resolve() and (
                entry.name == Path(spare).name or entry.name.startswith(f".{Path(spare).name}.fruitimpact-")):
            continue
        entries.append(entry)
    return entries


class WorkDir:
    """A locked work folder of one job: its completed chunks and the files to remove at the end."""

    def __init__(self, path: Path, created: bool, lock: RunLock):
        self.path = path
        self.created = created
        self.lock = lock

    @classmethod
    def open(cls, path, fingerprint: str, identity: dict, *, fresh: bool = False, spare=None) -> "WorkDir":
        """Create, adopt (an empty folder) or reopen the work folder of job ``fingerprint``, locked.

        Raises ``RunError`` for a folder that is not fruitimpact's, one locked by another run,
        or one of another job (unless ``fresh``: then the files of the other job are removed).
        ``spare``: the output's path, whose own files do not make a folder non-empty."""
        path = Path(path).resolve()
        if not path.exists():
            try:
                path.mkdir()  # its own folder only: a run removes what it made, never folders above
            except FileExistsError:
                pass  # another run was faster: treated as an existing folder below
            except OSError as exc:
                raise RunError(f"work folder {path}: cannot create it ({exc.strerror})") from None
            else:
                return cls._claim(path, created=True, fingerprint=fingerprint, identity=identity)
        if not path.is_dir():
            raise RunError(f"work folder {path} exists and is not a folder")
        if not (path / MARKER).exists():
            if _visible(path, spare):
                raise RunError(f"work folder {path} exists and is not fruitimpact's (no {MARKER} file); "
                               f"fruitimpact only writes in and deletes folders it made: give a new or empty "
                               f"folder with --workdir")
            return cls._claim(path, created=False, fingerprint=fingerprint, identity=identity)
        lock = RunLock(path / LOCK, f"work folder {path}").acquire()
        try:
            work = cls(path, json.loads((path / MARKER).read_text()).get("created_folder", False), lock)
            header = work._header()
            if header is None or fresh:
                work._remove_files()
                work._write_header(fingerprint, identity)
            elif header.get("fingerprint") != fingerprint:
                raise RunError(f"{path} holds the parts of a different job; finish that job, or pass --fresh "
                               f"to discard its parts")
            else:
                work._remove_temporaries()
        except BaseException:
            lock.release()
            raise
        return work

    @classmethod
    def _claim(cls, path: Path, created: bool, fingerprint: str, identity: dict) -> "WorkDir":
        """Lock a new (or empty) folder and mark it as fruitimpact's."""
        lock = RunLock(path / LOCK, f"work folder {path}").acquire()
        try:
            with open(path / MARKER, "x") as handle:
                json.dump({"fruitimpact": "work folder of a batch, sweep or population run",
                           "format": WORK_FORMAT, "created_folder": created}, handle)
            work = cls(path, created, lock)
            work._write_header(fingerprint, identity)
        except FileExistsError:
            lock.release()
            raise RunError(f"work folder {path} was just claimed by another fruitimpact run") from None
        except OSError as exc:
            lock.release(remove=True)
            raise RunError(f"work folder {path}: cannot write in it ({exc.strerror})") from None
        return work

    def _write_header(self, fingerprint: str, identity: dict) -> None:
        header = {"format": WORK_FORMAT, "fingerprint": fingerprint, "job": identity}
        tmp = temporary_path(self.path / MANIFEST)
        tmp.write_text(json.dumps(header, sort_keys=True) + "\n")
        os.replace(tmp, self.path / MANIFEST)

    def _lines(self) -> list[dict]:
        return manifest_lines(self.path)

    def _header(self) -> dict | None:
        lines = self._lines()
        return lines[0] if lines and "fingerprint" in lines[0] else None

    def records(self) -> dict[int, dict]:
        """The completed chunks the manifest records, by index (the last record of a chunk wins)."""
        return recorded_chunks(self.path)

    def verified(self, record: dict) -> bool:
        """Whether every file of ``record`` is there with its recorded size and SHA-256."""
        return all(read_verified(self.path, record[key]) is not None
                   for key in ("part", "summary") if record.get(key))

    def append(self, record: dict) -> None:
        """Record a completed chunk (its files are in place)."""
        with open(self.path / MANIFEST, "a") as handle:
            handle.write(json.dumps(record, sort_keys=True) + "\n")

    def _remove_temporaries(self) -> None:
        # the folder is locked: any temporary in it was left by a run that is gone
        for entry in self.path.iterdir():
            if entry.name.startswith(".") and _OWN.match(entry.name):
                _discard(entry)

    def _remove_files(self) -> None:
        """Delete the parts, summaries, temporaries and manifest (not marker and lock)."""
        for entry in self.path.iterdir():
            if _OWN.match(entry.name):
                _discard(entry)
        _discard(self.path / MANIFEST)

    def remove(self) -> None:
        """Delete every file the runs wrote here, then the folder if fruitimpact created it and
        it is empty; releases the lock."""
        self._remove_files()
        _discard(self.path / MARKER)
        self.lock.release(remove=True)
        if self.created:
            try:
                self.path.rmdir()
            except OSError:  # the user put something there: it stays, and so does the folder
                pass

    def release(self) -> None:
        """Unlock, keeping every file (an interrupted run, for the resume)."""
        self.lock.release()
