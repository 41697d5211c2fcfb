"""FLL, the FuzzyLite Language: a Takagi-Sugeno engine with constant output terms.

The engine computes eq. 1-3 as flctool does: Trapezoid / Triangle input terms (eq. 1's sets;
the other shapes as fuzzylite's Gaussian, GaussianProduct, Bell, Sigmoid, SigmoidDifference,
SigmoidProduct, SShape, ZShape and PiShape terms, :mod:`flctool.export.shapes`),
conjunction Minimum (eq. 2), and the WeightedAverage of the constant terms over every fired
rule (eq. 3). Inputs have ``lock-range: true`` so that fuzzylite clips them to their range as
flctool does. The output has ``aggregation: none``: with an aggregation, pyfuzzylite 8's
WeightedAverage merges the rules that share a term and no longer computes eq. 3.
Numbers are written with repr (full precision), never fuzzylite's default 3 decimals.
"""

from __future__ import annotations

import re

from flctool.errors import ExportError
from flctool.export import shapes
from flctool.export.base import Exporter, Importer, header_lines, number
from flctool.export.imported import (
    ImportedCommand,
    ImportedController,
    ImportedInput,
    ImportedRule,
    Method,
    build_behaviour,
    excerpt,
    fuzzylite_set,
    parse_number,
    zero_order_constant,
)
from flctool.spec import Behaviour, require_deployable
from flctool.spec.base import identifier
from flctool.spec.models import FuzzySet
from flctool.spec.shapes import ShapedSet

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
        lines = [f"# {line}" for line in header_lines(behaviour, self.options.provenance)]
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
                  f"{INDENT}conjunction: Minimum", f"{INDENT}disjunction: none",
                  f"{INDENT}implication: none", f"{INDENT}activation: General"]
        for rule in behaviour.rules:
            condition = " and ".join(f"{n} is {rule.if_[n]}" for n in behaviour.input_names)
            lines.append(f"{INDENT}rule: if {condition} then {output.name} is {rule.then}")
        return "\n".join(lines) + "\n"


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
    """Reads a Takagi-Sugeno FLL engine with constant terms (the FllExporter's subset)."""

    format = "fll"

    def parse(self, text: str, file: str) -> Behaviour:
        return build_behaviour(_FllReader(file).read(text))


class _FllReader:
    def __init__(self, file: str) -> None:
        self.file = file
        self.result = ImportedController(file)
        self.fail = self.result.error
        self.section = ""
        self.blocks = 0
        # fuzzylite's default conjunction is none, which cannot combine two memberships
        self.result.conjunction = Method("conjunction none", 1, "use conjunction: Minimum")
        self.current: ImportedInput | None = None

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
        if not self.result.output_declared:
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
            self.result.declare_output(value, line)
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
            self.current.sets.append(fuzzylite_set(name, kind, values, self.file, line))
        else:
            raise self.fail(line, f"'{key}' in an InputVariable")

    def output_entry(self, key: str, value: str, line: int) -> None:
        # The output's range, lock-range and default never matter (every state fires a rule
        # and eq. 3 lies between the commands), but they must still say something valid.
        if self.common_entry(key, value, line):
            return
        if key in ("lock-range", "lock-previous"):
            self.boolean(key, value, line)
        elif key == "range":
            self.pair(value, line)
        elif key == "default":
            if value.lower() not in ("nan", "-nan"):
                parse_number(value, self.file, line, "default")
        elif key == "aggregation":
            self.result.accumulation = (None if value.lower() == "none" else
                                        Method(f"aggregation {value}", line,
                                               "use aggregation: none"))
        elif key == "defuzzifier":
            words = value.split()
            if not words or words[0] != "WeightedAverage" or any(
                    w not in ("TakagiSugeno", "Automatic") for w in words[1:]):
                raise self.fail(line, f"defuzzifier {value}: flctool's output is the weighted "
                                "average of constant terms (eq. 3)",
                                "use defuzzifier: WeightedAverage TakagiSugeno")
        elif key == "term":
            name, kind, params = self.term(value, line)
            if kind not in ("Constant", "Linear"):
                zero_order_constant(kind, [], 0, self.file, line, name)  # refuses it
            numbers = [parse_number(p, self.file, line, f"term '{name}'") for p in params]
            constant = zero_order_constant(kind, numbers, len(self.result.inputs), self.file,
                                           line, name)
            self.result.commands.append(ImportedCommand(name, constant, line))
        else:
            raise self.fail(line, f"'{key}' in an OutputVariable")

    def rule_block_entry(self, key: str, value: str, line: int) -> None:
        if self.common_entry(key, value, line) or key in ("disjunction", "implication"):
            return  # OR rules are refused one by one; implication is unused by Takagi-Sugeno
        if key == "conjunction":
            self.result.conjunction = (None if value == "Minimum" else Method(
                f"conjunction {value}", line, "use conjunction: Minimum"))
        elif key == "activation":
            if value != "General":
                raise self.fail(line, f"activation {value}: flctool fires every rule",
                                "use activation: General")
        elif key == "rule":
            self.result.rules.append(self.rule(value, line))
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

    def rule(self, text: str, line: int) -> ImportedRule:
        words = text.split()
        if not words or words[0] != "if" or "then" not in words:
            raise self.fail(line, f"rule '{text}' is not 'if ... then ...'")
        cut = words.index("then")
        condition, conclusion = words[1:cut], words[cut + 1:]
        if "(" in text or ")" in text:
            raise self.fail(line, "a rule with parentheses", "write one 'and' chain")
        if "or" in condition:
            raise self.fail(line, "an 'or' rule: flctool's rules are one AND chain (eq. 1)")
        antecedent: dict[str, str] = {}
        for clause in _split(condition, "and"):
            name, term = self.proposition(clause, line, "condition")
            if name in antecedent:
                raise self.fail(line, f"the rule names input '{name}' twice")
            antecedent[name] = term
        if "with" in conclusion:
            at = conclusion.index("with")
            weight = parse_number(" ".join(conclusion[at + 1:]), self.file, line, "weight")
            if weight != 1.0:
                raise self.fail(line, f"a rule weight of {conclusion[at + 1]}: flctool's "
                                "rules all weigh 1")
            conclusion = conclusion[:at]
        clauses = _split(conclusion, "and")
        if len(clauses) != 1:
            raise self.fail(line, "a rule with several conclusions")
        output, command = self.proposition(clauses[0], line, "conclusion")
        if output != self.result.output_name:
            raise self.fail(line, f"the rule concludes on '{output}', not on the output "
                            f"'{self.result.output_name}'")
        return ImportedRule(antecedent, command, line, text.strip())

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
