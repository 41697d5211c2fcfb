"""The one exception tree: how problems and errors read."""

from __future__ import annotations

import pytest

from flctool.errors import (
    EnvError,
    FlcError,
    LinkError,
    MissingDependencyError,
    Problem,
    SpecError,
    format_path,
)


def test_paths_read_as_written() -> None:
    assert format_path(("inputs", "pan", "sets", "left")) == "inputs.pan.sets.left"
    assert format_path(("rules", 3, "then")) == "rules[3].then"
    assert format_path(()) == "(top level)"


def test_a_problem_names_file_line_column_field_and_fix() -> None:
    problem = Problem(("output", "name"), "is missing", "add it", file="b.yaml", line=4,
                      column=3)
    assert str(problem) == "b.yaml:4:3: output.name: is missing (fix: add it)"
    assert str(Problem((), "bad")) == "<behaviour>: (top level): bad"


def test_spec_error_lists_every_problem() -> None:
    error = SpecError([Problem(("a",), "one"), Problem(("b",), "two")], "f.yaml")
    assert str(error).splitlines() == ["f.yaml: 2 problems", "  <behaviour>: a: one",
                                       "  <behaviour>: b: two"]


def test_the_tree_and_the_install_hint() -> None:
    assert issubclass(LinkError, EnvError) and issubclass(EnvError, FlcError)
    error = MissingDependencyError("gymnasium", "gym", "The gymnasium adapter")
    assert str(error) == ("The gymnasium adapter needs the optional package 'gymnasium', which "
                          "is not installed (fix: pip install 'flctool[gym]')")


def test_every_exception_and_warning_is_exported_from_flctool() -> None:
    import inspect

    import flctool
    from flctool import errors

    defined = {name for name, value in vars(errors).items()
               if inspect.isclass(value) and issubclass(value, (Exception, Warning))}
    assert defined and defined <= set(flctool.__all__)
    for name in defined:
        assert getattr(flctool, name) is getattr(errors, name)


@pytest.mark.slow
def test_no_other_module_defines_a_public_exception() -> None:
    import ast
    from pathlib import Path

    import flctool

    root = Path(flctool.__file__).parent
    found = []
    for path in root.rglob("*.py"):
        if path.name == "errors.py" and path.parent == root:
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ClassDef) and not node.name.startswith("_") and any(
                    isinstance(base, ast.Name) and base.id.endswith(("Error", "Exception",
                                                                     "Warning"))
                    for base in node.bases):
                found.append(f"{path.relative_to(root)}:{node.name}")
    assert found == [], "define exceptions in flctool/errors.py"
