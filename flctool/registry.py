"""Name -> implementation registries with lazy ``"module:attr"`` entries.

Heavy or optional dependencies (gymnasium, numba, a robot link) load only when their entry is
used. Registering a taken name is an error rather than a silent overwrite.
"""

from __future__ import annotations

import difflib
import importlib
from collections.abc import Iterator
from typing import Generic, TypeVar

from flctool.errors import FlcError, UnknownNameError

T = TypeVar("T")

__all__ = ["Registry", "UnknownNameError", "did_you_mean"]


def did_you_mean(name: str, choices: list[str] | tuple[str, ...]) -> str:
    """``" Did you mean 'x'?"`` for the closest choice, or ``""`` when nothing is close."""
    close = difflib.get_close_matches(name, list(choices), n=1, cutoff=0.5)
    return f" Did you mean '{close[0]}'?" if close else ""


class Registry(Generic[T]):
    """A registry of one kind of thing (learners, environments, exporters)."""

    def __init__(self, kind: str) -> None:
        self.kind = kind
        self._entries: dict[str, T | str] = {}

    def register(self, name: str, entry: T | str) -> None:
        """Register ``entry`` (an object, or a lazy ``"package.module:attr"`` string)."""
        if name in self._entries:
            raise FlcError(f"{self.kind} '{name}' is already registered")
        self._entries[name] = entry

    def get(self, name: str) -> T:
        """The entry called ``name``, importing it first if it is lazy."""
        try:
            entry = self._entries[name]
        except KeyError:
            known = ", ".join(sorted(self.names()))
            raise UnknownNameError(
                f"unknown {self.kind} '{name}'.{did_you_mean(name, self.names())}",
                hint=f"use one of: {known}",
            ) from None
        if isinstance(entry, str):
            module_name, _, attr = entry.partition(":")
            loaded: T = getattr(importlib.import_module(module_name), attr)
            self._entries[name] = loaded
            return loaded
        return entry

    def names(self) -> tuple[str, ...]:
        return tuple(self._entries)

    def __contains__(self, name: object) -> bool:
        return name in self._entries

    def __iter__(self) -> Iterator[str]:
        return iter(self.names())
