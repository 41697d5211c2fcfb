"""One process at a time in a directory: an advisory lock on a file inside it.

The lock is ``flock``'d, so the kernel releases it when the process ends, however it ends (a
SIGKILL leaves no stale lock to delete by hand); the file holds the holder's pid, for the
message the next process gets. The lock file is never followed through a symbolic link.
"""

from __future__ import annotations

import fcntl
import os
from pathlib import Path


class DirectoryLock:
    """The lock of ``path`` (a file, created if missing): :meth:`acquire` then
    :meth:`release`."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.holder: int | None = None
        """After a refused :meth:`acquire`: the pid of the process holding the lock, if it
        wrote one."""
        self._fd: int | None = None

    def acquire(self) -> bool:
        """Take the lock; False if another process holds it (see :attr:`holder`). Raises the
        OSError of opening the file (a link, a read-only folder)."""
        fd = os.open(self.path, os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW, 0o666)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = os.read(fd, 32).decode("ascii", "replace").strip()
            os.close(fd)
            self.holder = int(holder) if holder.isdigit() else None
            return False
        os.ftruncate(fd, 0)
        os.write(fd, f"{os.getpid()}\n".encode())
        self._fd = fd
        return True

    def release(self) -> None:
        if self._fd is not None:
            os.close(self._fd)  # closing releases the lock
            self._fd = None


def is_locked(path: Path) -> bool:
    """Whether a process (this one included) holds the lock of ``path`` now."""
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NOFOLLOW)
    except OSError:
        return False
    try:
        fcntl.flock(fd, fcntl.LOCK_SH | fcntl.LOCK_NB)
    except BlockingIOError:
        return True
    finally:
        os.close(fd)
    return False
