"""What an export starts from: a deployable behaviour file, or a run directory."""

from __future__ import annotations

from pathlib import Path

from flctool.behaviour import Behaviour, load_behaviour
from flctool.errors import ExportError
from flctool.inputs import no_such_file


def load_source(path: str | Path, generation: int | None = None,
                individual: int | None = None) -> tuple[Behaviour, dict[str, object]]:
    """The behaviour to export and where it came from (its provenance).

    A run directory gives its best controller, or the one of ``generation`` / ``individual``;
    provenance then holds learner, seed, generation, individual and fitness. A behaviour file
    is exported as it is.
    """
    path = Path(path)
    if path.is_dir():
        return _from_run(path, generation, individual)
    if not path.exists():
        raise no_such_file(path, "behaviour file or run directory")
    if generation is not None or individual is not None:
        raise ExportError(f"{path} is a behaviour file; --generation and --individual pick a "
                          "controller of a run directory", hint="leave them out")
    return load_behaviour(path), {"source": str(path)}


def _from_run(path: Path, generation: int | None,
              individual: int | None) -> tuple[Behaviour, dict[str, object]]:
    # Run directories are read through flctool.runs, which knows the learners' checkpoints;
    # exporting a behaviour file must not load them.
    from flctool.runs import open_run

    behaviour, provenance = open_run(path).behaviour_for(generation=generation,
                                                         individual=individual)
    return behaviour, {"source": str(path), **provenance}
