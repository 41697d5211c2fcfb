"""The reference engines as the tests run them: the fuzzylite 6 command line (Debian package
``fuzzylite``) and Octave with its fuzzy-logic-toolkit (Debian packages ``octave`` and
``octave-fuzzy-logic-toolkit``).

Each engine's tests skip only when it is absent *and* its ``FLCTOOL_REQUIRE_FUZZYLITE`` /
``FLCTOOL_REQUIRE_OCTAVE`` is unset; CI sets both, so there a missing engine fails the tests
instead of skipping them.
"""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from flctool import compile_behaviour
from flctool.behaviour import Behaviour
from flctool.behaviour.shapes import set_row

#: fuzzylite 6 compares with an absolute tolerance of 1e-6 (fuzzylite::macheps, fixed in the
#: command line): memberships within 1e-6 of a corner take the corner's value, and rules
#: whose activation is within 1e-6 of 0 do not fire.
FUZZYLITE_TOLERANCE = 1e-6


def fuzzylite_binary() -> str:
    """The fuzzylite command, or skip (fail if FLCTOOL_REQUIRE_FUZZYLITE is set)."""
    found = shutil.which("fuzzylite")
    if found is None:
        if os.environ.get("FLCTOOL_REQUIRE_FUZZYLITE"):
            pytest.fail("FLCTOOL_REQUIRE_FUZZYLITE is set but the fuzzylite command is missing "
                        "(apt-get install fuzzylite)")
        pytest.skip("the fuzzylite 6 command line is not installed (apt-get install fuzzylite)")
    return found


def fuzzylite_outputs(text: str, format: str, states: np.ndarray, folder: Path,
                      outputs: int = 1) -> np.ndarray:
    """fuzzylite 6's outputs for (S, N) ``states`` of the engine in ``text`` (fll/fis/fcl):
    (S,), or (S, outputs) for an engine of several outputs."""
    engine = folder / f"engine.{format}"
    engine.write_text(text, encoding="utf-8")
    data = folder / "states.fld"
    data.write_text("\n".join(" ".join(repr(float(x)) for x in row) for row in states) + "\n",
                    encoding="utf-8")
    result = subprocess.run(
        [fuzzylite_binary(), "-i", str(engine), "-if", format, "-of", "fld", "-d", str(data),
         "-dheader", "false", "-dinputs", "false", "-decimals", "17"],
        capture_output=True, text=True, timeout=120, check=False)
    assert result.returncode == 0, result.stderr + result.stdout
    values = np.array([float(line) for line in result.stdout.split()])
    assert values.shape == (len(states) * outputs,), result.stdout[:500]
    return values if outputs == 1 else values.reshape(len(states), outputs)


def outside_tolerance(behaviour: Behaviour, states: np.ndarray, corners: list[np.ndarray]
                      ) -> np.ndarray:
    """(S,) True where fuzzylite's 1e-6 tolerance cannot matter: every input lies on a corner
    of its sets (``corners[i]``: as flctool and the export have them) or 1e-6 or more from
    all of them, and no set's membership is within 1e-6 of 0 or 1 without being 0 or 1."""
    keep = np.ones(len(states), dtype=bool)
    controller = compile_behaviour(behaviour)
    clipped = np.clip(states, controller.ranges[:, 0], controller.ranges[:, 1])
    for i, points in enumerate(corners):
        for column in (states[:, i], clipped[:, i]):
            gap = np.min(np.abs(column[:, None] - points[None, :]), axis=1)
            keep &= (gap == 0) | (gap >= FUZZYLITE_TOLERANCE)
    for mu in controller.memberships(clipped):
        near = (((mu > 0) & (mu <= FUZZYLITE_TOLERANCE))
                | ((mu < 1) & (mu >= 1 - FUZZYLITE_TOLERANCE)))
        keep &= ~np.any(near, axis=1)
    return keep


def fuzzylite_fired(behaviour: Behaviour, states: np.ndarray) -> np.ndarray:
    """(S,) flctool's output computed from its own activations but without the rules whose
    activation is within 1e-6 of 0, which fuzzylite does not fire. With activation: product a
    rule's activation comes that close to 0 at many states whose memberships do not (a product
    of two memberships of 1e-3); so these states are compared with this, not excluded."""
    controller = compile_behaviour(behaviour)
    alpha = controller.activations(states)  # (S, M), clipped as the output clips
    alpha[alpha <= FUZZYLITE_TOLERANCE] = 0.0
    assert controller.consequents is not None
    values = controller.singletons[controller.consequents]
    with np.errstate(invalid="ignore", divide="ignore"):
        out: np.ndarray = (alpha @ values) / alpha.sum(axis=1)
    return out


def corners_of(behaviour: Behaviour, quads: list[list[tuple[float, ...]]]) -> list[np.ndarray]:
    """Each input's range ends and the points of its sets, as flctool has them and as an
    export wrote them (``quads``)."""
    return [np.array([*variable.range, *(x for q in variable.sets.values() for x in set_row(q)[1]),
                      *(x for q in sets for x in set_row(q)[1])])
            for variable, sets in zip(behaviour.inputs.values(), quads, strict=True)]


def assert_fuzzylite_agrees(behaviour: Behaviour, text: str, format: str, states: np.ndarray,
                            quads: list[list[tuple[float, ...]]], folder: Path,
                            comparable: float = 0.99) -> float:
    """fuzzylite 6 computes flctool's outputs within 1e-12 wherever its 1e-6 tolerance cannot
    matter (see :func:`outside_tolerance`); returns the largest difference there.

    At least ``comparable`` of the states (99 %) must be such states, so the check cannot
    pass vacuously (Gaussians and sigmoids have memberships near 0 over much of a range).
    With activation: product, states where fuzzylite leaves out a tiny activation are
    compared with :func:`fuzzylite_fired`.
    """
    got = fuzzylite_outputs(text, format, states, folder)
    want = compile_behaviour(behaviour).output(states)
    keep = outside_tolerance(behaviour, states, corners_of(behaviour, quads))
    if behaviour.activation == "product":
        dropped = fuzzylite_fired(behaviour, states)
        # where fuzzylite leaves out a tiny activation, flctool's activations without it
        differs = ~np.isclose(dropped, want, rtol=0.0, atol=1e-12)
        want = np.where(differs, dropped, want)
        keep &= np.isfinite(want)  # (every activation tiny: fuzzylite has no output)
    assert keep.mean() >= comparable, f"only {keep.sum()} of {len(states)} states are comparable"
    worst = float(np.max(np.abs(got[keep] - want[keep])))
    assert worst <= 1e-12, f"fuzzylite 6 differs by {worst} ({format})"
    return worst


def _missing_octave(what: str) -> None:
    hint = "apt-get install octave octave-fuzzy-logic-toolkit"
    if os.environ.get("FLCTOOL_REQUIRE_OCTAVE"):
        pytest.fail(f"FLCTOOL_REQUIRE_OCTAVE is set but {what} ({hint})")
    pytest.skip(f"{what} ({hint})")


def octave_outputs(fis_text: str, states: np.ndarray, folder: Path) -> np.ndarray:
    """Octave's fuzzy-logic-toolkit ``evalfis`` on (S, N) ``states`` (it refuses states
    outside the ranges, so clip them first); skips when Octave or the toolkit is missing."""
    octave = shutil.which("octave")
    if octave is None:
        _missing_octave("Octave is not installed")
    (folder / "system.fis").write_text(fis_text, encoding="utf-8")
    np.savetxt(folder / "states.txt", states, fmt="%.17g")
    script = ("pkg load fuzzy-logic-toolkit; fis = readfis('system.fis'); "
              "y = evalfis(load('states.txt'), fis); printf('%.17g\\n', y);")
    result = subprocess.run([octave, "--no-gui", "--quiet", "--no-init-file", "--eval", script],
                            cwd=folder, capture_output=True, text=True, timeout=300,
                            check=False)
    if "package" in result.stderr and "not installed" in result.stderr:
        _missing_octave("Octave's fuzzy-logic-toolkit is not installed")
    assert result.returncode == 0, result.stderr + result.stdout
    return np.array([float(v) for v in result.stdout.split()])


def reference_controller(source: object, activation: str = "min") -> Behaviour:
    """A controller for the reference-engine tests: random controller ``source`` (an int),
    or a shipped behaviour file, given seeded random consequents if it has no rules yet
    (so every shipped partition is checked, learned or not); with ``activation: product``
    if asked."""
    from flctool import load_behaviour, with_rules

    from .controllers import random_behaviour, with_product

    if isinstance(source, int):
        return random_behaviour(source, max_inputs=3, activation=activation)
    behaviour = load_behaviour(str(source))
    if not behaviour.is_deployable:
        rng = np.random.default_rng(0)
        behaviour = with_rules(behaviour, rng.integers(0, len(behaviour.output.commands),
                                                       behaviour.rule_count))
    return with_product(behaviour) if activation == "product" else behaviour


#: Every shipped behaviour file.
ALL_SHIPPED = sorted((Path(__file__).resolve().parents[2] / "behaviours").glob("*.yaml"))

#: The controllers the reference-engine tests also run with ``activation: product``: shipped
#: files with trapezoids, triangles, vertical edges and other shapes, and random ones.
PRODUCT_SOURCES = [path for path in ALL_SHIPPED
                   if path.name in ("ballchase-handmade.yaml", "cartpole.yaml",
                                    "avoid-obstacle-handmade.yaml", "pendulum.yaml")] + [3, 12]
