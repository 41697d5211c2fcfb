"""Composed behaviours: a pitch behaviour whose commands are other behaviours (its parts).

``environment.compose`` maps each of the arbiter's commands to a part: a behaviour file,
named relative to the composing file. Loading reads each part file (a trust boundary: a
relative path inside the composing file's folder, a ``.yaml``/``.yml`` file, the usual size
and depth bounds of a behaviour file, no cycles, parts that do not compose others) and
inlines the validated part, so the behaviour is self-contained from then on: a run's
``behaviour.yaml`` and ``best.yaml`` carry their parts and read back anywhere.
"""

from __future__ import annotations

from collections.abc import Callable
from contextvars import ContextVar
from pathlib import Path
from typing import TYPE_CHECKING, Any

from flctool.errors import Problem, SpecError

if TYPE_CHECKING:
    from flctool.behaviour.models import Behaviour
    from flctool.behaviour.yaml_source import SourceMap

#: The files being loaded, outermost first: a part that is already loading is a cycle.
_LOADING: ContextVar[tuple[Path, ...]] = ContextVar("flctool_composing", default=())


def inline_parts(data: dict[str, Any], source: SourceMap,
                 load: Callable[[Path], Behaviour],
                 to_data: Callable[[Behaviour], dict[str, Any]],
                 ) -> tuple[dict[str, Any], list[Problem]]:
    """``data`` with each part file of ``environment.compose`` replaced by the part's data;
    problems (a path outside the folder, a missing file, a cycle, a part that composes) are
    located at the part's key."""
    environment = data.get("environment")
    compose = environment.get("compose") if isinstance(environment, dict) else None
    if not isinstance(environment, dict) or not isinstance(compose, dict) or not any(
            isinstance(v, str) for v in compose.values()):
        return data, []
    problems: list[Problem] = []
    here = Path(source.file)
    chain = _LOADING.get()
    folder = (chain[0] if chain else here.resolve()).parent
    inlined: dict[str, Any] = {}
    for name, part in compose.items():
        path = ("environment", "compose", name)
        if not isinstance(part, str):
            inlined[name] = part  # an inlined part (a run's file): validated by the model
            continue
        where = _part_path(part, here, folder, chain)
        if isinstance(where, str):
            problems.append(source.problem(path, where, "name a behaviour file beside this "
                                           "one, e.g. 'chase: chase.yaml'"))
            continue
        token = _LOADING.set((*(chain or (here.resolve(),)), where))
        try:
            behaviour = load(where)
        except SpecError as exc:
            problems.append(source.problem(path, f"the part '{part}' does not load: "
                                           f"{_first(exc)}", "fix the part's file"))
            continue
        finally:
            _LOADING.reset(token)
        part_env = behaviour.environment
        if part_env is not None and getattr(part_env, "compose", None):
            problems.append(source.problem(path, f"the part '{part}' composes others itself",
                                           "compose leaves only: one level of parts"))
            continue
        inlined[name] = to_data(behaviour)
    return {**data, "environment": {**environment, "compose": inlined}}, problems


def _part_path(part: str, here: Path, folder: Path, chain: tuple[Path, ...]) -> Path | str:
    """The part's resolved file, or why it is refused."""
    if here.name.startswith("<"):
        return "a behaviour read from text cannot name part files; inline the parts"
    written = Path(part)
    if written.is_absolute() or part.startswith("~"):
        return f"'{part}' is an absolute path; parts are named relative to this file"
    if written.suffix not in (".yaml", ".yml"):
        return f"'{part}' is not a .yaml or .yml file"
    resolved = (here.parent / written).resolve()
    if not resolved.is_relative_to(folder):
        return f"'{part}' lies outside the composing file's folder ({folder.name}/)"
    if resolved in chain or resolved == here.resolve():
        return f"'{part}' is already being loaded: the parts form a cycle"
    if not resolved.is_file():
        return f"no such file '{part}'"
    return resolved


def _first(error: SpecError) -> str:
    problems = getattr(error, "problems", None)
    if problems:
        first = problems[0]
        line = f":{first.line}" if first.line else ""
        return f"{first.file or ''}{line}: {first.message}"
    return str(error)
