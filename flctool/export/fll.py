"""FLL, the FuzzyLite Language: a Takagi-Sugeno engine with constant output terms.

The engine computes eq. 1-3 as flctool does: Trapezoid / Triangle input terms (eq. 1's sets;
the other shapes as fuzzylite's Gaussian, GaussianProduct, Bell, Sigmoid, SigmoidDifference,
SigmoidProduct, SShape, ZShape and PiShape terms, :mod:`flctool.export.shapes`), conjunction
Minimum (eq. 2; AlgebraicProduct with ``activation: product``), and the WeightedAverage of
the constant terms over every fired rule (eq. 3). Inputs have ``lock-range: true`` so that
fuzzylite clips them to their range as flctool does. The output has ``aggregation: none``:
with an aggregation, pyfuzzylite 8's WeightedAverage merges the rules that share a term and
no longer computes eq. 3. Numbers are written with repr (full precision), never fuzzylite's
default 3 decimals.
"""

from __future__ import annotations

import dataclasses
import math
import re
from dataclasses import dataclass, field

from flctool.behaviour import Behaviour, require_deployable
from flctool.behaviour.base import identifier
from flctool.behaviour.fuzzy import FuzzySet
from flctool.behaviour.shapes import ShapedSet, set_row
from flctool.errors import ExportError
from flctool.export import shapes
from flctool.export.base import Exporter, Importer, header_lines, number, vote_note
from flctool.export.imported import (
    QUAD0,
    ImportedCommand,
    ImportedController,
    ImportedInput,
    ImportedRule,
    ImportedSet,
    Method,
    build_behaviour,
    excerpt,
    fuzzylite_set,
    output_constant,
    parse_number,
)
from flctool.export.linear import converted_notes
from flctool.export.mamdani import (
    AGGREGATIONS,
    IMPLICATIONS,
    MAMDANI_HINT,
    MamdaniOutput,
    import_notes,
)

#: Words a fuzzylite rule reads as keywords or hedges, so they cannot name a variable or term.
RESERVED = frozenset({"if", "is", "then", "and", "or", "with", "not", "any", "extremely",
                      "seldom", "somewhat", "very"})
HEDGES = frozenset({"not", "any", "extremely", "seldom", "somewhat", "very"})
INDENT = "  "


class FllExporter(Exporter):
    format = "fll"

    def to_string(self, behaviour: Behaviour) -> str:
        require_deployable(behaviour)
        _check_names(behaviour)
        lines = [f"# {line}" for line in (header_lines(behaviour, self.options.provenance)
                                          + vote_note(behaviour))]
        lines.append(f"Engine: {identifier(behaviour.name)}")
        if behaviour.description:
            # FLL values are one line long and '#' starts a comment.
            description = " ".join(behaviour.description.split()).partition("#")[0].strip()
            lines.append(f"{INDENT}description: {description}")
        for name, variable in behaviour.inputs.items():
            lo, hi = variable.range
            lines += [f"InputVariable: {name}", f"{INDENT}enabled: true",
                      f"{INDENT}range: {number(lo)} {number(hi)}",
                      f"{INDENT}lock-range: true"]
            for set_name, value in variable.sets.items():
                lines.append(f"{INDENT}term: {set_name} {fuzzylite_term(value)}")
        output = behaviour.output
        values = list(output.commands.values())
        lines += [f"OutputVariable: {output.name}", f"{INDENT}enabled: true",
                  f"{INDENT}range: {number(min(values))} {number(max(values))}",
                  f"{INDENT}lock-range: true", f"{INDENT}aggregation: none",
                  f"{INDENT}defuzzifier: WeightedAverage TakagiSugeno",
                  f"{INDENT}default: nan", f"{INDENT}lock-previous: false"]
        lines += [f"{INDENT}term: {command} Constant {number(value)}"
                  for command, value in output.commands.items()]
        lines += ["RuleBlock: rules", f"{INDENT}enabled: true",
                  f"{INDENT}conjunction: {CONJUNCTION[behaviour.activation]}",
                  f"{INDENT}disjunction: none",
                  f"{INDENT}implication: none", f"{INDENT}activation: General"]
        for rule in behaviour.rules:
            condition = " and ".join(f"{n} is {rule.if_[n]}" for n in behaviour.input_names)
            lines.append(f"{INDENT}rule: if {condition} then {output.name} is {rule.then}")
        return "\n".join(lines) + "\n"


#: Eq. 2 as fuzzylite names it, by the behaviour's activation.
CONJUNCTION = {"min": "Minimum", "product": "AlgebraicProduct"}


def fuzzylite_term(value: FuzzySet) -> str:
    """A set as fuzzylite writes its term (FLL, and FCL in fuzzylite's dialect)."""
    if isinstance(value, ShapedSet):
        name, params = shapes.written(shapes.FUZZYLITE, value.kind, value.params)
        return f"{name} {' '.join(number(v) for v in params)}"
    pa, pb, pc, pd = value
    if pb == pc:
        return f"Triangle {number(pa)} {number(pb)} {number(pd)}"
    return f"Trapezoid {number(pa)} {number(pb)} {number(pc)} {number(pd)}"


def _check_names(behaviour: Behaviour) -> None:
    names = [("input", n) for n in behaviour.inputs]
    names += [(f"set of input '{n}'", s) for n, v in behaviour.inputs.items() for s in v.sets]
    names += [("output", behaviour.output.name)]
    names += [("command", c) for c in behaviour.output.commands]
    for kind, name in names:
        if name in RESERVED:
            raise ExportError(f"the {kind} '{name}' is a keyword of FLL rules, so fuzzylite "
                              "would misread the rules", hint="rename it in the behaviour file")


_KEY = re.compile(r"[A-Za-z-]+")


class FllImporter(Importer):
    """Reads a Takagi-Sugeno FLL engine with constant terms (the FllExporter's subset), one
    behaviour per output; with ``mamdani_singletons``, also Mamdani outputs (see
    :mod:`flctool.export.mamdani`), and then ``report`` says how far that moved each."""

    format = "fll"

    def __init__(self, mamdani_singletons: bool = False, linear_singletons: bool = False
                 ) -> None:
        self.mamdani_singletons = mamdani_singletons
        self.linear_singletons = linear_singletons
        self.report = ""

    def parse(self, text: str, file: str) -> Behaviour:
        return self.from_string(text, file)

    def parse_all(self, text: str, file: str) -> list[Behaviour]:
        reader = _FllReader(file, self.mamdani_singletons, self.linear_singletons)
        controllers = reader.read_all(text)
        behaviours, notes = converted_notes([build_behaviour(c) for c in controllers],
                                            controllers, [o.range for o in reader.outputs])
        self.report = import_notes(file, behaviours, [
            (controller, output.mamdani()) if output.sets else note
            for output, controller, note in zip(reader.outputs, controllers, notes,
                                                strict=True)])
        return behaviours


@dataclass
class _Output:
    """One OutputVariable as read."""

    name: str
    line: int
    commands: list[ImportedCommand] = field(default_factory=list)
    aggregation: tuple[str, int] = ("none", 0)
    defuzzifier: tuple[str, int] = ("", 0)  # "weighted" or "centroid", and its line
    resolution: int = 100  # fuzzylite 6's default for a Centroid
    range: tuple[float, float] = (0.0, 1.0)
    range_line: int = 0
    #: Mamdani output sets: name -> (shape code, row), and the line of the first
    sets: dict[str, tuple[int, tuple[float, float, float, float]]] = field(
        default_factory=dict)
    set_line: int = 0
    implication: str = "Minimum"
    #: Refusals of this output's terms, reported with the file's others
    pending: list[ExportError] = field(default_factory=list)

    def mamdani(self) -> MamdaniOutput:
        return MamdaniOutput({identifier(n): row for n, row in self.sets.items()}, self.range,
                             self.resolution, self.implication,
                             "Maximum" if self.aggregation[0] == "Maximum" else "AlgebraicSum")


class _FllReader:
    def __init__(self, file: str, mamdani_singletons: bool = False,
                 linear_singletons: bool = False) -> None:
        self.file = file
        self.mamdani_singletons = mamdani_singletons
        self.linear_singletons = linear_singletons
        self.result = ImportedController(file)
        self.fail = self.result.error
        self.section = ""
        self.blocks = 0
        # fuzzylite's default conjunction is none, which cannot combine two memberships
        self.result.conjunction = Method("conjunction none", 1,
                                         "use conjunction: Minimum or AlgebraicProduct")
        self.result.disjunction = Method("disjunction none", 1, "use disjunction: Maximum")
        self.current: ImportedInput | None = None
        self.outputs: list[_Output] = []
        #: every rule as read: its antecedent (or an OR rule's conditions), the inputs it
        #: negates, its conclusions (output, term), weight, line, text
        self.rules: list[tuple[dict[str, str], list[tuple[str, str]], set[str],
                               list[tuple[str, str]], float, int, str]] = []
        self.implication = ("none", 0)

    def read_all(self, text: str) -> list[ImportedController]:
        """One controller per output, each with the rules that conclude on it."""
        self.read(text)
        controllers = []
        for output in self.outputs:
            pending = [*self.result.pending, *output.pending]
            try:
                self.check_output(output)
            except ExportError as error:  # reported with the rules' refusals
                pending.append(error)
            imported = dataclasses.replace(
                self.result, output_name=output.name, output_line=output.line,
                output_declared=True, commands=output.commands, rules=[
                    ImportedRule(dict(antecedent), term, line, text_, list(disjuncts), weight,
                                 set(negated))
                    for antecedent, disjuncts, negated, conclusions, weight, line, text_
                    in self.rules
                    for name, term in conclusions if name == output.name],
                accumulation=None, pending=pending, merged_commands=[])
            if len(self.outputs) > 1:
                imported.name, imported.name_line = output.name, output.line
            imported.expand_rules = bool(output.sets) and self.mamdani_singletons
            # a Takagi-Sugeno output, converted if it needs to be (build_behaviour)
            imported.convert_linear = self.linear_singletons and not output.sets
            if not output.sets and output.aggregation[0].lower() != "none":
                imported.accumulation = Method(f"aggregation {output.aggregation[0]}",
                                               output.aggregation[1], "use aggregation: none")
            controllers.append(imported)
        return controllers

    def check_output(self, output: _Output) -> None:
        """An output's terms and methods fit together: constants and the weighted average,
        or (converting) Mamdani sets and the centroid."""
        kind, line = output.defuzzifier
        if not output.sets:
            if kind == "centroid":
                raise self.fail(line, f"defuzzifier Centroid of output '{output.name}', whose "
                                "terms are constants", "use defuzzifier: WeightedAverage")
            return
        if not self.mamdani_singletons:
            raise self.fail(output.set_line, f"output '{output.name}' has Mamdani sets (a "
                            f"{'centroid' if kind == 'centroid' else 'set'} output): flctool's "
                            "commands are singletons (eq. 3)", MAMDANI_HINT)
        if len(output.sets) != len(output.commands):
            raise self.fail(output.set_line, f"output '{output.name}' mixes constant terms "
                            "and sets", "make every term of a Mamdani output a set")
        if kind != "centroid":
            raise self.fail(line or output.line, f"the Mamdani output '{output.name}' is not "
                            "defuzzified by Centroid, which the conversion measures against",
                            "use defuzzifier: Centroid")
        aggregation, at = output.aggregation
        if aggregation not in AGGREGATIONS:
            raise self.fail(at or output.line, f"aggregation {aggregation} of the Mamdani "
                            f"output '{output.name}': the conversion measures "
                            f"{' or '.join(AGGREGATIONS)}", "use aggregation: Maximum")
        implication, at = self.implication
        if implication not in IMPLICATIONS:
            raise self.fail(at or output.line, f"implication {implication}: the conversion "
                            f"of a Mamdani output measures {' or '.join(IMPLICATIONS)}",
                            "use implication: Minimum")
        output.implication = implication
        lo, hi = output.range
        if not lo < hi:  # the centroid integrates over the range
            raise self.fail(output.range_line or output.line, f"the range [{lo!r}, {hi!r}] of "
                            f"the Mamdani output '{output.name}' is not low then high",
                            "write the range low end first, and make it wider than a point")
        for name, (code, row) in output.sets.items():
            # a shoulder's infinite foot (a Ramp): the centroid integrates over the output
            # range only, where the shoulder ending at the range's end has the same membership
            if code == 0:
                pa, pb, pc, pd = (lo if v == -math.inf else hi if v == math.inf else v
                                  for v in row)
                output.sets[name] = (0, (pa, pb, pc, pd))
        mamdani = output.mamdani()
        for command in output.commands:
            command.value = mamdani.singleton(identifier(command.name))

    def read(self, text: str) -> ImportedController:
        for number_, raw in enumerate(text.splitlines(), start=1):
            line = raw.partition("#")[0]
            if not line.strip():
                continue
            key, colon, value = line.partition(":")
            key = key.strip()
            if not colon or _KEY.fullmatch(key) is None:
                raise self.fail(number_, f"'{excerpt(line.strip())}' is not a 'key: value' "
                                "line")
            self.entry(key, value.strip(), number_)
        if not self.outputs:
            raise self.fail(1, "the engine has no OutputVariable")
        if self.blocks == 0:
            raise self.fail(1, "the engine has no RuleBlock")
        return self.result

    def entry(self, key: str, value: str, line: int) -> None:
        if key in ("Engine", "InputVariable", "OutputVariable", "RuleBlock"):
            self.begin(key, value, line)
        elif self.section == "Engine":
            self.engine_entry(key, value, line)
        elif self.section == "InputVariable":
            self.input_entry(key, value, line)
        elif self.section == "OutputVariable":
            self.output_entry(key, value, line)
        elif self.section == "RuleBlock":
            self.rule_block_entry(key, value, line)
        else:
            raise self.fail(line, f"'{key}' outside an Engine, variable or RuleBlock")

    def begin(self, key: str, value: str, line: int) -> None:
        self.section = key
        if key == "Engine":
            self.result.name, self.result.name_line = value, line
        elif key == "InputVariable":
            self.current = ImportedInput(value, line)
            self.result.inputs.append(self.current)
        elif key == "OutputVariable":
            self.outputs.append(_Output(value, line))
        else:
            self.blocks += 1
            if self.blocks > 1:
                raise self.fail(line, "a second RuleBlock", "put every rule in one block")

    def common_entry(self, key: str, value: str, line: int) -> bool:
        """Keys every variable has; True if handled."""
        if key == "enabled":
            if value != "true":
                raise self.fail(line, f"a disabled {self.section}")
            return True
        return key == "description"

    def engine_entry(self, key: str, value: str, line: int) -> None:
        if key != "description":
            raise self.fail(line, f"'{key}' in the Engine section")
        self.result.description = value

    def input_entry(self, key: str, value: str, line: int) -> None:
        assert self.current is not None  # set by begin() before any input key
        if self.common_entry(key, value, line):
            return
        if key == "lock-range":
            # flctool always clips inputs to their range; lock-range false differs only
            # outside the range.
            self.boolean(key, value, line)
        elif key == "range":
            self.current.range = self.pair(value, line)
        elif key == "term":
            name, kind, params = self.term(value, line)
            values = [self.point(p, line, kind) for p in params]
            try:
                item = fuzzylite_set(name, kind, values, self.file, line)
            except ExportError as error:  # reported with the file's other refusals
                item = self.result.put_off(error, ImportedSet(name, QUAD0, line))
            self.current.sets.append(item)
        else:
            raise self.fail(line, f"'{key}' in an InputVariable")

    def output_entry(self, key: str, value: str, line: int) -> None:
        # The output's range, lock-range and default never matter (every state fires a rule
        # and eq. 3 lies between the commands), but they must still say something valid.
        if self.common_entry(key, value, line):
            return
        output = self.outputs[-1]
        if key in ("lock-range", "lock-previous"):
            self.boolean(key, value, line)
        elif key == "range":
            output.range = self.pair(value, line)
            output.range_line = line
        elif key == "default":
            if value.lower() not in ("nan", "-nan"):
                parse_number(value, self.file, line, "default")
        elif key == "aggregation":
            output.aggregation = (value, line)
        elif key == "defuzzifier":
            output.defuzzifier = (self.defuzzifier(value, line, output), line)
        elif key == "term":
            name, kind, params = self.term(value, line)
            if kind in ("Constant", "Linear"):
                numbers = [parse_number(p, self.file, line, f"term '{name}'") for p in params]
                try:
                    constant, linear = output_constant(kind, numbers, len(self.result.inputs),
                                                       self.file, line, name,
                                                       self.linear_singletons)
                except ExportError as error:  # reported with the output's other refusals
                    output.pending.append(error)
                    constant, linear = 0.0, None
                output.commands.append(ImportedCommand(name, constant, line, linear))
                return
            else:  # a Mamdani output set: a singleton at its centroid, if converting
                values = [self.point(p, line, kind) for p in params]
                item = fuzzylite_set(name, kind, values, self.file, line)
                output.sets[name] = set_row(item.shape_value())
                output.set_line = output.set_line or line
                constant = 0.0  # set by check_output
            output.commands.append(ImportedCommand(name, constant, line))
        else:
            raise self.fail(line, f"'{key}' in an OutputVariable")

    def defuzzifier(self, value: str, line: int, output: _Output) -> str:
        """``weighted`` or ``centroid`` (and its resolution into ``output``)."""
        words = value.split()
        if words and words[0] == "WeightedAverage" and all(
                w in ("TakagiSugeno", "Automatic") for w in words[1:]):
            return "weighted"
        if words and words[0] == "Centroid" and len(words) <= 2:
            if len(words) == 2:
                resolution = parse_number(words[1], self.file, line, "resolution")
                if resolution != int(resolution) or not 1 <= resolution <= 100_000:
                    raise self.fail(line, f"a Centroid resolution of {words[1]}",
                                    "give a whole number of at most 100,000")
                output.resolution = int(resolution)
            return "centroid"
        raise self.fail(line, f"defuzzifier {value}: flctool's output is the weighted "
                        "average of constant terms (eq. 3); a Mamdani output's Centroid is "
                        "converted on request", "use defuzzifier: WeightedAverage TakagiSugeno")

    def rule_block_entry(self, key: str, value: str, line: int) -> None:
        if key == "implication":
            self.implication = (value, line)
            return
        if key == "disjunction":  # how an OR rule (converted Mamdani outputs only) fires
            self.result.disjunction = (None if value == "Maximum" else Method(
                f"disjunction {value}", line, "use disjunction: Maximum"))
            return
        if self.common_entry(key, value, line):
            return
        if key == "conjunction":
            self.result.conjunction = (None if value == "Minimum" else Method(
                f"conjunction {value}", line, "use conjunction: Minimum or AlgebraicProduct",
                product=value == "AlgebraicProduct"))
        elif key == "activation":
            if value != "General":
                raise self.fail(line, f"activation {value}: flctool fires every rule",
                                "use activation: General")
        elif key == "rule":
            self.rule(value, line)
        else:
            raise self.fail(line, f"'{key}' in a RuleBlock")

    def boolean(self, key: str, value: str, line: int) -> bool:
        if value not in ("true", "false"):
            raise self.fail(line, f"{key}: '{excerpt(value)}' is neither true nor false")
        return value == "true"

    def pair(self, value: str, line: int) -> tuple[float, float]:
        parts = value.split()
        if len(parts) != 2:
            raise self.fail(line, f"range '{excerpt(value)}' is not two numbers")
        lo, hi = (parse_number(p, self.file, line, "range") for p in parts)
        return lo, hi

    def term(self, value: str, line: int) -> tuple[str, str, list[str]]:
        parts = value.split()
        if len(parts) < 2:
            raise self.fail(line, f"term '{value}' is not 'name Kind parameters'")
        return parts[0], parts[1], parts[2:]

    def point(self, text: str, line: int, kind: str) -> float:
        """A term's point: a number, or -inf / inf for a shoulder's foot."""
        if text.lower() in ("inf", "+inf", "-inf"):
            return float(text)
        return parse_number(text, self.file, line, kind)

    def rule(self, text: str, line: int) -> None:
        words = text.split()
        if not words or words[0] != "if" or "then" not in words:
            raise self.fail(line, f"rule '{text}' is not 'if ... then ...'")
        cut = words.index("then")
        condition, conclusion = words[1:cut], words[cut + 1:]
        if "(" in text or ")" in text:
            raise self.fail(line, "a rule with parentheses", "write one 'and' chain")
        if "or" in condition and "and" in condition:
            raise self.fail(line, "a rule mixing 'and' and 'or'", "write one 'and' chain")
        antecedent: dict[str, str] = {}
        disjuncts: list[tuple[str, str]] = []
        # OR and NOT are refused unless a Mamdani output is converted (imported.py)
        conditions = [self.condition(c, line) for c in
                      _split(condition, "or" if "or" in condition else "and")]
        negated = {name for name, _, negation in conditions if negation}
        named = [name for name, _, _ in conditions]
        if any(named.count(n) > 1 for n in negated):
            raise self.fail(line, "'not' on an input the rule names more than once",
                            "write the sets meant instead")
        if "or" in condition:
            disjuncts = [(name, term) for name, term, _ in conditions]
        for name, term, _ in [] if disjuncts else conditions:
            if name in antecedent:
                raise self.fail(line, f"the rule names input '{name}' twice")
            antecedent[name] = term
        weight = 1.0  # another is refused unless a Mamdani output is converted (imported.py)
        if "with" in conclusion:
            at = conclusion.index("with")
            weight = parse_number(" ".join(conclusion[at + 1:]), self.file, line, "weight")
            conclusion = conclusion[:at]
        conclusions: list[tuple[str, str]] = []
        names = [o.name for o in self.outputs]
        for clause in _split(conclusion, "and"):
            output, command = self.proposition(clause, line, "conclusion")
            if output not in names:
                raise self.fail(line, f"the rule concludes on '{output}', which is not an "
                                f"output ({', '.join(names)})")
            if output in [name for name, _ in conclusions]:
                raise self.fail(line, f"the rule concludes on '{output}' twice")
            conclusions.append((output, command))
        self.rules.append((antecedent, disjuncts, negated, conclusions, weight, line,
                           text.strip()))

    def condition(self, words: list[str], line: int) -> tuple[str, str, bool]:
        """``variable is [not] term``: the variable, the term and whether it is negated."""
        if len(words) == 4 and words[1] == "is" and words[2] == "not":
            return words[0], words[3], True
        name, term = self.proposition(words, line, "condition")
        return name, term, False

    def proposition(self, words: list[str], line: int, part: str) -> tuple[str, str]:
        if len(words) == 3 and words[1] == "is":
            return words[0], words[2]
        hedges = [w for w in words[2:-1] if w in HEDGES]
        if len(words) > 3 and words[1] == "is" and hedges:
            raise self.fail(line, f"the hedge '{hedges[0]}' in '{' '.join(words)}'",
                            "flctool's rules use plain terms")
        raise self.fail(line, f"'{' '.join(words)}' in a rule's {part} is not "
                        "'variable is term'")


def _split(words: list[str], separator: str) -> list[list[str]]:
    parts: list[list[str]] = [[]]
    for word in words:
        if word == separator:
            parts.append([])
        else:
            parts[-1].append(word)
    return parts
