"""The shared parts: deployability, headers, and careful atomic writes."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from flctool import load_behaviour
from flctool.errors import ExportError
from flctool.export import ExportOptions
from flctool.export.base import check_writable, header_lines, require_deployable
from flctool.export.yaml_format import YamlExporter

from ..conftest import BEHAVIOURS
from .roundtrip import SHIPPED


def test_require_deployable_lists_the_missing_rules() -> None:
    require_deployable(load_behaviour(SHIPPED[0]))
    with pytest.raises(ExportError) as error:
        require_deployable(load_behaviour(BEHAVIOURS / "ballchase.yaml"))
    text = str(error.value)
    assert "15 of 15 rules" in text
    assert text.count("\n  IF ") == 10 and "... and 5 more" in text
    assert "flctool learn" in text


def test_header_says_where_a_controller_came_from() -> None:
    behaviour = load_behaviour(SHIPPED[0])
    lines = header_lines(behaviour, {"source": "runs/a", "learner": "hybrid", "seed": 3,
                                     "generation": 29, "individual": None, "fitness": 0.75})
    assert lines[1] == "source: runs/a"
    assert lines[2] == "learner: hybrid, seed: 3, generation: 29, fitness: 0.75"


def test_to_file_refuses_to_overwrite_without_force(tmp_path: Path) -> None:
    behaviour = load_behaviour(SHIPPED[0])
    target = tmp_path / "out.yaml"
    target.write_text("keep me")
    with pytest.raises(ExportError, match=r"already exists.*--force"):
        YamlExporter().to_file(behaviour, target)
    assert target.read_text() == "keep me"
    assert YamlExporter().to_file(behaviour, target, force=True) == [target]
    assert target.read_text().startswith("# ")
    assert [p.name for p in tmp_path.iterdir()] == ["out.yaml"]  # no temporary file is left


def test_unwritable_paths_get_clear_messages(tmp_path: Path) -> None:
    with pytest.raises(ExportError, match=r"the folder .*missing does not exist"):
        check_writable(tmp_path / "missing" / "out.yaml", force=False)
    with pytest.raises(ExportError, match="is a folder"):
        check_writable(tmp_path, force=True)
    if os.geteuid() != 0:  # root may write anywhere
        locked = tmp_path / "locked"
        locked.mkdir()
        locked.chmod(0o500)
        try:
            with pytest.raises(ExportError, match="is not writable"):
                check_writable(locked / "out.yaml", force=False)
        finally:
            locked.chmod(0o700)


def test_options_default_to_flc_prefix_and_double() -> None:
    options = ExportOptions()
    assert options.prefix == "flc_" and not options.single and dict(options.provenance) == {}
