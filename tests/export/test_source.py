"""Export sources: a behaviour file as it is, or a run directory's controller."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from flctool import load_behaviour
from flctool.errors import ExportError, FlcError, RunDirError
from flctool.export import load_source

from .roundtrip import SHIPPED


def test_a_behaviour_file_is_its_own_source() -> None:
    behaviour, provenance = load_source(SHIPPED[0])
    assert behaviour == load_behaviour(SHIPPED[0])
    assert provenance == {"source": str(SHIPPED[0])}


def test_generation_needs_a_run_directory() -> None:
    with pytest.raises(ExportError, match="--generation and --individual pick a controller"):
        load_source(SHIPPED[0], generation=3)


def test_a_missing_source_is_named(tmp_path: Path) -> None:
    with pytest.raises(FlcError, match=r"nope\.yaml: no such file or directory"):
        load_source(tmp_path / "nope.yaml")


@pytest.mark.slow
def test_a_run_directory_gives_its_best_or_a_chosen_controller(tmp_path: Path) -> None:
    from typer.testing import CliRunner

    from flctool import compile_behaviour
    from flctool.cli import app

    from ..conftest import BEHAVIOURS

    run = tmp_path / "run"
    result = CliRunner().invoke(app, ["learn", str(BEHAVIOURS / "ballchase.yaml"), "-g", "2",
                                      "-p", "4", "-o", str(run), "--json"])
    assert result.exit_code == 0, result.output
    behaviour, provenance = load_source(run)
    assert behaviour.is_deployable
    assert provenance["source"] == str(run)
    assert {"learner", "seed", "generation", "individual", "fitness"} <= set(provenance)
    best = load_behaviour(run / "best.yaml")
    assert np.array_equal(compile_behaviour(behaviour).consequents,
                          compile_behaviour(best).consequents)
    _, provenance = load_source(run, generation=0, individual=1)
    assert (provenance["generation"], provenance["individual"]) == (0, 1)
    with pytest.raises(RunDirError, match="no generation 9"):
        load_source(run, generation=9)
