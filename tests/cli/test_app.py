"""The conventions every command shares (docs/cli.md), checked over every registered command,
so a command added later is held to them without a test of its own."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest
import typer
from typer.testing import CliRunner

from flctool.cli import app
from flctool.cli.app import COMMANDS as COMMAND_TABLE
from flctool.cli.app import output_format

from ..conftest import BEHAVIOURS, restore_sigint

runner = CliRunner()
HANDMADE = str(BEHAVIOURS / "ballchase-handmade.yaml")


def _commands() -> dict[str, typer.core.TyperCommand]:
    group = typer.main.get_command(app)
    assert isinstance(group, typer.core.TyperGroup)
    context = group.context_class(group, info_name="flctool")
    return {name: group.get_command(context, name)  # type: ignore[misc]
            for name in group.list_commands(context)}


COMMANDS = sorted(_commands())


def test_the_known_commands_are_registered() -> None:
    assert {"validate", "show", "schema", "infer", "learn", "evaluate", "export", "import",
            "plot", "serve"} <= set(COMMANDS)


@pytest.mark.parametrize("command", COMMANDS)
@pytest.mark.parametrize("flag", ["-h", "--help"])
def test_help_has_usage_and_an_example(command: str, flag: str) -> None:
    result = runner.invoke(app, [command, flag])
    assert result.exit_code == 0, result.output
    assert result.output.startswith(f"Usage: flctool {command}")
    assert re.search(rf"Examples?:\n\s+flctool {command}\b", result.output), result.output


@pytest.mark.parametrize("command", COMMANDS)
def test_boolean_options_are_flags(command: str) -> None:
    text = runner.invoke(app, [command, "--help"]).output
    for param in _commands()[command].params:
        if getattr(param, "is_flag", False):
            # shown as the bare flag, then its help: no value to give
            for name in param.opts:
                assert re.search(rf"{re.escape(name)}(, -\w)?\s{{2,}}\w", text), (name, text)
    assert "<bool>" not in text and "BOOLEAN" not in text


@pytest.mark.parametrize("command", COMMANDS)
def test_an_unknown_option_is_a_usage_error_in_one_style(command: str) -> None:
    result = runner.invoke(app, [command, "--no-such-option"])
    assert result.exit_code == 2
    first = result.output.splitlines()[0]
    assert first.startswith(f"error: flctool {command}: no such option: --no-such-option")
    assert f"(fix: see 'flctool {command} --help')" in first
    assert "╭" not in result.output and "Traceback" not in result.output


def _takes_a_path(command: str) -> bool:
    """Whether the command runs with nothing but one path given (its only required value is
    a path argument)."""
    required = [p for p in _commands()[command].params if p.required]
    return len(required) == 1 and all(
        p.param_type_name == "argument" and "Path" in str(getattr(p, "bare_type", str)())
        for p in required)


@pytest.mark.parametrize("command", [c for c in COMMANDS if _takes_a_path(c)])
def test_a_missing_input_is_bad_input(command: str, tmp_path: Path) -> None:
    missing = tmp_path / "none.yaml"
    result = runner.invoke(app, [command, str(missing)], input="")
    assert result.exit_code == 1, result.output
    assert result.output.startswith("error: ")
    assert "none.yaml" in result.output and "Traceback" not in result.output


def test_a_missing_argument_and_a_bad_value_are_usage_errors() -> None:
    missing = runner.invoke(app, ["show"])
    assert missing.exit_code == 2 and missing.output.startswith("error: flctool show: ")
    bad = runner.invoke(app, ["evaluate", HANDMADE, "--episodes", "many"])
    assert bad.exit_code == 2 and "invalid value for '--episodes'" in bad.output


def test_unknown_command_and_no_command() -> None:
    unknown = runner.invoke(app, ["lern"])
    assert unknown.exit_code == 2 and unknown.output.startswith("error: flctool: no such "
                                                                "command 'lern'")
    bare = runner.invoke(app, [])
    assert bare.exit_code == 0 and bare.output.startswith("Usage: flctool")


@pytest.mark.parametrize("command", ["show", "evaluate", "infer", "validate"])  # export: its own
def test_a_run_directory_stands_for_its_best_controller(command: str, tmp_path: Path) -> None:
    run = tmp_path / "run"
    run.mkdir()
    empty = runner.invoke(app, [command, str(run)], input="ball_size,pan\n0.1,2\n")
    assert empty.exit_code == 1 and empty.output.startswith("error: ")
    assert "best.yaml" in empty.output or "not a run directory" in empty.output
    (run / "best.yaml").write_text((BEHAVIOURS / "ballchase-handmade.yaml").read_text())
    extra = {"evaluate": ["--episodes", "3"]}.get(command, [])
    result = runner.invoke(app, [command, str(run), *extra], input="ball_size,pan\n0.1,2\n")
    assert result.exit_code == 0, result.output


@pytest.mark.parametrize("command, arguments", [
    ("export", [HANDMADE, "-o", "{target}.yaml"]),
    ("infer", [HANDMADE, "-o", "{target}.csv"]),
    ("evaluate", [HANDMADE, "--episodes", "2", "--trace", "{target}.csv"]),
    ("schema", ["-o", "{target}.json"]),
])
@pytest.mark.slow
def test_outputs_create_folders_and_are_replaced_only_with_force(
        command: str, arguments: list[str], tmp_path: Path) -> None:
    target = tmp_path / "new" / "folder" / "out"
    args = [command, *(a.format(target=target) for a in arguments)]
    states = "ball_size,pan\n0.1,2\n"
    first = runner.invoke(app, args, input=states)
    assert first.exit_code == 0, first.output
    written = next(target.parent.iterdir())
    written.write_text("mine")
    again = runner.invoke(app, args, input=states)
    assert again.exit_code == 1 and "already exists" in again.output
    assert "--force" in again.output and written.read_text() == "mine"
    forced = runner.invoke(app, [*args, "--force"], input=states)
    assert forced.exit_code == 0, forced.output
    assert written.read_text() != "mine"


@pytest.mark.parametrize("suffix, magic", [(".fll", "Engine:"), (".json", "{"),
                                           (".fcl", "FUNCTION_BLOCK"), (".fis", "[System]")])
def test_export_format_follows_the_suffix(suffix: str, magic: str, tmp_path: Path) -> None:
    target = tmp_path / f"x{suffix}"
    result = runner.invoke(app, ["export", HANDMADE, "-o", str(target)])
    assert result.exit_code == 0, result.output
    assert magic in target.read_text()


def test_export_format_and_suffix_must_agree(tmp_path: Path) -> None:
    result = runner.invoke(app, ["export", HANDMADE, "-o", str(tmp_path / "x.fll"),
                                 "--format", "yaml"])
    assert result.exit_code == 1
    assert "has the suffix of the fll format, but --format is yaml" in result.output
    assert not (tmp_path / "x.fll").exists()
    c_files = runner.invoke(app, ["export", HANDMADE, "-o", str(tmp_path / "flc.c")])
    assert c_files.exit_code == 0 and (tmp_path / "flc.h").exists()


def test_import_writes_yaml_only_under_a_yaml_name(tmp_path: Path) -> None:
    fll = tmp_path / "x.fll"
    runner.invoke(app, ["export", HANDMADE, "-o", str(fll)])
    wrong = runner.invoke(app, ["import", str(fll), "-o", str(tmp_path / "y.json")])
    assert wrong.exit_code == 1 and "import writes a behaviour file (YAML)" in wrong.output


def test_output_format_rules() -> None:
    suffixes = {".a": "a", ".b": "b"}
    assert output_format(None, None, suffixes, "a") == "a"
    assert output_format(Path("x.B"), None, suffixes, "a") == "b"
    assert output_format(Path("x"), "b", suffixes, "a") == "b"
    with pytest.raises(Exception, match="cannot tell the format"):
        output_format(Path("x.txt"), None, suffixes, "a")


def test_the_command_list_is_that_of_the_commands_themselves() -> None:
    # `flctool --help` lists the commands from app.COMMANDS without importing them
    commands = _commands()
    assert list(commands)[: len(COMMAND_TABLE)] == list(COMMAND_TABLE)
    for name, (module, summary) in COMMAND_TABLE.items():
        command = commands[name]
        assert command.callback is not None and command.callback.__module__ == module, name
        first_paragraph = (command.help or "").split("\n\n")[0]
        assert " ".join(first_paragraph.split()) == summary, name


@pytest.mark.parametrize("options", [["--version"], ["--help"], []])
def test_start_up_loads_no_command_and_no_heavy_module(options: list[str]) -> None:
    result = _run_python(
        "import sys\n"
        f"sys.argv = ['flctool', *{options!r}]\n"
        "from flctool.cli import run\n"
        "try:\n"
        "    run()\n"
        "finally:\n"
        "    loaded = [m for m in ('numpy', 'pydantic', 'rich', 'yaml', 'flctool.behaviour')\n"
        "              if m in sys.modules]\n"
        "    loaded += [m for m in sys.modules if m.startswith('flctool.cli.')\n"
        "               and m != 'flctool.cli.app']\n"
        "    print('loaded:', loaded)\n")
    assert result.returncode == 0, result.stderr
    assert result.stdout.splitlines()[-1] == "loaded: []"


@pytest.mark.slow
def test_a_command_loads_its_own_module_only() -> None:
    result = _run_python(
        "import sys\n"
        "sys.argv = ['flctool', 'new', '--help']\n"
        "from flctool.cli import run\n"
        "try:\n"
        "    run()\n"
        "finally:\n"
        "    print('loaded:', sorted(m for m in sys.modules if m.startswith('flctool.cli.')))\n")
    assert result.returncode == 0, result.stderr
    assert "Scaffold a valid behaviour file" in result.stdout
    assert result.stdout.splitlines()[-1] == "loaded: ['flctool.cli.app', 'flctool.cli.new']"


@pytest.mark.slow
def test_a_mistyped_command_is_suggested_before_any_is_loaded() -> None:
    result = _run_python(
        "import sys\n"
        "sys.argv = ['flctool', 'lern']\n"
        "from flctool.cli import run\n"
        "run()\n")
    assert result.returncode == 2
    assert "no such command 'lern'. Did you mean 'learn'?" in result.stderr


def _run_python(code: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=120, preexec_fn=restore_sigint)


def test_ctrl_c_during_start_up_imports_is_one_line_and_130() -> None:
    # Ctrl-C while the command line's modules are still being imported
    result = _run_python(
        "import sys\n"
        "class Interrupt:\n"
        "    def find_spec(self, name, path=None, target=None):\n"
        "        if name == 'typer':\n"
        "            raise KeyboardInterrupt\n"
        "sys.meta_path.insert(0, Interrupt())\n"
        "sys.argv = ['flctool', '--version']\n"
        "from flctool.cli import run\n"
        "run()\n")
    assert result.returncode == 130
    assert result.stderr == "interrupted\n"


@pytest.mark.slow
def test_ctrl_c_turned_into_another_error_is_still_an_interruption() -> None:
    # numba, interrupted while it compiles, raises its own error chained to the
    # KeyboardInterrupt: still one line and 130, not a traceback and exit 1
    result = _run_python(
        "import os, signal, sys\n"
        "from flctool.cli import app, run\n"
        "@app.command('compile-now')\n"
        "def compile_now() -> None:\n"
        "    try:\n"
        "        os.kill(os.getpid(), signal.SIGINT)\n"
        "        import time; time.sleep(5)\n"
        "    except KeyboardInterrupt as error:\n"
        "        raise RuntimeError('failed in nopython mode pipeline') from error\n"
        "sys.argv = ['flctool', 'compile-now']\n"
        "run()\n")
    assert result.returncode == 130, result.stderr
    assert result.stderr == "interrupted\n"


@pytest.mark.parametrize("command", ["export", "infer", "show"])
@pytest.mark.slow
def test_stdout_to_a_full_device_is_a_clear_error(command: str, tmp_path: Path) -> None:
    if not Path("/dev/full").exists():
        pytest.skip("no /dev/full on this system")
    states = tmp_path / "states.csv"
    states.write_text("ball_size,pan\n" + "0.25,12.5\n" * 5000)
    extra = ["-i", str(states)] if command == "infer" else []
    with open("/dev/full", "w") as full:
        result = subprocess.run([sys.executable, "-m", "flctool", command, HANDMADE, *extra],
                                stdout=full, stderr=subprocess.PIPE, text=True, timeout=60)
    assert result.returncode == 1, result.stderr
    assert "no space left on device" in result.stderr and "Traceback" not in result.stderr
