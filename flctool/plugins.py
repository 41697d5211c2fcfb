"""Plugins: the one place that describes each learner, environment adapter and export format.

A :class:`Plugin` is a name, the model of the behaviour-file section it reads (learners and
adapters) and a lazy ``"module:Class"`` implementation. The registries
(:data:`flctool.learners.LEARNERS`, :data:`flctool.envs.ENVIRONMENTS`,
:data:`flctool.export.EXPORTERS`) and the behaviour-file models (``learning:`` chosen by
``learner``, ``environment:`` by ``adapter``) are all built from these lists, so adding a
learner is one module plus one entry.

Installed packages add entries through the entry-point groups ``flctool.learners``,
``flctool.environments`` and ``flctool.exporters``; each entry point names a :class:`Plugin`
object (docs/plugins.md). Only packages the user installed are loaded this way: nothing a
behaviour file says makes flctool import a module.
"""

from __future__ import annotations

import importlib
import warnings
from dataclasses import dataclass
from functools import cache
from importlib.metadata import entry_points
from typing import Any

from pydantic import BaseModel

from flctool.errors import PluginWarning
from flctool.registry import Registry

GROUPS = {"learner": "flctool.learners", "environment": "flctool.environments",
          "exporter": "flctool.exporters"}


@dataclass(frozen=True)
class Plugin:
    """One learner, environment adapter or export format.

    ``config`` is the model of the section the plugin reads: for a learner a subclass of
    :class:`~flctool.spec.learning.LearningConfig` adding the learner's own keys whose
    ``learner`` is ``Literal[name]``; for an adapter a subclass of
    :class:`~flctool.spec.environment.AdapterConfig` whose ``adapter`` is ``Literal[name]``;
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


_LEARNING = "flctool.spec.learning"
_ENVIRONMENT = "flctool.spec.environment"

BUILTIN: dict[str, tuple[Plugin, ...]] = {
    "learner": (
        Plugin("pitt", "flctool.learners.pitt:PittLearner", f"{_LEARNING}:PittConfig"),
        Plugin("fuzzy_q", "flctool.learners.fuzzy_q:FuzzyQLearner",
               f"{_LEARNING}:FuzzyQConfig"),
        Plugin("hybrid", "flctool.learners.hybrid:HybridLearner", f"{_LEARNING}:HybridConfig"),
    ),
    "environment": (
        Plugin("ballchase-sim", "flctool.envs.ballchase:BallchaseSim",
               f"{_ENVIRONMENT}:BallchaseSimConfig"),
        Plugin("pitch", "flctool.envs.pitch:PitchSim", f"{_ENVIRONMENT}:PitchConfig"),
        Plugin("gymnasium", "flctool.envs.gym_adapter:GymnasiumEnv",
               f"{_ENVIRONMENT}:GymnasiumConfig"),
        Plugin("robot-link", "flctool.envs.robot_link:RobotLinkEnv",
               f"{_ENVIRONMENT}:RobotLinkConfig"),
        Plugin("ros2", "flctool.envs.ros2_env:Ros2Env", "flctool.spec.ros2:Ros2Config"),
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
    installed ones, in entry-point name order. A broken installed plugin is skipped with a
    :class:`PluginWarning` saying which package to fix or uninstall."""
    found = list(BUILTIN[kind])
    taken = {plugin.name for plugin in found}
    points = sorted(entry_points(group=GROUPS[kind]), key=lambda p: p.name)
    if points and kind != "exporter":
        # An installed learner's or adapter's config extends a model of flctool.spec, whose
        # behaviour model is built from these lists: built first, so that loading the plugin
        # does not come back here halfway through (and see a half-imported plugin).
        importlib.import_module("flctool.spec.models")
    for point in points:
        where = f"entry point '{point.name}' = '{point.value}' in group {GROUPS[kind]}"
        try:
            plugin = point.load()
        except Exception as error:  # a third party's import error must not stop flctool
            warnings.warn(f"skipped the {kind} plugin of {where}: it does not import "
                          f"({type(error).__name__}: {error}); fix or uninstall its package",
                          PluginWarning, stacklevel=2)
            continue
        problem = _problem(kind, plugin, taken)
        if problem:
            warnings.warn(f"skipped the {kind} plugin of {where}: {problem}", PluginWarning,
                          stacklevel=2)
            continue
        found.append(plugin)
        taken.add(plugin.name)
    return tuple(found)


def names(kind: str) -> tuple[str, ...]:
    """The names of every plugin of ``kind``, built-in first."""
    return tuple(plugin.name for plugin in plugins(kind))


def _problem(kind: str, plugin: object, taken: set[str]) -> str | None:
    if not isinstance(plugin, Plugin):
        return f"it names a {type(plugin).__name__}, not a flctool.plugins.Plugin"
    if plugin.name in taken:
        return f"the name '{plugin.name}' is taken"
    if ":" not in plugin.target:
        return f"target '{plugin.target}' is not 'module:attribute'"
    if kind == "exporter":
        bad = [s for s in plugin.suffixes if not (s.startswith(".") and len(s) > 1)]
        return f"suffixes {bad} must each be '.' and a name" if bad else None
    from flctool.spec.environment import AdapterConfig
    from flctool.spec.learning import LearningConfig

    try:
        config = plugin.config_model()
    except Exception as error:  # a third party's config that does not import or is no model
        return f"its config cannot be used ({type(error).__name__}: {error})"
    if kind == "environment" and not issubclass(config, AdapterConfig):
        return "an adapter's config must extend flctool.spec.environment.AdapterConfig"
    if kind == "learner" and not issubclass(config, LearningConfig):
        return "a learner's config must extend flctool.spec.learning.LearningConfig"
    tag = "learner" if kind == "learner" else "adapter"
    field = config.model_fields.get(tag)
    if field is None or getattr(field.annotation, "__args__", None) != (plugin.name,):
        return f"its config must declare {tag}: Literal['{plugin.name}']"
    return None


def export_suffixes() -> dict[str, str]:
    """Suffix -> export format, from the exporters' entries (the first to claim one keeps it)."""
    found: dict[str, str] = {}
    for plugin in plugins("exporter"):
        for suffix in plugin.suffixes:
            found.setdefault(suffix.lower(), plugin.name)
    return found


def registry(kind: str, label: str) -> Registry[Any]:
    """A registry of every plugin of ``kind`` by name, each loaded when first used."""
    found: Registry[Any] = Registry(label)
    for plugin in plugins(kind):
        found.register(plugin.name, plugin.target)
    return found
