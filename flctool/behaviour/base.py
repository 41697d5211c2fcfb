"""Shared pydantic base for every section of a behaviour file."""

from __future__ import annotations

import re
from collections.abc import Mapping
from typing import Annotated, Any, NoReturn

from pydantic import BaseModel, ConfigDict, StringConstraints, model_validator
from typing_extensions import Self


class FrozenDict(dict[Any, Any]):
    """A dict that refuses changes: a validated section's mappings (sets, commands, ...)."""

    def _refuse(self, *args: Any, **kwargs: Any) -> NoReturn:
        raise TypeError("a validated behaviour cannot be changed; build a new one "
                        "(model_copy(update=...) or flctool.runs.resolve_behaviour)")

    __setitem__ = __delitem__ = __ior__ = _refuse
    clear = pop = popitem = setdefault = update = _refuse

    def __reduce__(self) -> tuple[Any, ...]:
        return (FrozenDict, (dict(self),))


class FrozenList(list[Any]):
    """A list that refuses changes: a validated section's lists (rules)."""

    def _refuse(self, *args: Any, **kwargs: Any) -> NoReturn:
        raise TypeError("a validated behaviour cannot be changed; build a new one "
                        "(model_copy(update=...) or flctool.runs.resolve_behaviour)")

    __setitem__ = __delitem__ = __iadd__ = __imul__ = _refuse
    append = clear = extend = insert = pop = remove = reverse = sort = _refuse

    def __reduce__(self) -> tuple[Any, ...]:
        return (FrozenList, (list(self),))


class Section(BaseModel):
    """Frozen, strict about unknown keys: a typo is an error, never silently ignored.

    Frozen all the way down: the dicts and lists a section holds refuse changes too, so a
    behaviour that passed validation stays what was validated.
    """

    model_config = ConfigDict(extra="forbid", frozen=True, populate_by_name=True,
                              allow_inf_nan=False)

    @model_validator(mode="after")
    def _freeze_containers(self) -> Any:
        _freeze(self)
        return self

    def model_copy(self, *, update: Mapping[str, Any] | None = None,
                   deep: bool = False) -> Self:
        """A copy with ``update`` applied (not validated, as pydantic's), frozen as well."""
        copy = super().model_copy(update=update, deep=deep)
        _freeze(copy)
        return copy


def _freeze(section: BaseModel) -> None:
    for name in type(section).model_fields:
        value = getattr(section, name)
        if type(value) is dict:
            object.__setattr__(section, name, FrozenDict(value))
        elif type(value) is list:
            object.__setattr__(section, name, FrozenList(value))


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
