"""Uploaded recordings: kept in a folder of the server's own, for the recording page and the monitor's replay.

The browser never names a path the server reads: a recording reaches the server only as an upload, stored under
a name the server makes (a random id and the upload's extension, which picks the reader).  The folder is made
by the server (``tempfile.mkdtemp``), marked as its own by a marker file, and removed when the server stops;
only files the server wrote there are ever deleted.  At most ``MAX_UPLOADS`` recordings are kept (the oldest
goes first); each is at most ``MAX_UPLOAD`` bytes, refused beyond that before it is read.  A file is written
under a temporary name and renamed once complete, with its SHA-256, which is checked before it is read again.
"""

from __future__ import annotations

import hashlib
import os
import re
import secrets
import shutil
import tempfile
import threading
from dataclasses import dataclass
from pathlib import Path

from fruitimpact.impact.validation import InputError
from fruitimpact.signals.read.common import error as read_error

#: Largest upload [bytes] (stated on the page): a 4-lane float32 recording of 20 min at 10 kHz.
MAX_UPLOAD = 200 * 1024 * 1024
#: Uploads kept at once; the oldest is deleted when another arrives.
MAX_UPLOADS = 6
#: The folders' prefix in the temporary folder.
PREFIX = "fruitimpact-app-"
#: The file that marks the folder as the server's own (and names its process).
MARKER = ".fruitimpact-app-uploads"


@dataclass(frozen=True)
class Upload:
    """One stored upload: ``id`` (what the page names it by), the ``name`` the user's file had (shown, never
    opened), the stored ``path``, its ``size`` [bytes] and ``sha256``."""

    id: str
    name: str
    path: Path
    size: int
    sha256: str

    def checked_path(self) -> Path:
        """The stored file, after its checksum is verified (a file changed on disk is refused, not read)."""
        digest = hashlib.sha256()
        try:
            with open(self.path, "rb") as handle:
                for block in iter(lambda: handle.read(1 << 20), b""):
                    digest.update(block)
        except OSError as error:
            raise InputError(f"the upload {self.name!r} is no longer stored ({error.strerror}): upload it again",
                             "upload") from None
        if digest.hexdigest() != self.sha256:
            raise InputError(f"the stored upload {self.name!r} changed on disk since it was uploaded: upload it again",
                             "upload")
        return self.path


def extension_of(name: str) -> str:
    """The recording extension of an uploaded file's name (lower case); ``InputError`` naming ``file`` if it is
    not one the readers take (their own message)."""
    from fruitimpact.signals.read import recording_format

    try:
        recording_format(name)  # the readers' own refusal, as `fruitimpact analyze` words it
    except ValueError as error:
        raise InputError(str(error), "file") from None
    return Path(str(name)).suffix.lower()


class UploadStore:
    """The server's uploads (module docstring).  Thread-safe: uploads arrive on the event loop, analyses read
    them in worker threads."""

    def __init__(self, max_uploads: int = MAX_UPLOADS):
        remove_orphans()
        self.folder = Path(tempfile.mkdtemp(prefix=PREFIX))
        (self.folder / MARKER).write_text(f"uploads of a fruitimpact serve; removed when it stops\npid={os.getpid()}\n")
        self.max_uploads = max_uploads
        self._uploads: dict[str, Upload] = {}
        self._lock = threading.Lock()

    def begin(self, name: str):
        """A writer for a new upload named ``name`` (its extension checked first): ``write(bytes)`` then
        ``finish()`` → :class:`Upload`, or ``abort()``."""
        return _Writer(self, str(name)[:200], extension_of(name))

    def _add(self, upload: Upload) -> None:
        with self._lock:
            self._uploads[upload.id] = upload
            while len(self._uploads) > self.max_uploads:
                oldest = next(iter(self._uploads))
                self._uploads.pop(oldest).path.unlink(missing_ok=True)

    def get(self, upload_id) -> Upload:
        """The upload of that id; ``InputError`` naming ``upload`` when there is none (or it was replaced)."""
        with self._lock:
            upload = self._uploads.get(upload_id) if isinstance(upload_id, str) else None
        if upload is None:
            raise InputError(f"no upload {str(upload_id)[:40]!r} on this server (the server keeps the last "
                             f"{self.max_uploads}): upload the recording again", "upload")
        return upload

    def close(self) -> None:
        """Delete the uploads and the folder, if the folder is still the server's own (its marker)."""
        if (self.folder / MARKER).is_file():
            shutil.rmtree(self.folder, ignore_errors=True)


def remove_orphans() -> int:
    """Remove the upload folders of servers that were killed before they could (SIGKILL, a crash): only folders
    marked as a server's own whose process is gone.  Returns how many."""
    from fruitimpact.impact.outputs import process_alive

    removed = 0
    for folder in Path(tempfile.gettempdir()).glob(PREFIX + "*"):
        try:
            text = (folder / MARKER).read_text()
        except OSError:  # not a folder, not ours, or not readable: left alone
            continue
        match = re.search(r"^pid=(\d+)$", text, re.MULTILINE)
        if match and not process_alive(int(match[1])):
            shutil.rmtree(folder, ignore_errors=True)
            removed += 1
    return removed


class _Writer:
    def __init__(self, store: UploadStore, name: str, extension: str):
        self.store, self.name = store, name
        self.id = secrets.token_hex(8)
        self.path = store.folder / f"{self.id}{extension}"
        self.partial = store.folder / f".{self.id}.part"
        self.handle = open(self.partial, "xb")
        self.digest = hashlib.sha256()
        self.size = 0

    def write(self, data: bytes) -> None:
        if self.size + len(data) > MAX_UPLOAD:
            raise InputError(f"file {self.name!r} is larger than {MAX_UPLOAD // (1024 * 1024)} MB, the upload "
                             f"limit: analyse it with `fruitimpact analyze` instead", "file")
        self.handle.write(data)
        self.digest.update(data)
        self.size += len(data)

    def finish(self) -> Upload:
        self.handle.flush()
        os.fsync(self.handle.fileno())
        self.handle.close()
        if self.size == 0:
            self.partial.unlink(missing_ok=True)
            raise read_error(self.name, "empty file", "file")
        os.replace(self.partial, self.path)
        upload = Upload(self.id, self.name, self.path, self.size, self.digest.hexdigest())
        self.store._add(upload)
        return upload

    def abort(self) -> None:
        if not self.handle.closed:
            self.handle.close()
        self.partial.unlink(missing_ok=True)


__all__ = ["MAX_UPLOAD", "MAX_UPLOADS", "Upload", "UploadStore", "extension_of", "remove_orphans"]
