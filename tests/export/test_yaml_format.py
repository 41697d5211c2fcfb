"""YAML: a complete behaviour file that loads back to the same controller, bit for bit."""

from __future__ import annotations

from pathlib import Path

from typer.testing import CliRunner

from flctool import load_behaviour, parse_behaviour
from flctool.cli import app
from flctool.export import ExportOptions
from flctool.export.yaml_format import YamlExporter

from .controllers import random_states
from .roundtrip import SHIPPED, assert_same_controller


def test_header_and_validate(tmp_path: Path) -> None:
    behaviour = load_behaviour(SHIPPED[0])
    options = ExportOptions(provenance={"source": "runs/x", "learner": "pitt", "seed": 4,
                                        "generation": 7, "fitness": 0.5})
    target = tmp_path / "best.yaml"
    YamlExporter(options).to_file(behaviour, target)
    text = target.read_text()
    assert text.splitlines()[:3] == [
        f"# {behaviour.name}: exported by flctool 0.1.0", "# source: runs/x",
        "# learner: pitt, seed: 4, generation: 7, fitness: 0.5"]
    result = CliRunner().invoke(app, ["validate", str(target)])
    assert result.exit_code == 0 and "deployable" in result.output
    again = parse_behaviour(text)
    assert again == behaviour  # every section, learning and environment included
    assert_same_controller(again, behaviour, random_states(behaviour, 5000, seed=2))
