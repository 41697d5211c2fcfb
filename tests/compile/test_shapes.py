"""The set shapes besides the trapezoid: scikit-fuzzy's formulas, computed alike by every
path (plain Python, numpy, the compiled kernels), and validated."""

from __future__ import annotations

import math

import numpy as np
import pytest
import skfuzzy.membership as skm
from hypothesis import given, settings
from hypothesis import strategies as st

from flctool import compile_behaviour
from flctool.behaviour import behaviour_from_data, parse_behaviour
from flctool.behaviour.shapes import CODES
from flctool.compile.sparse import SparseRules
from flctool.errors import SpecError
from flctool.membership import memberships, shape_membership

#: (shape, parameters in flctool's order, scikit-fuzzy's value on x)
REFERENCE = [
    ("gauss", (0.3, 0.7), lambda x: skm.gaussmf(x, 0.3, 0.7)),
    ("gauss2", (-0.5, 0.3, 0.5, 0.6), lambda x: skm.gauss2mf(x, -0.5, 0.3, 0.5, 0.6)),
    ("bell", (0.8, 2.5, 0.2), lambda x: skm.gbellmf(x, 0.8, 2.5, 0.2)),
    ("sigmoid", (0.1, -4.0), lambda x: skm.sigmf(x, 0.1, -4.0)),
    ("sigmoid_difference", (-1.0, 5.0, 1.0, 5.0), lambda x: skm.dsigmf(x, -1.0, 5.0, 1.0, 5.0)),
    ("sigmoid_product", (-1.0, 5.0, 1.0, -5.0), lambda x: skm.psigmf(x, -1.0, 5.0, 1.0, -5.0)),
    ("s_shape", (-1.0, 1.5), lambda x: skm.smf(x, -1.0, 1.5)),
    ("z_shape", (-1.0, 1.5), lambda x: skm.zmf(x, -1.0, 1.5)),
    ("pi_shape", (-2.0, -1.0, 0.5, 2.0), lambda x: skm.pimf(x, -2.0, -1.0, 0.5, 2.0)),
]


def _cosine(x: np.ndarray, c: float, w: float) -> np.ndarray:
    inside = (x >= c - 0.5 * w) & (x <= c + 0.5 * w)
    return np.where(inside, 0.5 * (1.0 + np.cos(2.0 / w * np.pi * (x - c))), 0.0)


def _concave(x: np.ndarray, i: float, e: float) -> np.ndarray:
    with np.errstate(divide="ignore"):
        if i <= e:
            return np.where(x < e, (e - i) / (2.0 * e - i - x), 1.0)
        return np.where(x > e, (i - e) / (i - 2.0 * e + x), 1.0)


#: scikit-fuzzy has no cosine, concave or spike: the reference is fuzzylite's formulas as
#: pyfuzzylite 8 writes them in numpy (the slow export tests compare with fuzzylite 6 itself).
FUZZYLITE_REFERENCE = [
    ("cosine", (0.3, 1.7), lambda x: _cosine(x, 0.3, 1.7)),
    ("concave", (0.5, 1.5), lambda x: _concave(x, 0.5, 1.5)),
    ("concave", (-0.5, -1.5), lambda x: _concave(x, -0.5, -1.5)),
    ("spike", (0.25, 2.0), lambda x: np.exp(-np.abs(10.0 / 2.0 * (x - 0.25)))),
]
X = np.concatenate([np.linspace(-3.0, 3.0, 4001), [-1.0, -0.5, 0.25, 0.3, 0.5, 1.5, 2.0]])


@pytest.mark.parametrize(("kind", "params", "reference"), REFERENCE + FUZZYLITE_REFERENCE,
                         ids=[f"{case[0]}{case[1]}" for case in REFERENCE + FUZZYLITE_REFERENCE])
def test_each_shape_is_scikit_fuzzys(kind: str, params: tuple[float, ...],
                                     reference: object) -> None:
    """Within 2 ulps of 1 (numpy's exp, cos and power round differently from the C
    library's, which flctool, fuzzylite and the C export use); fuzzylite's formulas for the
    shapes scikit-fuzzy lacks."""
    padded = (*params, *(0.0,) * (4 - len(params)))
    rows = np.array([padded])
    got = memberships(X, rows, [CODES[kind]])[:, 0]
    want = reference(X)  # type: ignore[operator]
    assert np.max(np.abs(got - want)) <= 4.5e-16
    assert got.min() >= 0.0 and got.max() <= 1.0
    scalar = [shape_membership(CODES[kind], *padded, float(x)) for x in X]
    assert got.tolist() == scalar


def test_exp_and_pow_overflow_give_the_limit_not_an_error() -> None:
    assert shape_membership(CODES["sigmoid"], 0.0, 100.0, 0.0, 0.0, -50.0) == 0.0
    assert shape_membership(CODES["bell"], 1e-300, 50.0, 0.0, 0.0, 1.0) == 0.0


EVERY_SHAPE = """\
flctool: 1
name: every_shape
inputs:
  a:
    range: [-1, 1]
    sets:
      low: {gauss2: [-1.0, 0.3, -0.7, 0.2]}
      mid: {gauss: [0.0, 0.25]}
      high: {bell: [0.4, 2.0, 0.9]}
  b:
    range: [0, 10]
    sets:
      low: {sigmoid: [3.0, -2.0]}
      mid: {sigmoid_difference: [3.0, 2.0, 7.0, 2.0]}
      high: {sigmoid_product: [7.0, 2.0, 20.0, -1.0]}
  c:
    range: [0, 1]
    sets:
      low: {z_shape: [0.1, 0.4]}
      mid: {pi_shape: [0.2, 0.4, 0.5, 0.8]}
      high: {s_shape: [0.6, 0.9]}
      top: [0.85, 1, 1, 1]
output:
  name: turn
  commands: {hard_left: -1, left: -0.4, none: 0, right: 0.5, hard_right: 1}
"""


#: The shapes fuzzylite has and MATLAB / Octave lack (their FIS names are fuzzylite's own),
#: with trapezoids: a controller Octave cannot read, kept apart from EVERY_SHAPE.
FUZZYLITE_SHAPES = """\
flctool: 1
name: fuzzylite_shapes
inputs:
  a:
    range: [-1, 1]
    sets:
      low: [-1, -1, -0.5, 0]
      mid: {cosine: [0.0, 1.2]}
      high: [0, 0.5, 1, 1]
  d:
    range: [0, 1]
    sets:
      low: {concave: [0.4, 0.0]}
      mid: {cosine: [0.5, 0.6]}
      peak: {spike: [0.7, 0.5]}
      high: {concave: [0.6, 1.0]}
output:
  name: turn
  commands: {hard_left: -1, left: -0.4, none: 0, right: 0.5, hard_right: 1}
"""


def every_shape_behaviour(text: str = EVERY_SHAPE):  # type: ignore[no-untyped-def]
    """A controller with every shape of scikit-fuzzy's (and a trapezoid), or ``text``'s,
    its rules (one per combination of sets) seeded at random."""
    import itertools

    import yaml

    data = yaml.safe_load(text)
    rng = np.random.default_rng(3)
    commands = list(data["output"]["commands"])
    names = list(data["inputs"])
    data["rules"] = [{"if": dict(zip(names, sets, strict=True)),
                      "then": commands[rng.integers(5)]}
                     for sets in itertools.product(*(data["inputs"][n]["sets"] for n in names))]
    return behaviour_from_data(data)


def fuzzylite_shapes_behaviour():  # type: ignore[no-untyped-def]
    """The cosine, concave and spike sets (:data:`FUZZYLITE_SHAPES`)."""
    return every_shape_behaviour(FUZZYLITE_SHAPES)


def reference_outputs(behaviour, states: np.ndarray) -> np.ndarray:  # type: ignore[no-untyped-def]
    """Eq. 1-3 by a loop over the rules, from the plain-Python memberships."""
    controller = compile_behaviour(behaviour)
    mus = controller.memberships(states)
    numerator = np.zeros(len(states))
    total = np.zeros(len(states))
    assert controller.consequents is not None
    for m, sets in enumerate(np.ndindex(*controller.shape)):
        alpha = mus[0][:, sets[0]]
        for i in range(1, len(sets)):
            alpha = np.minimum(alpha, mus[i][:, sets[i]])
        numerator += alpha * controller.singletons[controller.consequents[m]]
        total += alpha
    return np.clip(numerator / total, controller.singletons.min(), controller.singletons.max())


@pytest.mark.parametrize("text", [EVERY_SHAPE, FUZZYLITE_SHAPES], ids=["skfuzzy", "fuzzylite"])
def test_every_inference_path_computes_the_same_bits(text: str) -> None:
    behaviour = every_shape_behaviour(text)
    controller = compile_behaviour(behaviour)
    rng = np.random.default_rng(0)
    lo, hi = controller.ranges[:, 0], controller.ranges[:, 1]
    states = rng.uniform(lo - 0.1 * (hi - lo), hi + 0.1 * (hi - lo), (3_000, len(lo)))
    out = controller.output(states)
    assert np.max(np.abs(out - reference_outputs(behaviour, states))) <= 1e-15
    assert np.array_equal(controller.output(states[:5]), out[:5])  # state by state
    assert [controller.output_one(s) for s in states[:50]] == out[:50].tolist()
    population = np.stack([controller.consequents, controller.consequents[::-1]])
    assert np.array_equal(controller.output(states, population)[0], out)
    sparse = SparseRules.from_behaviour(behaviour)
    for state in states[:30]:
        rules, alphas = controller.active_rules(state)
        got_rules, got_alphas, _ = sparse.activations(state.tolist())
        assert got_rules == rules.tolist() and got_alphas == alphas.tolist()
    dense = controller.activations(states[:100])
    for b in range(100):
        rules, alphas = controller.active_rules(states[b])
        assert dense[b, rules].tolist() == alphas.tolist()


def test_shaped_sets_read_and_write_back() -> None:
    from flctool.behaviour import behaviour_to_yaml

    behaviour = every_shape_behaviour()
    text = behaviour_to_yaml(behaviour)
    assert "mid: {gauss: [0.0, 0.25]}" in text
    assert parse_behaviour(text) == behaviour


def _input(sets: str, low: float = 0.0, high: float = 10.0) -> str:
    return (f"flctool: 1\nname: t\ninputs:\n  x:\n    range: [{low}, {high}]\n    sets:\n{sets}"
            "output:\n  name: a\n  commands: {l: -1, r: 1}\n")


def _with_rules(text: str) -> str:
    return text + "rules:\n" + "".join(
        f"  - {{if: {{x: {name}}}, then: l}}\n" for name in ("a", "b"))


def _problems(text: str) -> list[tuple[int | None, str, str]]:
    with pytest.raises(SpecError) as caught:
        parse_behaviour(text, "t.yaml")
    return [(p.line, ".".join(map(str, p.path)), p.message) for p in caught.value.problems]


def test_gaussians_too_far_apart_leave_a_gap() -> None:
    # at the midpoint each is exp(-12.5) = 3.7e-6 with sigma 1, exp(-50) with sigma 0.5
    parse_behaviour(_input("      a: {gauss: [0, 1]}\n      b: {gauss: [10, 1]}\n"))
    far = _input("      a: {gauss: [0, 0.5]}\n      b: {gauss: [10, 0.5]}\n")
    (line, path, message), = _problems(far)
    assert (line, path) == (6, "inputs.x.sets")
    assert "a membership below 1e-06 in every set" in message


def test_a_gaussian_covers_the_range_alone() -> None:
    parse_behaviour(_input("      a: {gauss: [5, 1]}\n"))
    assert "below 1e-06" in _problems(_input("      a: {gauss: [5, 0.5]}\n"))[0][2]


@pytest.mark.parametrize(("written", "message"), [
    ("{gauss: [0, 0]}", "sigma is 0.0; it must be above 0"),
    ("{gauss: [0, 1e-300]}", "so small that its square is 0"),
    ("{gauss: [0, 1, 2]}", "a gauss set takes 2 numbers [mean, sigma]; this one has 3"),
    ("{bell: [1, -2, 3]}", "slope is -2.0; it must be above 0"),
    ("{sigmoid: [1, 0]}", "slope is 0, a constant 0.5"),
    ("{gauss2: [3, 1, 2, 1]}", "mean1 is above its mean2"),
    ("{s_shape: [3, 3]}", "foot must be below its shoulder"),
    ("{pi_shape: [1, 3, 2, 4]}", "foot1 < shoulder1 <= shoulder2 < foot2"),
    ("{gauss: [0, 1], bell: [1, 2, 3]}", "names exactly one shape; this one names 2"),
    ("{cauchy: [1, 2]}", "unknown key 'cauchy'"),
])
def test_bad_shapes_are_reported_at_their_line(written: str, message: str) -> None:
    text = _input(f"      a: [0, 0, 5, 10]\n      b: {written}\n")
    problems = _problems(text)
    assert any(line == 8 and path.startswith("inputs.x.sets.b") and message in text_
               for line, path, text_ in problems), problems


@settings(max_examples=40, deadline=None)
@given(st.floats(-5, 5), st.floats(0.05, 3), st.floats(-5, 5), st.floats(0.05, 3))
@pytest.mark.slow
def test_coverage_holds_wherever_the_check_accepts(m1: float, s1: float, m2: float,
                                                   s2: float) -> None:
    """Accepted inputs have a set at least 1e-6 high at 20,001 points of the range."""
    text = _input(f"      a: {{gauss: [{m1!r}, {s1!r}]}}\n      b: {{gauss: [{m2!r}, {s2!r}]}}\n",
                  -5.0, 5.0)
    try:
        behaviour = parse_behaviour(_with_rules(text))
    except SpecError:
        return
    controller = compile_behaviour(behaviour)
    xs = np.linspace(-5.0, 5.0, 20_001)[:, None]
    assert controller.memberships(xs)[0].max(axis=1).min() >= 1e-6
    assert math.isfinite(float(controller.output(xs).max()))


def test_learning_the_sets_of_a_shaped_input_is_refused_at_the_set() -> None:
    text = _input("      a: [0, 0, 5, 10]\n      b: {gauss: [10, 3]}\n") + (
        "learning:\n  learner: hybrid\n  sets:\n    inputs: all\n")
    problems = _problems(text)
    assert any(line == 8 and path == "inputs.x.sets.b" and "only trapezoid partitions can "
               "be learned" in message for line, path, message in problems), problems
