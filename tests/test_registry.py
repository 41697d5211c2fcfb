"""Registries: lazy entries load on first use, unknown names get a suggestion."""

from __future__ import annotations

import pytest

from flctool.errors import FlcError
from flctool.registry import Registry, UnknownNameError, did_you_mean


def test_lazy_entries_load_on_first_use() -> None:
    registry: Registry[object] = Registry("thing")
    registry.register("path", "pathlib:PurePosixPath")
    registry.register("direct", int)
    import pathlib

    assert registry.get("path") is pathlib.PurePosixPath
    assert registry.get("direct") is int
    assert registry.names() == ("path", "direct")
    assert "path" in registry and "other" not in registry
    assert list(registry) == ["path", "direct"]


def test_unknown_name_suggests_the_closest() -> None:
    registry: Registry[object] = Registry("environment adapter")
    registry.register("ballchase-sim", int)
    registry.register("gymnasium", float)
    with pytest.raises(UnknownNameError) as info:
        registry.get("gymnasum")
    assert str(info.value) == ("unknown environment adapter 'gymnasum'. Did you mean "
                               "'gymnasium'? (fix: use one of: ballchase-sim, gymnasium)")


def test_a_taken_name_is_an_error_not_an_overwrite() -> None:
    registry: Registry[object] = Registry("learner")
    registry.register("pitt", int)
    with pytest.raises(FlcError, match="learner 'pitt' is already registered"):
        registry.register("pitt", float)
    assert registry.get("pitt") is int


def test_did_you_mean_stays_quiet_when_nothing_is_close() -> None:
    assert did_you_mean("xyz", ["pitt", "hybrid"]) == ""
    assert did_you_mean("hybird", ["pitt", "hybrid"]) == " Did you mean 'hybrid'?"
