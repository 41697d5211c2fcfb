"""JSON: the behaviour file's content, valid against schemas/behaviour.schema.json."""

from __future__ import annotations

import json

import jsonschema
import pytest

from flctool import load_behaviour
from flctool.behaviour import behaviour_from_data
from flctool.export.json_format import JsonExporter

from ..conftest import ROOT
from .controllers import random_behaviour
from .roundtrip import SHIPPED


@pytest.mark.slow
def test_json_is_the_behaviour_and_matches_the_schema() -> None:
    schema = json.loads((ROOT / "schemas" / "behaviour.schema.json").read_text())
    for behaviour in [load_behaviour(SHIPPED[0]), random_behaviour(4)]:
        data = json.loads(JsonExporter().to_string(behaviour))
        assert behaviour_from_data(data) == behaviour
        jsonschema.validate(data, schema)
        assert set(data) <= set(schema["properties"])
        assert set(schema["required"]) <= set(data)
