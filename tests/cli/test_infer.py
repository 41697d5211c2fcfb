"""``flctool infer``: both paths give the same bits, and awkward CSV is handled."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from flctool import compile_behaviour, load_behaviour
from flctool.behaviour import Behaviour
from flctool.cli import app
from flctool.cli import infer as infer_module
from flctool.cli.infer import outputs_in_python
from flctool.compile.rules import rule_consequents
from flctool.compile.sparse import SparseRules
from flctool.errors import InferenceError

from ..conftest import BEHAVIOURS, ROOT
from ..export.controllers import random_behaviour, random_states

runner = CliRunner()
HANDMADE = BEHAVIOURS / "ballchase-handmade.yaml"


def _controllers() -> list[tuple[str, Behaviour]]:
    pitch = BEHAVIOURS / "dribble-handmade.yaml"  # a pitch-world behaviour
    return [("ballchase", load_behaviour(HANDMADE)), ("pitch", load_behaviour(pitch)),
            *((f"random_{seed}", random_behaviour(seed, max_inputs=4, min_inputs=3))
              for seed in (3, 4, 5))]


@pytest.mark.parametrize(("name", "behaviour"), _controllers(), ids=lambda v: str(v)[:20])
def test_the_python_path_gives_the_kernels_bits(name: str, behaviour: Behaviour) -> None:
    controller = compile_behaviour(behaviour)
    # the rule base built from the behaviour holds the compiled controller's numbers
    rules = SparseRules.from_behaviour(behaviour)
    assert vars(rules) == vars(SparseRules(controller))
    assert rule_consequents(behaviour) == controller.consequents.tolist()  # type: ignore[union-attr]
    states = random_states(behaviour, 4000, seed=len(name))  # set edges and range ends
    low, high = controller.ranges[:, 0], controller.ranges[:, 1]
    states[-2:] = [low - 1, high + 1]
    states[-4:-2] = [np.full(len(low), -np.inf), np.full(len(low), np.inf)]
    python = outputs_in_python(rules, rule_consequents(behaviour) or [], states.tolist())
    assert np.array(python).tobytes() == controller.output(states).tobytes()


def test_both_paths_refuse_nan() -> None:
    behaviour = load_behaviour(HANDMADE)
    state = [0.2, float("nan")]
    with pytest.raises(InferenceError, match="NaN"):
        outputs_in_python(SparseRules.from_behaviour(behaviour),
                          rule_consequents(behaviour) or [], [state])
    with pytest.raises(InferenceError, match="NaN"):
        compile_behaviour(behaviour).output(np.array([state]))


@pytest.mark.slow
def test_a_small_table_is_inferred_without_numpy() -> None:
    # In a fresh process, as the command runs: neither numpy nor numba is imported.
    probe = (
        "import sys\nfrom flctool.cli import run\n"
        "sys.argv = ['flctool', 'infer', sys.argv[1]]\n"
        "try:\n    run()\nexcept SystemExit as stop:\n    assert not stop.code, stop.code\n"
        "print(sorted(m for m in sys.modules if m.split('.')[0] in ('numpy', 'numba')),"
        " file=sys.stderr)\n")
    result = subprocess.run([sys.executable, "-c", probe, str(HANDMADE)], input=_rows(10),
                            capture_output=True, text=True, timeout=600)
    assert result.returncode == 0, result.stderr
    assert result.stderr.strip() == "[]"
    assert result.stdout == runner.invoke(app, ["infer", str(HANDMADE)], input=_rows(10)).stdout


def _rows(count: int) -> str:
    rng = np.random.default_rng(1)
    lines = [f"{s:.6f},{p:.3f}" for s, p in zip(rng.uniform(0, 1, count),
                                                 rng.uniform(-90, 90, count), strict=True)]
    return "ball_size,pan\n" + "\n".join(lines) + "\n"


def test_small_and_large_tables_agree(monkeypatch: pytest.MonkeyPatch) -> None:
    text = _rows(300)
    small = runner.invoke(app, ["infer", str(HANDMADE)], input=text)
    monkeypatch.setattr(infer_module, "SMALL_TABLE", 10)
    large = runner.invoke(app, ["infer", str(HANDMADE)], input=text)
    assert small.exit_code == 0 and large.exit_code == 0, small.output + large.output
    assert small.stdout == large.stdout
    assert small.stdout.splitlines()[0] == "ball_size,pan,turn"


def test_cr_only_bom_and_trailing_blank_line_on_stdin() -> None:
    plain = runner.invoke(app, ["infer", str(HANDMADE)], input="ball_size,pan\n0.2,10\n")
    for data in (b"ball_size,pan\r0.2,10\r", b"\xef\xbb\xbfball_size,pan\n0.2,10\n",
                 b"ball_size,pan\n0.2,10\n\n"):
        result = runner.invoke(app, ["infer", str(HANDMADE)], input=data)
        assert result.exit_code == 0, (data, result.output)
        assert result.stdout == plain.stdout


def test_a_duplicated_column_and_a_huge_cell_are_errors() -> None:
    duplicated = runner.invoke(app, ["infer", str(HANDMADE)],
                               input="ball_size,pan,pan\n0.2,10,11\n")
    assert duplicated.exit_code == 1 and "the column 'pan' appears twice" in duplicated.output
    huge = runner.invoke(app, ["infer", str(HANDMADE)],
                         input="ball_size,pan\n" + "9" * 131_073 + "x,1\n")
    assert huge.exit_code == 1 and "(131,074 characters)' is not a number" in huge.output


def test_output_file_is_written_whole_or_not_at_all(tmp_path: Path) -> None:
    out = tmp_path / "out.csv"
    bad = runner.invoke(app, ["infer", str(HANDMADE), "-o", str(out)],
                        input="ball_size,pan\n0.2,10\nq,1\n")
    assert bad.exit_code == 1 and not out.exists() and list(tmp_path.iterdir()) == []


@pytest.mark.slow
def test_loading_the_kernels_for_a_large_table_spares_scipy_blas() -> None:
    # In a fresh process, as the command runs: numba's probe for scipy's BLAS is spared while
    # the kernels load, and scipy's BLAS imports normally afterwards.
    probe = (
        "import sys\nimport numpy as np\nimport flctool\n"
        "from flctool.cli.infer import _numba_without_scipy_blas\n"
        "from flctool.compile.controller import set_inference\n"
        "set_inference('kernels')  # the kernels, however small the job\n"
        f"c = flctool.compile_behaviour(flctool.load_behaviour({str(HANDMADE)!r}))\n"
        "with _numba_without_scipy_blas():\n"
        "    values = c.output(np.array([[0.2, 10.0]] * 100))\n"
        "print('scipy.linalg.cython_blas' in sys.modules)\n"
        "import scipy.linalg.cython_blas\n"
        "print(values[0] == c.output_one(np.array([0.2, 10.0])))\n")
    result = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True,
                            timeout=600)
    assert result.returncode == 0, result.stderr
    assert result.stdout.split() == ["False", "True"]


def test_a_behaviour_that_acts_by_vote_gives_the_voted_command_on_both_paths(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """infer says what the behaviour does: for environment.action: vote, the singleton of
    the command the vote picks (as learning and evaluate act), not eq. 3's blend."""
    from flctool.rollout import vote_output

    park = ROOT / "benchmarks" / "tasks" / "park-handmade.yaml"
    behaviour = load_behaviour(park)
    states = random_states(behaviour, 300, seed=2)
    text = "spot_bearing,spot_distance\n" + "\n".join(
        ",".join(repr(float(v)) for v in row) for row in states.tolist()) + "\n"
    small = runner.invoke(app, ["infer", str(park)], input=text)
    monkeypatch.setattr(infer_module, "SMALL_TABLE", 10)
    large = runner.invoke(app, ["infer", str(park)], input=text)
    assert small.exit_code == 0 and small.stdout == large.stdout, small.output
    got = np.array([float(line.rsplit(",", 1)[1]) for line in small.stdout.splitlines()[1:]])
    controller = compile_behaviour(behaviour)
    want = vote_output(controller, np.clip(states, controller.ranges[:, 0],
                                           controller.ranges[:, 1]))
    assert np.array_equal(got, want)
    assert not np.array_equal(got, controller.output(states))  # eq. 3 blends: not the vote
