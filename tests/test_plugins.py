"""Plugins: every entry honours the contract, and an installed third-party package's learner
and environment are used from a behaviour file without touching flctool."""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
import typing
from pathlib import Path

import pytest

from flctool.behaviour.learning import LearningConfig
from flctool.behaviour.sections import ENVIRONMENT, LEARNING
from flctool.envs import ENVIRONMENTS
from flctool.export import EXPORTERS, Exporter
from flctool.learners import LEARNERS, Learner
from flctool.plugins import BUILTIN, Plugin, _problem, plugins

PACKAGE = Path(__file__).parent / "plugin_package"
ROOT = Path(__file__).resolve().parents[1]

DEMO = """\
flctool: 1
name: line-demo
inputs:
  x:
    range: [0, 10]
    sets: {low: [0, 0, 2, 6], mid: [2, 5, 5, 8], high: [4, 8, 10, 10]}
output:
  name: u
  commands: {down: -1, stay: 0, up: 1}
learning:
  learner: random_search
  keep: 2
  population: 6
  generations: 4
  selection: {candidates: 2, episodes: 5}
environment:
  adapter: line
  max_steps: 15
"""


@pytest.mark.parametrize("plugin", plugins("learner"), ids=lambda p: p.name)
def test_every_learner_entry_loads_a_learner_reading_learning_config(plugin: Plugin) -> None:
    assert issubclass(LEARNERS.get(plugin.name), Learner)
    assert issubclass(plugin.config_model(), LearningConfig)
    assert _problem("learner", plugin, set()) is None
    assert LEARNING.checked(plugin) is plugin.config_model()


@pytest.mark.parametrize("plugin", plugins("environment"), ids=lambda p: p.name)
def test_every_environment_entry_loads_a_factory_tagged_by_its_name(plugin: Plugin) -> None:
    assert callable(ENVIRONMENTS.get(plugin.name).from_behaviour)
    annotation = plugin.config_model().model_fields["adapter"].annotation
    assert typing.get_args(annotation) == (plugin.name,)
    assert _problem("environment", plugin, set()) is None
    assert ENVIRONMENT.checked(plugin) is plugin.config_model()


@pytest.mark.parametrize("plugin", plugins("exporter"), ids=lambda p: p.name)
def test_every_exporter_entry_loads_an_exporter(plugin: Plugin) -> None:
    assert issubclass(EXPORTERS.get(plugin.name), Exporter)


def test_registries_hold_exactly_the_plugins() -> None:
    for kind, registry in (("learner", LEARNERS), ("environment", ENVIRONMENTS),
                           ("exporter", EXPORTERS)):
        assert registry.names() == tuple(p.name for p in plugins(kind))
        assert set(p.name for p in BUILTIN[kind]) <= set(registry.names())


@pytest.mark.parametrize(("plugin", "problem"), [
    (object(), "not a flctool.plugins.Plugin"),
    (Plugin("pitt", "x:Y", LearningConfig), "the name 'pitt' is taken"),
    (Plugin("mine", "no_colon", LearningConfig), "is not 'module:attribute'"),
    (Plugin("mine", "x:Y"), "it names no config"),
])
def test_a_bad_learner_plugin_is_refused_with_the_reason(plugin: object, problem: str) -> None:
    found = _problem("learner", plugin, {"pitt"})
    assert found is not None and problem in found


@pytest.mark.parametrize(("plugin", "problem"), [
    (Plugin("mine", "x:Y", "no.such.module:Config"), "its config cannot be used"),
    (Plugin("mine", "x:Y", "flctool.behaviour.environment:PitchConfig"), "must extend"),
    (Plugin("mine", "x:Y", "flctool.behaviour.base:Section"), "must extend"),
    (Plugin("mine", "x:Y", type("Mine", (LearningConfig,), {})),
     "must declare learner: Literal['mine']"),
    (Plugin("mine", "x:Y", LearningConfig), "must declare learner: Literal['mine']"),
    (Plugin("mine", "x:Y", "flctool.behaviour.learning:PittConfig"),
     "must declare learner: Literal['mine']"),
])
def test_a_learner_plugin_whose_model_cannot_read_learning_is_refused(plugin: Plugin,
                                                                      problem: str) -> None:
    found = LEARNING.checked(plugin)
    assert isinstance(found, str) and problem in found


def _with_package(site: Path = PACKAGE) -> dict[str, str]:
    """The environment of a process in which the plugin package in ``site`` is installed:
    its package and dist-info folders on the path are what ``pip install`` leaves."""
    return {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(site), *filter(None, [os.environ.get("PYTHONPATH")])])}


def _flctool(tmp_path: Path, *args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "flctool", *args], cwd=tmp_path,
                          env=_with_package(), capture_output=True, text=True, timeout=120)


@pytest.fixture
def installed_copy(tmp_path: Path) -> dict[str, str]:
    """An environment with a copy of the plugin package installed in a folder of its own."""
    site = tmp_path / "site-packages"
    shutil.copytree(PACKAGE, site, ignore=shutil.ignore_patterns("__pycache__"))
    return _with_package(site)


@pytest.mark.slow
def test_with_a_plugin_installed_the_schema_check_passes(installed_copy: dict[str, str]) -> None:
    # The committed schema describes the built-ins, wherever it is checked.
    checked = subprocess.run([sys.executable, "-m", "flctool", "schema", "--check"], cwd=ROOT,
                             env=installed_copy, capture_output=True, text=True, timeout=120)
    assert checked.returncode == 0, checked.stderr
    listed = subprocess.run([sys.executable, "-m", "flctool", "learn", "--help"], cwd=ROOT,
                            env=installed_copy, capture_output=True, text=True, timeout=120)
    assert "random_search" in listed.stdout  # and it is installed


@pytest.mark.slow
def test_a_file_naming_only_built_ins_does_not_import_an_installed_plugin(
        installed_copy: dict[str, str]) -> None:
    code = ("import sys; from flctool import load_behaviour; from flctool.envs import make_env; "
            "make_env(load_behaviour('behaviours/ballchase.yaml')); "
            "print('flctool_demo' in sys.modules)")
    result = subprocess.run([sys.executable, "-c", code], cwd=ROOT, env=installed_copy,
                            capture_output=True, text=True, timeout=120)
    assert result.stdout.split() == ["False"], result.stderr


@pytest.mark.slow
def test_with_a_plugin_installed_the_readme_runs(installed_copy: dict[str, str]) -> None:
    # The part of the README's test command that a plugin once broke: its code blocks,
    # the schema check among them.
    result = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider",
                             "tests/test_docs.py", "-k", "README", "-m", "slow"],
                            cwd=ROOT, env=installed_copy, capture_output=True, text=True,
                            timeout=600)
    assert result.returncode == 0, result.stdout[-3000:]
    assert "1 passed" in result.stdout


@pytest.mark.slow
def test_an_installed_learner_and_environment_run_from_a_behaviour_file(tmp_path: Path) -> None:
    (tmp_path / "demo.yaml").write_text(DEMO)
    validated = _flctool(tmp_path, "validate", "demo.yaml")
    assert validated.returncode == 0, validated.stderr
    learned = _flctool(tmp_path, "learn", "demo.yaml", "--out", "run")
    assert learned.returncode in (0, 3), learned.stderr  # 3: it ended, but not learned
    assert (tmp_path / "run" / "best.yaml").is_file()
    assert "learner: random_search" in (tmp_path / "run" / "best.yaml").read_text()
    evaluated = _flctool(tmp_path, "evaluate", "run/best.yaml", "--episodes", "20")
    assert evaluated.returncode == 0, evaluated.stderr


def test_a_plugins_own_keys_are_checked_and_located(tmp_path: Path) -> None:
    (tmp_path / "demo.yaml").write_text(DEMO.replace("  keep: 2", "  kepp: 2")
                                        .replace("max_steps: 15", "max_steps: -1"))
    result = _flctool(tmp_path, "validate", "demo.yaml")
    assert result.returncode == 1
    assert "demo.yaml:12:3: learning.kepp: unknown key 'kepp'. Did you mean 'keep'?" in (
        result.stderr)
    assert ("demo.yaml:18:3: environment.max_steps: input should be greater than or equal to 1"
            in result.stderr)


@pytest.mark.slow
def test_another_learners_key_under_a_plugin_learner_names_who_reads_it(
        tmp_path: Path) -> None:
    (tmp_path / "demo.yaml").write_text(DEMO.replace("  keep: 2", "  crossover: 0.3"))
    result = _flctool(tmp_path, "validate", "demo.yaml")
    assert result.returncode == 1
    assert ("demo.yaml:12:3: learning.crossover: 'crossover' is read by the pitt and hybrid "
            "learners, not by random_search") in " ".join(result.stderr.split())
    (tmp_path / "pitt.yaml").write_text(DEMO.replace("learner: random_search\n  keep: 2",
                                                     "learner: pitt\n  mutation: 0.2"))
    switched = _flctool(tmp_path, "learn", "pitt.yaml", "--learner", "random_search",
                        "--out", "run", "--json")
    assert switched.returncode in (0, 3), switched.stderr
    assert "keep: 1" in (tmp_path / "run" / "behaviour.yaml").read_text()


@pytest.mark.slow
def test_without_the_package_its_names_are_unknown(tmp_path: Path) -> None:
    (tmp_path / "demo.yaml").write_text(DEMO)
    result = subprocess.run([sys.executable, "-m", "flctool", "validate", "demo.yaml"],
                            cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert result.returncode == 1
    assert "unknown adapter 'line'" in result.stderr
    assert "unknown learner 'random_search'" in result.stderr


def test_an_entry_point_must_be_named_like_its_plugin() -> None:
    # flctool finds an installed plugin by the name of its entry point, importing no other
    found = _problem("learner", Plugin("mine", "x:Y", LearningConfig), set(), "yours")
    assert found is not None and "name the entry point 'mine'" in found


def test_an_adapter_plugin_must_extend_adapter_config() -> None:
    found = ENVIRONMENT.checked(Plugin("mine", "x:Y", "flctool.behaviour.base:Section"))
    assert isinstance(found, str)
    assert "must extend flctool.behaviour.environment.AdapterConfig" in found


BROKEN = '''\
from typing import Literal

from pydantic import field_validator

from flctool.plugins import Plugin
from flctool.behaviour.environment import AdapterConfig


class WobblyConfig(AdapterConfig):
    adapter: Literal["wobbly"]
    max_steps: int = 5

    @field_validator("max_steps")
    @classmethod
    def _check(cls, value: int) -> int:
        return {}[value]  # a bug of the plugin's: KeyError


ENVIRONMENT = Plugin("wobbly", "flctool_wobbly:Nothing", WobblyConfig)
'''


def test_an_error_inside_a_plugins_check_is_named_as_the_plugins(tmp_path: Path) -> None:
    site = tmp_path / "site-packages"
    (site / "flctool_wobbly-0.1.dist-info").mkdir(parents=True)
    (site / "flctool_wobbly-0.1.dist-info" / "METADATA").write_text(
        "Metadata-Version: 2.1\nName: flctool-wobbly\nVersion: 0.1\n")
    (site / "flctool_wobbly-0.1.dist-info" / "entry_points.txt").write_text(
        "[flctool.environments]\nwobbly = flctool_wobbly:ENVIRONMENT\n")
    (site / "flctool_wobbly.py").write_text(BROKEN)
    (tmp_path / "demo.yaml").write_text(DEMO.replace("adapter: line", "adapter: wobbly")
                                        .replace("  max_steps: 15", "  max_steps: 3"))
    result = subprocess.run([sys.executable, "-m", "flctool", "validate", "demo.yaml"],
                            cwd=tmp_path, env=_with_package(site), capture_output=True,
                            text=True, timeout=120)
    assert result.returncode == 1
    message = " ".join(result.stderr.split())
    assert "the environment plugin 'wobbly' (flctool_wobbly:Nothing) failed: KeyError: 3" in (
        message)
    assert "report it to the authors of its package (flctool_wobbly)" in message
    assert "internal error" not in message and "Traceback" not in result.stderr


@pytest.mark.slow
def test_a_plugin_learners_own_state_is_checkpointed_and_resumed_bit_for_bit(
        tmp_path: Path) -> None:
    (tmp_path / "demo.yaml").write_text(DEMO)
    for args in (("--out", "parts", "-g", "2"), ("--resume", "parts", "-g", "4"),
                 ("--out", "straight",)):
        result = _flctool(tmp_path, "learn", *(("demo.yaml",) if "--out" in args else ()),
                          *args)
        assert result.returncode in (0, 3), result.stderr  # 3: it ended, but not learned
    checkpoints = sorted((tmp_path / "parts" / "checkpoints").iterdir())
    assert json.loads(checkpoints[-1].read_text())["drawn"] == 6 + 3 * (6 - 2)  # its hook
    assert (tmp_path / "parts" / "best.yaml").read_text().split("\n", 2)[2] == (
        tmp_path / "straight" / "best.yaml").read_text().split("\n", 2)[2]


def test_the_plugins_page_shows_the_package_as_it_is() -> None:
    # docs/plugins.md lists the package's files for readers to copy: word for word these
    page = (ROOT / "docs" / "plugins.md").read_text(encoding="utf-8")
    blocks = re.findall(r"^```(?:python|toml)\n# (\S+)\n(.*?)^```$", page, re.M | re.S)
    assert sorted(name for name, _ in blocks) == [
        "flctool_demo/__init__.py", "flctool_demo/env.py", "flctool_demo/learner.py",
        "pyproject.toml"]
    for name, text in blocks:
        assert text == (PACKAGE / name).read_text(encoding="utf-8"), name
