"""The deployment bundle: its wiring, and harnesses that the real C compiler builds and that
compute flctool's outputs and actions."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

from flctool import compile_behaviour, load_behaviour, with_rules
from flctool.behaviour import Behaviour, behaviour_from_data
from flctool.errors import ExportError
from flctool.export.bundle import BundleExporter

from ..conftest import BEHAVIOURS
from .controllers import random_states
from .roundtrip import SHIPPED

CC = shutil.which("cc") or shutil.which("gcc") or shutil.which("clang")
needs_cc = pytest.mark.skipif(CC is None, reason="no C compiler (cc, gcc or clang) on PATH")


def cartpole(observations: dict[str, int]) -> Behaviour:
    """CartPole with its inputs reading permuted observation components, rules from seed 0."""
    data = yaml.safe_load((BEHAVIOURS / "cartpole.yaml").read_text(encoding="utf-8"))
    data["environment"]["observations"] = observations
    behaviour = behaviour_from_data(data)
    rules = np.random.default_rng(0).integers(0, 2, behaviour.rule_count)
    return with_rules(behaviour, rules)


def run_harnesses(folder: Path, lines: list[str]) -> tuple[list[list[str]], list[list[str]]]:
    """The C harness (built with the system compiler) and the Python one on ``lines``."""
    assert CC is not None
    sources = [str(p) for p in folder.glob("*.c")]
    program = folder / "harness"
    subprocess.run([CC, "-std=c99", "-pedantic", "-Wall", "-Wextra", "-Werror", "-O2", "-o",
                    str(program), *sources], check=True, capture_output=True, text=True)
    text = "\n".join(lines) + "\n"
    c = subprocess.run([str(program)], input=text, check=True, capture_output=True, text=True)
    py = subprocess.run([sys.executable, str(folder / "harness.py")], input=text, check=True,
                        capture_output=True, text=True)
    return ([line.split() for line in c.stdout.splitlines()],
            [line.split() for line in py.stdout.splitlines()])


@needs_cc
@pytest.mark.slow
def test_the_gymnasium_bundle_wires_observations_and_actions(tmp_path: Path) -> None:
    mapping = {"cart_position": 3, "cart_velocity": 0, "pole_angle": 2, "pole_velocity": 1}
    behaviour = cartpole(mapping)
    folder = tmp_path / "bundle"
    written = BundleExporter().to_file(behaviour, folder)
    assert {p.name for p in written} == {"controller.yaml", "wiring.json", "cartpole.h",
                                         "cartpole.c", "harness.c", "harness.py"}
    wires = json.loads((folder / "wiring.json").read_text())
    assert [i["source"] for i in wires["inputs"]] == [{"observation_index": i}
                                                      for i in mapping.values()]
    assert [i["unit"] for i in wires["inputs"]] == ["m", "m/s", "rad", "rad/s"]
    assert wires["action"]["kind"] == "discrete"
    # raw observations: the controller's states, placed where the mapping reads them
    states = random_states(behaviour, 1_000, seed=3)
    raw = np.empty_like(states)
    raw[:, list(mapping.values())] = states
    c, py = run_harnesses(folder, [" ".join(map(repr, row)) for row in raw.tolist()])
    outputs = compile_behaviour(behaviour).output(states)
    commands = behaviour.output.commands
    values = np.array(list(commands.values()))
    order = np.argsort(values, kind="stable")
    nearest = order[np.argmin(np.abs(values[order][None, :] - outputs[:, None]), axis=1)]
    actions = [behaviour.environment.actions[list(commands)[k]]  # type: ignore[union-attr]
               for k in nearest]
    for lines in (c, py):
        assert np.max(np.abs(np.array([float(x[0]) for x in lines]) - outputs)) <= 1e-12
        assert [int(x[1]) for x in lines] == nearest.tolist()
        assert [int(x[3]) for x in lines] == actions


@needs_cc
@pytest.mark.slow
def test_the_ballchase_bundle_reads_named_sensors(tmp_path: Path) -> None:
    behaviour = load_behaviour(SHIPPED[0])
    folder = tmp_path / "bundle"
    BundleExporter().to_file(behaviour, folder)
    wires = json.loads((folder / "wiring.json").read_text())
    assert [i["source"] for i in wires["inputs"]] == [{"sensor": n} for n in behaviour.inputs]
    states = random_states(behaviour, 1_000, seed=4)
    c, py = run_harnesses(folder, [" ".join(map(repr, row)) for row in states.tolist()])
    outputs = compile_behaviour(behaviour).output(states)
    for lines in (c, py):
        assert np.max(np.abs(np.array([float(x[0]) for x in lines]) - outputs)) <= 1e-12
        assert [x[1:3] for x in lines] == [x[1:3] for x in c]


def test_vote_and_stdout_are_refused_clearly() -> None:
    behaviour = cartpole({"cart_position": 0, "cart_velocity": 1, "pole_angle": 2,
                          "pole_velocity": 3})
    environment = behaviour.environment
    assert environment is not None
    voting = behaviour.model_copy(update={"environment": environment.model_copy(
        update={"action": "vote"})})
    with pytest.raises(ExportError, match=r"environment\.action is vote"):
        BundleExporter().texts(voting, Path("out"))
    with pytest.raises(ExportError, match="a bundle is a folder"):
        BundleExporter().to_string(behaviour)


def test_an_existing_bundle_is_kept_without_force(tmp_path: Path) -> None:
    behaviour = load_behaviour(SHIPPED[0])
    BundleExporter().to_file(behaviour, tmp_path / "b")
    with pytest.raises(ExportError, match="already exists"):
        BundleExporter().to_file(behaviour, tmp_path / "b")
    BundleExporter().to_file(behaviour, tmp_path / "b", force=True)


def test_the_cli_writes_a_bundle_folder(tmp_path: Path) -> None:
    from typer.testing import CliRunner

    from flctool.cli import app

    result = CliRunner().invoke(app, ["export", str(SHIPPED[0]), "--format", "bundle", "-o",
                                      str(tmp_path / "deploy")])
    assert result.exit_code == 0, result.output
    assert (tmp_path / "deploy" / "wiring.json").is_file()
    result = CliRunner().invoke(app, ["export", str(SHIPPED[0]), "--format", "bundle"])
    assert result.exit_code != 0
    assert "a bundle is a folder" in result.output
