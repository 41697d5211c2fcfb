"""Every command words a missing, folder, unreadable or non-UTF-8 input file alike
(flctool.inputs), on one line, with exit code 1."""

from __future__ import annotations

import errno
from pathlib import Path
from typing import Any

import pytest
from typer.testing import CliRunner

from flctool.cli import app

from ..conftest import BEHAVIOURS

runner = CliRunner()
HANDMADE = str(BEHAVIOURS / "ballchase-handmade.yaml")

#: Each command with the arguments around the file it reads (FILE stands for it).
COMMANDS: list[list[str]] = [
    ["validate", "FILE"], ["show", "FILE"], ["evaluate", "FILE", "--episodes", "1"],
    ["export", "FILE"], ["infer", "FILE"], ["learn", "FILE"], ["experiment", "FILE"],
    ["serve", "FILE", "--once"], ["import", "FILE", "--format", "fll"],
    ["infer", HANDMADE, "-i", "FILE"],
]


def _error(command: list[str], file: Path) -> str:
    result = runner.invoke(app, [str(file) if part == "FILE" else part for part in command],
                           input="ball_size,pan\n")
    assert result.exit_code == 1, (command, result.output)
    lines = [line for line in result.output.splitlines() if line.startswith("error:")]
    assert len(lines) == 1, result.output
    return lines[0]


@pytest.mark.parametrize("command", COMMANDS, ids=" ".join)
def test_a_missing_file(command: list[str], tmp_path: Path) -> None:
    line = _error(command, tmp_path / "nothere.yaml")
    assert line.startswith(f"error: {tmp_path / 'nothere.yaml'}: no such file or directory "
                           "(fix: check the path; it should name a ")


@pytest.mark.parametrize("command", [c for c in COMMANDS if c[0] in ("learn", "experiment",
                                                                      "serve", "import")
                                     or "-i" in c], ids=" ".join)
def test_a_folder_where_a_file_is_wanted(command: list[str], tmp_path: Path) -> None:
    line = _error(command, tmp_path)
    assert line.startswith(f"error: {tmp_path}: is a folder, not a ")
    assert line.endswith("(fix: name a file in it)")


@pytest.mark.parametrize("command", COMMANDS, ids=" ".join)
def test_a_file_that_cannot_be_read(command: list[str], tmp_path: Path,
                                    monkeypatch: pytest.MonkeyPatch) -> None:
    import builtins

    path = tmp_path / "locked.yaml"
    path.write_text("flctool: 1\n")
    real = builtins.open

    def guarded(file: Any, *args: Any, **kwargs: Any) -> Any:
        if str(file) == str(path):  # (tests may run as root, which chmod does not stop)
            raise PermissionError(errno.EACCES, "Permission denied", str(path))
        return real(file, *args, **kwargs)

    monkeypatch.setattr(builtins, "open", guarded)
    line = _error(command, path)
    assert line.startswith(f"error: {path}: cannot read the ")
    assert line.endswith(": permission denied (fix: make it readable (chmod u+r), or read a "
                         "copy)")


@pytest.mark.parametrize("command", COMMANDS, ids=" ".join)
@pytest.mark.parametrize(("data", "where", "what"), [
    ("flctool: 1  # caf\u00e9\n".encode("latin-1"), ":1:18:", "(byte 0xe9; a Latin-1"),
    ("flctool: 1\n".encode("utf-16"), ":1:1:", "is UTF-16 text (it starts with a UTF-16 byte "
     "order mark), not UTF-8"),
])
def test_text_that_is_not_utf8_is_located(command: list[str], tmp_path: Path, data: bytes,
                                          where: str, what: str) -> None:
    path = tmp_path / "encoded.yaml"
    path.write_bytes(data)
    line = _error(command, path)
    assert line.startswith(f"error: {path}{where}") and what in line
    assert line.endswith("(fix: save it as UTF-8 text)")
