"""Locating an adapter's complaint in the behaviour file (or the --set) it is about."""

from __future__ import annotations

from pathlib import Path

import pytest

from flctool.cli.locate import locate_in_file, located_in
from flctool.errors import Problem, SpecError

TEXT = """\
name: x
environment:
  adapter: gymnasium
  id: Nope-v0
  observations: {a: 0}
"""


def test_problems_without_a_file_get_its_line_and_column(tmp_path: Path) -> None:
    file = tmp_path / "b.yaml"
    file.write_text(TEXT, encoding="utf-8")
    kept = Problem(("name",), "already placed", file="elsewhere.yaml", line=9)
    error = SpecError([Problem(("environment", "id"), "no such id", "use another"),
                       Problem(("environment", "observations", "a"), "out of range"),
                       Problem(("environment", "max_steps"), "missing"), kept])
    located = locate_in_file(error, file)
    assert located.file == str(file)
    assert [(p.file, p.line, p.column) for p in located.problems] == [
        (str(file), 4, 3), (str(file), 5, 18), (str(file), 2, 1), ("elsewhere.yaml", 9, None)]
    assert located.problems[0].hint == "use another"
    assert f"{file}:4:3: environment.id: no such id (fix: use another)" in str(located)


def test_a_field_set_on_the_command_line_is_placed_there(tmp_path: Path) -> None:
    file = tmp_path / "b.yaml"
    file.write_text(TEXT, encoding="utf-8")
    error = SpecError([Problem(("environment", "id"), "no such id"),
                       Problem(("learning", "seed"), "bad")])
    located = locate_in_file(error, file, ["environment.id", "seed"])
    assert [p.location() for p in located.problems] == [
        "command line (--set environment.id)", "command line (--set seed)"]


def test_an_unreadable_file_is_named_without_a_line(tmp_path: Path) -> None:
    error = SpecError([Problem(("environment", "id"), "no such id")])
    located = locate_in_file(error, tmp_path / "gone.yaml")
    assert located.problems[0].location() == str(tmp_path / "gone.yaml")


def test_located_in_leaves_located_errors_and_others_alone(tmp_path: Path) -> None:
    placed = SpecError([Problem(("x",), "bad", file="f.yaml", line=1)], "f.yaml")
    with pytest.raises(SpecError) as caught, located_in(tmp_path / "b.yaml"):
        raise placed
    assert caught.value is placed
    with pytest.raises(ValueError, match="other"), located_in(tmp_path / "b.yaml"):
        raise ValueError("other")
