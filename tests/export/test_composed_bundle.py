"""The bundle of a composed behaviour: the real C compiler builds the arbiter, every part and
the composition step, and both harnesses choose the part and compute its output as the pitch
world runs the composition."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from flctool import compile_behaviour, load_behaviour
from flctool.envs import make_env
from flctool.envs.pitch_compose import ComposedDrive
from flctool.export.bundle import BundleExporter

from ..conftest import BEHAVIOURS
from .test_bundle import needs_cc, run_harnesses


@needs_cc
@pytest.mark.slow
def test_the_composed_bundle_runs_the_composition_as_flctool(tmp_path: Path) -> None:
    behaviour = load_behaviour(BEHAVIOURS / "striker-handmade.yaml")
    folder = tmp_path / "bundle"
    written = {p.name for p in BundleExporter().to_file(behaviour, folder)}
    assert {"arbiter.c", "part_approach.c", "part_dribble.c", "composed.c", "harness.c",
            "harness.py", "wiring.json", "controller.yaml"} <= written
    wires = json.loads((folder / "wiring.json").read_text())
    drive = make_env(behaviour).drive
    assert isinstance(drive, ComposedDrive)
    # readings of every channel, within the ranges of the inputs that read them
    ranges: dict[str, tuple[float, float]] = {}
    for part in (behaviour, *(load_behaviour(BEHAVIOURS / "parts" / f"{n}-learned.yaml")
                              for n in ("approach", "dribble"))):
        for name, variable in part.inputs.items():
            ranges[name] = variable.range
    rng = np.random.default_rng(7)
    readings = np.array([[rng.uniform(*ranges[c]) for c in wires["channels"]]
                         for _ in range(400)])
    c, py = run_harnesses(folder, [" ".join(map(repr, row)) for row in readings.tolist()])
    arbiter = compile_behaviour(behaviour)
    order = list(drive.order)
    expected = []
    for row in readings:
        chosen = order[drive.chosen(arbiter.output_one(row[wires["arbiter"]["inputs"]]))]
        part = drive.parts[order.index(chosen)]
        output = part.controller.output_one(row[list(part.indices)])
        expected.append((chosen, output))
    assert {name for name, _ in expected} == {"approach", "dribble"}  # both parts run
    for lines in (c, py):
        assert [line[1] for line in lines] == [name for name, _ in expected]
        assert np.max(np.abs(np.array([float(line[2]) for line in lines])
                             - np.array([o for _, o in expected]))) <= 1e-12
        assert [line[3:] for line in lines] == [line[3:] for line in c]
