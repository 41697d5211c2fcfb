"""The JSON Schema of behaviour files, generated from the pydantic models."""

from __future__ import annotations

import json
from typing import Any

from flctool.spec.models import Behaviour

SCHEMA_ID = "https://flctool.dev/schemas/behaviour.schema.json"


def behaviour_schema() -> dict[str, Any]:
    schema = Behaviour.model_json_schema(by_alias=True, mode="validation")
    return {"$schema": "https://json-schema.org/draft/2020-12/schema", "$id": SCHEMA_ID,
            **schema}


def behaviour_schema_text() -> str:
    """The schema as the committed file holds it (stable key order, trailing newline)."""
    return json.dumps(behaviour_schema(), indent=2, ensure_ascii=False) + "\n"
