"""Plugins: the one place that describes each learner, environment adapter and export format.

A :class:`Plugin` is a name, the model of the behaviour-file section it reads (learners and
adapters) and a lazy ``"module:Class"`` implementation. The registries
(:data:`flctool.learners.LEARNERS`, :data:`flctool.envs.ENVIRONMENTS`,
:data:`flctool.export.EXPORTERS`) and the behaviour-file sections (``learning:`` read by the
model of the plugin its ``learner`` names, ``environment:`` by its ``adapter``'s,
:mod:`flctool.behaviour.sections`) are all found from these lists, so adding a learner is one
module plus one entry.

Installed packages add entries through the entry-point groups ``flctool.learners``,
``flctool.environments`` and ``flctool.exporters``; each entry point is named like its plugin
and names a :class:`Plugin` object (docs/plugins.md). Like Gymnasium's ``make()``,
:func:`plugin` imports only the entry a name asks for; :func:`plugins` (every plugin, for
listings and error hints) imports them all. Only packages the user installed are loaded this
way: nothing a behaviour file says makes flctool import a module that is not installed.
"""

from __future__ import annotations

import importlib
import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from functools import cache
from importlib.metadata import EntryPoint, entry_points
from typing import Any

from pydantic import BaseModel, ValidationError

from flctool.errors import FlcError, PluginError, PluginWarning
from flctool.registry import Registry

GROUPS = {"learner": "flctool.learners", "environment": "flctool.environments",
          "exporter": "flctool.exporters"}


@dataclass(frozen=True)
class Plugin:
    """One learner, environment adapter or export format.

    ``config`` is the model of the section the plugin reads: for a learner a subclass of
    :class:`~flctool.behaviour.learning.LearningConfig` adding the learner's own keys whose
    ``learner`` is ``Literal[name]``; for an adapter a subclass of
    :class:`~flctool.behaviour.environment.AdapterConfig` whose ``adapter`` is ``Literal[name]``;
    ``None`` for an export format. ``config`` may be given lazily as a ``"module:Class"``
    string too (the built-ins are, so that this module imports no model);
    ``target`` is imported only when used.
    """

    name: str
    target: str
    config: type[BaseModel] | str | None = None
    #: For an export format: the file suffixes that name it (``export -o x.fll``).
    suffixes: tuple[str, ...] = ()

    def config_model(self) -> type[BaseModel]:
        """The section model, imported if it was given as ``"module:Class"``."""
        if self.config is None:
            raise TypeError(f"the plugin '{self.name}' reads no section of a behaviour file")
        loaded = load_attribute(self.config) if isinstance(self.config, str) else self.config
        if not (isinstance(loaded, type) and issubclass(loaded, BaseModel)):
            raise TypeError(f"the config of plugin '{self.name}' is not a pydantic model")
        return loaded


def load_attribute(target: str) -> Any:
    """The attribute that ``"package.module:attr"`` names, importing its module."""
    module_name, _, attr = target.partition(":")
    return getattr(importlib.import_module(module_name), attr)


_LEARNING = "flctool.behaviour.learning"
_ENVIRONMENT = "flctool.behaviour.environment"

BUILTIN: dict[str, tuple[Plugin, ...]] = {
    "learner": (
        Plugin("pitt", "flctool.learners.genetic:PittLearner", f"{_LEARNING}:PittConfig"),
        Plugin("fuzzy_q", "flctool.learners.fuzzy_q:FuzzyQLearner",
               f"{_LEARNING}:FuzzyQConfig"),
        Plugin("hybrid", "flctool.learners.genetic:HybridLearner", f"{_LEARNING}:HybridConfig"),
        Plugin("credit", "flctool.learners.credit:CreditLearner", f"{_LEARNING}:CreditConfig"),
    ),
    "environment": (
        Plugin("ballchase-sim", "flctool.envs.ballchase:BallchaseSim",
               f"{_ENVIRONMENT}:BallchaseSimConfig"),
        Plugin("pitch", "flctool.envs.pitch:PitchSim", f"{_ENVIRONMENT}:PitchConfig"),
        Plugin("gymnasium", "flctool.envs.gym_adapter:GymnasiumEnv",
               f"{_ENVIRONMENT}:GymnasiumConfig"),
        Plugin("robot-link", "flctool.envs.robot_link:RobotLinkEnv",
               f"{_ENVIRONMENT}:RobotLinkConfig"),
        Plugin("ros2", "flctool.envs.ros2_env:Ros2Env", "flctool.behaviour.ros2:Ros2Config"),
    ),
    "exporter": (
        Plugin("yaml", "flctool.export.yaml_format:YamlExporter", suffixes=(".yaml", ".yml")),
        Plugin("json", "flctool.export.json_format:JsonExporter", suffixes=(".json",)),
        Plugin("fll", "flctool.export.fll:FllExporter", suffixes=(".fll",)),
        Plugin("fcl", "flctool.export.fcl:FclExporter", suffixes=(".fcl",)),
        Plugin("fis", "flctool.export.fis:FisExporter", suffixes=(".fis",)),
        Plugin("c", "flctool.export.c_source:CExporter", suffixes=(".c", ".h")),
        Plugin("bundle", "flctool.export.bundle:BundleExporter"),
    ),
}


@cache
def plugins(kind: str) -> tuple[Plugin, ...]:
    """The built-in plugins of ``kind`` ("learner", "environment" or "exporter"), then the
    installed ones, in entry-point name order; every installed one is imported. A broken
    installed plugin is skipped with a :class:`PluginWarning` saying which package to fix or
    uninstall."""
    found = list(BUILTIN[kind])
    for point in sorted(entry_points(group=GROUPS[kind]), key=lambda p: (p.name, p.value)):
        installed = _installed(kind, point)
        if installed is not None and installed.name not in {p.name for p in found}:
            found.append(installed)  # two packages naming one plugin: plugin() takes this one
    return tuple(found)


@cache
def plugin(kind: str, name: str) -> Plugin | None:
    """The plugin of ``kind`` called ``name``, or None if there is none: a built-in, or the
    installed entry point of that name, imported alone (and skipped with a
    :class:`PluginWarning` if it is broken)."""
    for builtin in BUILTIN[kind]:
        if builtin.name == name:
            return builtin
    point = next(iter(sorted(entry_points(group=GROUPS[kind], name=name),
                             key=lambda p: p.value)), None)
    return None if point is None else _installed(kind, point)


@cache
def _installed(kind: str, point: EntryPoint) -> Plugin | None:
    """The plugin an entry point names, checked; None (with a warning) if it is broken."""
    where = f"entry point '{point.name}' = '{point.value}' in group {GROUPS[kind]}"
    try:
        loaded = point.load()
    except Exception as error:  # a third party's import error must not stop flctool
        warnings.warn(f"skipped the {kind} plugin of {where}: it does not import "
                      f"({type(error).__name__}: {error}); fix or uninstall its package",
                      PluginWarning, stacklevel=3)
        return None
    problem = _problem(kind, loaded, {p.name for p in BUILTIN[kind]}, point.name)
    if problem:
        warnings.warn(f"skipped the {kind} plugin of {where}: {problem}", PluginWarning,
                      stacklevel=3)
        return None
    found: Plugin = loaded
    return found


@contextmanager
def blamed(kind: str, name: str) -> Iterator[None]:
    """Run code of the plugin ``name`` of ``kind`` (its section's checks, building it): an
    exception its code raises that is no :class:`FlcError` and no validation error becomes a
    :class:`PluginError` naming the plugin, for an installed one. A built-in's failure stays
    what it is (flctool's own bug)."""
    try:
        yield
    except (FlcError, ValidationError):
        raise
    except Exception as error:
        found = plugin(kind, name)
        if found is None or found in BUILTIN[kind]:
            raise
        package = found.target.partition(":")[0].split(".")[0]
        raise PluginError(
            f"the {kind} plugin '{name}' ({found.target}) failed: {type(error).__name__}: "
            f"{error}", hint=f"a fault of the plugin, not of the file: report it to the "
            f"authors of its package ({package}), or uninstall it; --debug shows the "
            "traceback") from error


def names(kind: str) -> tuple[str, ...]:
    """The names of every plugin of ``kind``, built-in first."""
    return tuple(plugin.name for plugin in plugins(kind))


def _problem(kind: str, plugin: object, taken: set[str],
             entry_name: str | None = None) -> str | None:
    """Why ``plugin`` cannot be used as a plugin of ``kind`` (None if it can); ``taken``
    holds the names already used, ``entry_name`` the name of the entry point naming it."""
    if not isinstance(plugin, Plugin):
        return f"it names a {type(plugin).__name__}, not a flctool.plugins.Plugin"
    if plugin.name in taken:
        return f"the name '{plugin.name}' is taken"
    if entry_name is not None and plugin.name != entry_name:
        return (f"its plugin is called '{plugin.name}': name the entry point '{plugin.name}' "
                "too, flctool finds a plugin by its entry point's name")
    if ":" not in plugin.target:
        return f"target '{plugin.target}' is not 'module:attribute'"
    if kind == "exporter":
        bad = [s for s in plugin.suffixes if not (s.startswith(".") and len(s) > 1)]
        return f"suffixes {bad} must each be '.' and a name" if bad else None
    if plugin.config is None:
        return "it names no config: a learner or an adapter names the model of its section"
    return None


def export_suffixes() -> dict[str, str]:
    """Suffix -> export format, from the exporters' entries (the first to claim one keeps it)."""
    found: dict[str, str] = {}
    for plugin in plugins("exporter"):
        for suffix in plugin.suffixes:
            found.setdefault(suffix.lower(), plugin.name)
    return found


class PluginRegistry(Registry[Any]):
    """The plugins of one kind by name: each one's module, and an installed plugin's entry
    point, is imported when its name is first used; listing the names imports every entry."""

    def __init__(self, kind: str, label: str) -> None:
        super().__init__(label)
        self.plugin_kind = kind
        for builtin in BUILTIN[kind]:
            self.register(builtin.name, builtin.target)

    def get(self, name: str) -> Any:
        if name not in self._entries:
            found = plugin(self.plugin_kind, name)  # an installed one: its entry point alone
            if found is not None:
                self.register(name, found.target)
        return super().get(name)

    def names(self) -> tuple[str, ...]:
        return names(self.plugin_kind)

    def __contains__(self, name: object) -> bool:
        return isinstance(name, str) and plugin(self.plugin_kind, name) is not None


def registry(kind: str, label: str) -> Registry[Any]:
    """A registry of every plugin of ``kind`` by name, each imported when first used."""
    return PluginRegistry(kind, label)
