"""Shared pydantic base for every section of a behaviour file."""

from __future__ import annotations

import re
from typing import Annotated

from pydantic import BaseModel, ConfigDict, StringConstraints


class Section(BaseModel):
    """Frozen, strict about unknown keys: a typo is an error, never silently ignored."""

    model_config = ConfigDict(extra="forbid", frozen=True, populate_by_name=True,
                              allow_inf_nan=False)


# Names become identifiers in FLL, FCL, FIS and C exports, so they are kept to identifiers.
Name = Annotated[str, StringConstraints(pattern=r"^[A-Za-z_][A-Za-z0-9_]*$", max_length=64)]
#: A behaviour's own name may also hold hyphens (``chase-mine``); formats whose names must be
#: identifiers write :func:`identifier` of it.
BehaviourName = Annotated[str, StringConstraints(pattern=r"^[A-Za-z_][A-Za-z0-9_-]*$",
                                                 max_length=64)]


def identifier(name: str) -> str:
    """``name`` as an identifier of C, FCL and FLL: each character other than a letter, digit
    or _ becomes _ (``chase-mine`` -> ``chase_mine``)."""
    text = re.sub(r"[^A-Za-z0-9_]", "_", name)
    return text if text and not text[0].isdigit() else f"_{text}"
