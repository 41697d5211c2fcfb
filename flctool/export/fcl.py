"""FCL, the Fuzzy Control Language of IEC 61131-7.

Sets are point lists ``TERM name := (x, mu) ...``; commands are singleton terms of the
output, defuzzified by ``METHOD : COGS`` (centre of gravity for singletons, eq. 3); the rule
block combines memberships by ``AND : MIN`` (eq. 2), or ``AND : PROD`` with ``activation:
product`` (both dialects have it: IEC 61131-7 and fuzzylite read it as the product). Its
accumulation is ``ACCU : NSUM``: COGS divides by the accumulated total, so the sum's
normalisation cancels and every rule counts as in eq. 3, while ``MAX`` (the usual default)
would merge the rules that share a command.

IEC reads a point list as constant before its first point and after its last, so a shoulder
at the end of the range is written from its plateau on, and an edge inside the range that is
vertical (``pa == pb``) is two points at the same x.
"""

from __future__ import annotations

import dataclasses
import math
import re
from dataclasses import dataclass, field
from typing import NamedTuple

from flctool.behaviour import Behaviour, require_deployable
from flctool.behaviour.base import identifier
from flctool.behaviour.fuzzy import FuzzySet
from flctool.behaviour.shapes import ShapedSet, set_row
from flctool.errors import ExportError
from flctool.export import shapes
from flctool.export.base import (
    Exporter,
    Importer,
    header_lines,
    sloped_quad,
    vote_note,
)
from flctool.export.imported import (
    QUAD0,
    ImportedCommand,
    ImportedController,
    ImportedInput,
    ImportedRule,
    ImportedSet,
    Method,
    build_behaviour,
    check_unique,
    fuzzylite_set,
    output_constant,
    parse_number,
    quad_from_points,
    span,
    unsupported,
)
from flctool.export.linear import converted_notes
from flctool.export.mamdani import MAMDANI_HINT, MamdaniOutput, import_notes

#: fuzzylite 6's resolution of a Centroid read from FCL (the one FIS and FLL use).
CENTROID_RESOLUTION = 100

#: The reserved keywords of IEC 61131-7 FCL, and REAL (case does not matter): they cannot
#: name a variable or a term.
KEYWORDS = frozenset({
    "ACCU", "ACT", "AND", "ASUM", "BDIF", "BSUM", "COA", "COG", "COGS", "DEFAULT", "DEFUZZIFY",
    "END_DEFUZZIFY", "END_FUNCTION_BLOCK", "END_FUZZIFY", "END_OPTIONS", "END_RULEBLOCK",
    "END_VAR", "FUNCTION_BLOCK", "FUZZIFY", "IF", "IS", "LM", "MAX", "METHOD", "MIN", "NC",
    "NOT", "NSUM", "OPTIONS", "OR", "PROD", "RANGE", "REAL", "RM", "RULE", "RULEBLOCK", "TERM",
    "THEN", "VAR_INPUT", "VAR_OUTPUT", "WITH",
})
INDENT = "    "


def fcl_number(value: float) -> str:
    """repr's digits, with the decimal point IEC 61131-3 real literals require (1.0e-05)."""
    text = repr(float(value))
    if "." not in text:
        mantissa, _, exponent = text.partition("e")
        text = f"{mantissa}.0" + (f"e{exponent}" if exponent else "")
    return text


def set_points(quad: tuple[float, float, float, float],
               span: tuple[float, float]) -> list[tuple[float, int]]:
    """The point list of a trapezoid, in IEC's reading (see the module docstring)."""
    pa, pb, pc, pd = quad
    lo, hi = span
    points: list[tuple[float, int]] = []
    if not pa == pb == lo:  # a vertical edge at the range's end needs no foot: inputs clip
        # an edge inside the range gets its foot one ulp away: no double lies between
        points.append((math.nextafter(pb, -math.inf) if pa == pb else pa, 0))
    points.append((pb, 1))
    if pc != pb:
        points.append((pc, 1))
    if not pc == pd == hi:
        points.append((math.nextafter(pc, math.inf) if pc == pd else pd, 0))
    return points


#: The dialects the exporter writes.
DIALECTS = ("iec", "fuzzylite")


class FclExporter(Exporter):
    format = "fcl"

    def to_string(self, behaviour: Behaviour) -> str:
        require_deployable(behaviour)
        _check_names(behaviour)
        dialect = self.options.dialect
        if dialect not in DIALECTS:
            raise ExportError(f"unknown FCL dialect '{dialect}'",
                              hint=f"use one of {', '.join(DIALECTS)}")
        fuzzylite = dialect == "fuzzylite"
        if not fuzzylite:
            _check_points_only(behaviour)
        output = behaviour.output
        about = header_lines(behaviour, self.options.provenance) + vote_note(behaviour)
        # fuzzylite 6 skips lines starting with '//' (and refuses '(* ... *)')
        lines = [f"// {line}" if fuzzylite else f"(* {line} *)" for line in about]
        lines += [f"FUNCTION_BLOCK {identifier(behaviour.name)}", "", "VAR_INPUT"]
        lines += [f"{INDENT}{name} : REAL;" for name in behaviour.inputs]
        lines += ["END_VAR", "", "VAR_OUTPUT", f"{INDENT}{output.name} : REAL;", "END_VAR", ""]
        for name, variable in behaviour.inputs.items():
            lines.append(f"FUZZIFY {name}")
            lo, hi = variable.range
            for set_name, quad in variable.sets.items():
                lines.append(f"{INDENT}TERM {set_name} := "
                             f"{_term(quad, variable.range, fuzzylite=fuzzylite)};")
            lines += [f"{INDENT}RANGE := ({fcl_number(lo)} .. {fcl_number(hi)});",
                      "END_FUZZIFY", ""]
        values = list(output.commands.values())
        lines.append(f"DEFUZZIFY {output.name}")
        lines += [f"{INDENT}TERM {command} := {fcl_number(value)};"
                  for command, value in output.commands.items()]
        lines += [f"{INDENT}METHOD : COGS;"]
        if fuzzylite:  # fuzzylite 6 reads ACCU here, and refuses it in the RULEBLOCK
            lines.append(f"{INDENT}ACCU : NSUM;")
        lines += [f"{INDENT}DEFAULT := 0.0;",
                  f"{INDENT}RANGE := ({fcl_number(min(values))} .. {fcl_number(max(values))});",
                  "END_DEFUZZIFY", "", "RULEBLOCK rules",
                  f"{INDENT}AND : {AND_METHOD[behaviour.activation]};",
                  f"{INDENT}ACT : MIN;"]
        if not fuzzylite:
            lines.append(f"{INDENT}ACCU : NSUM;")
        # fuzzylite 6 parses rules with lower-case keywords only (and silently drops others)
        if_, is_, and_, then = ("if", "is", "and", "then") if fuzzylite else (
            "IF", "IS", "AND", "THEN")
        for index, rule in enumerate(behaviour.rules, start=1):
            condition = f" {and_} ".join(f"{n} {is_} {rule.if_[n]}"
                                         for n in behaviour.input_names)
            lines.append(f"{INDENT}RULE {index} : {if_} {condition} {then} {output.name} "
                         f"{is_} {rule.then};")
        lines += ["END_RULEBLOCK", "", "END_FUNCTION_BLOCK"]
        return "\n".join(lines) + "\n"


#: Eq. 2 as FCL names it, by the behaviour's activation.
AND_METHOD = {"min": "MIN", "product": "PROD"}


def _term(quad: FuzzySet, span: tuple[float, float], *, fuzzylite: bool) -> str:
    """A set as IEC points, or as fuzzylite's Trapezoid / Triangle with shoulders' feet
    outside the range (fuzzylite does not clip FCL inputs; see sloped_quad), or as
    fuzzylite's term of its shape."""
    if isinstance(quad, ShapedSet):
        name, params = shapes.written(shapes.FUZZYLITE, quad.kind, quad.params)
        return f"{name} {' '.join(fcl_number(v) for v in params)}"
    if not fuzzylite:
        return " ".join(f"({fcl_number(x)}, {mu})" for x, mu in set_points(quad, span))
    pa, pb, pc, pd = sloped_quad(quad, span, interior=False)
    if pb == pc:
        return f"Triangle {fcl_number(pa)} {fcl_number(pb)} {fcl_number(pd)}"
    return "Trapezoid " + " ".join(fcl_number(x) for x in (pa, pb, pc, pd))


def _check_points_only(behaviour: Behaviour) -> None:
    """IEC 61131-7 writes sets as point lists: a shape other than the trapezoid has none."""
    for name, variable in behaviour.inputs.items():
        for set_name, value in variable.sets.items():
            if isinstance(value, ShapedSet):
                raise ExportError(
                    f"set '{set_name}' of input '{name}' is a {value.kind}, which IEC "
                    "61131-7 FCL cannot write (its sets are point lists, piecewise linear)",
                    hint="export with --dialect fuzzylite, which writes fuzzylite's "
                    f"{shapes.FUZZYLITE[value.kind][0]} term, or use FLL or FIS")


def _check_names(behaviour: Behaviour) -> None:
    names = [behaviour.name, *behaviour.inputs, behaviour.output.name, *behaviour.output.commands]
    names += [s for v in behaviour.inputs.values() for s in v.sets]
    for name in names:
        if name.upper() in KEYWORDS:
            raise ExportError(f"'{name}' is an FCL keyword, so it cannot name a variable, a "
                              "term or the function block", hint="rename it in the behaviour")


# -- reading ---------------------------------------------------------------------------------
_TOKEN = re.compile(r"""
    (?P<space>\s+) | (?P<comment>\(\*.*?\*\)|//[^\n]*|/\*.*?\*/)
  | (?P<number>[+-]?(\d(_?\d)*(\.(?!\.)(\d(_?\d)*)?)?|\.\d(_?\d)*)([eE][+-]?\d(_?\d)*)?)
  | (?P<name>[A-Za-z_][A-Za-z0-9_]*)
  | (?P<symbol>:=|\.\.|[:;(),|])
""", re.VERBOSE | re.DOTALL)


class Token(NamedTuple):
    """One token (a tuple: a file of 100,000 rules has a million of them, and a frozen
    dataclass costs three times as long to make)."""

    kind: str
    text: str
    line: int

    @property
    def word(self) -> str:
        """The token as a keyword would be spelled: keywords are case-insensitive."""
        return self.text.upper() if self.kind == "name" else self.text


def tokenize(text: str, file: str) -> list[Token]:
    tokens: list[Token] = []
    append, match_at = tokens.append, _TOKEN.match
    position, line, end = 0, 1, len(text)
    while position < end:
        match = match_at(text, position)
        if match is None:
            raise unsupported(file, line, f"unexpected character {text[position]!r}")
        kind = match.lastgroup or ""
        value = match.group()
        if kind != "space" and kind != "comment":
            append(Token(kind, value, line))
        if "\n" in value:
            line += value.count("\n")
        position = match.end()
    return tokens


class FclImporter(Importer):
    """Reads the IEC 61131-7 subset that the FclExporter writes (singleton outputs, COGS), one
    behaviour per output; with ``mamdani_singletons``, also Mamdani outputs (sets defuzzified
    by COG, see :mod:`flctool.export.mamdani`), and then ``report`` says how far that moved
    each."""

    format = "fcl"

    def __init__(self, mamdani_singletons: bool = False, linear_singletons: bool = False
                 ) -> None:
        self.mamdani_singletons = mamdani_singletons
        self.linear_singletons = linear_singletons
        self.report = ""

    def parse(self, text: str, file: str) -> Behaviour:
        return self.from_string(text, file)

    def parse_all(self, text: str, file: str) -> list[Behaviour]:
        parser = _FclParser(tokenize(text, file), file, self.mamdani_singletons,
                            self.linear_singletons)
        controllers = parser.parse_all()
        behaviours, notes = converted_notes(
            [build_behaviour(c) for c in controllers], controllers,
            [o.range or (0.0, 0.0) for o in parser.outputs])
        self.report = import_notes(file, behaviours, [
            (controller, output.mamdani()) if output.sets else note
            for output, controller, note in zip(parser.outputs, controllers, notes,
                                                strict=True)])
        return behaviours


@dataclass
class _Output:
    """One VAR_OUTPUT and its DEFUZZIFY block as read."""

    name: str
    line: int
    defuzzified: bool = False
    commands: list[ImportedCommand] = field(default_factory=list)
    #: Mamdani output sets: name -> (shape code, row), and the line of the first
    sets: dict[str, tuple[int, tuple[float, float, float, float]]] = field(
        default_factory=dict)
    set_line: int = 0
    set_name: str = ""
    #: Point-list sets, made trapezoids once the range is known: (name token, points)
    point_sets: list[tuple[Token, list[tuple[float, float]]]] = field(default_factory=list)
    method: tuple[str, int] | None = None
    accumulation: tuple[str, int] | None = None
    range: tuple[float, float] | None = None
    implication: str = "Minimum"
    #: Refusals of this output's terms, reported with the file's others
    pending: list[ExportError] = field(default_factory=list)

    def mamdani(self) -> MamdaniOutput:
        return MamdaniOutput({identifier(n): row for n, row in self.sets.items()},
                             self.resolved_range(), CENTROID_RESOLUTION, self.implication,
                             "Maximum" if self.accumulation_word() == "MAX" else
                             "AlgebraicSum")

    def resolved_range(self) -> tuple[float, float]:
        """The RANGE, or the span of the sets' points (as fuzzylite does without one)."""
        if self.range is not None:
            return self.range
        return span(x for _, points in self.point_sets for x, _ in points)

    @property
    def mamdani_terms(self) -> bool:
        """Whether any term is a set (a Mamdani output), not a singleton."""
        return bool(self.sets or self.point_sets)

    def accumulation_word(self) -> str:
        """The accumulation, MAX when the file gives none (IEC's and fuzzylite's default)."""
        return self.accumulation[0] if self.accumulation else "MAX"


class _FclParser:
    def __init__(self, tokens: list[Token], file: str, mamdani_singletons: bool = False,
                 linear_singletons: bool = False) -> None:
        self.tokens = tokens
        self.file = file
        self.mamdani_singletons = mamdani_singletons
        self.linear_singletons = linear_singletons
        self.at = 0
        self.result = ImportedController(file)
        self.input_names: list[tuple[str, int]] = []
        self.outputs: list[_Output] = []
        #: every rule as read: its antecedent (or an OR rule's conditions), the inputs it
        #: negates, its conclusions (output, term, weight), line, text
        self.rules: list[tuple[dict[str, str], list[tuple[str, str]], set[str],
                               list[tuple[str, str, float]], int, str]] = []
        #: ACCU and ACT written in the RULEBLOCK (older IEC drafts and jFuzzyLogic put them
        #: there): they apply to every output without its own
        self.block_accumulation: tuple[str, int] | None = None
        self.implication: tuple[str, int] = ("MIN", 0)
        self.blocks = 0

    # -- token helpers ---------------------------------------------------------------------
    def peek(self) -> Token:
        if self.at >= len(self.tokens):
            last = self.tokens[-1].line if self.tokens else 1
            raise unsupported(self.file, last, "the file ends before END_FUNCTION_BLOCK")
        return self.tokens[self.at]

    def take(self) -> Token:
        token = self.peek()
        self.at += 1
        return token

    def expect(self, word: str) -> Token:
        token = self.take()
        if token.word != word:
            raise unsupported(self.file, token.line, f"expected '{word}' but found "
                              f"'{token.text}'")
        return token

    def name(self) -> Token:
        token = self.take()
        if token.kind != "name" or token.word in KEYWORDS:
            raise unsupported(self.file, token.line, f"expected a name but found "
                              f"'{token.text}'")
        return token

    def number(self) -> float:
        token = self.take()
        if token.kind != "number":
            raise unsupported(self.file, token.line, f"expected a number but found "
                              f"'{token.text}'")
        return parse_number(token.text, self.file, token.line, "number")

    def fail(self, token: Token, construct: str, hint: str = "") -> ExportError:
        return self.result.error(token.line, construct, hint)

    # -- grammar ---------------------------------------------------------------------------
    def parse_all(self) -> list[ImportedController]:
        """One controller per output, each with the rules that conclude on it (outputs are
        computed independently, so each is exact)."""
        self.parse()
        order = [v.name for v in self.result.inputs]  # FUZZIFY's order, the behaviour's
        declared = [name for name, _ in self.input_names]
        controllers = []
        for output in self.outputs:
            for command in output.commands:  # a linear term's coefficients: VAR_INPUT's order
                if command.linear is not None and sorted(order) == sorted(declared):
                    by_name = dict(zip(declared, command.linear, strict=False))
                    command.linear = (*(by_name[n] for n in order), command.linear[-1])
            pending = [*self.result.pending, *output.pending]
            try:
                self.check_output(output)
            except ExportError as error:  # reported with the rules' refusals
                pending.append(error)
            imported = dataclasses.replace(
                self.result, output_name=output.name, output_line=output.line,
                output_declared=True, commands=output.commands, rules=[
                    ImportedRule(dict(antecedent), term, line, text, list(disjuncts), weight,
                                 set(negated))
                    for antecedent, disjuncts, negated, conclusions, line, text in self.rules
                    for name, term, weight in conclusions if name == output.name],
                accumulation=None, pending=pending, merged_commands=[],
                expand_rules=output.mamdani_terms and self.mamdani_singletons,
                # a Takagi-Sugeno output, converted if it needs to be (build_behaviour)
                convert_linear=self.linear_singletons and not output.mamdani_terms)
            if len(self.outputs) > 1:
                imported.name, imported.name_line = output.name, output.line
            word = output.accumulation_word()
            if not output.mamdani_terms and word not in ("NSUM", "SUM"):
                # NSUM (and jFuzzyLogic's SUM) keep every rule in COGS; MAX, BSUM and ASUM
                # merge the rules that share a command
                written = (f"ACCU : {word}" if output.accumulation else
                           "the default accumulation (ACCU : MAX)")
                imported.accumulation = Method(
                    written, output.accumulation[1] if output.accumulation else output.line,
                    "use ACCU : NSUM" if output.accumulation else "write ACCU : NSUM;")
            controllers.append(imported)
        return controllers

    def parse(self) -> ImportedController:
        self.expect("FUNCTION_BLOCK")
        if self.peek().kind == "name" and self.peek().word not in KEYWORDS:
            token = self.take()
            self.result.name, self.result.name_line = token.text, token.line
        fuzzified: set[str] = set()
        while self.peek().word != "END_FUNCTION_BLOCK":
            token = self.take()
            if token.word == "VAR_INPUT":
                self.variables(self.input_names)
            elif token.word == "VAR_OUTPUT":
                outputs: list[tuple[str, int]] = []
                self.variables(outputs)
                self.outputs += [_Output(name, line) for name, line in outputs]
            elif token.word == "FUZZIFY":
                fuzzified.add(self.fuzzify())
            elif token.word == "DEFUZZIFY":
                self.defuzzify()
            elif token.word == "RULEBLOCK":
                self.ruleblock(token)
            elif token.word == "OPTIONS":
                if self.take().word != "END_OPTIONS":
                    raise self.fail(token, "an OPTIONS block: its manufacturer-specific "
                                    "options may change the computation",
                                    "remove the options, or the whole block")
            else:
                raise self.fail(token, f"'{token.text}' where a block (VAR_INPUT, FUZZIFY, "
                                "DEFUZZIFY, RULEBLOCK) should start")
        self.take()
        self.finish(fuzzified)
        return self.result

    def finish(self, fuzzified: set[str]) -> None:
        check_unique(self.file, self.input_names, "input")
        check_unique(self.file, [(o.name, o.line) for o in self.outputs], "output")
        for name, line in self.input_names:
            if name not in fuzzified:
                raise unsupported(self.file, line, f"input '{name}' has no FUZZIFY block")
        if not self.outputs:
            raise unsupported(self.file, 1, "the controller has no output variable",
                              "declare one in VAR_OUTPUT ... END_VAR")
        for output in self.outputs:
            if not output.defuzzified:
                raise unsupported(self.file, output.line,
                                  f"output '{output.name}' has no DEFUZZIFY block")
            if output.accumulation is None:
                output.accumulation = self.block_accumulation

    def check_output(self, output: _Output) -> None:
        """An output's terms and method fit together: singletons and COGS, or (converting)
        Mamdani sets and COG, with an accumulation and activation the conversion measures."""
        if output.method is None:
            raise unsupported(self.file, output.line, f"the output '{output.name}' has no "
                              f"'METHOD : {'COG' if output.mamdani_terms else 'COGS'}'",
                              "write METHOD : COGS; (singletons) or METHOD : COG; (sets)")
        method, line = output.method
        if not output.mamdani_terms:
            if method != "COGS":
                raise unsupported(self.file, line, f"METHOD : {method}: flctool's output is "
                                  "the centre of gravity of singletons (eq. 3)",
                                  "use METHOD : COGS")
            return
        if not self.mamdani_singletons:
            raise unsupported(self.file, output.set_line, f"output term '{output.set_name}' "
                              "is not a singleton: a Mamdani output set cannot be expressed "
                              "exactly (flctool's commands are singletons, eq. 3)",
                              MAMDANI_HINT)
        if len(output.sets) + len(output.point_sets) != len(output.commands):
            raise unsupported(self.file, output.set_line, f"output '{output.name}' mixes "
                              "singletons and sets", "make every term of a Mamdani output a "
                              "set")
        if method != "COG":
            raise unsupported(self.file, line, f"METHOD : {method} of the Mamdani output "
                              f"'{output.name}': the conversion measures against the centre "
                              "of gravity", "use METHOD : COG")
        if output.accumulation_word() not in ("MAX", "ASUM"):
            word, at = output.accumulation or ("MAX", output.line)
            raise unsupported(self.file, at, f"ACCU : {word} of the Mamdani output "
                              f"'{output.name}': the conversion measures ACCU : MAX or ASUM",
                              "use ACCU : MAX")
        implication, at = self.implication
        if implication not in ("MIN", "PROD"):
            raise unsupported(self.file, at, f"ACT : {implication}: the conversion of a "
                              "Mamdani output measures ACT : MIN or PROD", "use ACT : MIN")
        output.implication = "Minimum" if implication == "MIN" else "AlgebraicProduct"
        lo, hi = output.resolved_range()
        if not lo < hi:  # the centroid integrates over the range
            raise unsupported(self.file, output.line, f"the range [{lo!r}, {hi!r}] of the "
                              f"Mamdani output '{output.name}' is not low then high",
                              "write RANGE := (low .. high); with low below high")
        for term, points in output.point_sets:
            quad = quad_from_points(points, (lo, hi), (self.file, term.line), term.text)
            output.sets[term.text] = (0, quad)
        for name, (code, row) in output.sets.items():
            if code == 0:  # a shoulder's infinite foot: the same membership inside the range
                pa, pb, pc, pd = (lo if v == -math.inf else hi if v == math.inf else v
                                  for v in row)
                output.sets[name] = (0, (pa, pb, pc, pd))
        mamdani = output.mamdani()
        for command in output.commands:
            command.value = mamdani.singleton(identifier(command.name))

    def variables(self, into: list[tuple[str, int]]) -> None:
        while self.peek().word != "END_VAR":
            name = self.name()
            self.expect(":")
            kind = self.take()
            if kind.word != "REAL":
                raise self.fail(kind, f"variable '{name.text}' of type {kind.text}",
                                "declare it REAL")
            self.expect(";")
            into.append((name.text, name.line))
        self.take()

    def fuzzify(self) -> str:
        token = self.name()
        if token.text not in [n for n, _ in self.input_names]:
            raise self.fail(token, f"FUZZIFY of '{token.text}', which is not a VAR_INPUT")
        variable = ImportedInput(token.text, token.line)
        self.result.inputs.append(variable)
        terms: list[tuple[Token, list[tuple[float, float]]]] = []
        while self.peek().word != "END_FUZZIFY":
            key = self.take()
            if key.word == "TERM":
                term = self.name()
                self.expect(":=")
                if self.peek().kind == "name":  # fuzzylite's syntax: Trapezoid a b c d
                    start = self.at
                    try:
                        variable.sets.append(self.fuzzylite_term(term))
                    except ExportError as error:  # reported with the file's other refusals
                        self.at = start
                        while self.peek().word != ";":  # the term's tokens, to go on reading
                            self.take()
                        variable.sets.append(self.result.put_off(
                            error, ImportedSet(term.text, QUAD0, term.line)))
                else:
                    terms.append((term, self.points(term)))
                self.expect(";")
            elif key.word == "RANGE":
                variable.range = self.range_()
            else:
                raise self.fail(key, f"'{key.text}' in FUZZIFY {token.text}")
        self.take()
        # Without RANGE, the sets' points span the input (shoulders reach its ends).
        extent = variable.range or span(x for _, points in terms for x, _ in points)
        for term, points in terms:
            quad = quad_from_points(points, extent, (self.file, term.line), term.text)
            variable.sets.append(ImportedSet(term.text, quad, term.line))
        return token.text

    def term_values(self, term: Token, kind: Token) -> list[float]:
        """A fuzzylite or jFuzzyLogic term's numbers, up to ';'."""
        values: list[float] = []
        while self.peek().word != ";":
            token = self.take()
            if token.kind == "name" and token.text.lower() in ("inf", "-inf"):
                values.append(float(token.text))
            elif token.kind == "number":
                values.append(parse_number(token.text, self.file, token.line, kind.text))
            else:
                raise self.fail(token, f"'{token.text}' in the {kind.text} term "
                                f"'{term.text}'", "write the term's numbers, then ';'")
            if len(values) > 5:
                break
        return values

    def fuzzylite_term(self, term: Token, kind: Token | None = None) -> ImportedSet:
        """fuzzylite's term syntax, ``Trapezoid a b c d`` or ``Gaussian m s`` (see
        fuzzylite_set), or jFuzzyLogic's (``trape a b c d``, ``gauss m s``), to ';'."""
        kind = kind or self.take()
        values = self.term_values(term, kind)
        name, values = shapes.from_jfuzzylogic(kind.text, values)  # gauss 0.2 0.1, ...
        return fuzzylite_set(term.text, name, values, self.file, kind.line)

    def output_term(self, term: Token, output: _Output
                    ) -> tuple[float, tuple[float, ...] | None]:
        """An output term: a singleton (``c``, fuzzylite's ``Constant c`` or zero-order
        ``Linear 0 ... 0 c``), or a Mamdani set (points, or a fuzzylite or jFuzzyLogic term)
        whose singleton :meth:`check_output` gives when converting."""
        if self.peek().kind == "number":
            return self.number(), None
        if self.peek().kind == "name":
            kind = self.take()
            if kind.word in ("CONSTANT", "LINEAR"):
                numbers: list[float] = []
                while self.peek().kind == "number" and len(numbers) <= len(self.input_names):
                    numbers.append(self.number())
                if self.peek().word != ";":
                    numbers = []  # not numbers only: refused below as not a constant
                try:
                    return output_constant(kind.text, numbers, len(self.input_names),
                                           self.file, kind.line, term.text,
                                           self.linear_singletons)
                except ExportError as error:  # reported with the output's other refusals
                    while self.peek().word != ";":
                        self.take()
                    output.pending.append(error)
                    return 0.0, None
            item = self.fuzzylite_term(term, kind)
            output.sets[term.text] = set_row(item.shape_value())
        elif self.peek().word == "(":
            output.point_sets.append((term, self.points(term)))
        else:
            found = self.peek()
            raise self.fail(found, f"output term '{term.text}' is '{found.text} ...': "
                            "neither a singleton nor a set", "write TERM name := value;")
        if not output.set_line:
            output.set_line, output.set_name = term.line, term.text
        return 0.0, None  # the singleton, once the range is known (check_output)

    def points(self, term: Token) -> list[tuple[float, float]]:
        points = []
        while self.peek().word == "(":
            self.take()
            x = self.number()
            self.expect(",")
            mu = self.number()
            self.expect(")")
            points.append((x, mu))
        if not points:
            found = self.peek()
            raise self.fail(found, f"term '{term.text}' is '{found.text} ...', not a point "
                            "list: flctool's sets are trapezoids written as points",
                            "write TERM name := (pa, 0) (pb, 1) (pc, 1) (pd, 0);")
        return points

    def range_(self) -> tuple[float, float]:
        self.expect(":=")
        self.expect("(")
        lo = self.number()
        self.expect("..")
        hi = self.number()
        self.expect(")")
        self.expect(";")
        return lo, hi

    def defuzzify(self) -> None:
        token = self.name()
        output = next((o for o in self.outputs if o.name == token.text), None)
        if output is None:
            raise self.fail(token, f"DEFUZZIFY of '{token.text}', which is not a VAR_OUTPUT")
        if output.defuzzified:
            raise self.fail(token, f"a second DEFUZZIFY block of '{token.text}'",
                            "merge them into one")
        output.defuzzified = True
        while self.peek().word != "END_DEFUZZIFY":
            key = self.take()
            if key.word == "TERM":
                term = self.name()
                self.expect(":=")
                value, linear = self.output_term(term, output)
                self.expect(";")
                output.commands.append(ImportedCommand(term.text, value, term.line, linear))
            elif key.word == "METHOD":
                self.expect(":")
                method = self.take()
                output.method = (method.word, method.line)
                self.expect(";")
            elif key.word == "ACCU":
                output.accumulation = self.accumulation()
            elif key.word == "RANGE":
                output.range = self.range_()
            elif key.word == "DEFAULT":
                # Never used: every state fires a rule, and COGS lies between the singletons.
                while self.take().word != ";":
                    pass
            else:
                raise self.fail(key, f"'{key.text}' in DEFUZZIFY {token.text}")
        self.take()

    def accumulation(self) -> tuple[str, int]:
        self.expect(":")
        method = self.take()
        self.expect(";")
        return method.word, method.line

    def ruleblock(self, start: Token) -> None:
        self.blocks += 1
        if self.blocks > 1:
            raise self.fail(start, "a second RULEBLOCK", "put every rule in one block")
        if self.peek().kind == "name" and self.peek().word not in KEYWORDS:
            self.take()
        while self.peek().word != "END_RULEBLOCK":
            key = self.take()
            if key.word == "AND":
                self.expect(":")
                method = self.take()
                self.result.conjunction = (None if method.word == "MIN" else Method(
                    f"AND : {method.text}", method.line, "use AND : MIN or AND : PROD",
                    product=method.word == "PROD"))
                self.expect(";")
            elif key.word == "OR":  # how OR rules fire (converted Mamdani outputs only)
                self.expect(":")
                method = self.take()
                self.result.disjunction = (None if method.word == "MAX" else Method(
                    f"OR : {method.text}", method.line, "use OR : MAX"))
                self.expect(";")
            elif key.word == "ACT":  # a singleton's activation does not change it
                self.expect(":")
                method = self.take()
                self.implication = (method.word, method.line)
                self.expect(";")
            elif key.word == "ACCU":
                self.block_accumulation = self.accumulation()
            elif key.word == "RULE":
                self.rule(key)
            else:
                raise self.fail(key, f"'{key.text}' in a RULEBLOCK")
        self.take()

    def rule(self, start: Token) -> None:
        first = self.at - 1  # the RULE token
        self.take()  # the rule's number or name
        self.expect(":")
        self.expect("IF")
        conditions: list[tuple[Token, str, bool]] = []
        joints: set[str] = set()
        while True:
            conditions.append(self.proposition())
            joint = self.take()
            if joint.word == "THEN":
                break
            if joint.word not in ("AND", "OR"):
                raise self.fail(joint, f"'{joint.text}' in a rule's condition")
            joints.add(joint.word)
            if len(joints) > 1:
                raise self.fail(joint, "a rule mixing AND and OR", "write one AND chain")
        antecedent: dict[str, str] = {}
        disjuncts: list[tuple[str, str]] = []
        # OR and NOT are refused unless a Mamdani output is converted (imported.py)
        negated = {name.text for name, _, negation in conditions if negation}
        named = [name.text for name, _, _ in conditions]
        if any(named.count(n) > 1 for n in negated):
            raise self.fail(start, "NOT on an input the rule names more than once",
                            "write the sets meant instead")
        if "OR" in joints:
            disjuncts = [(name.text, term) for name, term, _ in conditions]
        for name, term, _ in [] if disjuncts else conditions:
            if name.text in antecedent:
                raise self.fail(name, f"the rule names input '{name.text}' twice")
            antecedent[name.text] = term
        conclusions: list[tuple[str, str, float]] = []
        names = [o.name for o in self.outputs]
        while True:
            output, command, negation = self.proposition()
            if negation:
                raise self.fail(output, "NOT in a rule's conclusion", "conclude on a term")
            if output.text not in names:
                raise self.fail(output, f"the rule concludes on '{output.text}', which is not "
                                f"an output ({', '.join(names)})")
            if output.text in [name for name, _, _ in conclusions]:
                raise self.fail(output, f"the rule concludes on '{output.text}' twice")
            end = self.take()
            weight = 1.0  # another is refused unless a Mamdani output is converted
            if end.word == "WITH":
                weight = self.number()
                end = self.take()
            conclusions.append((output.text, command, weight))
            if end.word not in (",", "AND"):  # IEC separates conclusions by ',', fuzzylite
                break                         # by 'and'
        if end.word in ("RULE", "END_RULEBLOCK"):  # fuzzylite ends rules at the line's end
            self.at -= 1
        elif end.word != ";":
            raise self.fail(end, f"'{end.text}' where the rule should end with ';'",
                            "end the rule with ';'")
        written = [t.text for t in self.tokens[first:self.at] if t.text != ";"]
        self.rules.append((antecedent, disjuncts, negated, conclusions, start.line,
                           " ".join(written)))

    def proposition(self) -> tuple[Token, str, bool]:
        """``variable IS [NOT] term``: the variable, the term and whether it is negated."""
        first = self.take()
        if first.word == "(":
            raise self.fail(first, "a rule with parentheses", "write one AND chain")
        if first.kind != "name":
            raise self.fail(first, f"'{first.text}' where a variable name should be")
        self.expect("IS")
        term = self.take()
        negation = term.word == "NOT"
        if negation:
            term = self.take()
        if term.kind != "name":
            raise self.fail(term, f"'{term.text}' where a term name should be")
        following = self.peek()
        if following.kind == "name" and following.word not in ("AND", "OR", "THEN", "WITH",
                                                                 "RULE", "END_RULEBLOCK"):
            raise self.fail(term, f"the hedge '{term.text}' before '{following.text}': "
                            "flctool's rules use plain terms")
        return first, term.text, negation
