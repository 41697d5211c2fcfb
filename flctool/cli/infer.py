"""``flctool infer``: a controller's outputs for states read from CSV, streamed.

Two paths give the same bits (tests compare them):

- a small table (at most :data:`SMALL_TABLE` rows) is read and inferred in plain Python over
  the rules that fire (:class:`flctool.compile.sparse.SparseRules`, the path learning uses,
  built from the behaviour without compiling it), so a few rows never load numpy, nor wait
  for numba to load or to compile the kernels;
- a larger one goes through :meth:`Controller.output` (compiled kernels) chunk by chunk, so
  memory follows the chunk, not the file.

See docs/performance.md ("Whole commands").
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Iterator
from contextlib import ExitStack, contextmanager
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, TextIO

import typer

from flctool.cli.app import Force, app, check_output, example, load_controller, user_errors
from flctool.cli.behaviour_commands import ControllerArgument
from flctool.cli.progress import compiling
from flctool.errors import FlcError
from flctool.inputs import open_error

if TYPE_CHECKING:
    import numpy as np
    from numpy.typing import NDArray

    from flctool.behaviour import Behaviour
    from flctool.compile.sparse import SparseRules

#: Tables up to this many rows skip numpy and the compiled kernels: in plain Python a row costs
#: a few microseconds, while loading numpy costs about 0.1 s of CPU, numba about 0.3 s more
#: (and compiling, on a machine's first run, several seconds). Counted a chunk at a time: once
#: a chunk is larger, the rest of the table goes through the kernels.
SMALL_TABLE = 2_000


@app.command(epilog=example(
    "flctool infer behaviours/ballchase-handmade.yaml -i states.csv -o outputs.csv",
    "printf 'ball_size,pan\\n0.2,10\\n' | flctool infer runs/first"))
def infer(
    file: ControllerArgument,
    input: Annotated[str, typer.Option(
        "--input", "-i", help="CSV of states with a header naming the inputs; - for stdin.")]
    = "-",
    output: Annotated[Path | None, typer.Option(
        "--output", "-o", help="Where to write the CSV (default: stdout).")] = None,
    force: Force = False,
) -> None:
    """Run a deployable controller on states from CSV; adds the output column.

    The output is eq. 3's, or, for a behaviour that acts by vote (environment.action: vote),
    the singleton of the command the vote picks, as the behaviour acts.

    Rows are read, inferred and written in chunks, so a table of any length runs in bounded
    memory. Writing to stdout, rows before a bad one have already been printed when it is
    reported; with -o the file is written only if every row is good.
    """
    from flctool.compile.rules import rule_consequents
    from flctool.compile.sparse import SparseRules
    from flctool.tabular import StateReader, format_rows

    with user_errors():
        behaviour, _ = load_controller(file)
        input_names = list(behaviour.inputs)
        output_name = behaviour.output.name
        if output is not None:
            check_output(output, "output CSV", force=force)
        with _states(input) as (stream, name), _target(output) as target:
            reader = StateReader(stream, input_names, name, reserved=[output_name])
            target.write(f"{reader.header_line},{output_name}\n")
            rules = SparseRules.from_behaviour(behaviour)
            consequents = rule_consequents(behaviour)
            assert consequents is not None  # load_controller refused rules still to learn
            votes = behaviour.acts_by_vote  # the voted command's singleton, as it acts
            act: Callable[[NDArray[np.float64]], NDArray[np.float64]] | None = None
            for lines in reader.row_chunks():  # the compiled controller once a chunk is large
                if act is None and len(lines) <= SMALL_TABLE:
                    values = outputs_in_python(rules, consequents, reader.parse_in_python(lines),
                                               votes)
                else:
                    if act is None:
                        act = _compiled(behaviour, votes)
                    states = reader.parse(lines)
                    # numpy first; the kernels once the table is large enough to pay for them
                    with _numba_without_scipy_blas():
                        values = act(states).tolist()
                target.write(format_rows(lines, values))


def outputs_in_python(rules: SparseRules, consequents: list[int],
                      states: list[list[float]], votes: bool = False) -> list[float]:
    """``controller.output(states)`` computed in plain Python over the rules that fire:
    B states of N values -> B outputs, the same bits, without numpy or the kernels; with
    ``votes``, the singleton of the command the vote picks (``environment.action: vote``)."""
    act = rules.vote if votes else rules.output
    values = []
    for state in states:
        fired, alphas, _ = rules.activations(state)
        values.append(act(alphas, [consequents[m] for m in fired]))
    return values


def _compiled(behaviour: Behaviour, votes: bool,
              ) -> Callable[[NDArray[np.float64]], NDArray[np.float64]]:
    """The compiled controller's outputs for (B, N) states, or its vote's."""
    from flctool.compile import compile_behaviour
    from flctool.compile import controller as controller_module
    from flctool.rollout import vote_output

    controller_module.kernel_loading = compiling  # announced if slow
    controller = compile_behaviour(behaviour)
    return partial(vote_output, controller) if votes else controller.output


#: What numba's array functions import only to learn whether BLAS is there.
_SCIPY_BLAS = "scipy.linalg.cython_blas"


@contextmanager
def _numba_without_scipy_blas() -> Iterator[None]:
    """While the kernels load, scipy's BLAS looks absent to numba.

    numba loads its implementations of numpy's functions with the first kernel, and they
    import scipy.linalg's BLAS only to choose how np.correlate and np.convolve compute (about
    0.17 s of CPU: a tenth of ``infer`` on 10^6 rows). The kernels call neither, and nothing
    else runs numba in this command's process, so it is spared here; the library itself does
    not do this, as a program using it may run numba code of its own.
    """
    if _SCIPY_BLAS in sys.modules or "numba.np.arraymath" in sys.modules:
        yield  # loaded already, or too late to matter
        return
    sys.modules[_SCIPY_BLAS] = None  # type: ignore[assignment]  # import raises ImportError
    try:
        yield
    finally:
        if sys.modules.get(_SCIPY_BLAS, 0) is None:
            del sys.modules[_SCIPY_BLAS]


@contextmanager
def _states(input: str) -> Iterator[tuple[TextIO, str]]:
    from flctool.tabular import text_stream

    if input == "-":
        yield text_stream(sys.stdin.buffer), "<stdin>"
        return
    try:
        handle = open(input, "rb")  # noqa: SIM115 - closed below
    except OSError as error:
        raise open_error(input, "states CSV", error) from None
    with handle:
        yield text_stream(handle), input


@contextmanager
def _target(output: Path | None) -> Iterator[TextIO]:
    """stdout, or a temporary file beside ``output`` renamed over it once every row is
    written (a failure leaves no half file)."""
    if output is None:
        yield sys.stdout
        return
    from flctool.atomic import atomic_text_writer

    with ExitStack() as stack:
        try:
            handle = stack.enter_context(atomic_text_writer(output))
        except OSError as error:
            raise FlcError(f"cannot write the output CSV {output}: {error.strerror or error}",
                           hint="check that the folder exists and is writable") from None
        yield handle
