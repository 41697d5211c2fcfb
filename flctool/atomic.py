"""Atomic file writes: write a temporary file beside the target, then rename over it.

A reader (or a run resumed after a kill) sees either the old file or the new one, never half.
The new file gets the permissions a plain ``open(path, "w")`` would give it (the old file's
mode, or 0o666 less the umask), a symbolic link is written through to the file it points to
(unless ``follow_symlinks=False``, as in run directories: then a link is refused), and
anything that is not a regular file (a device, a directory) is refused, never replaced.

A process killed between creating its temporary file and renaming it leaves the temporary
file behind (``.NAME.<8 hex digits>.tmp``); :func:`remove_stale_temporaries` deletes those once no
writer can be running.

Every writer of flctool goes through here: single files (:func:`write_bytes_atomic`), output
streamed piece by piece (:func:`atomic_writer`), several files replaced together
(:func:`replace_all`), and an fsync deferred to later (:func:`sync_file`).
"""

from __future__ import annotations

import errno
import io
import os
import re
import secrets
import stat
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path
from typing import BinaryIO, TextIO

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


@contextmanager
def _temporary(target: Path, durable: bool) -> Iterator[tuple[BinaryIO, Path]]:
    """A new temporary file beside ``target``, open for writing, and its path; on a clean
    exit it is flushed, given ``target``'s permissions and (``durable``) fsync'd, on any
    error deleted. The one place flctool writes a file that is renamed into place."""
    tmp = target.with_name(f".{target.name}.{secrets.token_hex(4)}.tmp")
    # Created like open(path, "w") creates a file: 0o666 less the umask (the kernel applies it).
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)
    try:
        with os.fdopen(fd, "wb") as handle:
            yield handle, tmp
            handle.flush()
            if target.exists():  # keep the replaced file's permissions
                os.fchmod(handle.fileno(), stat.S_IMODE(target.stat().st_mode))
            if durable:
                os.fsync(handle.fileno())
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


@contextmanager
def atomic_writer(path: str | Path, *, durable: bool = True,
                  follow_symlinks: bool = True) -> Iterator[BinaryIO]:
    """A binary handle whose content replaces ``path`` at once when the block ends without
    an error (an error leaves ``path`` as it was). For output written piece by piece."""
    target = regular_target(path, follow_symlinks)
    with _temporary(target, durable) as (handle, tmp):
        yield handle
    try:
        os.replace(tmp, target)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


@contextmanager
def atomic_text_writer(path: str | Path, *, durable: bool = True,
                       follow_symlinks: bool = True) -> Iterator[TextIO]:
    """:func:`atomic_writer` as UTF-8 text, each line ended by a newline alone."""
    with atomic_writer(path, durable=durable, follow_symlinks=follow_symlinks) as raw:
        text = io.TextIOWrapper(raw, encoding="utf-8", newline="\n")
        try:
            yield text
            text.flush()
        finally:
            text.detach()  # the raw handle is closed by atomic_writer


def write_bytes_atomic(path: str | Path, data: bytes, *, durable: bool = True,
                       follow_symlinks: bool = True) -> None:
    """Replace ``path`` with ``data`` at once. ``durable`` also waits for the data to reach
    the disk (fsync) before the rename: without it a killed process still leaves the old file
    or the new one (the kernel holds the written data), but a power loss may not."""
    with atomic_writer(path, durable=durable, follow_symlinks=follow_symlinks) as handle:
        handle.write(data)


def write_text_atomic(path: str | Path, text: str, *, durable: bool = True,
                      follow_symlinks: bool = True) -> None:
    write_bytes_atomic(path, text.encode("utf-8"), durable=durable,
                       follow_symlinks=follow_symlinks)


def replace_all(contents: Mapping[str | Path, bytes], *, durable: bool = True) -> None:
    """Write several files as nearly at once as the file system allows.

    Each file is written in full to a temporary file beside its target first (as
    :func:`write_bytes_atomic` does); only when every one is written (and, ``durable``, on
    disk) are they renamed over their targets, one ``os.replace`` each. Any error before the
    renames removes the temporary files and leaves every target as it was.
    """
    staged: list[tuple[Path, Path]] = []
    try:
        for path, data in contents.items():
            target = regular_target(path)
            with _temporary(target, durable) as (handle, tmp):
                handle.write(data)
            staged.append((tmp, target))
    except BaseException:
        for tmp, _ in staged:
            tmp.unlink(missing_ok=True)
        raise
    for tmp, target in staged:
        os.replace(tmp, target)


def sync_file(path: str | Path, *, follow_symlinks: bool = True) -> None:
    """Wait until a file written earlier without ``durable`` is on disk (fsync); OSError if
    it cannot be opened (or, without ``follow_symlinks``, is a link)."""
    flags = os.O_RDONLY | (0 if follow_symlinks else os.O_NOFOLLOW)
    descriptor = os.open(path, flags)
    try:
        os.fsync(descriptor)
    finally:
        os.close(descriptor)


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
