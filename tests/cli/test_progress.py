"""Progress when stderr is not a terminal: plain lines, every few seconds and at the end."""

from __future__ import annotations

import pytest

from flctool.cli import progress
from flctool.cli.progress import Progress, compiling


def test_plain_lines_when_not_a_terminal(capsys: pytest.CaptureFixture[str]) -> None:
    with Progress("hybrid generation", 3, log_every=0.0) as bar:
        for done in range(1, 4):
            bar.update(done, best=f"{done / 10:.3f}")
    lines = capsys.readouterr().err.splitlines()
    assert lines[0].startswith("hybrid generation 1/3  best 0.100  (")
    assert lines[-1].startswith("hybrid generation 3/3  best 0.300  (")
    assert len(lines) == 3  # one per update; the end was the last of them: not again


def test_the_end_is_printed_when_the_last_line_is_behind(
        capsys: pytest.CaptureFixture[str]) -> None:
    with Progress("runs", 3, log_every=0.0) as bar:
        bar.update(1)
        bar._log_every = 1e9  # the next line is not due before the end
        bar.update(2)
    lines = capsys.readouterr().err.splitlines()
    assert [line.split("  (")[0] for line in lines] == ["runs 1/3", "runs 2/3"]


def test_short_work_prints_nothing_and_disabled_prints_nothing(
        capsys: pytest.CaptureFixture[str]) -> None:
    with Progress("episodes", 10) as bar:  # finished before the first line was due
        bar.update(10)
    with Progress("episodes", 10, enabled=False, log_every=0.0) as bar:
        bar.update(10)
    assert capsys.readouterr().err == ""


def test_compile_notice_only_when_numba_compiled(capsys: pytest.CaptureFixture[str],
                                                 monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(progress._compiled, "done", False)
    monkeypatch.setattr(progress, "_numba_compiled", lambda: False)
    with compiling():
        pass
    assert capsys.readouterr().err == ""  # loaded from the cache: nothing to say
    monkeypatch.setitem(progress._compiled, "done", False)
    monkeypatch.setattr(progress, "_numba_compiled", lambda: True)
    with compiling():
        pass
    assert capsys.readouterr().err.startswith("compiled the inference kernels in ")
    with compiling():  # once per process
        pass
    assert capsys.readouterr().err == ""
