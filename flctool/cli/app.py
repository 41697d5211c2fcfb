"""The typer app, its global options, and the one place errors become exit codes."""

from __future__ import annotations

import sys
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console
from rich.markup import escape

from flctool import __version__
from flctool.atomic import write_text_atomic
from flctool.errors import FlcError, SpecError

app = typer.Typer(
    name="flctool",
    help="Learned fuzzy logic controllers for reactive robot behaviours: declare a behaviour "
    "in YAML, learn its rules, export the controller.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)
# soft_wrap: messages carry long file paths; hard-wrapping them breaks copy-paste and grep.
console = Console(soft_wrap=True)
err_console = Console(stderr=True, soft_wrap=True)

_state = {"debug": False}


def _version(value: bool) -> None:
    if value:
        console.print(f"flctool {__version__}")
        raise typer.Exit()


@app.callback()
def main(
    debug: Annotated[bool, typer.Option("--debug", help="Show full tracebacks on errors.")] = False,
    version: Annotated[bool | None, typer.Option(
        "--version", callback=_version, is_eager=True, help="Print the version and exit.")] = None,
    import_module: Annotated[list[str] | None, typer.Option(
        "--import-module", metavar="MODULE", help="Import this Python module first (it "
        "registers Gymnasium environments); an environment id 'MODULE:Env-v0' may then name "
        "it. A behaviour file never imports modules by itself.")] = None,
) -> None:
    _state["debug"] = debug
    if import_module:
        from flctool.envs.gym_adapter import import_user_modules

        with user_errors():
            import_user_modules(import_module)


def debug_enabled() -> bool:
    """Whether --debug was given (tracebacks are wanted)."""
    return _state["debug"]


def print_error(error: FlcError) -> None:
    """Render a flctool error for a person: one located line per problem."""
    if isinstance(error, SpecError):
        count = len(error.problems)
        err_console.print(f"[bold red]error:[/] {escape(error.file or 'input')} has "
                          f"{count} problem{'s' if count != 1 else ''}")
        for problem in error.problems:
            err_console.print(f"  {escape(str(problem))}", highlight=False)
        return
    err_console.print(f"[bold red]error:[/] {escape(str(error))}", highlight=False)


def read_user_file(path: Path, what: str) -> str:
    """The text of a file the user named; an unreadable one is a clear error, not a traceback."""
    try:
        return path.read_text(encoding="utf-8")
    except UnicodeDecodeError as error:
        raise FlcError(f"{path}: the {what} is not UTF-8 text (byte {error.start})",
                       hint="save it as UTF-8 text") from None
    except OSError as error:
        raise FlcError(f"cannot read the {what} {path}: {error.strerror}",
                       hint="check the path") from None


def write_user_file(path: Path, text: str, what: str) -> None:
    """Write ``text`` atomically where the user asked; failures are clear errors."""
    try:
        write_text_atomic(path, text)
    except OSError as error:
        raise FlcError(f"cannot write the {what} {path}: {error.strerror}",
                       hint="check that the folder exists and is writable") from None


@contextmanager
def user_errors() -> Iterator[None]:
    """Turn flctool errors into a message and exit code 1 (a traceback only with --debug)."""
    try:
        yield
    except FlcError as error:
        if _state["debug"]:
            raise
        print_error(error)
        raise typer.Exit(1) from None
    except KeyboardInterrupt:
        err_console.print("[yellow]interrupted[/]")
        raise typer.Exit(130) from None
    except BrokenPipeError:  # e.g. `flctool infer ... | head`
        sys.stderr.close()
        raise typer.Exit(0) from None
