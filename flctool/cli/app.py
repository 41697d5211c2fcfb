"""The typer app, the conventions every command shares, and the one place errors become exit
codes. The conventions are written down for users in docs/cli.md.

- **Errors**: one style, ``error: what (fix: how)`` on stderr. Exit 1 for bad input (a file
  that is missing or invalid, an output that exists), 2 for bad usage (an unknown option, a
  missing argument, a value of the wrong type), 130 after Ctrl-C. A traceback only with
  ``--debug``.
- **Input**: wherever a controller is expected, a behaviour file or a run directory (its
  ``best.yaml``) -- :func:`controller_file`.
- **Output**: ``-o`` creates missing parent folders; an existing file is replaced only with
  ``--force`` -- :func:`check_output` and :func:`write_output`.
- **Formats** follow the output's suffix; ``--format`` overrides it; a suffix that names
  another format is an error -- :func:`output_format`.
- **Progress** on stderr: a rich bar on a terminal, a plain line every few seconds otherwise
  -- :mod:`flctool.cli.progress`.

Every command module is imported only when its command runs (:data:`COMMANDS`), and imports
only what its command needs, inside the command, so that ``flctool --version`` and
``flctool --help`` load neither numpy, pydantic nor rich, and ``flctool validate`` does not pay
for numba or the learners.
"""

from __future__ import annotations

import difflib
import errno
import importlib
import os
import re
import signal
import sys
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from pathlib import Path
from types import FrameType
from typing import TYPE_CHECKING, Annotated, Any

import typer
from typer import _click as click  # typer >= 0.29 bundles click
from typer._click import exceptions as click_errors
from typer._click.globals import get_current_context
from typer._click.utils import make_default_short_help
from typer.core import TyperGroup
from typer.main import get_command_from_info, get_command_name

from flctool.errors import FlcError, InputFileError, Problem, SpecError
from flctool.inputs import no_such_file
from flctool.version import __version__

if TYPE_CHECKING:
    from flctool.behaviour import Behaviour
    from flctool.behaviour.overrides import Override

#: Exit codes, the same for every command.
EXIT_INPUT, EXIT_USAGE, EXIT_INTERRUPTED = 1, 2, 130

#: The file of a run directory that holds its best controller.
RUN_BEST_FILE = "best.yaml"

_state: dict[str, bool] = {"debug": False, "interrupted": False, "reported": False}


class FlctoolGroup(TyperGroup):
    """The top-level command group: renders usage errors in flctool's own style (instead of
    typer's boxes) and turns every way a command can end into one exit code."""

    def main(self, args: Sequence[str] | None = None, prog_name: str | None = None,
             complete_var: str | None = None, standalone_mode: bool = True,
             windows_expand_args: bool = True, **extra: Any) -> Any:
        _state.update(interrupted=False, reported=False)
        with _sigint_noted():
            code = self._run(args, prog_name or "flctool", complete_var,
                             windows_expand_args=windows_expand_args, **extra)
        code = _flush_stdout(code)
        if standalone_mode:
            sys.exit(code)
        return code

    # -- commands, imported on first use (see COMMANDS) ---------------------------------
    def list_commands(self, ctx: click.Context) -> list[str]:
        return [*COMMANDS, *(name for name in self.commands if name not in COMMANDS)]

    def get_command(self, ctx: click.Context, cmd_name: str) -> click.Command | None:
        command = self.commands.get(cmd_name)
        if command is None and cmd_name in COMMANDS:
            importlib.import_module(COMMANDS[cmd_name][0])  # registers its commands on app
            for info in app.registered_commands:
                name = info.name or get_command_name(info.callback.__name__)  # type: ignore[union-attr]
                if name == cmd_name:
                    command = get_command_from_info(
                        info, pretty_exceptions_short=app.pretty_exceptions_short,
                        rich_markup_mode=app.rich_markup_mode)
                    self.add_command(command, cmd_name)
        return command

    def format_commands(self, ctx: click.Context, formatter: click.HelpFormatter) -> None:
        """The list of commands from COMMANDS, without importing one."""
        limit = formatter.width - 6 - max(len(name) for name in COMMANDS)
        rows = [(name, make_default_short_help(summary, limit))
                for name, (_, summary) in COMMANDS.items()]
        with formatter.section("Commands"):
            formatter.write_dl(rows)

    def resolve_command(self, ctx: click.Context, args: list[str]
                        ) -> tuple[str | None, click.Command | None, list[str]]:
        try:
            return super().resolve_command(ctx, args)
        except click_errors.UsageError as error:
            # typer suggests only among the commands imported so far
            if args and "Did you mean" not in error.message:
                close = difflib.get_close_matches(args[0], list(COMMANDS))
                if close:
                    error.message = (error.message.rstrip(".") + ". Did you mean "
                                     + ", ".join(repr(name) for name in close) + "?")
            raise

    def _run(self, args: Sequence[str] | None, prog_name: str, complete_var: str | None,
             **extra: Any) -> int:
        try:
            result = super().main(args, prog_name, complete_var, standalone_mode=False,
                                  **extra)
        except click_errors.NoArgsIsHelpError as error:
            typer.echo(error.ctx.get_help() if error.ctx else "")
            return 0
        except click_errors.UsageError as error:
            _print_usage_error(error)
            return EXIT_USAGE
        except click_errors.ClickException as error:  # e.g. a file argument that cannot be opened
            print_message(error.format_message())
            return error.exit_code
        except typer.Abort:  # EOF or Ctrl-C at a prompt
            return _interrupted()
        except KeyboardInterrupt:
            return _interrupted()
        except OSError as error:
            if error.errno != errno.ENOSPC or _state["debug"]:
                raise
            _silence_stdout()  # e.g. stdout on a full device, while printing a table
            print_message("cannot write the output: no space left on device",
                          "free some space, or write elsewhere")
            return EXIT_INPUT
        except BaseException:
            if _state["interrupted"] and not _state["debug"]:
                # Ctrl-C inside a library that turned it into another exception (numba does,
                # while it compiles): still an interruption, not a crash.
                return _interrupted()
            raise
        if _state["interrupted"] or result == EXIT_INTERRUPTED:
            return _interrupted()
        return int(result) if isinstance(result, int) else 0


app = typer.Typer(
    name="flctool",
    cls=FlctoolGroup,
    help="Learned fuzzy logic controllers for reactive robot behaviours: declare a behaviour "
    "in YAML, learn its rules, export the controller.",
    epilog="\b\nExample:\n  flctool validate behaviours/ballchase.yaml\n"
    "  flctool learn behaviours/ballchase.yaml -o runs/first\n"
    "  flctool evaluate runs/first\n\nConventions shared by every command: docs/cli.md.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
    rich_markup_mode=None,  # plain click help: flags shown as flags, examples kept as written
    context_settings={"help_option_names": ["-h", "--help"], "max_content_width": 100},
)


def example(*lines: str) -> str:
    """A ``--help`` epilog giving example command lines, kept unwrapped."""
    return "\b\nExamples:\n" + "".join(f"  {line}\n" for line in lines)


def _version(value: bool) -> None:
    if value:
        typer.echo(f"flctool {__version__}")
        raise typer.Exit()


@app.callback()
def main(
    debug: Annotated[bool, typer.Option("--debug", help="Show full tracebacks on errors.")] = False,
    version: Annotated[bool, typer.Option(
        "--version", callback=_version, is_eager=True, help="Print the version and exit.")]
    = False,
    import_module: Annotated[list[str] | None, typer.Option(
        "--import-module", metavar="MODULE", help="Import this Python module first (it "
        "registers Gymnasium environments); an environment id 'MODULE:Env-v0' may then name "
        "it. A behaviour file never imports modules by itself.")] = None,
) -> None:
    _state["debug"] = debug
    if import_module:
        from flctool.behaviour.gym_registry import import_user_modules

        with user_errors():
            import_user_modules(import_module)


def debug_enabled() -> bool:
    """Whether --debug was given (tracebacks are wanted)."""
    return _state["debug"]


# -- messages --------------------------------------------------------------------------------
class _Consoles:
    """rich consoles, made on first use (importing rich costs start-up time)."""

    def __init__(self, stderr: bool) -> None:
        self._stderr = stderr
        self._console: Any = None

    def get(self) -> Any:
        """The rich Console itself."""
        if self._console is None:
            from rich.console import Console

            # soft_wrap: messages carry long file paths; hard-wrapping them breaks copy-paste.
            self._console = Console(stderr=self._stderr, soft_wrap=True)
        return self._console

    def __getattr__(self, name: str) -> Any:
        return getattr(self.get(), name)


console: Any = _Consoles(stderr=False)
err_console: Any = _Consoles(stderr=True)


def escape(text: str) -> str:
    """``text`` safe to print through rich (its square brackets are not markup)."""
    from rich.markup import escape as rich_escape

    return rich_escape(text)


_CONTROL = re.compile(r"[\x00-\x08\x0b-\x1f\x7f-\x9f]")


def plain(text: str) -> str:
    """``text`` with control characters (terminal escape sequences, carriage returns) shown
    as escapes: a message may quote a file or a robot, and must not drive the terminal."""
    return _CONTROL.sub(lambda match: f"\\x{ord(match.group()):02x}", text)


def say(text: str, label: str = "", colour: str = "green", err: bool = False) -> None:
    """One plain line (``label`` coloured on a terminal), without loading rich."""
    head = typer.style(label, fg=colour, bold=True) + " " if label else ""
    typer.echo(head + plain(text), err=err)


def print_message(message: str, hint: str = "") -> None:
    """One ``error: message (fix: hint)`` line on stderr."""
    fix = f" (fix: {hint})" if hint else ""
    say(message + fix, "error:", "red", err=True)


def print_error(error: FlcError) -> None:
    """Render a flctool error for a person: one located line per problem."""
    if isinstance(error, InputFileError):  # one line: the file and what is wrong with it
        say(str(error), "error:", "red", err=True)
        return
    if isinstance(error, SpecError):
        count = len(error.problems)
        say(f"{error.file or 'input'} has {count} problem{'s' if count != 1 else ''}",
            "error:", "red", err=True)
        for problem in error.problems:
            say(f"  {problem}", err=True)
        return
    say(str(error), "error:", "red", err=True)


def _print_usage_error(error: click_errors.UsageError) -> None:
    ctx = error.ctx
    path = ctx.command_path if ctx is not None else "flctool"
    message = error.format_message()
    print_message(f"{path}: {message[:1].lower() + message[1:]}",
                  f"see '{path} --help'")
    if ctx is not None:
        say(f"  {ctx.get_usage()}", err=True)


def usage_error(message: str, option: str | None = None) -> click_errors.UsageError:
    """A usage error (exit 2) of the running command, found after parsing (e.g. options that
    exclude each other)."""
    ctx = get_current_context(silent=True)
    if option is not None:
        return click_errors.BadParameter(message, ctx=ctx, param_hint=f"'{option}'")
    return click_errors.UsageError(message, ctx=ctx)


# -- exits -----------------------------------------------------------------------------------
def _interrupted() -> int:
    if not _state["reported"]:
        say("interrupted", err=True)
        _state["reported"] = True
    return EXIT_INTERRUPTED


def report_interrupted(message: str) -> None:
    """Say once, after Ctrl-C, what was interrupted (instead of a bare 'interrupted')."""
    say(message, "interrupted:", "yellow", err=True)
    _state["reported"] = True


@contextmanager
def _sigint_noted() -> Iterator[None]:
    """Note every Ctrl-C, so that one turned into another exception by a library is still
    reported as an interruption. SIGINT ignored by the caller stays ignored."""
    try:
        previous = signal.getsignal(signal.SIGINT)
    except ValueError:  # not the main thread
        yield
        return
    if previous is not signal.default_int_handler:
        yield
        return

    def handler(signum: int, frame: FrameType | None) -> None:
        _state["interrupted"] = True
        signal.default_int_handler(signum, frame)

    try:
        signal.signal(signal.SIGINT, handler)
    except ValueError:
        yield
        return
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


def _flush_stdout(code: int) -> int:
    """Flush stdout inside the command, so that a full device or a closed pipe is an error
    message (or, for a closed pipe, a quiet end), never a traceback at interpreter exit."""
    try:
        sys.stdout.flush()
    except BrokenPipeError:
        _silence_stdout()
        return code
    except OSError as error:
        _silence_stdout()
        if error.errno == errno.ENOSPC:
            print_message("cannot write to standard output: no space left on device",
                          "redirect the output to a device with free space, or use -o")
        else:
            print_message(f"cannot write to standard output: {error.strerror or error}")
        return code or EXIT_INPUT
    return code


def _silence_stdout() -> None:
    # Whatever is still buffered cannot be written; let the interpreter exit cleanly.
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
    except (OSError, ValueError):
        pass


@contextmanager
def user_errors() -> Iterator[None]:
    """Turn flctool errors into a message and exit code 1 (a traceback only with --debug)."""
    try:
        yield
    except FlcError as error:
        if _state["debug"]:
            raise
        print_error(error)
        raise typer.Exit(EXIT_INPUT) from None
    except KeyboardInterrupt:
        _interrupted()
        raise typer.Exit(EXIT_INTERRUPTED) from None
    except BrokenPipeError:  # e.g. `flctool infer ... | head`
        _silence_stdout()
        raise typer.Exit(0) from None
    except OSError as error:
        if error.errno != errno.ENOSPC or _state["debug"]:
            raise
        name = error.filename or "the output"
        print_message(f"cannot write {name}: no space left on device",
                      "free some space or write elsewhere")
        raise typer.Exit(EXIT_INPUT) from None


# -- input -----------------------------------------------------------------------------------
def command_line_overrides(assignments: Sequence[str],
                           options: Mapping[str, tuple[str, Any]] | None = None,
                           ) -> list[Override]:
    """The overrides a command line gives, each placed where it was given: ``--set
    key=value`` (the value read as YAML, or kept as text if it is not YAML) is at
    ``command line (--set key)``; ``options`` maps a key an option sets to the option and its
    value (``{"seed": ("--seed", 3)}``), at ``command line (--seed)``; None values are left
    out."""
    import yaml

    from flctool.behaviour.overrides import Override

    overrides: list[Override] = []
    for text in assignments:
        key, sep, value = text.partition("=")
        key = key.strip()
        if not sep or not key:
            raise SpecError([Problem(("--set",), f"'{text}' is not key=value",
                                     "write e.g. --set q.temperature=0.2", file="command line")],
                            "command line")
        try:
            parsed = yaml.safe_load(value) if value.strip() else ""
        except yaml.YAMLError:  # not YAML: the text itself
            parsed = value
        overrides.append(Override(key, parsed, f"command line (--set {key})"))
    overrides += [Override(key, value, f"command line ({option})")
                  for key, (option, value) in (options or {}).items() if value is not None]
    return overrides


def controller_file(path: Path) -> Path:
    """The behaviour file a controller argument names: the file itself, or a run directory's
    ``best.yaml``. A missing path or a run without a best controller is a clear error."""
    if path.is_dir():
        best = path / RUN_BEST_FILE
        if not best.is_file():
            raise FlcError(f"{path} is a folder without {RUN_BEST_FILE}, so it holds no "
                           "learned controller yet",
                           hint="give a behaviour file, or a run directory after at least "
                           "one generation (flctool learn)")
        return best
    if not path.exists():
        raise no_such_file(path, "behaviour file or run directory")
    return path


def load_controller(path: Path) -> tuple[Behaviour, Path]:
    """The deployable behaviour a controller argument names (see :func:`controller_file`),
    and the file it was read from. One with rules still to learn is a clear error."""
    from flctool.behaviour import load_behaviour, require_deployable

    source = controller_file(path)
    behaviour = load_behaviour(source)
    require_deployable(behaviour, str(source))
    return behaviour, source


def read_user_file(path: Path, what: str) -> str:
    """The text of a file the user named; an unreadable one is a clear error, not a traceback
    (worded by :mod:`flctool.inputs`, as every command words it)."""
    from flctool.inputs import read_input

    return read_input(path, what)


# -- output ----------------------------------------------------------------------------------
Force = Annotated[bool, typer.Option(
    "--force", help="Replace output files that already exist.")]


def check_output(path: Path, what: str, *, force: bool) -> None:
    """Refuse early to replace ``path`` without ``force`` (before any work is done), and
    create its missing parent folders."""
    if path.is_dir():
        raise FlcError(f"the {what} {path} is a folder", hint="give a file name")
    if path.exists() and not force:
        raise FlcError(f"the {what} {path} already exists",
                       hint="pass --force to replace it, or choose another name")
    make_parent(path, what)


def make_parent(path: Path, what: str) -> None:
    """Create the folders above ``path`` that do not exist yet."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise FlcError(f"cannot create the folder {path.parent} for the {what}: "
                       f"{error.strerror}", hint="choose another path") from None


def write_output(path: Path, text: str, what: str, *, force: bool) -> None:
    """Write ``text`` atomically to ``path`` under the overwrite policy (see
    :func:`check_output`); failures are clear errors."""
    from flctool.atomic import write_text_atomic

    check_output(path, what, force=force)
    try:
        write_text_atomic(path, text)
    except OSError as error:
        raise FlcError(f"cannot write the {what} {path}: {error.strerror}",
                       hint="check that the folder is writable and has space") from None


def output_format(path: Path | None, given: str | None, suffixes: Mapping[str, str],
                  default: str) -> str:
    """The format to write: ``--format`` if given, else the one ``path``'s suffix names, else
    ``default`` (for stdout). A suffix that names a different format than ``--format`` is an
    error, and so is a file name whose suffix names no format when ``--format`` is absent."""
    suffix = path.suffix.lower() if path is not None else ""
    implied = suffixes.get(suffix)
    known = ", ".join(sorted(set(suffixes)))
    if given is not None:
        if implied is not None and implied != given:
            raise FlcError(f"{path} has the suffix of the {implied} format, but --format is "
                           f"{given}", hint=f"name the file for {given}, or drop --format")
        return given
    if path is None:
        return default
    if implied is None:
        raise FlcError(f"cannot tell the format of {path} from its suffix",
                       hint=f"use one of {known}, or pass --format")
    return implied


# -- registration ----------------------------------------------------------------------------
# Every command module registers its commands on `app` when imported, and is imported only
# when its command runs (or its --help is asked for): `flctool --version` and `flctool --help`
# load neither numpy, pydantic nor rich. This is the one list of commands, in the order
# `flctool --help` shows them, each with its module and the first paragraph of its help (a
# test checks these against the commands themselves). A new command: its module, one line here.
COMMANDS: dict[str, tuple[str, str]] = {
    "validate": ("flctool.cli.behaviour_commands", "Check behaviour files and report every problem "
                 "in each (exit 1 if any is invalid)."),
    "show": ("flctool.cli.behaviour_commands", "Show a behaviour: its inputs and sets, M and K, "
             "and the rule table."),
    "schema": ("flctool.cli.behaviour_commands", "Write the behaviour JSON Schema generated from "
               "the models (or check it is current)."),
    "evaluate": ("flctool.cli.evaluate", "Run a controller in its environment: success rate, "
                 "steps to success and fitness, each with a 95 % confidence interval. Success "
                 "lines appear only when the environment defines success."),
    "experiment": ("flctool.cli.experiment", "Run the paper's experiment: every learner on "
                   "every seed, then report the spread across seeds, held-out success, rank "
                   "tests and whether the paper's claims hold."),
    "export": ("flctool.cli.export_commands", "Export a controller so that it runs elsewhere, "
               "with the same outputs."),
    "fit-sim": ("flctool.cli.bags", "Fit the simulator's motion and noise tables (per command: "
                "forward, sideways and rotation per step, their standard deviations) to logged "
                "commands and odometry; writes an environment: section and reports the fit."),
    "import": ("flctool.cli.export_commands", "Import a controller from FLL, FCL or FIS as a "
               "behaviour file."),
    "infer": ("flctool.cli.infer", "Run a deployable controller on states from CSV; adds the "
              "output column."),
    "learn": ("flctool.cli.learn", "Learn the rule consequents of a behaviour (Pitt GA, fuzzy "
              "Q-learning or the hybrid)."),
    "new": ("flctool.cli.new", "Scaffold a valid behaviour file: evenly spaced, overlapping "
            "sets over each input's range (shoulders at the ends), the commands, and rules "
            "left to learn."),
    "plot": ("flctool.cli.plot", "Plot learning curves, strengths, a trajectory and the "
             "controller as PNG and SVG files."),
    "record": ("flctool.cli.bags", "Record a learning or deployment session over ROS 2 (inputs, "
               "commands, status, rewards, and any --topic) as an MCAP bag, until --duration or "
               "Ctrl-C."),
    "replay": ("flctool.cli.bags", "Run a controller over a bag's recorded inputs: at each "
               "recorded command, its output from the latest inputs, beside the recorded one "
               "and their difference (CSV)."),
    "run": ("flctool.cli.run", "Deploy a controller on a robot. --ros2: publish its command "
            "at the control rate from the latest inputs, with a watchdog that publishes stop "
            "at once on a stale, NaN or out-of-range input or a lost publisher, and again on "
            "Ctrl-C. --link: run episodes on a robot-link robot. Either way a composed "
            "behaviour runs whole, its arbiter and parts here."),
    "serve": ("flctool.cli.serve", "Serve a behaviour's simulator over the robot-link "
              "protocol (docs/robot-link.md), for trying the link without a robot and as an "
              "example for bridge writers."),
}
