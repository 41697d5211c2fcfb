"""How fuzzylite (FLL, and FCL in its dialect) and MATLAB / Octave (FIS) write the shapes of
:mod:`flctool.behaviour.shapes`: their term names and parameter orders, both ways.

flctool writes a shape's parameters in scikit-fuzzy's order; fuzzylite and MATLAB each have
their own. Each entry here is ``flctool shape -> (their name, order)``, where ``order[k]`` is
the index in flctool's parameters of their k-th parameter. The same formulas are computed
(:mod:`flctool.membership`), so an export reads back to the same set, and the
engines compute what flctool does.
"""

from __future__ import annotations

from collections.abc import Sequence

from flctool.behaviour.shapes import SHAPES

#: fuzzylite 6 / pyfuzzylite terms: Gaussian(mean, sd), GaussianProduct(meanA, sdA, meanB,
#: sdB), Bell(center, width, slope), Sigmoid(inflection, slope), SigmoidDifference(left,
#: rising, falling, right), SigmoidProduct(left, rising, falling, right), SShape(start, end),
#: ZShape(start, end), PiShape(bottomLeft, topLeft, topRight, bottomRight), Cosine(center,
#: width), Concave(inflection, end), Spike(center, width).
FUZZYLITE: dict[str, tuple[str, tuple[int, ...]]] = {
    "gauss": ("Gaussian", (0, 1)),
    "gauss2": ("GaussianProduct", (0, 1, 2, 3)),
    "bell": ("Bell", (2, 0, 1)),
    "sigmoid": ("Sigmoid", (0, 1)),
    "sigmoid_difference": ("SigmoidDifference", (0, 1, 3, 2)),
    "sigmoid_product": ("SigmoidProduct", (0, 1, 3, 2)),
    "s_shape": ("SShape", (0, 1)),
    "z_shape": ("ZShape", (0, 1)),
    "pi_shape": ("PiShape", (0, 1, 2, 3)),
    "cosine": ("Cosine", (0, 1)),
    "concave": ("Concave", (0, 1)),
    "spike": ("Spike", (0, 1)),
}

#: MATLAB / Octave membership functions: gaussmf [sigma c], gauss2mf [sig1 c1 sig2 c2],
#: gbellmf [a b c], sigmf [a c], dsigmf / psigmf [a1 c1 a2 c2], smf [a b], zmf [a b],
#: pimf [a b c d]; and fuzzylite's own FIS names for the shapes MATLAB and Octave lack,
#: cosinemf [center width], concavemf [inflection end], spikemf [center width] (fuzzylite
#: reads them; MATLAB and Octave do not).
MATLAB: dict[str, tuple[str, tuple[int, ...]]] = {
    "gauss": ("gaussmf", (1, 0)),
    "gauss2": ("gauss2mf", (1, 0, 3, 2)),
    "bell": ("gbellmf", (0, 1, 2)),
    "sigmoid": ("sigmf", (1, 0)),
    "sigmoid_difference": ("dsigmf", (1, 0, 3, 2)),
    "sigmoid_product": ("psigmf", (1, 0, 3, 2)),
    "s_shape": ("smf", (0, 1)),
    "z_shape": ("zmf", (0, 1)),
    "pi_shape": ("pimf", (0, 1, 2, 3)),
    "cosine": ("cosinemf", (0, 1)),
    "concave": ("concavemf", (0, 1)),
    "spike": ("spikemf", (0, 1)),
}


def written(table: dict[str, tuple[str, tuple[int, ...]]], kind: str,
            params: Sequence[float]) -> tuple[str, list[float]]:
    """Shape ``kind`` with flctool's ``params`` as ``table``'s format writes it."""
    name, order = table[kind]
    return name, [params[k] for k in order]


def read(table: dict[str, tuple[str, tuple[int, ...]]], name: str,
         values: Sequence[float]) -> tuple[str, tuple[float, ...]] | None:
    """The flctool shape and parameters of ``table``'s term ``name`` with ``values`` (in
    its order), or None if ``name`` is not one of these shapes. The count is checked by the
    shape's validation (a located error) when it is wrong."""
    for kind, (their, order) in table.items():
        if their == name:
            if len(values) != len(order):
                return kind, tuple(values)  # refused with the shape's message
            params = [0.0] * len(order)
            for k, index in enumerate(order):
                params[index] = values[k]
            return kind, tuple(params)
    return None


def arity(table: dict[str, tuple[str, tuple[int, ...]]], name: str) -> int | None:
    """How many parameters ``table``'s term ``name`` takes, or None if it is not a shape."""
    for kind, (their, _) in table.items():
        if their == name:
            return len(SHAPES[kind])
    return None


#: jFuzzyLogic's FCL terms, as fuzzylite's term and the order of their parameters in it:
#: ``trape a b c d``, ``trian a b c``, ``gauss mean stdev``, ``gbell a b mean``,
#: ``sigm gain center`` (the same formulas).
JFUZZYLOGIC: dict[str, tuple[str, tuple[int, ...]]] = {
    "trape": ("Trapezoid", (0, 1, 2, 3)),
    "trian": ("Triangle", (0, 1, 2)),
    "gauss": ("Gaussian", (0, 1)),
    "gbell": ("Bell", (2, 0, 1)),
    "sigm": ("Sigmoid", (1, 0)),
}


def from_jfuzzylogic(name: str, values: Sequence[float]) -> tuple[str, list[float]]:
    """jFuzzyLogic's term ``name`` as fuzzylite's term and values (unchanged if ``name`` is
    not one of jFuzzyLogic's terms, or has another count). jFuzzyLogic reads its keywords in
    any case, and its examples write ``GAUSS 0 1`` as often as ``gauss 0 1``."""
    found = JFUZZYLOGIC.get(name.lower())
    if found is None or len(values) != len(found[1]):
        return name, list(values)
    their, order = found
    return their, [values[k] for k in order]
