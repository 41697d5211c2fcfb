"""Where a behaviour's fields were written, so that any layer can raise a located error.

A behaviour loaded from a file keeps that file's source map (:class:`SourceMap`: the line and
column of every field path, and which fields a ``--set`` gave). An adapter, a learner or a
check that finds a problem with a field names the field path only; :func:`locate` (or the
:func:`located` block around building one) adds the file, line and column::

    raise SpecError([locate(behaviour, ("environment", "id"), "no such Gymnasium id",
                            "check the spelling")])

The source map takes no part in a behaviour's equality and travels with it when pickled.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from typing import TYPE_CHECKING

from flctool.behaviour.yaml_source import SourceMap, SourceRef
from flctool.errors import PathPart, Problem, SpecError

if TYPE_CHECKING:
    from flctool.behaviour.models import Behaviour

#: The source of a behaviour built in Python rather than read from a file.
UNKNOWN_SOURCE = SourceMap("<behaviour>")


def attach_source(behaviour: Behaviour, source: SourceMap) -> None:
    """Give a behaviour just validated from ``source`` its source map (the loader does; a
    behaviour refuses to have it set as an attribute, like its fields)."""
    private: dict[str, object] | None = behaviour.__pydantic_private__
    if private is not None:
        private["_source"] = SourceRef(source)


def source_of(behaviour: Behaviour) -> SourceMap:
    """The source map of ``behaviour``: its file's, or an empty one if it was built in
    Python."""
    ref = getattr(behaviour, "_source", None)  # None: e.g. built with model_construct
    return ref.source if isinstance(ref, SourceRef) and ref.source is not None \
        else UNKNOWN_SOURCE


def locate(behaviour: Behaviour, path: Sequence[PathPart], message: str,
           hint: str = "") -> Problem:
    """A problem with the field at ``path``, placed where ``behaviour`` got that field: the
    file's line and column, or the ``--set`` that gave it."""
    return source_of(behaviour).problem(tuple(path), message, hint)


def locate_error(behaviour: Behaviour, error: SpecError) -> SpecError:
    """``error`` with each problem that names no file placed by :func:`locate`; the error
    itself if every problem is placed already."""
    if all(problem.file is not None for problem in error.problems):
        return error
    source = source_of(behaviour)
    problems = [problem if problem.file is not None
                else source.problem(problem.path, problem.message, problem.hint)
                for problem in error.problems]
    return SpecError(problems, error.file or source.file)


@contextmanager
def located(behaviour: Behaviour) -> Iterator[None]:
    """Re-raise a :class:`SpecError` from the block with its problems placed in
    ``behaviour``'s file (see :func:`locate_error`): around building an adapter or a
    learner, whose checks know field paths but not files."""
    try:
        yield
    except SpecError as error:
        placed = locate_error(behaviour, error)
        if placed is error:
            raise
        raise placed from None
