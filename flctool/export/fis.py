"""FIS, the text format of MATLAB's Fuzzy Logic Toolbox: a Sugeno system, constant outputs.

Sets of the other shapes are MATLAB's ``gaussmf``, ``gauss2mf``, ``gbellmf``, ``sigmf``,
``dsigmf``, ``psigmf``, ``smf``, ``zmf`` and ``pimf`` (:mod:`flctool.export.shapes`).
Sets are ``trapmf`` (or ``trimf`` when ``pb == pc``) with no vertical edge, as MATLAB and
Octave require: a shoulder's plateau and foot lie outside the range, an edge inside it has its
foot one ulp away (:func:`~flctool.export.base.sloped_quad`); commands are ``constant`` MFs,
``AndMethod='min'`` is eq. 2 (``'prod'`` with ``activation: product``) and
``DefuzzMethod='wtaver'`` is eq. 3. A rule line lists the set index of every input, then
the command index, the weight (1) and the connection (1 = AND).
MATLAB does not clip inputs to their range: clip states before evaluating to match flctool.
"""

from __future__ import annotations

import itertools
import re

from flctool.behaviour import Behaviour, require_deployable
from flctool.behaviour.shapes import ShapedSet, set_row
from flctool.errors import ExportError
from flctool.export import shapes
from flctool.export.base import Exporter, Importer, number, sloped_quad
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
    fuzzylite_quad,
    identifier,
    output_constant,
    parse_number,
    shaped_set,
)
from flctool.export.linear import converted_notes
from flctool.export.mamdani import MAMDANI_HINT, MamdaniOutput, centroid, import_notes

#: Eq. 2 as FIS names it, by the behaviour's activation.
AND_METHOD = {"min": "min", "product": "prod"}


def _vector(values: list[float]) -> str:
    return "[" + " ".join(number(v) for v in values) + "]"


class FisExporter(Exporter):
    format = "fis"

    def to_string(self, behaviour: Behaviour) -> str:
        # FIS has no comment syntax that every reader skips, so no provenance header.
        require_deployable(behaviour)
        output = behaviour.output
        lines = ["[System]", f"Name='{behaviour.name}'", "Type='sugeno'", "Version=2.0",
                 f"NumInputs={len(behaviour.inputs)}", "NumOutputs=1",
                 f"NumRules={len(behaviour.rules)}",
                 f"AndMethod='{AND_METHOD[behaviour.activation]}'", "OrMethod='max'",
                 "ImpMethod='prod'", "AggMethod='sum'", "DefuzzMethod='wtaver'"]
        for index, (name, variable) in enumerate(behaviour.inputs.items(), start=1):
            lines += ["", f"[Input{index}]", f"Name='{name}'",
                      f"Range={_vector(list(variable.range))}", f"NumMFs={len(variable.sets)}"]
            for k, (set_name, quad) in enumerate(variable.sets.items(), start=1):
                if isinstance(quad, ShapedSet):
                    kind, params = shapes.written(shapes.MATLAB, quad.kind, quad.params)
                    lines.append(f"MF{k}='{set_name}':'{kind}',{_vector(params)}")
                    continue
                # MATLAB and Octave refuse trapmf with a == b and trimf with a == b or
                # b == c: no vertical edges (exact under clipping, see sloped_quad)
                pa, pb, pc, pd = sloped_quad(quad, variable.range)
                shape = (f"'trimf',{_vector([pa, pb, pd])}" if pb == pc
                         else f"'trapmf',{_vector([pa, pb, pc, pd])}")
                lines.append(f"MF{k}='{set_name}':{shape}")
        values = list(output.commands.values())
        lo, hi = min(values), max(values)
        if lo == hi:  # MATLAB wants a range of positive width
            lo, hi = lo - 1.0, hi + 1.0
        lines += ["", "[Output1]", f"Name='{output.name}'", f"Range={_vector([lo, hi])}",
                  f"NumMFs={len(values)}"]
        lines += [f"MF{k}='{command}':'constant',[{number(value)}]"
                  for k, (command, value) in enumerate(output.commands.items(), start=1)]
        lines += ["", "[Rules]"]
        set_index = [{s: k for k, s in enumerate(v.sets, start=1)}
                     for v in behaviour.inputs.values()]
        command_index = {c: k for k, c in enumerate(output.commands, start=1)}
        for rule in behaviour.rules:
            sets = " ".join(str(index[rule.if_[name]])
                            for index, name in zip(set_index, behaviour.input_names, strict=True))
            lines.append(f"{sets}, {command_index[rule.then]} (1) : 1")
        return "\n".join(lines) + "\n"


# Every pattern here matches in time linear in the line: no nested or adjacent quantifiers
# over the same characters (a rule line is split by hand, see _FisReader.rule).
_WORD = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
_MF = re.compile(r"'([^']*)'\s*:\s*'([^']*)'\s*,\s*\[([^\]]*)\]")
#: The most digits a count or an index may have.
MAX_DIGITS = 6


#: The Mamdani centroid's resolution: fuzzylite 6's default for an imported FIS.
CENTROID_RESOLUTION = 100


class FisImporter(Importer):
    """Reads a Sugeno FIS with constant outputs, trapmf / trimf inputs and AND rules; with
    ``mamdani_singletons``, also a Mamdani one (see :mod:`flctool.export.mamdani`), and then
    ``report`` says how far the conversion moved the output."""

    format = "fis"

    def __init__(self, mamdani_singletons: bool = False, linear_singletons: bool = False
                 ) -> None:
        self.mamdani_singletons = mamdani_singletons
        self.linear_singletons = linear_singletons
        self.report = ""

    def parse(self, text: str, file: str) -> Behaviour:
        return self.from_string(text, file)

    def parse_all(self, text: str, file: str) -> list[Behaviour]:
        """One behaviour per output: each output's system (:func:`one_output`) read alone."""
        outputs = output_count(text)
        behaviours: list[Behaviour] = []
        conversions: list[tuple[ImportedController, MamdaniOutput] | str | None] = []
        for k in range(1, outputs + 1):
            reader = _FisReader(file, self.mamdani_singletons, self.linear_singletons)
            behaviour = build_behaviour(reader.read(one_output(text, k) if outputs > 1
                                                   else text))
            converted, notes = converted_notes([behaviour], [reader.result],
                                               [reader.output_range])
            behaviour = converted[0]
            if outputs > 1:  # named after its output
                behaviour = behaviour.model_copy(update={"name": behaviour.output.name})
            behaviours.append(behaviour)
            conversions.append((reader.result, reader.mamdani_output()) if reader.output_sets
                               else notes[0])
        self.report = import_notes(file, behaviours, conversions)
        return behaviours


_SECTION = re.compile(r"\[\s*(Output)(\d{1,6})\s*\]")


def output_count(text: str) -> int:
    """How many ``[OutputK]`` sections the file has (1 if none: the reader says what is
    missing)."""
    return max(1, len({m.group(2) for m in _SECTION.finditer(text)}))


def _is_zero(word: str) -> bool:
    try:
        return float(word) == 0.0
    except ValueError:
        return False  # for the reader to refuse


def one_output(text: str, k: int) -> str:
    """The file as the system of its ``k``-th output alone, line for line (so that every
    message names the file's own line): the other output sections and the rules that give
    output ``k`` no MF (index 0) become blank lines, ``[Outputk]`` becomes ``[Output1]``, each
    rule keeps its ``k``-th output index, and NumOutputs / NumRules count what is left. A
    line this cannot read is kept as it is, for the reader to refuse."""
    lines = text.splitlines()
    inputs = len({m.group(1) for m in re.finditer(r"\[\s*Input(\d{1,6})\s*\]", text)})
    section, kept, counts = "", 0, {}
    for at, raw in enumerate(lines):
        line = raw.strip()
        if line.startswith("[") and line.endswith("]"):
            section = line[1:-1].strip()
            if section == f"Output{k}":
                lines[at] = "[Output1]"
            elif section.startswith("Output"):
                lines[at] = ""
            continue
        if section.startswith("Output") and section != f"Output{k}":
            lines[at] = ""
        elif section == "System" and line.replace(" ", "").startswith(("NumOutputs=",
                                                                       "NumRules=")):
            counts[line.partition("=")[0].strip()] = at
        elif section == "Rules" and line and not line.startswith(("%", "#")):
            head, paren, tail = line.partition("(")
            indices, comma, outputs = head.partition(",")
            words = outputs.split() if comma else indices.split()[inputs:]
            ins = indices.split() if comma else indices.split()[:inputs]
            if not paren or len(words) < k:
                continue
            if _is_zero(words[k - 1]):  # (fuzzylite writes 0.000)
                lines[at] = ""
                continue
            lines[at] = f"{' '.join(ins)}, {words[k - 1]} ({tail}"
            kept += 1
    if "NumOutputs" in counts:
        lines[counts["NumOutputs"]] = "NumOutputs=1"
    if "NumRules" in counts:
        lines[counts["NumRules"]] = f"NumRules={kept}"
    return "\n".join(lines) + "\n"


class _FisReader:
    def __init__(self, file: str, mamdani_singletons: bool = False,
                 linear_singletons: bool = False) -> None:
        self.file = file
        self.mamdani_singletons = mamdani_singletons
        self.linear_singletons = linear_singletons
        #: Mamdani output sets (name -> shape code and row) replaced by singletons
        self.output_sets: dict[str, tuple[int, tuple[float, float, float, float]]] = {}
        self.output_range = (0.0, 1.0)
        self.result = ImportedController(file, omission="index 0")
        self.fail = self.result.error
        self.system: dict[str, tuple[str, int]] = {}
        self.section = ("", 0)
        self.rule_lines: list[tuple[str, int]] = []
        # NumMFs as declared (count, line) for each input, then the output
        self.declared_mfs: list[tuple[int, int] | None] = []
        self.output_mfs: tuple[int, int] | None = None

    def read(self, text: str) -> ImportedController:
        for line_number, raw in enumerate(text.splitlines(), start=1):
            line = raw.strip()
            if not line or line.startswith(("%", "#")):
                continue
            if line.startswith("[") and line.endswith("]"):
                self.section_line(line, line_number)
            elif self.section[0] == "Rules":
                self.rule_lines.append((line, line_number))
            else:
                key, equals, value = line.partition("=")
                key = key.strip()
                if not equals or _WORD.fullmatch(key) is None:
                    raise self.fail(line_number, f"'{excerpt(line)}' is not a 'Key=value' line")
                self.entry(key, value.strip(), line_number)
        self.check_system()
        self.check_counts()
        self.result.expand_rules = bool(self.output_sets)  # a Mamdani output, converting
        # a Takagi-Sugeno output, converted if it needs to be (build_behaviour)
        self.result.convert_linear = (self.linear_singletons and not self.mamdani
                                      and not self.output_sets)
        disjunction, at = self.system.get("OrMethod", ("max", 1))
        if disjunction.lower() != "max":
            self.result.disjunction = Method(f"OrMethod='{disjunction}'", at,
                                             "use OrMethod='max'")
        for line, line_number in self.rule_lines:
            self.result.rules.append(self.rule(line, line_number))
        self.methods()
        return self.result

    def section_line(self, text: str, line: int) -> None:
        """``[Name]`` or ``[NameK]``: a word, then an optional index of at most MAX_DIGITS."""
        inner = text[1:-1].strip()
        name = inner.rstrip("0123456789")
        index = inner[len(name):]
        if _WORD.fullmatch(name) is None:
            raise self.fail(line, f"'{excerpt(text)}' is not a section header like [Input1]")
        if len(index) > MAX_DIGITS:
            raise self.fail(line, f"the section index of [{name}...] has {len(index)} digits",
                            "number the sections 1, 2, ... in order")
        self.begin(name, index, line)

    def begin(self, name: str, index: str, line: int) -> None:
        if name == "Input" and index:
            expected = len(self.result.inputs) + 1
            if int(index) != expected:
                raise self.fail(line, f"[Input{index}] where [Input{expected}] should come",
                                "number the input sections 1, 2, ... in order")
            self.result.inputs.append(ImportedInput("", line))
            self.declared_mfs.append(None)
        elif name == "Output" and index:
            self.result.declare_output("", line)
            if index != "1":
                raise self.fail(line, f"[Output{index}] where [Output1] should come")
        elif (name, index) not in (("System", ""), ("Rules", "")):
            raise self.fail(line, f"an unknown section [{name}{index}]")
        self.section = (name, line)

    def entry(self, key: str, value: str, line: int) -> None:
        section = self.section[0]
        if section == "System":
            self.system[key] = (value.strip("'"), line)
            if key == "Name":
                self.result.name, self.result.name_line = value.strip("'"), line
        elif section == "Input":
            self.input_entry(self.result.inputs[-1], key, value, line)
        elif section == "Output":
            self.output_entry(key, value, line)
        else:
            raise self.fail(line, f"'{key}' outside a section")

    def mf_key(self, key: str, count: int, line: int) -> None:
        """MFk must be the k-th MF of its section: the rules refer to MFs by that index."""
        if key != f"MF{count + 1}":
            raise self.fail(line, f"{key} where MF{count + 1} should come",
                            "number the MFs of a section 1, 2, ... in order")

    def count(self, value: str, line: int, key: str) -> int:
        # isdigit alone accepts '²' and other digits int() refuses
        if not (value.isascii() and value.isdigit()) or len(value) > MAX_DIGITS:
            raise self.fail(line, f"{key}={excerpt(value)} is not a whole number of at most "
                            f"{MAX_DIGITS} digits", f"write the count, e.g. {key}=3")
        return int(value)

    def input_entry(self, variable: ImportedInput, key: str, value: str, line: int) -> None:
        if key == "Name":
            variable.name, variable.line = value.strip("'"), line
        elif key == "Range":
            values = self.vector(value, line, "Range")
            if len(values) != 2:
                raise self.fail(line, f"Range {value} is not [low high]")
            variable.range = (values[0], values[1])
        elif key.startswith("MF") and key != "NumMFs":
            self.mf_key(key, len(variable.sets), line)
            name, kind, params = self.mf(value, line)
            arity = {"trapmf": 4, "trimf": 3, "rampmf": 2}
            found = shapes.read(shapes.MATLAB, kind, params)
            if found is not None:
                variable.sets.append(shaped_set(name, found[0], found[1], self.file, line))
                return
            if kind not in arity:  # reported with the file's other refusals
                known = ", ".join([*arity, *(n for n, _ in shapes.MATLAB.values())])
                variable.sets.append(self.result.put_off(self.fail(
                    line, f"membership function '{name}' is a {kind}, which flctool's sets "
                    "do not include", f"use one of {known}"), ImportedSet(name, QUAD0, line)))
                return
            if len(params) != arity[kind]:
                raise self.fail(line, f"a {kind} takes {arity[kind]} parameters",
                                f"give it {arity[kind]} numbers")
            if kind == "rampmf":  # fuzzylite's extension: a shoulder
                quad = fuzzylite_quad("Ramp", params, self.file, line)
            else:
                quad = ((params[0], params[1], params[1], params[2]) if kind == "trimf"
                        else (params[0], params[1], params[2], params[3]))
            variable.sets.append(ImportedSet(name, quad, line))
        elif key == "NumMFs":
            self.declared_mfs[-1] = (self.count(value, line, key), line)
        elif key == "Enabled":  # fuzzylite's extension
            self.enabled(value, line)
        else:
            raise self.fail(line, f"'{key}' in an input section",
                            "remove the line: an input section holds Name, Range, NumMFs and "
                            "MFk")

    def flag(self, key: str, value: str, line: int) -> bool:
        if value not in ("0", "1"):
            raise self.fail(line, f"{key}={excerpt(value)} is neither 0 nor 1")
        return value == "1"

    def enabled(self, value: str, line: int) -> None:
        if not self.flag("Enabled", value, line):
            raise self.fail(line, "a disabled variable (Enabled=0)",
                            "enable it, or remove it and its rules")

    def output_entry(self, key: str, value: str, line: int) -> None:
        if key == "Name":
            self.result.output_name, self.result.output_line = value.strip("'"), line
        elif key.startswith("MF"):
            self.mf_key(key, len(self.result.commands), line)
            name, kind, params = self.mf(value, line)
            if kind in ("trimf", "trapmf", "rampmf") or shapes.read(shapes.MATLAB, kind,
                                                                     params):
                constant = self.mamdani_set(name, kind, params, line)
            else:
                try:  # a refusal is reported with the file's others
                    constant, linear = output_constant(kind, params, len(self.result.inputs),
                                                       self.file, line, name,
                                                       self.linear_singletons)
                except ExportError as error:
                    constant, linear = self.result.put_off(error, 0.0), None
                self.result.commands.append(ImportedCommand(name, constant, line, linear))
                return
            self.result.commands.append(ImportedCommand(name, constant, line))
        elif key == "NumMFs":
            self.output_mfs = (self.count(value, line, key), line)
        elif key in ("LockPrevious", "LockRange"):
            # fuzzylite's extensions; neither matters when every state fires a rule
            self.flag(key, value, line)
        elif key == "Default":
            if value.lower() != "nan":
                parse_number(value, self.file, line, key)
        elif key == "Enabled":
            self.enabled(value, line)
        elif key == "Range":
            values = self.vector(value, line, "Range")
            if len(values) != 2 or not values[0] < values[1]:
                raise self.fail(line, f"Range {excerpt(value)} is not [low high] with low "
                                "below high", "write Range=[low high]")
            self.output_range = (values[0], values[1])
        else:
            raise self.fail(line, f"'{key}' in the output section",
                            "remove the line: an output section holds Name, Range, NumMFs "
                            "and MFk")

    def mamdani_set(self, name: str, kind: str, params: list[float], line: int) -> float:
        """A Mamdani output set, refused unless converting: then its centroid."""
        if not self.mamdani_singletons:
            if self.mamdani:
                return 0.0  # the Type='mamdani' refusal names the system (check_system)
            raise self.fail(line, f"output term '{name}' is a {kind}, a Mamdani output set: "
                            "flctool's commands are singletons", MAMDANI_HINT)
        found = shapes.read(shapes.MATLAB, kind, params)
        if found is not None:
            row = set_row(shaped_set(name, found[0], found[1], self.file, line).shape_value())
            self.output_sets[name] = row
            return 0.0  # the centroid, once the output range is known (mamdani_output)
        if kind == "rampmf":  # fuzzylite's shoulder, to the output range's end
            if len(params) != 2:
                raise self.fail(line, "a rampmf takes 2 parameters", "give it start and end")
            ramp = fuzzylite_quad("Ramp", params, self.file, line)
            self.output_sets[name] = (0, ramp)
            return 0.0  # the centroid, once the output range is known (mamdani_output)
        n = 3 if kind == "trimf" else 4
        if len(params) != n or any(b < a for a, b in itertools.pairwise(params)):
            raise self.fail(line, f"a {kind} takes {n} increasing parameters",
                            f"give it {n} numbers in increasing order")
        quad = ((params[0], params[1], params[1], params[2]) if n == 3
                else (params[0], params[1], params[2], params[3]))
        self.output_sets[name] = (0, quad)
        return centroid(quad)

    def mamdani_output(self) -> MamdaniOutput:
        """The Mamdani output as read (its sets under their behaviour-file names)."""
        implication = {"min": "Minimum", "prod": "AlgebraicProduct"}
        aggregation = {"max": "Maximum", "probor": "AlgebraicSum"}
        lo, hi = self.output_range
        # a shoulder's infinite foot (rampmf): the centroid integrates over the range only
        sets = {identifier(name): (code, row) if code else (0, (
            max(row[0], lo), max(row[1], lo), min(row[2], hi), min(row[3], hi)))
            for name, (code, row) in self.output_sets.items()}
        return MamdaniOutput(
            sets, self.output_range, CENTROID_RESOLUTION,
            implication[self.system.get("ImpMethod", ("min", 1))[0].lower()],
            aggregation[self.system.get("AggMethod", ("max", 1))[0].lower()])

    def mf(self, value: str, line: int) -> tuple[str, str, list[float]]:
        match = _MF.fullmatch(value)
        if match is None:
            raise self.fail(line, f"'{excerpt(value)}' is not 'name':'type',[parameters]")
        return match.group(1), match.group(2), self.vector(f"[{match.group(3)}]", line, "MF")

    def vector(self, value: str, line: int, what: str) -> list[float]:
        inner = value.strip()
        if not (inner.startswith("[") and inner.endswith("]")):
            raise self.fail(line, f"{what} '{value}' is not a [vector]")
        return [parse_number(p, self.file, line, what)
                for p in re.split(r"[\s,]+", inner[1:-1].strip()) if p]

    @property
    def mamdani(self) -> bool:
        return self.system.get("Type", ("", 1))[0].lower() == "mamdani"

    def check_system(self) -> None:
        kind, line = self.system.get("Type", ("", 1))
        if kind.lower() == "mamdani" and self.mamdani_singletons:
            self.check_mamdani(line)
            return
        if kind.lower() == "mamdani":  # reported with the rules' refusals
            self.result.pending.append(self.fail(
                line, f"Type='{kind}': flctool reads Sugeno systems with constant outputs; "
                "Mamdani output sets that are not singletons cannot be expressed exactly",
                MAMDANI_HINT))
            return
        if kind.lower() != "sugeno":
            raise self.fail(line, f"Type='{kind}': flctool reads Sugeno systems with constant "
                            "outputs; Mamdani output sets that are not singletons cannot be "
                            "expressed", MAMDANI_HINT if kind.lower() == "mamdani" else "")
        if self.output_sets:
            raise self.fail(line, "Type='sugeno' with trimf / trapmf output sets",
                            "give a Sugeno system constant outputs, or declare it mamdani")
        outputs, line = self.system.get("NumOutputs", ("1", 1))
        if outputs != "1":
            raise self.fail(line, f"NumOutputs={outputs}: flctool controllers have one output")
        method, line = self.system.get("DefuzzMethod", ("wtaver", 1))
        if method != "wtaver":
            raise self.fail(line, f"DefuzzMethod='{method}': flctool's output is the weighted "
                            "average (eq. 3)", "use DefuzzMethod='wtaver'")

    def check_mamdani(self, line: int) -> None:
        """The Mamdani settings that the conversion's measurement computes."""
        expected = {"ImpMethod": ("min", "prod"), "AggMethod": ("max", "probor"),
                    "DefuzzMethod": ("centroid",), "NumOutputs": ("1",)}
        found = []  # each reported with the file's other refusals (build_behaviour)
        for key, allowed in expected.items():
            value, at = self.system.get(key, (allowed[0], line))
            if value.lower() not in allowed:
                found.append(self.fail(at, f"{key}='{value}': the conversion of a Mamdani "
                                       f"system measures its error against {key}="
                                       f"{' or '.join(repr(a) for a in allowed)}",
                                       f"use {key}='{allowed[0]}' (or convert the system by "
                                       "hand)"))
        if len(self.output_sets) != len(self.result.commands):
            found.append(self.fail(line, "a Mamdani system with constant or linear output MFs",
                                   "make every output MF a set (trimf, trapmf, gaussmf, ...)"))
        if found:
            self.result.pending += found
            return
        # the singletons of other shapes are their centroids over the output range
        for command in self.result.commands:
            command.value = self.mamdani_output().singleton(identifier(command.name))

    def check_counts(self) -> None:
        """NumInputs, NumMFs and NumRules must count what the file holds."""
        declared = [("NumInputs", len(self.result.inputs), "input sections"),
                    ("NumRules", len(self.rule_lines), "rules")]
        for key, present, what in declared:
            if key in self.system:
                value, line = self.system[key]
                if self.count(value, line, key) != present:
                    raise self.fail(line, f"{key}={value}, but the file has {present} {what}",
                                    f"set {key}={present}")
        sections = [(f"[Input{k}]", len(v.sets), mfs) for k, (v, mfs) in
                    enumerate(zip(self.result.inputs, self.declared_mfs, strict=True), start=1)]
        sections.append(("[Output1]", len(self.result.commands), self.output_mfs))
        for section, present, mfs in sections:
            if mfs is not None and mfs[0] != present:
                raise self.fail(mfs[1], f"NumMFs={mfs[0]}, but {section} has {present} MFs",
                                f"set NumMFs={present}")

    def methods(self) -> None:
        method, line = self.system.get("AndMethod", ("min", 1))
        if method != "min":
            self.result.conjunction = Method(f"AndMethod='{method}'", line,
                                             "use AndMethod='min' or 'prod'",
                                             product=method == "prod")
        method, line = self.system.get("AggMethod", ("sum", 1))
        if method != "sum" and not self.mamdani:  # Mamdani: part of what is measured
            self.result.accumulation = Method(f"AggMethod='{method}'", line,
                                              "use AggMethod='sum'")

    def split_rule(self, text: str, line: int) -> tuple[list[str], list[str], str, str]:
        """``sets, outputs (weight) : connection`` as its four parts; MATLAB also writes
        rules without the comma, the output indices after the inputs'."""
        head, colon, connection = text.rpartition(":")
        opening, closing = head.find("("), head.rfind(")")
        connection = connection.strip()
        if (not colon or opening < 0 or closing < opening or head[closing + 1:].strip()
                or connection not in ("1", "2")):
            raise self.fail(line, f"rule '{excerpt(text)}' is not 'sets, command (weight) : "
                            "connection'", "write e.g. 1 2, 1 (1) : 1")
        indices, comma, outputs = head[:opening].partition(",")
        if comma:
            return indices.split(), outputs.split(), head[opening + 1:closing], connection
        words = indices.split()
        n = len(self.result.inputs)
        return words[:n], words[n:], head[opening + 1:closing], connection

    def rule(self, text: str, line: int) -> ImportedRule:
        sets, outputs, weight_text, connection = self.split_rule(text, line)
        # a weight other than 1 is refused unless a Mamdani output is converted (imported.py)
        weight = parse_number(weight_text.strip(), self.file, line, "rule weight")
        if len(sets) != len(self.result.inputs) or len(outputs) != 1:
            raise self.fail(line, f"the rule has {len(sets)} input and {len(outputs)} output "
                            f"indices; the system has {len(self.result.inputs)} inputs and 1 "
                            "output")
        antecedent: dict[str, str] = {}
        negated = set()  # NOT (a negative index): refused unless converting (imported.py)
        for variable, index in zip(self.result.inputs, sets, strict=True):
            k = self.index(index, line, f"input '{variable.name}'")
            if k == 0:  # an input left out: build_behaviour refuses it, as in every format
                continue
            if k < 0:
                negated.add(variable.name)
            if abs(k) > len(variable.sets):
                raise self.fail(line, f"input '{variable.name}' has no MF{abs(k)}")
            antecedent[variable.name] = variable.sets[abs(k) - 1].name
        k = self.index(outputs[0], line, "the output")
        if not 1 <= k <= len(self.result.commands):
            raise self.fail(line, f"the output has no MF{k}" if k > 0 else
                            "the rule gives no (or a negated) output MF")
        command = self.result.commands[k - 1].name
        if connection != "1" and len(antecedent) > 1:  # OR: imported.py refuses it unless
            return ImportedRule({}, command, line, text, list(antecedent.items()),  # converting
                                weight, negated)
        return ImportedRule(antecedent, command, line, text, weight=weight, negated=negated)

    def index(self, text: str, line: int, what: str) -> int:
        if len(text) > MAX_DIGITS + 3:
            raise self.fail(line, f"the index of {what} has {len(text)} characters",
                            "write the MF's number, 1, 2, ...")
        value = parse_number(text, self.file, line, what)
        if value != int(value):
            raise self.fail(line, f"the index {text} of {what} is not a whole number "
                            "(a hedge)")
        return int(value)
