"""The shared parts: deployability, headers, and careful atomic writes."""

from __future__ import annotations

import errno
import os
import stat
from pathlib import Path

import pytest

from flctool import load_behaviour
from flctool.atomic import replace_all
from flctool.behaviour import parse_behaviour, require_deployable
from flctool.errors import ExportError, NotDeployableError
from flctool.export import EXPORTERS, IMPORTERS, ExportOptions
from flctool.export.base import check_writable, header_lines
from flctool.export.c_source import CExporter
from flctool.export.yaml_format import YamlExporter

from ..conftest import BEHAVIOURS
from .roundtrip import SHIPPED


def test_require_deployable_lists_the_missing_rules() -> None:
    require_deployable(load_behaviour(SHIPPED[0]))
    with pytest.raises(NotDeployableError) as error:
        require_deployable(load_behaviour(BEHAVIOURS / "ballchase.yaml"))
    text = str(error.value)
    assert "15 of 15 rules" in text
    assert text.count("\n  IF ") == 10 and "... and 5 more" in text
    assert "flctool learn" in text


def test_header_says_where_a_controller_came_from() -> None:
    behaviour = load_behaviour(SHIPPED[0])
    lines = header_lines(behaviour, {"source": "runs/a", "learner": "hybrid", "seed": 3,
                                     "generation": 29, "individual": None, "fitness": 0.75})
    assert lines[1] == "source: runs/a"
    assert lines[2] == "learner: hybrid, seed: 3, generation: 29, fitness: 0.75"


def test_to_file_refuses_to_overwrite_without_force(tmp_path: Path) -> None:
    behaviour = load_behaviour(SHIPPED[0])
    target = tmp_path / "out.yaml"
    target.write_text("keep me")
    with pytest.raises(ExportError, match=r"already exists.*--force"):
        YamlExporter().to_file(behaviour, target)
    assert target.read_text() == "keep me"
    assert YamlExporter().to_file(behaviour, target, force=True) == [target]
    assert target.read_text().startswith("# ")
    assert [p.name for p in tmp_path.iterdir()] == ["out.yaml"]  # no temporary file is left


def test_unwritable_paths_get_clear_messages(tmp_path: Path) -> None:
    with pytest.raises(ExportError, match=r"the folder .*missing does not exist"):
        check_writable(tmp_path / "missing" / "out.yaml", force=False)
    with pytest.raises(ExportError, match="is a folder"):
        check_writable(tmp_path, force=True)
    if os.geteuid() != 0:  # root may write anywhere
        locked = tmp_path / "locked"
        locked.mkdir()
        locked.chmod(0o500)
        try:
            with pytest.raises(ExportError, match="is not writable"):
                check_writable(locked / "out.yaml", force=False)
        finally:
            locked.chmod(0o700)


def test_options_default_to_flc_prefix_and_double() -> None:
    options = ExportOptions()
    assert options.prefix == "flc_" and not options.single and dict(options.provenance) == {}


def test_a_failure_while_writing_the_second_file_writes_nothing(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The C pair: a disk that fills up on the second file (fsync fails) leaves neither."""
    calls = []
    real_fsync = os.fsync

    def fsync(fd: int) -> None:
        calls.append(fd)
        if len(calls) == 2:
            raise OSError(errno.ENOSPC, "No space left on device")
        real_fsync(fd)

    monkeypatch.setattr(os, "fsync", fsync)
    with pytest.raises(ExportError, match=r"cannot write .*ctl\.c: No space left on device"):
        CExporter().to_file(load_behaviour(SHIPPED[0]), tmp_path / "ctl")
    assert list(tmp_path.iterdir()) == []  # no ctl.h, no temporary file


def test_replace_all_keeps_permissions_and_follows_links(tmp_path: Path) -> None:
    mine = tmp_path / "mine.h"
    mine.write_text("old")
    mine.chmod(0o640)
    (tmp_path / "link.c").symlink_to("real.c")
    replace_all({mine: b"h", tmp_path / "link.c": b"c"})
    assert mine.read_text() == "h" and stat.S_IMODE(mine.stat().st_mode) == 0o640
    assert (tmp_path / "link.c").is_symlink() and (tmp_path / "real.c").read_text() == "c"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["link.c", "mine.h", "real.c"]


def test_a_special_file_is_refused_before_anything_is_written(tmp_path: Path) -> None:
    os.mkfifo(tmp_path / "ctl.c")
    with pytest.raises(ExportError, match=r"cannot write .*ctl\.c: not a regular file"):
        CExporter().to_file(load_behaviour(SHIPPED[0]), tmp_path / "ctl", force=True)
    assert not (tmp_path / "ctl.h").exists()


@pytest.mark.parametrize("source", ["r*/run", "a/*b", "(*x*)", "two\nlines", "cr\rtab\t\x00",
                                    "sep\u2028arator"])
def test_provenance_cannot_break_a_comment(source: str) -> None:
    behaviour = load_behaviour(SHIPPED[0])
    lines = header_lines(behaviour, {"source": source, "learner": "a*/b\nc"})
    for line in lines:
        assert len(line.splitlines()) == 1
        for marker in ("*/", "/*", "(*", "*)"):
            assert marker not in line
    options = ExportOptions(provenance={"source": source})
    for format in ("fll", "fcl"):  # each reads its own export back
        text = EXPORTERS.get(format)(options).to_string(behaviour)
        assert IMPORTERS.get(format)().from_string(text) == IMPORTERS.get(format)(
            ).from_string(EXPORTERS.get(format)().to_string(behaviour))
    assert parse_behaviour(YamlExporter(options).to_string(behaviour)) == behaviour
    text = CExporter(options).to_string(behaviour)
    assert text.count("*/") == text.count("/*")  # every comment closes where it should
