"""``flctool infer``: both paths give the same bits, and awkward CSV is handled."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from flctool import compile_behaviour, load_behaviour
from flctool.cli import app
from flctool.cli import infer as infer_module
from flctool.cli.infer import outputs_in_python

from ..conftest import BEHAVIOURS

runner = CliRunner()
HANDMADE = BEHAVIOURS / "ballchase-handmade.yaml"


def test_the_python_path_gives_the_kernels_bits() -> None:
    controller = compile_behaviour(load_behaviour(HANDMADE))
    rng = np.random.default_rng(7)
    low, high = controller.ranges[:, 0], controller.ranges[:, 1]
    span = high - low
    states = low + rng.uniform(-0.1, 1.1, size=(3000, controller.n_inputs)) * span
    # set edges, range ends and beyond: where rounding differences would show first
    edges = np.concatenate([q.ravel() for q in controller.quadruples])
    states[:len(edges), 0] = np.resize(edges, len(edges))
    states[-2:] = [low - 1, high + 1]
    assert outputs_in_python(controller, states).tobytes() == \
        controller.output(states).tobytes()


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


def test_loading_the_kernels_for_a_large_table_spares_scipy_blas() -> None:
    # In a fresh process, as the command runs: numba's probe for scipy's BLAS is spared while
    # the kernels load, and scipy's BLAS imports normally afterwards.
    probe = (
        "import sys\nimport numpy as np\nimport flctool\n"
        "from flctool.cli.infer import _numba_without_scipy_blas\n"
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
