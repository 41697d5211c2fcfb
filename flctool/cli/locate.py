"""Pointing an environment's complaint at the line of the behaviour file it is about.

Adapters check the behaviour when they are built (``make_env``): a Gymnasium id that does not
exist, an observation index past the space. They see only the validated behaviour, not the
file it came from, so their :class:`SpecError` names a field path but no file. The commands
that read the file re-read its source map to add file:line:column.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from pathlib import Path

from flctool.errors import Problem, SpecError
from flctool.runs import override_path
from flctool.spec.yaml_source import SourceMap, read_yaml

COMMAND_LINE = "command line"


def locate_in_file(error: SpecError, path: Path,
                   overrides: Iterable[str] = ()) -> SpecError:
    """``error`` with each problem that names no file located in the YAML file ``path``.

    A problem about a field set on the command line (``overrides``: the keys of ``--set``)
    is placed there instead. Problems that already name a file are kept as they are; if the
    file cannot be read any more, the problem names it without a line.
    """
    if all(problem.file is not None for problem in error.problems):
        return error
    try:
        _, source = read_yaml(path.read_text(encoding="utf-8"), str(path))
    except (OSError, UnicodeDecodeError, SpecError):
        source = SourceMap(str(path))
    overridden = [(key, override_path(key)) for key in overrides]
    problems: list[Problem] = []
    for problem in error.problems:
        if problem.file is not None:
            problems.append(problem)
            continue
        key = next((key for key, field in overridden
                    if problem.path[: len(field)] == field), None)
        if key is not None:
            problems.append(Problem(problem.path, problem.message, problem.hint,
                                    file=f"{COMMAND_LINE} (--set {key})"))
        else:
            problems.append(source.problem(problem.path, problem.message, problem.hint))
    return SpecError(problems, str(path))


@contextmanager
def located_in(path: Path, overrides: Iterable[str] = ()) -> Iterator[None]:
    """Re-raise a :class:`SpecError` from the block located in ``path`` (see
    :func:`locate_in_file`)."""
    try:
        yield
    except SpecError as error:
        located = locate_in_file(error, path, overrides)
        if located is error:
            raise
        raise located from None
