"""validate_file: the adapter's checks run whenever the adapter can be built, located in the
file; a robot link is not connected to, and says so; a module-naming id runs no code."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from flctool.behaviour import gym_registry
from flctool.envs.preflight import check_adapter, validate_file
from flctool.errors import EnvError, SpecError

from ..conftest import BEHAVIOURS

CARTPOLE = (BEHAVIOURS / "cartpole.yaml").read_text(encoding="utf-8")


def _write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "b.yaml"
    path.write_text(text, encoding="utf-8")
    return path


def _line_of(text: str, needle: str) -> int:
    return next(i for i, line in enumerate(text.splitlines(), 1) if needle in line)


def test_shipped_files_pass_with_their_adapters_checked() -> None:
    for name in ("ballchase.yaml", "cartpole.yaml", "mountaincar.yaml"):
        report = validate_file(BEHAVIOURS / name)
        assert report.adapter_note == "" and report.warnings == []


def test_a_robot_link_is_not_connected_and_says_so() -> None:
    report = validate_file(BEHAVIOURS / "ballchase-robot.yaml")
    assert "when learn connects to the robot" in report.adapter_note


@pytest.mark.parametrize(("old", "new", "needle", "message"), [
    ("id: CartPole-v1", "id: CartPol-v1", "id: CartPol-v1", "Gymnasium cannot make"),
    ("pole_velocity: 3", "pole_velocity: 7", "pole_velocity: 7", "index 7 is out of range"),
    ("push_right: 1}", "push_right: 5}", "push_right: 5}", "action 5 is not in the action space"),
])
def test_adapter_problems_are_reported_at_their_line(tmp_path: Path, old: str, new: str,
                                                     needle: str, message: str) -> None:
    assert old in CARTPOLE
    text = CARTPOLE.replace(old, new)
    with pytest.raises(SpecError) as info:
        validate_file(_write(tmp_path, text))
    problem = info.value.problems[0]
    assert message in problem.message
    assert problem.line == _line_of(text, needle)


def test_a_command_without_an_action_is_reported(tmp_path: Path) -> None:
    text = CARTPOLE.replace("    push_right: 1.0\n", "    push_right: 1.0\n    coast: 0.0\n")
    with pytest.raises(SpecError) as info:
        validate_file(_write(tmp_path, text))
    assert "command 'coast' has no action" in str(info.value)


def test_two_commands_on_one_value_are_a_located_warning(tmp_path: Path) -> None:
    text = CARTPOLE.replace("push_right: 1.0", "push_right: -1.0")
    report = validate_file(_write(tmp_path, text))
    assert [w.line for w in report.warnings] == [_line_of(text, "push_right: -1.0")]
    assert "the same value -1" in report.warnings[0].message


def test_an_id_naming_a_module_imports_nothing(tmp_path: Path,
                                               monkeypatch: pytest.MonkeyPatch) -> None:
    module = tmp_path / "planted_module.py"
    module.write_text("import sys\nsys.planted_module_ran = True\n", encoding="utf-8")
    monkeypatch.syspath_prepend(str(tmp_path))
    text = CARTPOLE.replace("id: CartPole-v1", "id: planted_module:CartPole-v1")
    with pytest.raises(SpecError) as info:
        validate_file(_write(tmp_path, text))
    assert "never runs code" in str(info.value) and "--import-module planted_module" in str(
        info.value)
    assert not hasattr(sys, "planted_module_ran")
    assert "planted_module" not in sys.modules
    # Only the user, on the command line, can allow it.
    monkeypatch.setattr(gym_registry, "_USER_MODULES", set())
    gym_registry.import_user_modules(["planted_module"])
    assert getattr(sys, "planted_module_ran", False)
    assert validate_file(_write(tmp_path, text)).behaviour.name == "cartpole"
    monkeypatch.delattr(sys, "planted_module_ran")
    monkeypatch.delitem(sys.modules, "planted_module")


def test_a_module_that_cannot_be_imported_is_a_clear_error() -> None:
    with pytest.raises(EnvError, match="cannot import the module 'no_such_module_x'"):
        gym_registry.import_user_modules(["no_such_module_x"])


def test_a_singleton_outside_a_box_action_space_is_reported(tmp_path: Path) -> None:
    text = ((BEHAVIOURS / "mountaincar.yaml").read_text(encoding="utf-8")
            .replace("id: MountainCar-v0", "id: MountainCarContinuous-v0")
            .replace("  actions: {push_left: 0, coast: 1, push_right: 2}\n", "")
            .replace("push_right: 1.0", "push_right: 3.0"))
    with pytest.raises(SpecError) as info:
        validate_file(_write(tmp_path, text))
    problem = info.value.problems[0]
    assert "singleton 3 is outside the action space [-1, 1]" in problem.message
    assert problem.line == _line_of(text, "push_right: 3.0")


@pytest.mark.slow
def test_the_simulators_are_checked_by_loading_without_numpy() -> None:
    # Their construction checks nothing beyond fit_problems (run by loading), so validate does
    # not build them and stays clear of numpy; building them must then never fail on a file
    # that loads.
    for path in sorted(BEHAVIOURS.glob("*.yaml")):
        report = validate_file(path)
        environment = report.behaviour.environment
        if environment is not None and environment.adapter in ("ballchase-sim", "pitch"):
            check_adapter(report.behaviour)
    probe = ("import sys\nfrom flctool.envs.preflight import validate_file\n"
             f"validate_file({str(BEHAVIOURS / 'ballchase.yaml')!r})\n"
             f"validate_file({str(BEHAVIOURS / 'dribble.yaml')!r})\n"
             "print('numpy' in sys.modules)\n")
    result = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True,
                            check=True)
    assert result.stdout.strip() == "False"
