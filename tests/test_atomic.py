"""Atomic writes keep permissions, follow links and never replace special files."""

from __future__ import annotations

import os
import stat
from pathlib import Path

import pytest

from flctool.atomic import write_text_atomic


def test_new_file_gets_the_usual_permissions(tmp_path: Path) -> None:
    old = os.umask(0o022)
    try:
        write_text_atomic(tmp_path / "a.txt", "hello\n")
    finally:
        os.umask(old)
    assert (tmp_path / "a.txt").read_text() == "hello\n"
    assert stat.S_IMODE((tmp_path / "a.txt").stat().st_mode) == 0o644


def test_an_existing_file_keeps_its_mode(tmp_path: Path) -> None:
    target = tmp_path / "b.txt"
    target.write_text("old")
    target.chmod(0o600)
    write_text_atomic(target, "new")
    assert target.read_text() == "new"
    assert stat.S_IMODE(target.stat().st_mode) == 0o600


def test_a_link_is_written_through(tmp_path: Path) -> None:
    real = tmp_path / "real.txt"
    real.write_text("old")
    link = tmp_path / "link.txt"
    link.symlink_to(real)
    write_text_atomic(link, "new")
    assert link.is_symlink() and real.read_text() == "new"


def test_special_files_and_directories_are_refused(tmp_path: Path) -> None:
    with pytest.raises(IsADirectoryError, match="is a directory"):
        write_text_atomic(tmp_path, "x")
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    with pytest.raises(OSError, match="not a regular file"):
        write_text_atomic(fifo, "x")
    assert stat.S_ISFIFO(fifo.stat().st_mode)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["pipe"]  # no temporary left behind


def test_without_following_links_a_link_is_refused(tmp_path: Path) -> None:
    victim = tmp_path / "victim.txt"
    victim.write_text("precious")
    link = tmp_path / "link.txt"
    link.symlink_to(victim)
    with pytest.raises(OSError, match="symbolic link"):
        write_text_atomic(link, "new", follow_symlinks=False)
    assert victim.read_text() == "precious" and link.is_symlink()


def test_stale_temporaries_are_removed_and_nothing_else(tmp_path: Path) -> None:
    from flctool.atomic import remove_stale_temporaries

    stale = tmp_path / ".run.json.0a1b2c3d.tmp"
    stale.write_text("{")
    others = [tmp_path / "run.json", tmp_path / ".hidden", tmp_path / "x.0a1b2c3d.tmp"]
    for other in others:
        other.write_text("keep")
    (tmp_path / ".dir.0a1b2c3d.tmp").mkdir()
    assert remove_stale_temporaries(tmp_path) == [stale]
    assert all(other.exists() for other in others)
    assert remove_stale_temporaries(tmp_path / "missing") == []


def test_only_durable_writes_wait_for_the_disk(tmp_path: Path,
                                               monkeypatch: pytest.MonkeyPatch) -> None:
    synced: list[int] = []
    real_fsync = os.fsync
    monkeypatch.setattr(os, "fsync", lambda fd: synced.append(fd) or real_fsync(fd))
    write_text_atomic(tmp_path / "quick.txt", "a", durable=False)
    assert synced == [] and (tmp_path / "quick.txt").read_text() == "a"
    write_text_atomic(tmp_path / "durable.txt", "b")
    assert len(synced) == 1 and (tmp_path / "durable.txt").read_text() == "b"


def test_streamed_output_replaces_the_file_only_when_complete(tmp_path: Path) -> None:
    from flctool.atomic import atomic_text_writer

    target = tmp_path / "out.csv"
    target.write_text("old\n")
    with pytest.raises(RuntimeError), atomic_text_writer(target) as handle:
        handle.write("half")
        raise RuntimeError("stopped mid-write")
    assert target.read_text() == "old\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.csv"]  # no temporary left
    with atomic_text_writer(target) as handle:
        handle.write("a,b\n1,2\n")
    assert target.read_bytes() == b"a,b\n1,2\n"


def test_several_files_are_replaced_together_or_not_at_all(tmp_path: Path,
                                                           monkeypatch: pytest.MonkeyPatch,
                                                           ) -> None:
    from flctool.atomic import replace_all

    first, second = tmp_path / "a.h", tmp_path / "a.c"
    first.write_text("old h")
    with pytest.raises(IsADirectoryError):
        replace_all({first: b"new h", tmp_path: b"x"})
    assert first.read_text() == "old h" and sorted(p.name for p in tmp_path.iterdir()) == ["a.h"]
    synced: list[int] = []
    real_fsync = os.fsync
    monkeypatch.setattr(os, "fsync", lambda fd: synced.append(fd) or real_fsync(fd))
    replace_all({first: b"new h", second: b"new c"}, durable=False)
    assert synced == [] and first.read_text() == "new h" and second.read_text() == "new c"
    replace_all({first: b"h", second: b"c"})
    assert len(synced) == 2


def test_a_deferred_sync_refuses_a_link_when_asked(tmp_path: Path) -> None:
    from flctool.atomic import sync_file

    real = tmp_path / "real.json"
    write_text_atomic(real, "{}", durable=False)
    sync_file(real, follow_symlinks=False)
    link = tmp_path / "link.json"
    link.symlink_to(real)
    sync_file(link)
    with pytest.raises(OSError):
        sync_file(link, follow_symlinks=False)
