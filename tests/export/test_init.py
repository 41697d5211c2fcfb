"""The registries, and the contract every exporter / importer keeps (golden round trips)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from flctool import load_behaviour, parse_behaviour
from flctool.behaviour import Behaviour, behaviour_from_data
from flctool.errors import NotDeployableError
from flctool.export import EXPORTERS, IMPORTERS, Exporter, Importer
from flctool.registry import UnknownNameError

from .controllers import random_behaviour, random_states, with_product
from .roundtrip import SHIPPED, assert_same_controller

TEXT_FORMATS = ("yaml", "json", "fll", "fcl", "fis")


def read_back(format: str, text: str) -> Behaviour:
    if format == "yaml":
        return parse_behaviour(text, "export.yaml")
    if format == "json":
        return behaviour_from_data(json.loads(text))
    return IMPORTERS.get(format)().from_string(text, f"export.{format}")


def test_registries_name_every_format() -> None:
    assert set(EXPORTERS.names()) == {"yaml", "json", "fll", "fcl", "fis", "c",
                                      "bundle"}
    assert set(IMPORTERS.names()) == {"fll", "fcl", "fis"}
    for name in EXPORTERS:
        exporter = EXPORTERS.get(name)
        assert issubclass(exporter, Exporter) and exporter.format == name
    for name in IMPORTERS:
        importer = IMPORTERS.get(name)
        assert issubclass(importer, Importer) and importer.format == name


def test_unknown_format_suggests_one() -> None:
    with pytest.raises(UnknownNameError, match="Did you mean 'fll'"):
        EXPORTERS.get("fl")


def test_something_ships_complete() -> None:
    assert any(p.name == "ballchase-handmade.yaml" for p in SHIPPED)


@pytest.mark.parametrize("activation", ["min", "product"])
@pytest.mark.parametrize("format", TEXT_FORMATS)
@pytest.mark.parametrize("path", SHIPPED, ids=lambda p: p.name)
def test_shipped_behaviours_round_trip(path: Path, format: str, activation: str) -> None:
    behaviour = load_behaviour(path)
    if activation == "product":
        behaviour = with_product(behaviour)
    text = EXPORTERS.get(format)().to_string(behaviour)
    again = read_back(format, text)
    assert_same_controller(again, behaviour, random_states(behaviour, 2000, seed=1))
    # and exporting the copy gives the same text: the export is a fixed point
    if format not in ("yaml", "json"):
        assert EXPORTERS.get(format)().to_string(again).splitlines()[1:] == \
            text.splitlines()[1:]


@pytest.mark.parametrize("activation", ["min", "product"])
@pytest.mark.parametrize("format", TEXT_FORMATS)
@pytest.mark.slow
def test_random_controllers_round_trip(format: str, activation: str) -> None:
    for seed in range(40):
        behaviour = random_behaviour(seed, activation=activation)
        text = EXPORTERS.get(format)().to_string(behaviour)
        assert_same_controller(read_back(format, text), behaviour,
                               random_states(behaviour, 500, seed=seed))


@pytest.mark.parametrize("format", sorted(EXPORTERS.names()))
def test_every_exporter_refuses_missing_rules(format: str) -> None:
    incomplete = load_behaviour(Path(SHIPPED[0]).parent / "ballchase.yaml")
    with pytest.raises(NotDeployableError, match=r"15 of 15 rules have no consequent") as error:
        EXPORTERS.get(format)().to_string(incomplete)
    assert "IF ball_size IS small AND pan IS far_right" in str(error.value)
    assert "... and 5 more" in str(error.value)


@pytest.mark.slow
def test_importing_export_loads_no_learner() -> None:
    import subprocess
    import sys

    code = ("import sys, flctool.export; "
            "print(sorted(m for m in sys.modules if m.startswith('flctool.learners') "
            "or m == 'flctool.runs'))")
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                            timeout=120, check=True)
    assert result.stdout.strip() == "[]"
