"""What the importers share: a controller read from a file, located line by line.

Each importer parses its format into an :class:`ImportedController`, refusing on the spot any
construct flctool cannot express. :func:`build_behaviour` then checks the rules against each
other and validates the result as a behaviour, with every problem located at its line in the
imported file; a problem that concerns another rule too (a duplicate) names that rule by its
line and text, never by a behaviour file's field path.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
import re
from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Any, TypeVar

from flctool.behaviour import FORMAT_VERSION, Behaviour, behaviour_from_data, behaviour_to_yaml
from flctool.behaviour.shapes import ShapedSet, shape_problem, shaped
from flctool.behaviour.yaml_source import SourceMap
from flctool.errors import ExportError, ImportRefusals, PathPart, line_of
from flctool.export import shapes

Quad = tuple[float, float, float, float]
_T = TypeVar("_T")


#: What each format's importer reads, for refusals that have no more specific fix.
SUBSET = {
    "fll": "a Takagi-Sugeno engine: Trapezoid/Triangle/Rectangle/Ramp/Gaussian/Bell/Sigmoid/"
           "... inputs, Constant outputs, WeightedAverage, conjunction Minimum or "
           "AlgebraicProduct, plain 'and' rules",
    "fcl": "singleton output terms with METHOD : COGS, trapezoid point lists or fuzzylite "
           "terms (Trapezoid, Triangle, Gaussian, ...), AND : MIN or PROD, plain AND rules",
    "fis": "Type='sugeno' with constant outputs, trapmf/trimf/gaussmf/gbellmf/sigmf/... "
           "inputs, AndMethod='min' or 'prod', DefuzzMethod='wtaver', AND rules of weight 1",
}


def refusals(file: str, errors: list[ExportError]) -> ExportError:
    """One error for every construct in ``errors`` (the error itself when there is one); a
    construct refused at several lines (one per output term, say) is listed once, at its
    first line, naming the others."""
    groups: dict[str, list[ExportError]] = {}
    for error in errors:
        text = str(error.args[0]).partition(": ")[2]  # without "file:line"
        groups.setdefault(re.sub(r"'[^']*'|-?\d[\d.e+-]*", "_", text), []).append(error)
    merged = []
    for group in groups.values():
        first = group[0]
        if len(group) > 1:
            lines = ", ".join(str(line_of(str(e))) for e in group[1:])
            first = ExportError(f"{first.args[0]}; the same at line{'s' * (len(group) > 2)} "
                                f"{lines}", hint=first.hint)
        merged.append(first)
    return merged[0] if len(merged) == 1 else ImportRefusals(file, merged)


def unsupported(file: str, line: int, construct: str, hint: str = "") -> ExportError:
    """An import error naming the construct flctool cannot express, where it is, and what to
    do: ``hint``, or (when there is no more specific fix) the subset that flctool reads."""
    if not hint:
        suffix = file.rpartition(".")[2].lower()
        subset = SUBSET.get(suffix, "the subset described in flctool's docs/formats")
        hint = f"rewrite it within what flctool imports: {subset}"
    return ExportError(f"{file}:{line}: {construct}", hint=hint)


def span(xs: Iterable[float]) -> tuple[float, float]:
    """The smallest range holding every finite x (0 to 1 when there is none)."""
    finite = [x for x in xs if math.isfinite(x)]
    return (min(finite), max(finite)) if finite else (0.0, 1.0)


#: The corners a set refused while reading stands in with (never validated: the file is
#: refused, see :meth:`ImportedController.put_off`).
QUAD0: Quad = (0.0, 0.0, 0.0, 0.0)


@dataclass
class ImportedSet:
    """A set as read; an infinite shoulder (pa = pb = -inf, pc = pd = inf) reaches the end of
    the input's range, where :func:`build_behaviour` puts it. A set of another shape
    (:mod:`flctool.behaviour.shapes`) has ``shape`` (its name and parameters in flctool's order)
    and no meaningful ``quad``."""

    name: str
    quad: Quad
    line: int
    shape: tuple[str, tuple[float, ...]] | None = None

    def shape_value(self) -> Quad | ShapedSet:
        """The set as the model holds it (a trapezoid's quadruple as read)."""
        return shaped(*self.shape) if self.shape else self.quad


def shaped_set(name: str, kind: str, params: tuple[float, ...], file: str, line: int
               ) -> ImportedSet:
    """A set of shape ``kind`` as read at ``line`` of ``file``, or the error saying what is
    wrong with its parameters (given in flctool's order)."""
    problem = shape_problem(kind, params)
    if problem is not None:
        raise unsupported(file, line, f"set '{name}': {problem}",
                          "correct the parameters (the formulas: docs/behaviour-files.md)")
    return ImportedSet(name, (0.0, 0.0, 0.0, 0.0), line, (kind, params))


@dataclass
class ImportedInput:
    name: str
    line: int
    range: tuple[float, float] | None = None
    sets: list[ImportedSet] = field(default_factory=list)

    def resolved_range(self) -> tuple[float, float]:
        """The declared range, or the span of the sets when the format declares none."""
        if self.range is not None:
            return self.range
        return span(v for s in self.sets for v in (s.shape[1] if s.shape else
                                                    (s.quad[0], s.quad[3])))

    def resolved_sets(self, file: str) -> dict[str, Any]:
        """Every set as a behaviour file writes it: a trapezoid's quadruple inside the range
        (see :func:`inside_range`), or a shape's ``{name: [parameters]}``."""
        quads = self.resolved_quads(file)
        return {s.name: ({s.shape[0]: list(s.shape[1])} if s.shape else list(quads[s.name]))
                for s in self.sets}

    def resolved_quads(self, file: str) -> dict[str, Quad]:
        """Every trapezoid's quadruple inside the range (see :func:`inside_range`)."""
        lo, hi = self.resolved_range()
        if not lo < hi:  # checked first: every set would seem to lie outside a backwards range
            raise unsupported(file, self.line, f"input '{self.name}' has the range "
                              f"[{lo!r}, {hi!r}], whose low end is not below its high end",
                              "write the range low end first, and make it wider than a point")
        return {s.name: inside_range(s, (lo, hi), file) for s in self.sets if not s.shape}


def inside_range(item: ImportedSet, span: tuple[float, float], file: str) -> Quad:
    """A set's quadruple with the same membership inside the range and no point outside it.

    Inputs are clipped to the range, so a shoulder whose plateau reaches the range's end (an
    infinite foot, or MATLAB's foot just outside the range: ``[-1 0 90 110]`` on ``[0, 300]``)
    is the shoulder ``[0, 0, 90, 110]``, exactly. A foot one ulp from its top (how flctool
    writes a vertical edge for readers that refuse one) is that vertical edge, exactly: no
    double lies between them. A ramp that the range's end cuts, or a set that does not reach
    into the range, is refused: no trapezoid inside the range has that membership.
    """
    lo, hi = span
    pa, pb, pc, pd = item.quad
    if pa < pb and math.nextafter(pa, math.inf) == pb:
        pa = pb
    if pc < pd and math.nextafter(pc, math.inf) == pd:
        pd = pc
    where = f"set '{item.name}' {list(item.quad)}"
    if pd < lo or pa > hi or (pd == lo and pc < lo) or (pa == hi and pb > hi):
        raise unsupported(file, item.line, f"{where} does not reach into the range "
                          f"[{lo!r}, {hi!r}], so it never fires",
                          "remove the set, or widen the range")
    if pa < lo:
        if pb > lo or pc < lo:
            raise unsupported(file, item.line, f"{where} has a ramp that the range's low end "
                              f"{lo!r} cuts, so its membership there is neither 0 nor 1; "
                              "flctool's sets are trapezoids inside the range",
                              f"move its first two points to {lo!r} (a shoulder) or inside "
                              "the range")
        pa = pb = lo
    if pd > hi:
        if pc < hi or pb > hi:
            raise unsupported(file, item.line, f"{where} has a ramp that the range's high "
                              f"end {hi!r} cuts, so its membership there is neither 0 nor 1; "
                              "flctool's sets are trapezoids inside the range",
                              f"move its last two points to {hi!r} (a shoulder) or inside "
                              "the range")
        pc = pd = hi
    return pa, pb, pc, pd


@dataclass
class ImportedCommand:
    name: str
    value: float
    line: int
    #: A first-order Takagi-Sugeno term being converted (:mod:`flctool.export.linear`): its
    #: input coefficients, in the order of the inputs, then its constant. ``value`` is then
    #: fitted once the behaviour is built.
    linear: tuple[float, ...] | None = None


@dataclass
class ImportedRule:
    """IF input_1 IS set AND ... THEN output IS command, as read at ``line``; ``text`` is the
    rule as the file writes it."""

    antecedent: dict[str, str]
    command: str
    line: int
    text: str = ""
    #: An OR rule's conditions (input, set), the antecedent then being empty; fuzzylite and
    #: MATLAB fire it with their maximum. Imported only by a Mamdani conversion (see
    #: :func:`expanded_rules`), as is a rule that leaves out an input.
    disjuncts: list[tuple[str, str]] = field(default_factory=list)
    #: The rule's weight (its activation is multiplied by it); not 1 only for a Mamdani
    #: output being converted, where the measurement takes it into account.
    weight: float = 1.0
    #: The inputs whose condition is negated (NOT: membership 1 - mu), refused unless a
    #: Mamdani output is converted, where it expands over the input's other sets.
    negated: set[str] = field(default_factory=set)

    def named(self) -> str:
        """The rule as a message about another rule names it: by its line and its text."""
        written = f" ('{excerpt(self.text)}')" if self.text else ""
        return f"the rule at line {self.line}{written}"


def excerpt(text: str, width: int = 60) -> str:
    """``text`` cut to ``width`` characters for a message."""
    return text if len(text) <= width else text[:width] + "..."


@dataclass(frozen=True)
class Method:
    """A way of combining that differs from flctool's, as the file writes it at ``line``."""

    text: str  # the setting as the format spells it, e.g. "AND : PROD"
    line: int
    hint: str = ""
    #: A conjunction by the product: the behaviour's ``activation: product`` (eq. 2 as the
    #: product of the memberships), which fuzzylite and MATLAB compute as flctool does.
    product: bool = False


@dataclass
class ImportedController:
    """A controller as read, with the line of every part.

    ``conjunction`` is set when the file combines a rule's memberships by something other than
    the minimum (eq. 2): the product is imported as ``activation: product``, anything else
    refused; ``accumulation`` when it accumulates the rules by something that
    merges the rules sharing an output term (a maximum) instead of summing them (eq. 3).
    :func:`build_behaviour` refuses either where it would change the output.
    """

    file: str
    name: str = ""
    name_line: int = 1
    description: str = ""
    inputs: list[ImportedInput] = field(default_factory=list)
    output_name: str = ""
    output_line: int = 1
    output_declared: bool = False
    commands: list[ImportedCommand] = field(default_factory=list)
    rules: list[ImportedRule] = field(default_factory=list)
    conjunction: Method | None = None
    accumulation: Method | None = None
    #: How the format writes that a rule leaves an input out, when it has a way (FIS: index 0).
    omission: str = ""
    #: A Mamdani output converted to singletons: its OR rules and rules that leave out an
    #: input are expanded over the sets (:func:`expanded_rules`), since the conversion is an
    #: approximation measured against the rules as written (:mod:`flctool.export.mamdani`).
    expand_rules: bool = False
    #: How the file combines an OR rule's conditions, when not by the maximum (refused then).
    disjunction: Method | None = None
    #: Refusals the reader found and put off, so that :func:`build_behaviour` reports them
    #: with the rest (a Mamdani output not being converted, say).
    pending: list[ExportError] = field(default_factory=list)
    #: The commands :func:`expanded_rules` added (the mean of several), none in the file.
    merged_commands: list[str] = field(default_factory=list)
    #: A first-order output being converted: the output terms as the file gives them
    #: (renamed), before :func:`_own_commands` gave rules commands of their own.
    terms: list[ImportedCommand] = field(default_factory=list)
    #: What a conversion changed besides the rules and commands, for the user (the sets
    #: :func:`_fill_gaps` added).
    notes: list[str] = field(default_factory=list)
    #: A Takagi-Sugeno output that may be converted (``--linear-singletons``): it is, by
    #: :mod:`flctool.export.linear`, when it has a first-order term or a rule flctool's grid
    #: has none like (OR, NOT, a weight, an input left out), which is then expanded as a
    #: Mamdani conversion's; :func:`build_behaviour` clears it otherwise.
    convert_linear: bool = False

    def put_off(self, error: ExportError, fallback: _T) -> _T:
        """Keep ``error`` for :func:`build_behaviour` to report with the file's other
        refusals, and go on reading with ``fallback`` in place of what it refused."""
        self.pending.append(error)
        return fallback

    def error(self, line: int, construct: str, hint: str = "") -> ExportError:
        """An import error at ``line`` of this file (see :func:`unsupported`)."""
        return unsupported(self.file, line, construct, hint)

    def declare_output(self, name: str, line: int) -> None:
        """The output variable starts at ``line``; a second one is refused."""
        if self.output_declared:
            named = f" '{name}'" if name else ""
            raise self.error(line, f"a second output{named}",
                             "flctool controllers have one output")
        self.output_declared = True
        self.output_name, self.output_line = name, line


def quad_from_points(points: list[tuple[float, float]], span: tuple[float, float],
                     where: tuple[str, int], term: str) -> Quad:
    """A trapezoid from a piecewise-linear point list, or an error naming the term.

    The point list is read as IEC 61131-7 does: before the first point and after the last the
    membership stays at that point's value. So a list that starts at 1 is a left shoulder
    reaching the range's low end, one that ends at 1 a right shoulder reaching its high end.
    A shoulder's points at membership 1 beyond the range's end move to that end: inputs are
    clipped to the range, so the membership inside it does not change.
    """
    file, line = where
    xs = [x for x, _ in points]
    if not points or any(b < a for a, b in itertools.pairwise(xs)):
        raise unsupported(file, line, f"term '{term}': the points must be in increasing x")
    written = [y for _, y in points]
    points = _clamp_shoulders(points, span)
    xs = [x for x, _ in points]
    low, high = min(span[0], xs[0]), max(span[1], xs[-1])
    if points[0][1] == 1:  # a left shoulder: a vertical edge at the range's low end
        points = [(low, 0.0), (low, 1.0), *points]
    if points[-1][1] == 1:
        points = [*points, (high, 1.0), (high, 0.0)]
    top = [i for i, (_, y) in enumerate(points) if y == 1]
    if top and top == list(range(top[0], top[-1] + 1)):  # a plateau: its two ends
        points = points[: top[0] + 1] + points[top[-1]:] if len(top) > 1 else points
    xs = [x for x, _ in points]
    ys = tuple(y for _, y in points)
    quad: Quad | None = None
    if ys == (0, 1, 1, 0):
        quad = (xs[0], xs[1], xs[2], xs[3])
    elif ys == (0, 1, 0):
        quad = (xs[0], xs[1], xs[1], xs[2])
    if quad is None:
        raise unsupported(
            file, line, f"term '{term}' with membership values {written} is not a trapezoid",
            "flctool sets are trapezoids: points (pa, 0) (pb, 1) (pc, 1) (pd, 0), "
            "a triangle (pa, 0) (pb, 1) (pd, 0), or shoulders that start or end at 1")
    return quad


def _clamp_shoulders(points: list[tuple[float, float]], span: tuple[float, float]
                     ) -> list[tuple[float, float]]:
    """Move the points at membership 1 beyond the range to its end where the membership stays
    1 up to the end (the next point inward is at 1 too, or there is none)."""
    lo, hi = span
    moved = list(points)
    for i, (x, y) in enumerate(moved):
        if y == 1 and x < lo and (i + 1 == len(moved) or moved[i + 1][1] == 1):
            moved[i] = (lo, y)
    for i in range(len(moved) - 1, -1, -1):
        x, y = moved[i]
        if y == 1 and x > hi and (i == 0 or moved[i - 1][1] == 1):
            moved[i] = (hi, y)
    return moved


#: fuzzylite's linear terms and their numbers of points.
FUZZYLITE_TERMS = {"Trapezoid": 4, "Triangle": 3, "Rectangle": 2, "Ramp": 2}


def check_term_arity(kind: str, count: int, file: str, line: int) -> int:
    """How many points a fuzzylite term ``kind`` takes (it may add a height); refuses the
    kinds and counts flctool cannot read."""
    n = FUZZYLITE_TERMS.get(kind) or shapes.arity(shapes.FUZZYLITE, kind)
    if n is None:
        known = ", ".join([*FUZZYLITE_TERMS, *(name for name, _ in shapes.FUZZYLITE.values())])
        raise unsupported(file, line, f"a {kind} term: flctool's sets do not include it",
                          f"use one of the terms {known}")
    if count not in (n, n + 1):
        raise unsupported(file, line, f"a {kind} takes {n} numbers (and an optional height)",
                          f"write {kind} followed by {n} numbers")
    return n


def fuzzylite_set(name: str, kind: str, values: list[float], file: str, line: int
                  ) -> ImportedSet:
    """The set of fuzzylite's term ``kind`` with ``values`` (an optional height after its
    parameters, which must be 1): a trapezoid, or a set of another shape."""
    n = check_term_arity(kind, len(values), file, line)
    if len(values) > n and values[n] != 1.0:
        raise unsupported(file, line, f"the term '{name}' has height {values[n]!r}: flctool's "
                          "sets reach 1 (eq. 2 takes memberships as they are)",
                          "remove the height, or write it as 1")
    found = shapes.read(shapes.FUZZYLITE, kind, values[:n])
    if found is not None:
        if not all(math.isfinite(v) for v in values[:n]):
            raise unsupported(file, line, f"the {kind} term '{name}' has a parameter that is "
                              "not a finite number", "write finite numbers")
        return shaped_set(name, found[0], found[1], file, line)
    return ImportedSet(name, fuzzylite_quad(kind, values[:n], file, line), line)


def fuzzylite_quad(kind: str, values: list[float], file: str, line: int) -> Quad:
    """The quadruple of fuzzylite's Trapezoid, Triangle, Rectangle or Ramp term.

    A Ramp is a shoulder: rising from its start to its end (then 1 on), or falling. An
    infinite foot gives membership 1 up to it, whatever the neighbouring point: a shoulder,
    which :func:`inside_range` brings to the range's end.
    """
    if kind == "Triangle":
        pa, pb, pc, pd = values[0], values[1], values[1], values[2]
    elif kind == "Rectangle":  # membership 1 on [a, b], 0 elsewhere
        pa, pb, pc, pd = values[0], values[0], values[1], values[1]
    elif kind == "Ramp":
        start, end = values
        if start == end or not (math.isfinite(start) and math.isfinite(end)):
            raise unsupported(file, line, f"a Ramp from {start!r} to {end!r} has no slope",
                              "give a Ramp two different finite points")
        pa, pb, pc, pd = ((start, end, math.inf, math.inf) if start < end else
                          (-math.inf, -math.inf, end, start))
    else:
        pa, pb, pc, pd = values
    if pa == -math.inf:
        pa = pb = -math.inf
    if pd == math.inf:
        pc = pd = math.inf
    left = pa == pb == -math.inf or (math.isfinite(pa) and math.isfinite(pb))
    right = pc == pd == math.inf or (math.isfinite(pc) and math.isfinite(pd))
    if not (left and right):
        raise unsupported(file, line, f"a {kind} with an infinite point that is not a "
                          "shoulder's foot", "only the outer feet may be -inf (first) or inf "
                          "(last)")
    if any(b < a for a, b in itertools.pairwise((pa, pb, pc, pd))):
        raise unsupported(file, line, f"a {kind} whose points {values} are not in "
                          "increasing order", "write the points from left to right")
    return pa, pb, pc, pd


#: The refusal's fix for an output term that is not a constant.
NOT_A_CONSTANT = ("flctool's commands are constants: give each output term one value (a "
                  "singleton at the set's centroid is the usual choice, but it changes a "
                  "Mamdani controller's output)")


#: The fix offered when a first-order Takagi-Sugeno output is imported without converting.
LINEAR_HINT = ("import with --linear-singletons to replace each rule's linear function by a "
               "constant fitted to the first-order output: an approximation, whose largest "
               "error the import measures and reports; or set every input coefficient to 0")


def output_constant(kind: str, params: list[float], inputs: int, file: str, line: int,
                    name: str, linear: bool = False) -> tuple[float, tuple[float, ...] | None]:
    """A Takagi-Sugeno output term's constant (:func:`zero_order_constant`), and, when
    ``linear`` (a first-order output being converted) and the term is first-order, its
    coefficients (the constant then being a placeholder, fitted later:
    :mod:`flctool.export.linear`)."""
    if (linear and kind.lower() == "linear" and len(params) == inputs + 1
            and any(c != 0 for c in params[:-1])):
        return params[-1], tuple(params)
    return zero_order_constant(kind, params, inputs, file, line, name), None


def zero_order_constant(kind: str, params: list[float], inputs: int, file: str, line: int,
                        name: str) -> float:
    """The constant of a zero-order Takagi-Sugeno output term: a constant, or a linear term
    whose input coefficients are all 0 (``linear [0 0 c]`` in FIS, ``Linear 0 0 c`` in FLL).
    A first-order term (a non-zero coefficient) or a Mamdani set is refused."""
    if kind.lower() == "constant" and len(params) == 1:
        return params[0]
    if kind.lower() == "linear" and len(params) == inputs + 1:
        if all(c == 0 for c in params[:-1]):
            return params[-1]
        raise unsupported(file, line, f"output term '{name}' is first-order Takagi-Sugeno "
                          f"(linear with coefficients {params[:-1]}): flctool's commands are "
                          "constants (eq. 3)", LINEAR_HINT)
    if kind.lower() == "linear":
        raise unsupported(file, line, f"output term '{name}' is linear with {len(params)} "
                          f"numbers; the controller has {inputs} inputs",
                          f"give {inputs} coefficients and a constant")
    raise unsupported(file, line, f"output term '{name}' is a {kind}, not a constant: "
                      "flctool's commands are singletons", NOT_A_CONSTANT)


#: The fix for an imported rule that leaves out an input.
DONT_CARE_HINT = ("name a set of every input in each rule (one rule per set of the input left "
                  "out), accepting the change in weight, or write the rules in a behaviour "
                  "file, where leaving out an input means just that expansion; a Mamdani "
                  "output imported with --mamdani-singletons (a first-order one with "
                  "--linear-singletons) is expanded so, and the difference measured")


def check_unique(file: str, items: Iterable[tuple[str, int]], kind: str, of: str = "") -> None:
    """Refuse a name given twice (``items`` are (name, line)), naming both lines."""
    first: dict[str, int] = {}
    for name, line in items:
        if name in first:
            raise unsupported(file, line, f"the {kind} '{name}'{of} is defined twice, at "
                              f"lines {first[name]} and {line}", "rename or remove one of them")
        first[name] = line


def build_behaviour(imported: ImportedController) -> Behaviour:
    """Check the names, rules and methods and validate the controller; errors point at lines
    of the file."""
    file = imported.file
    if not imported.inputs:
        raise unsupported(file, 1, "the controller has no input variable")
    if not imported.output_name:
        raise unsupported(file, 1, "the controller has no output variable")
    # Every construct that keeps the file out is reported together (each at its first line):
    # the ones the reader put off (pending) and each of these checks'.
    found = list(imported.pending)
    if imported.convert_linear:
        names = {v.name for v in imported.inputs}
        imported.convert_linear = any(c.linear is not None for c in imported.commands) or any(
            r.disjuncts or r.negated or r.weight != 1.0 or set(r.antecedent) != names
            for r in imported.rules)
        imported.expand_rules = imported.convert_linear
    checks = [_check_names_unique, _check_methods]
    if not imported.expand_rules:
        checks = [_check_no_or_rule, _check_no_negation, _check_weights,
                  _check_rules_cover_every_input, *checks]
    elif imported.disjunction is not None and any(r.disjuncts for r in imported.rules):
        method = imported.disjunction
        found.append(imported.error(method.line, f"{method.text}: the conversion of a "
                                    "Mamdani output measures OR rules by the maximum",
                                    method.hint))
    for check in checks:
        try:
            check(imported)
        except ExportError as error:
            found.append(error)
    if found:
        raise refusals(file, found)
    _identifiers(imported)
    if imported.expand_rules:
        _fill_gaps(imported)
    rules = expanded_rules(imported) if imported.expand_rules else imported.rules
    linear = imported.convert_linear
    if linear:
        imported.terms = [dataclasses.replace(c) for c in imported.commands
                          if c.name not in imported.merged_commands]
        rules = _own_commands(imported, rules)
    marks: dict[tuple[PathPart, ...], tuple[int, int]] = {
        (): (1, 1), ("name",): (imported.name_line, 1), ("output",): (imported.output_line, 1)}
    data: dict[str, Any] = {"flctool": FORMAT_VERSION, "name": imported.name or "imported"}
    if imported.description:
        data["description"] = imported.description
    data["inputs"] = {}
    for variable in imported.inputs:
        marks[("inputs", variable.name)] = (variable.line, 1)
        for item in variable.sets:
            marks[("inputs", variable.name, "sets", item.name)] = (item.line, 1)
        data["inputs"][variable.name] = {"range": list(variable.resolved_range()),
                                         "sets": variable.resolved_sets(file)}
    for command in imported.commands:
        marks[("output", "commands", command.name)] = (command.line, 1)
    data["output"] = {"name": imported.output_name,
                      "commands": {c.name: c.value for c in imported.commands}}
    for index, rule in enumerate(rules):
        marks[("rules", index)] = (rule.line, 1)
    data["rules"] = [{"if": dict(rule.antecedent), "then": rule.command} for rule in rules]
    if (imported.conjunction is not None and imported.conjunction.product
            and (linear or not imported.expand_rules)):
        # eq. 2 as the file computes it. A Mamdani conversion keeps the minimum instead, its
        # difference from the product measured with the rest: on the product-conjunction
        # Mamdani examples (MATLAB's tank and tank2, Octave's tipper) the minimum's singleton
        # controller stays closer to the Mamdani output (0.698 against 1.08 for tank2).
        data["activation"] = "product"
    # A rule check that names another rule names it by line, as the file does (an expanded
    # rule by the line of the rule it came from).
    return behaviour_from_data(data, SourceMap(file, marks),
                               rule_names=lambda index: rules[index].named())


def expanded_rules(imported: ImportedController) -> list[ImportedRule]:
    """The rules with every OR rule and every rule that leaves out an input replaced by the
    full-grid rules (one set of each input) where it fires: for an AND rule, every set of
    each input it leaves out; for an OR rule, every combination in which some condition
    holds (NOT: the input's other sets). Each keeps its line. A combination two rules give
    the same command appears once; one given different commands gets their mean
    (:func:`_merge_conflicts`).

    This is not exact (eq. 2 gives an expanded rule another activation), so it is done only
    for a Mamdani output being converted, whose measured deviation is taken against the
    rules as written (:func:`as_written`)."""
    names = [v.name for v in imported.inputs]
    sets = {v.name: [s.name for s in v.sets] for v in imported.inputs}
    seen: set[tuple[tuple[str, ...], str]] = set()
    result: list[ImportedRule] = []
    for rule in imported.rules:
        if not rule.antecedent and not rule.disjuncts:
            raise unsupported(imported.file, rule.line, "the rule has no condition (every "
                              "input left out), so it would fire everywhere with no "
                              "activation to weigh it by", "give the rule a condition, or "
                              "remove it")
        for name, term in rule.disjuncts or [(n, rule.antecedent.get(n, ""))
                                             for n in rule.negated]:
            if term not in sets.get(name, []):
                what = f"set '{term}' of input '{name}'" if name in sets else f"input '{name}'"
                raise unsupported(imported.file, rule.line, f"the rule names {what}, which "
                                  "the file does not define", "correct the name")
        def chosen(name: str, term: str, rule: ImportedRule = rule) -> list[str]:
            """The sets of input ``name`` where the condition holds in the expansion."""
            if name in rule.negated:  # NOT: the input's other sets
                return [t for t in sets.get(name, []) if t != term]
            return [term]

        if rule.disjuncts:
            cells: list[tuple[str, ...]] = []
            for name, term in rule.disjuncts:
                choices = [chosen(name, term) if n == name else sets.get(n, []) for n in names]
                cells += list(itertools.product(*choices))
        elif any(n not in sets for n in rule.antecedent):  # an unknown input: checked later
            result.append(rule)
            continue
        else:
            cells = list(itertools.product(*(chosen(n, rule.antecedent[n])
                                              if n in rule.antecedent else sets[n]
                                              for n in names)))
        for cell in cells:
            if (cell, rule.command) not in seen:
                seen.add((cell, rule.command))
                result.append(ImportedRule(dict(zip(names, cell, strict=True)), rule.command,
                                           rule.line, rule.text))
    return _merge_conflicts(imported, result)


def _fill_gaps(imported: ImportedController) -> None:
    """A conversion (measured): over each stretch of an input's range that no set covers
    (membership 0 in every set, which flctool's inputs may not have), add a set of
    membership 1 there and 0 elsewhere, ``gap1``, ``gap2``, ... Where the file's rules fire
    there (an OR rule's other condition, a rule that leaves the input out) the expanded rules
    fire with the new set just so; where none does, the file has no output there and the
    rules leave the new set's combinations without a command. Trapezoid inputs only (the
    other shapes reach across the whole line)."""
    from flctool.behaviour.checks import uncovered_gap
    from flctool.behaviour.fuzzy import InputVariable

    for variable in imported.inputs:
        if any(s.shape for s in variable.sets) or not variable.sets:
            continue
        try:
            quads = variable.resolved_quads(imported.file)
            model = InputVariable(range=variable.resolved_range(), sets=dict(quads))
        except (ExportError, ValueError):
            continue  # refused as the file writes it, later
        names = {s.name for s in variable.sets}
        for _ in range(len(variable.sets) + 1):  # at most one gap between two sets
            gap = uncovered_gap(model)
            if gap is None or not gap[0] < gap[1]:
                break
            k = 1
            while f"gap{k}" in names:
                k += 1
            name = f"gap{k}"
            names.add(name)
            a, b = gap
            variable.sets.append(ImportedSet(name, (a, a, b, b), variable.line))
            model = InputVariable(range=model.range, sets={**model.sets, name: (a, a, b, b)})
            imported.notes.append(
                f"input '{variable.name}': the values between {a:g} and {b:g} belong to no "
                f"set; a set '{name}' [{a:g}, {a:g}, {b:g}, {b:g}] is added there, so that "
                "the rules that fire there in the file (an OR rule's other condition, a rule "
                "that leaves the input out) fire with it (part of the measured difference)")


def _own_commands(imported: ImportedController, rules: list[ImportedRule]
                  ) -> list[ImportedRule]:
    """A first-order output being converted: each rule concluding a first-order term (or a
    command :func:`_merge_conflicts` made of one) gets a command of its own, named after the
    term and numbered (``term_2``), whose constant :mod:`flctool.export.linear` fits; a term
    only one rule concludes keeps its name. Terms that no rule concludes any more are
    dropped; constant terms stay as they are (exact)."""
    n = len(imported.inputs)
    functions = {c.name: c.linear if c.linear is not None else (0.0,) * n + (c.value,)
                 for c in imported.terms}
    linear = {c.name for c in imported.terms if c.linear is not None}
    merged = set(imported.merged_commands)  # fitted too: the file gives them no value
    free = {c: c in linear or c in merged or any(part in linear for part in c.split("_or_"))
            for c in {r.command for r in rules}}

    def function(command: str) -> tuple[float, ...]:
        """A command's function; a merged command's the mean of its terms'."""
        parts = [functions[p] for p in command.split("_or_") if p in functions]
        if command in functions or not parts:
            return functions.get(command, (0.0,))
        return tuple(math.fsum(f[i] for f in parts) / len(parts) for i in range(n + 1))
    uses: dict[str, int] = {}
    for rule in rules:
        uses[rule.command] = uses.get(rule.command, 0) + 1
    taken = {c.name for c in imported.commands}
    count: dict[str, int] = {}
    result = []
    added: list[ImportedCommand] = []
    for rule in rules:
        if not free.get(rule.command, False) or uses[rule.command] == 1:
            result.append(rule)
            continue
        count[rule.command] = count.get(rule.command, 0) + 1
        name = f"{rule.command}_{count[rule.command]}"
        while name in taken:
            name += "_"
        taken.add(name)
        added.append(ImportedCommand(name, 0.0, rule.line, function(rule.command)))
        result.append(ImportedRule(rule.antecedent, name, rule.line, rule.text))
    used = {r.command for r in result}
    imported.commands[:] = [c for c in imported.commands
                            if c.name in used or c.linear is None] + added
    for command in imported.commands:
        if free.get(command.name, False) and command.linear is None:
            command.linear = function(command.name)  # a merged command: fitted too
    return result


def _merge_conflicts(imported: ImportedController, rules: list[ImportedRule]
                     ) -> list[ImportedRule]:
    """One rule per combination of sets: where expanded rules give one combination several
    commands (the Mamdani output fires all their sets there), it gets a new command, the
    mean of their singletons, named after them (``cheap_or_average``) and added to the
    output. Part of the approximation the conversion measures."""
    by_cell: dict[tuple[tuple[str, str], ...], list[ImportedRule]] = {}
    for rule in rules:
        by_cell.setdefault(tuple(rule.antecedent.items()), []).append(rule)
    values = {c.name: c.value for c in imported.commands}
    merged = []
    for group in by_cell.values():
        commands = sorted({r.command for r in group}, key=list(values).index) if all(
            r.command in values for r in group) else []
        if len(commands) <= 1:
            merged += group
            continue
        name = "_or_".join(commands)
        if name not in values:
            values[name] = math.fsum(values[c] for c in commands) / len(commands)
            imported.commands.append(ImportedCommand(name, values[name], group[0].line))
            imported.merged_commands.append(name)
        merged.append(ImportedRule(group[0].antecedent, name, group[0].line,
                                   " / ".join(dict.fromkeys(r.text for r in group))))
    return merged


#: A rule as written, for measuring against: its conditions (input, set, negated), whether
#: they are joined by OR (else AND), its command and its weight.
OriginalRule = tuple[tuple[tuple[str, str, bool], ...], bool, str, float]


def as_written(imported: ImportedController) -> dict[str, Any]:
    """What a Mamdani conversion's measurement needs of the rules as the file writes them
    (after :func:`build_behaviour` renamed them to behaviour-file names): ``rules``, whether
    the behaviour's rules differ from them (``rewritten``: expanded, merged or weighted) and
    the ``conjunction`` (fuzzylite's name); for :class:`flctool.export.mamdani.
    MamdaniOutput`."""
    names = {v.name for v in imported.inputs}
    rules = tuple((tuple((n, t, n in r.negated) for n, t in r.disjuncts or
                         r.antecedent.items()), bool(r.disjuncts), r.command, r.weight)
                  for r in imported.rules)
    rewritten = bool(imported.merged_commands or imported.notes) or any(
        r.disjuncts or r.negated or set(r.antecedent) != names or r.weight != 1.0
        for r in imported.rules)
    product = imported.conjunction is not None and imported.conjunction.product
    return {"rules": rules, "rewritten": rewritten,
            "conjunction": "AlgebraicProduct" if product else "Minimum"}


def _check_no_or_rule(imported: ImportedController) -> None:
    for rule in imported.rules:
        if rule.disjuncts:
            raise unsupported(imported.file, rule.line, "an OR rule: flctool's rules are one "
                              "AND chain (eq. 1), and an OR rule's activation (the maximum "
                              "of its conditions) is no sum of such rules' activations",
                              "write it as AND rules over every input, accepting the change, "
                              "or (a Mamdani output) import with --mamdani-singletons, (a "
                              "first-order one) with --linear-singletons, which measures the "
                              "difference")


_NOT_IDENTIFIER = re.compile(r"[^A-Za-z0-9_]")


def identifier(name: str) -> str:
    """``name`` as a behaviour-file name: other characters become '_' (MATLAB and fuzzylite
    files often write ``Food-Quality``), and a leading digit gets a '_' before it."""
    derived = _NOT_IDENTIFIER.sub("_", name)
    return f"_{derived}" if derived[:1].isdigit() else derived


def _identifiers(imported: ImportedController) -> None:
    """Rename, in place, every name that is not an identifier to :func:`identifier`'s form.

    The names only label the controller, so the renamed one computes the same outputs; a
    rename that would make two names of one kind equal is refused.
    """
    file = imported.file
    if imported.name:
        imported.name = identifier(imported.name)
    imported.output_name = identifier(imported.output_name)
    for variable in imported.inputs:
        sets = {s.name: identifier(s.name) for s in variable.sets}
        _check_renames(file, [(s.name, sets[s.name], s.line) for s in variable.sets],
                       f"set of input '{variable.name}'")
        for item in variable.sets:
            item.name = sets[item.name]
        for rule in imported.rules:
            term = rule.antecedent.get(variable.name)
            if term is not None:  # (an unknown term is left for the rule checks to name)
                rule.antecedent[variable.name] = sets.get(term, term)
            rule.disjuncts = [(n, sets.get(t, t) if n == variable.name else t)
                              for n, t in rule.disjuncts]
    inputs = {v.name: identifier(v.name) for v in imported.inputs}
    _check_renames(file, [(v.name, inputs[v.name], v.line) for v in imported.inputs], "input")
    for variable in imported.inputs:
        variable.name = inputs[variable.name]
    for rule in imported.rules:
        rule.antecedent = {inputs.get(n, n): s for n, s in rule.antecedent.items()}
        rule.disjuncts = [(inputs.get(n, n), t) for n, t in rule.disjuncts]
        rule.negated = {inputs.get(n, n) for n in rule.negated}
    commands = {c.name: identifier(c.name) for c in imported.commands}
    _check_renames(file, [(c.name, commands[c.name], c.line) for c in imported.commands],
                   "output term")
    for command in imported.commands:
        command.name = commands[command.name]
    for rule in imported.rules:
        rule.command = commands.get(rule.command, rule.command)


def _check_renames(file: str, renames: list[tuple[str, str, int]], kind: str) -> None:
    first: dict[str, tuple[str, int]] = {}
    for old, new, line in renames:
        if new in first and first[new][0] != old:
            other, other_line = first[new]
            raise unsupported(file, line, f"the {kind} names '{other}' (line {other_line}) and "
                              f"'{old}' both become '{new}' as behaviour-file names",
                              "rename one of them in the file")
        first.setdefault(new, (old, line))


def _check_rules_cover_every_input(imported: ImportedController) -> None:
    """Refuse a rule that leaves out an input: in these formats it means something no rule of
    flctool's grid does. Every other rule check (unknown inputs, sets and commands, repeated
    antecedents) is the behaviour's own, located at the rule's line by :func:`build_behaviour`.
    """
    inputs = [i.name for i in imported.inputs]
    for rule in imported.rules:
        left_out = [n for n in inputs if n not in rule.antecedent]
        # (a rule naming an unknown input is a typo the behaviour's checks name instead)
        if left_out and all(n in inputs for n in rule.antecedent):
            names = ", ".join(f"'{n}'" for n in left_out)
            written = f" ({imported.omission})" if imported.omission else ""
            conjunction = imported.conjunction
            combined = ("product" if conjunction is not None and conjunction.product
                        else "minimum")
            raise unsupported(
                imported.file, rule.line, f"the rule leaves out input{'s' * (len(left_out) > 1)} "
                f"{names}{written}: it fires with the other inputs' {combined} alone, which no "
                "rule of the full grid (eq. 1-2) does, so expanding it over the sets would "
                "change the output", DONT_CARE_HINT)


def _check_names_unique(imported: ImportedController) -> None:
    file = imported.file
    check_unique(file, ((i.name, i.line) for i in imported.inputs), "input")
    for variable in imported.inputs:
        check_unique(file, ((s.name, s.line) for s in variable.sets), "set",
                     f" of input '{variable.name}'")
    check_unique(file, ((c.name, c.line) for c in imported.commands), "output term")


def _check_no_negation(imported: ImportedController) -> None:
    for rule in imported.rules:
        if rule.negated:
            name = sorted(rule.negated)[0]
            raise unsupported(imported.file, rule.line, f"NOT on input '{name}': flctool's "
                              "rules use plain terms (eq. 1), and NOT's membership (1 - mu) is "
                              "no sum of the other sets'", "name the sets meant instead, one "
                              "rule each, or (a Mamdani output) import with "
                              "--mamdani-singletons, (a first-order one) with "
                              "--linear-singletons, which measures the difference")


def _check_weights(imported: ImportedController) -> None:
    for rule in imported.rules:
        if rule.weight != 1.0:
            raise unsupported(imported.file, rule.line, f"a rule weight of {rule.weight!r}: "
                              "flctool's rules all weigh 1",
                              "remove the weight (accepting the change), or (a Mamdani "
                              "output) import with --mamdani-singletons, (a first-order one) "
                              "with --linear-singletons, which measures the difference")


def _check_methods(imported: ImportedController) -> None:
    conjunction = imported.conjunction
    if conjunction is not None and conjunction.product:
        pass  # activation: product, or measured by a Mamdani conversion (build_behaviour)
    elif conjunction is not None and any(len(r.antecedent) > 1 for r in imported.rules):
        raise imported.error(conjunction.line, f"{conjunction.text}: flctool's rules combine "
                             "their memberships by the minimum (eq. 2) or the product",
                             conjunction.hint)
    if imported.accumulation is not None:
        check_rules_share_no_term(imported, imported.accumulation.line,
                                  imported.accumulation.text)


def check_rules_share_no_term(imported: ImportedController, line: int, setting: str) -> None:
    """Refuse a max-style accumulation where it would change eq. 3 (rules sharing a term).

    Eq. 3 sums every rule's activation; accumulating by maximum merges the rules that share
    an output term, which gives the same output only when no two rules share one.
    """
    first: dict[str, int] = {}
    for rule in imported.rules:
        if rule.command in first:
            raise unsupported(
                imported.file, line,
                f"{setting} merges rules that share an output term (lines {first[rule.command]} "
                f"and {rule.line} both conclude '{rule.command}'), so the output is not the "
                "weighted average of every rule (eq. 3)",
                "accumulate by sum instead")
        first[rule.command] = rule.line


def parse_number(text: str, file: str, line: int, what: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise unsupported(file, line, f"{what}: '{text}' is not a number") from None
    if not math.isfinite(value):
        raise unsupported(file, line, f"{what}: '{text}' is not a finite number")
    return value


def imported_yaml(behaviour: Behaviour, header: str) -> str:
    """An imported controller as a behaviour file: ``flctool: 1`` and no learning section.

    The file format only knows the controller, so the learning defaults that the model fills
    in are left out rather than presented as if the file had chosen them.
    """
    return behaviour_to_yaml(behaviour, header, defaults=False)
