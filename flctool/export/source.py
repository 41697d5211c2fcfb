"""What an export starts from: a deployable behaviour file, or a run directory."""

from __future__ import annotations

import importlib
from pathlib import Path

from flctool.errors import ExportError, RunDirError
from flctool.spec import Behaviour, load_behaviour


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
        raise ExportError(f"{path}: no such file or directory",
                          hint="give a behaviour file or a run directory")
    if generation is not None or individual is not None:
        raise ExportError(f"{path} is a behaviour file; --generation and --individual pick a "
                          "controller of a run directory", hint="leave them out")
    return load_behaviour(path), {"source": str(path)}


def _from_run(path: Path, generation: int | None,
              individual: int | None) -> tuple[Behaviour, dict[str, object]]:
    try:
        # Imported here: reading run directories is the learners' module, not export's.
        runs = importlib.import_module("flctool.runs")
    except ModuleNotFoundError as exc:
        if exc.name != "flctool.runs":
            raise
        raise RunDirError(f"{path} is a directory, but this flctool cannot read run "
                          "directories (flctool.runs is missing)",
                          hint="export a behaviour file instead") from None
    run = runs.open_run(path)
    behaviour, provenance = run.behaviour_for(generation=generation, individual=individual)
    if not isinstance(behaviour, Behaviour):
        raise RunDirError(f"{path}: the run directory gave no behaviour to export")
    return behaviour, {"source": str(path), **dict(provenance)}
