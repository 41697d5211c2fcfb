"""Atomic file writes: write a temporary file beside the target, then rename over it.

A reader (or a run resumed after a kill) sees either the old file or the new one, never half.
The new file gets the permissions a plain ``open(path, "w")`` would give it (the old file's
mode, or 0o666 less the umask), a symbolic link is written through to the file it points to
(unless ``follow_symlinks=False``, as in run directories: then a link is refused), and
anything that is not a regular file (a device, a directory) is refused, never replaced.

A process killed between creating its temporary file and renaming it leaves the temporary
file behind (``.NAME.XXXXXXXX.tmp``); :func:`remove_stale_temporaries` deletes those once no
writer can be running.
"""

from __future__ import annotations

import errno
import os
import re
import secrets
import stat
from pathlib import Path

_TEMPORARY = re.compile(r"^\..+\.[0-9a-f]{8}\.tmp$")


def regular_target(path: str | Path, follow_symlinks: bool = True) -> Path:
    """The file a write to ``path`` replaces: links resolved (or, without
    ``follow_symlinks``, refused); it must be a regular file or not exist yet (OSError
    otherwise)."""
    if not follow_symlinks:
        if os.path.islink(path):
            raise OSError(errno.ELOOP, "is a symbolic link; flctool does not write through "
                          "it here", str(path))
        target = Path(path)
    else:
        target = Path(path).resolve()
    if target.is_dir():
        raise IsADirectoryError(errno.EISDIR, "is a directory", str(path))
    if target.exists() and not target.is_file():
        raise OSError(errno.EINVAL, "not a regular file; flctool writes only regular files",
                      str(path))
    return target


def write_bytes_atomic(path: str | Path, data: bytes, *, durable: bool = True,
                       follow_symlinks: bool = True) -> None:
    """Replace ``path`` with ``data`` at once. ``durable`` also waits for the data to reach
    the disk (fsync) before the rename: without it a killed process still leaves the old file
    or the new one (the kernel holds the written data), but a power loss may not."""
    target = regular_target(path, follow_symlinks)
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


def write_text_atomic(path: str | Path, text: str, *, durable: bool = True,
                      follow_symlinks: bool = True) -> None:
    write_bytes_atomic(path, text.encode("utf-8"), durable=durable,
                       follow_symlinks=follow_symlinks)


def remove_stale_temporaries(folder: str | Path) -> list[Path]:
    """Delete the temporary files killed writers left in ``folder`` (not in its subfolders);
    call it only while no writer can be running there. Returns what it deleted."""
    removed: list[Path] = []
    try:
        entries = list(os.scandir(folder))
    except OSError:
        return removed
    for entry in entries:
        if _TEMPORARY.match(entry.name) and entry.is_file(follow_symlinks=False):
            try:
                os.unlink(entry.path)
            except OSError:
                continue
            removed.append(Path(entry.path))
    return removed
