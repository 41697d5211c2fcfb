"""The public face: every name it lists loads, the whole flow runs on its names alone, and
``import flctool`` stays cheap."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import flctool

from .conftest import BEHAVIOURS


def test_every_public_name_loads_from_its_module() -> None:
    assert "__version__" in flctool.__all__ and "make_env" in flctool.__all__
    for name in flctool.__all__:
        assert getattr(flctool, name) is not None
    assert set(flctool.__all__) <= set(dir(flctool))


def test_the_whole_flow_runs_on_the_public_names(tmp_path: Path) -> None:
    behaviour = flctool.resolve_behaviour(
        flctool.load_behaviour(BEHAVIOURS / "ballchase.yaml"),
        [flctool.Override("population", 4, "a test (population)"),
         flctool.Override("generations", 1, "a test (generations)"),
         flctool.Override("selection.candidates", 0, "a test (selection)")])
    with flctool.make_env(behaviour) as env:
        learner = flctool.make_learner(behaviour, env)
        assert len(flctool.train(learner)) == 1
    summary = flctool.start_run(behaviour, out=tmp_path / "run").train()
    assert isinstance(summary, flctool.RunSummary) and summary.status == "finished"
    best = flctool.load_behaviour(tmp_path / "run" / "best.yaml")
    assert flctool.evaluate_behaviour(best, episodes=5).result.episodes == 5
    [written] = flctool.export_file(best, tmp_path / "best.fll")
    back = flctool.import_behaviour(written)
    assert flctool.compile_behaviour(back).consequents is not None
    assert "Engine:" in flctool.export_text(best, "fll")


def test_import_flctool_loads_no_heavy_module() -> None:
    code = ("import sys, flctool; print(sorted(m for m in ('numpy', 'pydantic', 'ast', "
            "'flctool.behaviour') if m in sys.modules))")
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                            timeout=60)
    assert result.stdout.split() == ["[]"], result.stderr
