"""Controllers whose sets were learned export exactly: fuzzylite 6 (FLL, FIS, FCL) and the
C build compute what ``flctool infer`` does."""

from __future__ import annotations

import csv
import io
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from flctool import compile_behaviour, load_behaviour, with_rules
from flctool.behaviour import Behaviour
from flctool.behaviour.dump import behaviour_to_data, behaviour_to_yaml
from flctool.behaviour.load import behaviour_from_data
from flctool.cli import app
from flctool.export import ExportOptions
from flctool.export.base import sloped_quad
from flctool.export.fcl import FclExporter
from flctool.export.fis import FisExporter
from flctool.export.fll import FllExporter
from flctool.sets.codec import SetCodec

from .controllers import random_states
from .engines import assert_fuzzylite_agrees
from .test_c_source import build, needs_cc, run

BEHAVIOURS = Path(__file__).resolve().parents[2] / "behaviours"
runner = CliRunner()


def tuned(file: str, mode: str, seed: int) -> Behaviour:
    """A shipped behaviour with its sets moved by a random set genome and random rules: what
    a run that learns the sets returns."""
    data = behaviour_to_data(load_behaviour(BEHAVIOURS / file))
    data["learning"]["sets"] = {"mode": mode, "floor": 0.05}
    behaviour = behaviour_from_data(data)
    codec = SetCodec(behaviour)
    rng = np.random.default_rng(seed)
    learned = codec.decode(rng.uniform(-1, 1, codec.size).tolist())
    assert learned.inputs != behaviour.inputs
    return with_rules(learned, rng.integers(0, len(learned.output.commands),
                                            learned.rule_count))


# pendulum: the shipped behaviour whose crisp output is the action itself (eq. 3 on a Box),
# with the narrow sets near upright that learning moves most
TUNED = [("ballchase.yaml", "partition", 1), ("ballchase.yaml", "lateral", 2),
         ("avoid-obstacle.yaml", "lateral", 3), ("mountaincar.yaml", "partition", 4),
         ("pendulum.yaml", "partition", 5), ("pendulum.yaml", "lateral", 6)]
IDS = [f"{f.split('.')[0]}-{m}" for f, m, _ in TUNED]


def infer(behaviour: Behaviour, states: np.ndarray, folder: Path) -> np.ndarray:
    """``flctool infer``'s outputs for (S, N) ``states``."""
    file = folder / "tuned.yaml"
    file.write_text(behaviour_to_yaml(behaviour), encoding="utf-8")
    table = io.StringIO()
    writer = csv.writer(table)
    writer.writerow(behaviour.input_names)
    writer.writerows([repr(float(v)) for v in row] for row in states)
    result = runner.invoke(app, ["infer", str(file)], input=table.getvalue())
    assert result.exit_code == 0, result.output
    rows = list(csv.DictReader(io.StringIO(result.stdout)))
    return np.array([float(row[behaviour.output.name]) for row in rows])


@pytest.mark.parametrize(("file", "mode", "seed"), TUNED, ids=IDS)
@pytest.mark.slow
def test_fuzzylite6_computes_what_infer_does(file: str, mode: str, seed: int,
                                             tmp_path: Path) -> None:
    behaviour = tuned(file, mode, seed)
    states = random_states(behaviour, 2_000, seed=seed)
    # infer is the reference the engines are held to (assert_fuzzylite_agrees compares them
    # with the compiled controller, which infer runs); of a behaviour that acts by vote
    # (mountaincar) infer gives the vote, which the engines cannot say: they give eq. 3
    from flctool.rollout import vote_output

    controller = compile_behaviour(behaviour)
    assert np.array_equal(infer(behaviour, states, tmp_path),
                          vote_output(controller, states) if behaviour.acts_by_vote
                          else controller.output(states))
    exact = [list(v.sets.values()) for v in behaviour.inputs.values()]
    sloped = [[sloped_quad(q, v.range) for q in v.sets.values()]
              for v in behaviour.inputs.values()]
    interior = [[sloped_quad(q, v.range, interior=False) for q in v.sets.values()]
                for v in behaviour.inputs.values()]
    assert_fuzzylite_agrees(behaviour, FllExporter().to_string(behaviour), "fll", states,
                            exact, tmp_path)
    assert_fuzzylite_agrees(behaviour, FisExporter().to_string(behaviour), "fis", states,
                            sloped, tmp_path)
    fcl = FclExporter(ExportOptions(dialect="fuzzylite")).to_string(behaviour)
    assert_fuzzylite_agrees(behaviour, fcl, "fcl", states, interior, tmp_path)


@needs_cc
@pytest.mark.slow
def test_the_c_build_computes_what_infer_does(tmp_path: Path) -> None:
    controllers = [tuned(f, m, s) for f, m, s in TUNED]
    program = build(tmp_path, [(b, ExportOptions(prefix=f"t{i}_"))
                               for i, b in enumerate(controllers)])
    for which, behaviour in enumerate(controllers):
        states = random_states(behaviour, 2_000, seed=which)
        # the program prints <prefix>output, eq. 3; of a behaviour that acts by vote infer
        # gives the vote, which the C export's <prefix>command computes (test_c_source.py)
        want = (compile_behaviour(behaviour).output(states) if behaviour.acts_by_vote
                else infer(behaviour, states, tmp_path))
        assert np.max(np.abs(run(program, which, states) - want)) <= 1e-12
