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
