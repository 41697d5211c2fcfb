"""Run records under failure: a full disk never leaves run.json 'running'."""

from __future__ import annotations

import errno
import json
import os
from pathlib import Path
from typing import Any

import pytest

from flctool.errors import RunDirError
from flctool.runs import create_run, open_run
from tests.test_runs import StopAfter, ballchase


def test_a_disk_that_fills_up_mid_run_leaves_run_json_stopped(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Every atomic write fails once the disk is full (checkpoint, best.yaml, run.json's
    copy), and so does appending to the tables; only rewriting run.json in place still fits."""
    from flctool import runs

    run = create_run(ballchase(learner="pitt"), tmp_path / "run")
    run.train([StopAfter(1)])  # two generations on disk
    real_write = runs.write_text_atomic
    real_fdopen = os.fdopen
    full = {"now": False}

    def write(target: Path, text: str, **options: Any) -> None:
        if Path(target).name.startswith("gen-00003"):
            full["now"] = True
        if full["now"]:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(target))
        real_write(target, text, **options)

    def fdopen(fd: int, mode: str = "r", *args: Any, **kwargs: Any) -> Any:
        if full["now"] and "a" in mode:
            os.close(fd)
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return real_fdopen(fd, mode, *args, **kwargs)

    monkeypatch.setattr(runs, "write_text_atomic", write)
    monkeypatch.setattr(runs.os, "fdopen", fdopen)
    with pytest.raises(RunDirError, match="No space left on device"):
        open_run(run.path).train()
    monkeypatch.undo()
    assert json.loads((run.path / "run.json").read_text())["status"] == "stopped"
    assert open_run(run.path).train().generations == 5  # and nothing is lost


def _stopped(tmp_path: Path) -> Path:
    run = create_run(ballchase(learner="pitt"), tmp_path / "run")
    run.train([StopAfter(0)])
    return run.path


@pytest.mark.parametrize(("edit", "message"), [
    ({"format": 99}, "has format 99; this flctool reads run directories of format 1"),
    ({"format": "1"}, "has format '1'"),
    ({"learner": "os:system"}, "records learner 'os:system', but the run's behaviour.yaml has "
     "'pitt': the record was edited"),
    ({"seed": 7}, "records seed 7"),
])
def test_an_edited_run_record_is_refused_at_resume(tmp_path: Path, edit: dict[str, Any],
                                                   message: str) -> None:
    from flctool.training import resume_run

    path = _stopped(tmp_path)
    record = json.loads((path / "run.json").read_text())
    (path / "run.json").write_text(json.dumps({**record, **edit}))
    with pytest.raises(RunDirError, match=message) as info:
        resume_run(path)
    assert "run.json" in str(info.value) and info.value.hint


@pytest.mark.parametrize("name", ["behaviour.yaml", "run.json", "best.yaml"])
def test_a_run_file_linked_out_of_the_run_directory_is_not_read(tmp_path: Path,
                                                               name: str) -> None:
    path = _stopped(tmp_path)
    outside = tmp_path / f"outside-{name}"
    outside.write_bytes((path / name).read_bytes())
    (path / name).unlink()
    (path / name).symlink_to(outside)
    with pytest.raises(RunDirError, match="is a symbolic link; flctool reads and writes only"):
        open_run(path)
