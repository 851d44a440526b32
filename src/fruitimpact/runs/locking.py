"""One run at a time on a work folder and on an output: advisory locks that die with their process.

A lock is ``fcntl.flock`` on a lock file; the kernel releases it when the
process ends, however it ends, so a killed run never leaves a lock behind
that blocks the next one.  The lock file holds the owner's pid, so that a
refused run can name it.
"""

from __future__ import annotations

import fcntl
import os
from pathlib import Path

from fruitimpact.runs.plan import RunError


class RunLock:
    """An exclusive lock on ``path`` (created if missing), taken without waiting.

    ``acquire`` raises ``RunError`` naming the holder's pid when another process
    holds it.  ``release(remove=True)`` deletes the lock file while still holding
    the lock (a lock file beside a user's output is ours to remove)."""

    def __init__(self, path, what: str):
        self.path = Path(path)
        self.what = what
        self._fd = None

    def acquire(self) -> "RunLock":
        while True:
            fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                holder = os.read(fd, 32).decode(errors="replace").strip() or "unknown"
                os.close(fd)
                raise RunError(f"{self.what} is in use by another fruitimpact run (pid {holder}); wait for it "
                               f"to finish or stop it") from None
            # the holder may have removed the file between our open and our lock: lock the file that is there
            try:
                same = os.path.samestat(os.fstat(fd), os.stat(self.path))
            except FileNotFoundError:
                same = False
            if same:
                break
            os.close(fd)
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"{os.getpid()}\n".encode(), 0)
        self._fd = fd
        return self

    def release(self, remove: bool = False) -> None:
        if self._fd is None:
            return
        try:
            if remove:
                self.path.unlink()
        except OSError:  # gone, or its folder turned read-only: the lock itself still ends with the descriptor
            pass
        finally:
            os.close(self._fd)
            self._fd = None
