"""Exports of a controller with every set shape: fuzzylite 6 (FLL, FIS, FCL), Octave (FIS,
where installed) and the C build compute flctool's outputs on 10,000 states, and each
import reads the export back to the same controller."""

from __future__ import annotations

import subprocess
from pathlib import Path

import numpy as np
import pytest

from flctool import compile_behaviour
from flctool.errors import ExportError
from flctool.export.base import ExportOptions
from flctool.export.c_source import CExporter
from flctool.export.fcl import FclExporter, FclImporter
from flctool.export.fis import FisExporter, FisImporter
from flctool.export.fll import FllExporter, FllImporter

from ..compile.test_shapes import every_shape_behaviour, fuzzylite_shapes_behaviour
from .controllers import with_product
from .engines import assert_fuzzylite_agrees, octave_outputs
from .test_c_source import CC, FLAGS, needs_cc

#: Every shape: scikit-fuzzy's (which Octave reads too) and fuzzylite's own, with eq. 2 as
#: the min and as the product (activation: product).
BEHAVIOURS = {"skfuzzy": every_shape_behaviour, "fuzzylite": fuzzylite_shapes_behaviour,
              "skfuzzy-product": lambda: with_product(every_shape_behaviour()),
              "fuzzylite-product": lambda: with_product(fuzzylite_shapes_behaviour())}


def inside_states(count: int, seed: int, shapes: str = "skfuzzy") -> np.ndarray:
    """States inside the ranges: MATLAB and fuzzylite's FCL do not clip inputs, and a
    Gaussian goes on past a range's end where flctool's input stops."""
    behaviour = BEHAVIOURS[shapes]()
    controller = compile_behaviour(behaviour)
    rng = np.random.default_rng(seed)
    states = rng.uniform(controller.ranges[:, 0], controller.ranges[:, 1],
                         (count, controller.n_inputs))
    states[:8] = controller.ranges[:, 0]
    states[8:16] = controller.ranges[:, 1]
    return states


EXPORTS = {"fll": lambda b: FllExporter().to_string(b),
           "fis": lambda b: FisExporter().to_string(b),
           "fcl": lambda b: FclExporter(ExportOptions(dialect="fuzzylite")).to_string(b)}
IMPORTERS = {"fll": FllImporter, "fis": FisImporter, "fcl": FclImporter}


@pytest.mark.parametrize("shapes", list(BEHAVIOURS))
@pytest.mark.parametrize("format", list(EXPORTS))
@pytest.mark.slow
def test_fuzzylite6_computes_every_shape_as_flctool(format: str, shapes: str,
                                                    tmp_path: Path) -> None:
    """Within 1e-12 wherever fuzzylite's 1e-6 tolerance cannot matter (it drops the rules
    whose activation is below 1e-6, which Gaussians' tails have over much of a range)."""
    behaviour = BEHAVIOURS[shapes]()
    text = EXPORTS[format](behaviour)
    quads = [list(v.sets.values()) for v in behaviour.inputs.values()]
    assert_fuzzylite_agrees(behaviour, text, format, inside_states(10_000, 1, shapes), quads,
                            tmp_path, comparable=0.5)


@pytest.mark.parametrize("shapes", list(BEHAVIOURS))
@pytest.mark.parametrize("format", list(EXPORTS))
def test_every_shape_reads_back(format: str, shapes: str) -> None:
    behaviour = BEHAVIOURS[shapes]()
    imported = IMPORTERS[format]().from_string(EXPORTS[format](behaviour), f"x.{format}")
    assert imported.inputs == behaviour.inputs
    assert imported.activation == behaviour.activation
    assert [r.then for r in imported.rules] == [r.then for r in behaviour.rules]


@pytest.mark.slow
@pytest.mark.parametrize("shapes", ["skfuzzy", "skfuzzy-product"])
def test_octave_computes_every_shape_as_flctool(shapes: str, tmp_path: Path) -> None:
    """500 states, not the 10,000 of fuzzylite and C: Octave's evalfis interprets each state
    (about 23 ms of CPU a state for these 36 rules, so 10,000 would cost four minutes). Drawn
    uniformly over the ranges (and the ranges' ends), they hold each set of every shape
    above 0.5 at 46 states or more."""
    behaviour = BEHAVIOURS[shapes]()
    states = inside_states(500, seed=2)
    got = octave_outputs(FisExporter().to_string(behaviour), states, tmp_path)
    want = compile_behaviour(behaviour).output(states)
    assert np.max(np.abs(got - want)) <= 1e-12


def test_iec_fcl_refuses_a_shape_it_cannot_write() -> None:
    with pytest.raises(ExportError, match="'low' of input 'a' is a gauss2, which IEC"):
        FclExporter(ExportOptions(dialect="iec")).to_string(every_shape_behaviour())


@needs_cc
@pytest.mark.parametrize("shapes", list(BEHAVIOURS))
def test_c_computes_every_shape_bit_for_bit(shapes: str, tmp_path: Path) -> None:
    behaviour = BEHAVIOURS[shapes]()
    header, source = CExporter().to_file(behaviour, tmp_path / "shapes")
    assert "(link with -lm" in header.read_text()
    assert "#include <math.h>" in source.read_text()
    driver = tmp_path / "driver.c"
    n = len(behaviour.inputs)
    driver.write_text('#include <stdio.h>\n#include "shapes.h"\nint main(void)\n{\n'
                      f"    double s[{n}];\n"
                      f'    while (scanf("{" ".join(["%lf"] * n)}", '
                      f'{", ".join(f"&s[{i}]" for i in range(n))}) == {n})\n'
                      '        printf("%.17g\\n", flc_output(s));\n    return 0;\n}\n')
    program = tmp_path / "driver"
    assert CC is not None
    subprocess.run([CC, *FLAGS, "-o", str(program), str(driver), str(source), "-lm"],
                   check=True, capture_output=True, text=True)
    states = inside_states(10_000, 3, shapes)
    states[:2_000] *= 1.3  # beyond the ranges too: C clips as flctool does
    text = "\n".join(" ".join(repr(float(v)) for v in row) for row in states) + "\n"
    result = subprocess.run([str(program)], input=text, check=True, capture_output=True,
                            text=True)
    got = np.array([float(v) for v in result.stdout.split()])
    assert np.array_equal(got, compile_behaviour(behaviour).output(states))


def test_a_trapezoid_controller_needs_no_libm() -> None:
    from flctool import load_behaviour

    from .roundtrip import SHIPPED

    text = CExporter().to_string(load_behaviour(SHIPPED[0]))
    assert "no libm" in text and "math.h" not in text


def test_float_c_refuses_shapes_it_does_not_measure() -> None:
    with pytest.raises(ExportError, match="measured for trapezoids only"):
        CExporter(ExportOptions(single=True)).to_string(every_shape_behaviour())
