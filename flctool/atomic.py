"""Atomic file writes: write a temporary file beside the target, then rename over it.

A reader (or a run resumed after a kill) sees either the old file or the new one, never half.
The new file gets the permissions a plain ``open(path, "w")`` would give it (the old file's
mode, or 0o666 less the umask), a symbolic link is written through to the file it points to,
and anything that is not a regular file (a device, a directory) is refused, never replaced.
"""

from __future__ import annotations

import errno
import os
import secrets
import stat
from pathlib import Path


def regular_target(path: str | Path) -> Path:
    """The file a write to ``path`` replaces: links resolved; it must be a regular file or not
    exist yet (OSError otherwise)."""
    target = Path(path).resolve()
    if target.is_dir():
        raise IsADirectoryError(errno.EISDIR, "is a directory", str(path))
    if target.exists() and not target.is_file():
        raise OSError(errno.EINVAL, "not a regular file; flctool writes only regular files",
                      str(path))
    return target


def write_bytes_atomic(path: str | Path, data: bytes, *, durable: bool = True) -> None:
    """Replace ``path`` with ``data`` at once. ``durable`` also waits for the data to reach
    the disk (fsync) before the rename: without it a killed process still leaves the old file
    or the new one (the kernel holds the written data), but a power loss may not."""
    target = regular_target(path)
    tmp = target.with_name(f".{target.name}.{secrets.token_hex(4)}.tmp")
    # Created like open(path, "w") creates a file: 0o666 less the umask (the kernel applies it).
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)
    try:
        with os.fdopen(fd, "wb") as handle:
            handle.write(data)
            handle.flush()
            if target.exists():  # keep the replaced file's permissions
                os.fchmod(handle.fileno(), stat.S_IMODE(target.stat().st_mode))
            if durable:
                os.fsync(handle.fileno())
        os.replace(tmp, target)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def write_text_atomic(path: str | Path, text: str, *, durable: bool = True) -> None:
    write_bytes_atomic(path, text.encode("utf-8"), durable=durable)
