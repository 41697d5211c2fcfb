"""Names: a behaviour's own name may hold hyphens; formats that need identifiers derive one."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from flctool.behaviour import parse_behaviour
from flctool.behaviour.base import identifier
from flctool.export import EXPORTERS, IMPORTERS

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.parametrize(("name", "expected"), [
    ("chase", "chase"), ("chase-mine", "chase_mine"), ("a-b-c", "a_b_c"), ("_x-1", "_x_1")])
def test_identifier(name: str, expected: str) -> None:
    assert identifier(name) == expected
    assert re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", identifier(name))


@pytest.mark.parametrize("fmt", ["fll", "fcl", "fis", "c", "yaml", "json"])
def test_a_hyphenated_name_exports_to_valid_files(fmt: str) -> None:
    text = (ROOT / "behaviours" / "ballchase-handmade.yaml").read_text(encoding="utf-8")
    behaviour = parse_behaviour(re.sub(r"(?m)^name: .*$", "name: chase-mine", text, count=1))
    assert behaviour.name == "chase-mine"
    exported = EXPORTERS.get(fmt)().to_string(behaviour)
    if fmt in IMPORTERS:
        again = IMPORTERS.get(fmt)().from_string(exported, f"chase.{fmt}")
        assert again.name in ("chase-mine", "chase_mine")
        assert [r.then for r in again.rules] == [r.then for r in behaviour.rules]
    if fmt == "c":
        assert "CHASE_MINE_H" in exported and "CHASE-MINE" not in exported

