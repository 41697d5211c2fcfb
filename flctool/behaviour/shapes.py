"""The set shapes besides the trapezoid: Gaussian, bell, sigmoids, S, Z, Pi, cosine, concave
and spike.

A set is a trapezoid quadruple ``[pa, pb, pc, pd]`` (the paper's sets, Sec. II, and the
default), or one of these shapes written as a one-key mapping, ``near: {gauss: [0.5, 0.1]}``.
The parameters are in scikit-fuzzy's order (``skfuzzy.membership``, the tests' reference):

========================  ======================================  =======================
shape                     parameters                              scikit-fuzzy
========================  ======================================  =======================
``gauss``                 mean, sigma                             ``gaussmf``
``gauss2``                mean1, sigma1, mean2, sigma2            ``gauss2mf``
``bell``                  width, slope, centre                    ``gbellmf``
``sigmoid``               centre, slope                           ``sigmf``
``sigmoid_difference``    centre1, slope1, centre2, slope2        ``dsigmf`` (absolute)
``sigmoid_product``       centre1, slope1, centre2, slope2        ``psigmf``
``s_shape``               foot, shoulder                          ``smf``
``z_shape``               shoulder, foot                          ``zmf``
``pi_shape``              foot1, shoulder1, shoulder2, foot2      ``pimf``
``cosine``                centre, width                           (fuzzylite's Cosine)
``concave``               inflection, end                         (fuzzylite's Concave)
``spike``                 centre, width                           (fuzzylite's Spike)
========================  ======================================  =======================

scikit-fuzzy has no cosine, concave or spike: their formulas and parameters are fuzzylite's
(the tests compare them with fuzzylite 6).

The formulas are coded once in Python, in :mod:`flctool.membership`. Only trapezoids
can be learned as sets; these shapes are fixed where the file puts them.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

from pydantic import model_validator
from typing_extensions import TypeIs

from flctool.behaviour.base import Section

#: Each shape's parameters, in scikit-fuzzy's order. The index of a shape in this mapping,
#: plus one, is its code in the compiled layout (0 is the trapezoid).
SHAPES: dict[str, tuple[str, ...]] = {
    "gauss": ("mean", "sigma"),
    "gauss2": ("mean1", "sigma1", "mean2", "sigma2"),
    "bell": ("width", "slope", "centre"),
    "sigmoid": ("centre", "slope"),
    "sigmoid_difference": ("centre1", "slope1", "centre2", "slope2"),
    "sigmoid_product": ("centre1", "slope1", "centre2", "slope2"),
    "s_shape": ("foot", "shoulder"),
    "z_shape": ("shoulder", "foot"),
    "pi_shape": ("foot1", "shoulder1", "shoulder2", "foot2"),
    "cosine": ("centre", "width"),
    "concave": ("inflection", "end"),
    "spike": ("centre", "width"),
}
#: The codes of the compiled layout: 0 the trapezoid, then the shapes in SHAPES' order.
CODES: dict[str, int] = {"trapezoid": 0} | {name: k + 1 for k, name in enumerate(SHAPES)}


def shape_problem(kind: str, params: tuple[float, ...]) -> str | None:
    """What is wrong with shape ``kind``'s ``params``, or None; every shape must be a
    function from the range to [0, 1] that the formulas compute without dividing by 0."""
    names = SHAPES[kind]
    if len(params) != len(names):
        return (f"a {kind} set takes {len(names)} numbers [{', '.join(names)}]; this one has "
                f"{len(params)}")
    p = dict(zip(names, params, strict=True))
    for name in ("sigma", "sigma1", "sigma2", "width"):
        if name in p and not p[name] > 0:
            return f"the {kind} set's {name} is {p[name]!r}; it must be above 0"
        if name.startswith("sigma") and name in p and not 2.0 * p[name] * p[name] > 0:
            return (f"the {kind} set's {name} is {p[name]!r}, so small that its square is 0 "
                    "in floating point; give it a sigma above 1e-150")
    if kind == "concave" and p["inflection"] == p["end"]:
        return ("the concave set's inflection equals its end (a step, not a curve); put the "
                "inflection below the end (rising) or above it (falling)")
    if kind == "bell" and not p["slope"] > 0:
        return f"the bell set's slope is {p['slope']!r}; it must be above 0"
    for name in ("slope", "slope1", "slope2"):
        if kind.startswith("sigmoid") and p.get(name) == 0:
            return f"the {kind} set's {name} is 0, a constant 0.5; give it a slope"
    if kind == "gauss2" and not p["mean1"] <= p["mean2"]:
        return ("the gauss2 set's mean1 is above its mean2; write the left mean first (its "
                "membership is 1 between them)")
    if kind == "s_shape" and not p["foot"] < p["shoulder"]:
        return "the s_shape set's foot must be below its shoulder (it rises from 0 to 1)"
    if kind == "z_shape" and not p["shoulder"] < p["foot"]:
        return "the z_shape set's shoulder must be below its foot (it falls from 1 to 0)"
    if kind == "pi_shape" and not (p["foot1"] < p["shoulder1"] <= p["shoulder2"] < p["foot2"]):
        return ("the pi_shape set's points must satisfy foot1 < shoulder1 <= shoulder2 < "
                "foot2")
    return None


class ShapedSet(Section):
    """A set of one of the shapes besides the trapezoid: ``{gauss: [mean, sigma]}``."""

    gauss: tuple[float, ...] | None = None
    gauss2: tuple[float, ...] | None = None
    bell: tuple[float, ...] | None = None
    sigmoid: tuple[float, ...] | None = None
    sigmoid_difference: tuple[float, ...] | None = None
    sigmoid_product: tuple[float, ...] | None = None
    s_shape: tuple[float, ...] | None = None
    z_shape: tuple[float, ...] | None = None
    pi_shape: tuple[float, ...] | None = None
    cosine: tuple[float, ...] | None = None
    concave: tuple[float, ...] | None = None
    spike: tuple[float, ...] | None = None

    @model_validator(mode="after")
    def _one_shape(self) -> Any:
        given = [name for name in SHAPES if getattr(self, name) is not None]
        if len(given) != 1:
            raise ValueError(
                f"a shaped set names exactly one shape; this one names {len(given)}"
                f"{' (' + ', '.join(given) + ')' if given else ''}: write e.g. "
                "{gauss: [mean, sigma]}, or a trapezoid [pa, pb, pc, pd]")
        problem = shape_problem(given[0], getattr(self, given[0]))
        if problem is not None:
            raise ValueError(problem)
        return self

    @property
    def kind(self) -> str:
        return next(name for name in SHAPES if getattr(self, name) is not None)

    @property
    def params(self) -> tuple[float, ...]:
        value: tuple[float, ...] = getattr(self, self.kind)
        return value


def shaped(kind: str, params: tuple[float, ...] | list[float]) -> ShapedSet:
    """The set of shape ``kind`` with ``params`` (validated)."""
    return ShapedSet.model_validate({kind: tuple(params)})


def set_row(value: Any) -> tuple[int, tuple[float, float, float, float]]:
    """A set as the compiled layout holds it: its code (:data:`CODES`) and four numbers (a
    trapezoid's corners, or the shape's parameters padded with 0)."""
    if isinstance(value, ShapedSet):
        params = tuple(float(v) for v in value.params)
        padded = (*params, *(0.0,) * (4 - len(params)))
        return CODES[value.kind], (padded[0], padded[1], padded[2], padded[3])
    pa, pb, pc, pd = value
    return 0, (float(pa), float(pb), float(pc), float(pd))


def is_trapezoid(value: tuple[float, float, float, float] | ShapedSet
                 ) -> TypeIs[tuple[float, float, float, float]]:
    """Whether a set is a trapezoid quadruple (not a set of another shape)."""
    return not isinstance(value, ShapedSet)


def trapezoids(sets: Iterable[tuple[float, float, float, float] | ShapedSet]
               ) -> list[tuple[float, float, float, float]]:
    """The quadruples of sets known to be trapezoids (a ValueError otherwise)."""
    quads = []
    for value in sets:
        if not is_trapezoid(value):
            raise ValueError(f"a {value.kind} set where a trapezoid is required")
        quads.append(value)
    return quads


#: How far inside a range end that no set fires the controller evaluates the input, as a
#: share of the range's width (see :func:`evaluated_range`).
END_MARGIN = 2.0**-30


def evaluated_range(range_: tuple[float, float],
                    sets: Iterable[tuple[float, float, float, float] | ShapedSet]
                    ) -> tuple[float, float]:
    """The interval an input's states are clipped to before its sets are evaluated.

    It is the declared range, except at an end where no set fires but a set rises from it
    (a triangle ``[0, 0.25, 0.5]`` on ``[0, 1]``, as fuzzylite's and MATLAB's examples write
    them): there eq. 3 has no value (fuzzylite gives the output's default, often nan), so the
    state is moved :data:`END_MARGIN` of the range's width inside, where that set fires and
    the controller is continuous. The controller thus gives at that end its value an
    imperceptible step inside (its limit there, within the slope times that step).
    """
    lo, hi = range_
    values = list(sets)
    if not all(is_trapezoid(v) for v in values):
        return lo, hi  # the other shapes are checked for coverage otherwise (no exact zeros)
    quads = trapezoids(values)
    step = (hi - lo) * END_MARGIN
    low_fires = any(pa == pb == lo for pa, pb, _, _ in quads)
    low_rises = any(pa == lo < pb for pa, pb, _, _ in quads)
    high_fires = any(pc == pd == hi for _, _, pc, pd in quads)
    high_falls = any(pc < pd == hi for _, _, pc, pd in quads)
    return (lo + step if low_rises and not low_fires else lo,
            hi - step if high_falls and not high_fires else hi)
