"""C: the generated source compiles with the system C compiler as strict C99 and gives
flctool's outputs (max abs difference <= 1e-12 in double) on 10,000 random states."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from flctool import compile_behaviour, load_behaviour, with_rules
from flctool.behaviour import Behaviour, behaviour_from_data
from flctool.errors import ExportError
from flctool.export import ExportOptions
from flctool.export.c_source import CExporter
from flctool.export.float_error import check_float_error
from flctool.rollout import vote_output

from ..conftest import BEHAVIOURS, ROOT
from .controllers import random_behaviour, random_states, with_product
from .roundtrip import SHIPPED

CC = shutil.which("cc") or shutil.which("gcc") or shutil.which("clang")
needs_cc = pytest.mark.skipif(CC is None, reason="no C compiler (cc, gcc or clang) on PATH")
FLAGS = ["-std=c99", "-pedantic", "-Wall", "-Wextra", "-Werror", "-O2"]
# AddressSanitizer and UBSan stop the program at a bad access; uninitialised locals are filled
# with a pattern (GCC 12+, Clang 8+) so that reading one gives a wild index they catch.
SANITIZE = ["-fsanitize=address,undefined", "-fno-sanitize-recover=all", "-g",
            "-ftrivial-auto-var-init=pattern"]


def build(tmp_path: Path, controllers: list[tuple[Behaviour, ExportOptions]],
          extra: tuple[str, ...] | list[str] = ()) -> Path:
    """One program running controller ``argv[1]`` on the states of stdin (count, then rows).

    Each controller is written as NAME.h + NAME.c and compiled separately; no -lm."""
    sources, includes, cases = [], [], []
    for index, (behaviour, options) in enumerate(controllers):
        files = CExporter(options).to_file(behaviour, tmp_path / f"ctl{index}")
        sources += [str(f) for f in files if f.suffix == ".c"]
        includes.append(f'#include "ctl{index}.h"')
        real = "float" if options.single else "double"
        n = len(behaviour.inputs)
        cases.append(f"""    if (which == {index}) {{
        {real} s[{n}];
        for (r = 0; r < rows; ++r) {{
            for (i = 0; i < {n}; ++i) {{ if (scanf("%lf", &v) != 1) return 2; s[i] = ({real})v; }}
            printf("%.17g\\n", (double){options.prefix}output(s));
        }}
        return 0;
    }}""")
    driver = tmp_path / "driver.c"
    driver.write_text("#include <stdio.h>\n#include <stdlib.h>\n" + "\n".join(includes) + """
int main(int argc, char **argv)
{
    int which = atoi(argv[argc - 1]);
    long rows, r;
    int i;
    double v;
    if (scanf("%ld", &rows) != 1) return 2;
""" + "\n".join(cases) + "\n    return 3;\n}\n")
    program = tmp_path / "driver"
    assert CC is not None
    subprocess.run([CC, *FLAGS, *extra, "-o", str(program), str(driver), *sources],
                   check=True, capture_output=True, text=True)
    return program


def decide_each(files: list[Path], prefix: str, states: np.ndarray, program: Path,
                wrong: str, extra: tuple[str, ...] | list[str] = ()) -> list[list[str]]:
    """Each state's ``<prefix>decide`` as text: (command, its *output, ``<prefix>output``), from
    a program built with the exported header and source ``files``; it stops with exit code 9
    where the C condition ``wrong`` (over ``s``, ``command`` and ``out``) holds."""
    n = states.shape[1]
    driver = program.with_suffix(".c")
    driver.write_text(f"""#include <stdio.h>
#include "{files[0].name}"
int main(void)
{{
    double s[{n}], out;
    int i, command;
    for (;;) {{
        for (i = 0; i < {n}; ++i) if (scanf("%lf", &s[i]) != 1) return 0;
        command = {prefix}decide(s, &out);
        if ({wrong}) return 9;
        printf("%d %.17g %.17g\\n", command, out, {prefix}output(s));
    }}
}}
""")
    assert CC is not None
    subprocess.run([CC, *FLAGS, *extra, "-o", str(program), str(driver), str(files[1])],
                   check=True, capture_output=True, text=True)
    result = subprocess.run([str(program)], check=True, capture_output=True, text=True,
                            input="\n".join(" ".join(map(repr, row)) for row in states.tolist()))
    return [line.split() for line in result.stdout.splitlines()]


def run(program: Path, which: int, states: np.ndarray) -> np.ndarray:
    lines = [str(len(states))] + [" ".join(repr(float(v)) for v in row) for row in states]
    result = subprocess.run([str(program), str(which)], input="\n".join(lines) + "\n",
                            check=True, capture_output=True, text=True)
    return np.array([float(v) for v in result.stdout.split()])


@pytest.mark.slow
@needs_cc
def test_c_matches_python_on_10000_states(tmp_path: Path) -> None:
    shipped = [load_behaviour(p) for p in SHIPPED]
    # with activation: product too (its C multiplies the memberships in input order)
    shipped += [with_product(shipped[k]) for k in (0, 1)]
    randoms = [random_behaviour(seed, max_sets=5, activation="product" if seed >= 10 else "min")
               for seed in range(14)]
    controllers = [(b, ExportOptions(prefix=f"c{i}_")) for i, b in enumerate(shipped + randoms)]
    controllers += [(b, ExportOptions(prefix=f"f{i}_", single=True))
                    for i, b in enumerate(shipped + [randoms[k] for k in (1, 2, 3, 6, 10)])]
    program = build(tmp_path, controllers)
    for which, (behaviour, options) in enumerate(controllers):
        states = random_states(behaviour, 10_000 if which < len(shipped) else 2_000, seed=which)
        want = compile_behaviour(behaviour).output(states)
        if options.single:
            # float arithmetic: the float-rounded tables and states, each step rounded
            scale = max(1.0, float(np.max(np.abs(list(behaviour.output.commands.values())))))
            assert np.max(np.abs(run(program, which, states) - want)) <= 1e-5 * scale
            # the header's error is what other states uniform in the ranges measure too
            # (measured: 0.74 to 1.02 times it on the shipped controllers)
            controller = compile_behaviour(behaviour)
            uniform = np.random.default_rng(which).uniform(
                controller.ranges[:, 0], controller.ranges[:, 1],
                (10_000, controller.n_inputs)).astype(np.float32).astype(np.float64)
            error = np.max(np.abs(run(program, which, uniform) - controller.output(uniform)))
            assert error <= 1.05 * check_float_error(behaviour)[0]
        else:
            assert np.max(np.abs(run(program, which, states) - want)) <= 1e-12


@needs_cc
def test_c_clips_infinities_and_passes_nan_through(tmp_path: Path) -> None:
    behaviour = load_behaviour(SHIPPED[0])
    program = build(tmp_path, [(behaviour, ExportOptions())])
    states = np.array([[np.inf, -np.inf], [-np.inf, np.inf], [np.nan, 0.0], [0.5, np.nan]])
    got = run(program, 0, states)
    want = compile_behaviour(behaviour).output(states[:2])
    assert np.array_equal(got[:2], want)
    assert np.isnan(got[2:]).all()


def test_files_convention(tmp_path: Path) -> None:
    behaviour = load_behaviour(SHIPPED[0])
    for name in ("ballchase", "ballchase.c", "ballchase.h"):
        files = CExporter().to_file(behaviour, tmp_path / name, force=True)
        assert [f.name for f in files] == ["ballchase.h", "ballchase.c"]
    source = (tmp_path / "ballchase.c").read_text()
    assert source.startswith('#include "ballchase.h"')
    for banned in ("malloc", "math.h", "<stdlib.h>"):
        assert banned not in source
    assert "static const double flc_sets" in source
    assert "double flc_output(const double state[FLC_N_INPUTS]);" in \
        (tmp_path / "ballchase.h").read_text()


def test_prefix_and_float(tmp_path: Path) -> None:
    behaviour = load_behaviour(SHIPPED[0])
    text = CExporter(ExportOptions(prefix="ballchase_", single=True)).to_string(behaviour)
    assert "float ballchase_output(const float state[BALLCHASE_N_INPUTS])" in text
    assert "double" not in text
    assert "0.1f" in text
    with pytest.raises(ExportError, match="the prefix '9x' cannot start a C identifier"):
        CExporter(ExportOptions(prefix="9x")).to_string(behaviour)


def test_an_existing_file_is_kept_without_force(tmp_path: Path) -> None:
    behaviour = load_behaviour(SHIPPED[0])
    (tmp_path / "ctl.c").write_text("mine")
    with pytest.raises(ExportError, match=r"ctl\.c already exists"):
        CExporter().to_file(behaviour, tmp_path / "ctl")
    assert (tmp_path / "ctl.c").read_text() == "mine"
    assert not (tmp_path / "ctl.h").exists()  # nothing written when one target is refused


def two_set_controller(low: list[float], high: list[float], upper: float = 1.0) -> Behaviour:
    behaviour = behaviour_from_data({
        "flctool": 1, "name": "two", "inputs": {"s": {"range": [0.0, upper],
                                                      "sets": {"low": low, "high": high}}},
        "output": {"name": "u", "commands": {"up": 1.0, "down": -1.0}}})
    return with_rules(behaviour, np.array([0, 1]))


def test_float_export_refuses_sets_that_rounding_leaves_apart() -> None:
    # In double, low's ramp ends just after high's starts; in float both ends are 0.3f, where
    # neither set fires.
    behaviour = two_set_controller([0.0, 0.0, 0.2, 0.30000000000000004], [0.3, 0.5, 1.0, 1.0])
    CExporter().to_string(behaviour)  # double keeps the overlap
    with pytest.raises(ExportError, match=r"input 's': rounded to float, its sets leave a gap "
                       r"at 0\.3000000119"):
        CExporter(ExportOptions(single=True)).to_string(behaviour)


@needs_cc
@pytest.mark.slow
def test_c_returns_nan_where_no_set_fires(tmp_path: Path) -> None:
    """A state where float arithmetic leaves every membership 0 (high's ramp (s - 0) / 10
    underflows at the smallest float) gives NaN, and the sanitizers see no unset memory read."""
    tiny = float(np.nextafter(np.float32(0), np.float32(1)))  # 2**-149
    behaviour = two_set_controller([0.0, 0.0, 0.0, tiny], [0.0, 10.0, 10.0, 10.0], 10.0)
    options = ExportOptions(single=True)
    assert compile_behaviour(behaviour).output(np.array([[tiny]]))[0] == -1.0  # fine in double
    program = build(tmp_path, [(behaviour, options)],
                    SANITIZE)
    got = run(program, 0, np.array([[tiny], [5.0]]))
    assert np.isnan(got[0]) and got[1] == -1.0


@needs_cc
def test_a_source_path_cannot_end_the_comment(tmp_path: Path) -> None:
    options = ExportOptions(provenance={"source": "runs/r*/run\n#error broken"})
    files = CExporter(options).to_file(load_behaviour(SHIPPED[0]), tmp_path / "ctl")
    assert CC is not None
    subprocess.run([CC, *FLAGS, "-fsyntax-only", str(files[1])], check=True,
                   capture_output=True, text=True)


@needs_cc
def test_command_is_the_nearest_singleton_and_the_header_gives_the_range(tmp_path: Path
                                                                        ) -> None:
    behaviour = random_behaviour(5, max_sets=4)
    files = CExporter(ExportOptions(prefix="r_")).to_file(behaviour, tmp_path / "ctl")
    header = files[0].read_text()
    values = list(behaviour.output.commands.values())
    assert f"#define R_OUTPUT_MIN ({min(values)!r})" in header
    assert f"#define R_OUTPUT_MAX ({max(values)!r})" in header
    assert f"#define R_N_COMMANDS {len(values)}" in header
    states = random_states(behaviour, 2_000, seed=1)
    # one inference: the output and its command
    rows = decide_each(files, "r_", states, tmp_path / "main",
                       "command != r_command(s) || !(out == r_output(s) || out != out)")
    got = np.array([int(command) for command, _, _ in rows])
    outputs = compile_behaviour(behaviour).output(states)
    assert np.array_equal(np.array([float(out) for _, out, _ in rows]), outputs)
    order = np.argsort(values, kind="stable")  # a tie goes to the smaller singleton
    nearest = np.argmin(np.abs(np.array(values)[order][None, :] - outputs[:, None]), axis=1)
    assert np.array_equal(got, order[nearest])


@needs_cc
def test_fast_math_is_refused_at_compile_time(tmp_path: Path) -> None:
    files = CExporter().to_file(load_behaviour(SHIPPED[0]), tmp_path / "ctl")
    assert CC is not None
    result = subprocess.run([CC, *FLAGS, "-ffast-math", "-c", "-o", str(tmp_path / "ctl.o"),
                             str(files[1])], capture_output=True, text=True, check=False)
    assert result.returncode != 0
    assert "compile without -ffast-math" in result.stderr


def test_float_error_is_measured_and_refused_beyond_the_bound() -> None:
    text = CExporter(ExportOptions(single=True)).to_string(load_behaviour(SHIPPED[0]))
    assert "measured at export on 200000 states" in text
    # a narrow range at a large magnitude: float keeps ~3 decimals of 10000.x
    narrow = with_rules(behaviour_from_data({
        "flctool": 1, "name": "narrow",
        "inputs": {"x": {"range": [10000.0, 10000.5], "sets": {
            "a": [10000.0, 10000.0, 10000.1, 10000.4],
            "b": [10000.1, 10000.4, 10000.5, 10000.5]}}},
        "output": {"name": "u", "commands": {"l": -1.0, "r": 1.0}}}), np.array([0, 1]))
    with pytest.raises(ExportError, match=r"in float, the controller differs from flctool's "
                       r"double output by up to 0.00\d+ .*beyond the float export's bound of "
                       r"1e-05.*\(fix: export without --float"):
        CExporter(ExportOptions(single=True)).to_string(narrow)
    CExporter().to_string(narrow)  # double is fine


@needs_cc
def test_c_evaluates_an_end_no_set_fires_as_flctool_does(tmp_path: Path) -> None:
    """Ramps rising from the range's low end (no set fires at 0): the C build clips
    to the same interval just inside them, so it gives flctool's outputs there too."""
    behaviour = two_set_controller([0.0, 5.0, 5.0, 10.0], [0.0, 10.0, 10.0, 10.0], 10.0)
    program = build(tmp_path, [(behaviour, ExportOptions())])
    states = np.array([[0.0], [-3.0], [2.5], [10.0]])
    want = compile_behaviour(behaviour).output(states)
    # both rise from 0, low twice as steeply: the limit is (2 * 1 + 1 * -1) / 3
    assert want[0] == want[1] == pytest.approx(1 / 3)
    assert run(program, 0, states).tolist() == want.tolist()


@needs_cc
def test_a_behaviour_that_acts_by_vote_exports_its_vote_as_the_command(tmp_path: Path) -> None:
    """environment.action: vote -- the command a deployed controller runs is the vote, as
    flctool acts in learning and evaluation, not the command nearest eq. 3's output."""
    mountaincar = load_behaviour(BEHAVIOURS / "mountaincar.yaml")
    table = np.random.default_rng(3).integers(3, size=mountaincar.rule_count)
    behaviours = [load_behaviour(ROOT / "benchmarks" / "tasks" / "park-handmade.yaml"),
                  with_rules(mountaincar, table)]
    for index, behaviour in enumerate(behaviours):
        files = CExporter(ExportOptions(prefix="v_")).to_file(behaviour, tmp_path / f"v{index}")
        assert "action: vote" in files[0].read_text()
        states = random_states(behaviour, 3_000, seed=index)
        states[0, 0] = np.nan
        rows = decide_each(files, "v_", states, tmp_path / f"main{index}",
                           "command != v_command(s)", SANITIZE)
        assert len(rows) == len(states)
        controller = compile_behaviour(behaviour)
        acted = vote_output(controller, states[1:])
        singletons = list(behaviour.output.commands.values())
        assert rows[0][0] == "-1"  # a NaN input: no command
        assert [int(r[0]) for r in rows[1:]] == [singletons.index(a) for a in acted]
        assert np.array_equal([float(r[1]) for r in rows[1:]], acted)
        assert np.array_equal([float(r[2]) for r in rows[1:]], controller.output(states[1:]))
        nearest = np.argmin(np.abs(np.array(singletons)[None, :]
                                   - controller.output(states[1:])[:, None]), axis=1)
        assert (nearest != [int(r[0]) for r in rows[1:]]).any()  # the vote is not the nearest
