"""C: a dependency-free C99 header and source computing eq. 1-3, ready for a robot.

``-o NAME`` (or ``NAME.c`` / ``NAME.h``) writes ``NAME.h`` and ``NAME.c``; the source includes
the header by its file name. Without a file the export is one self-contained translation
unit (header, then source) on stdout. The tables are ``static const`` data; the one public
function is ``<prefix>output(const double state[N])`` (``float`` with ``single``); a behaviour
that acts by vote (``environment.action: vote``) gets the vote as ``<prefix>command``. No heap, no
libm: clipping is two comparisons, and the arithmetic is exactly flctool's (membership as in
flctool/membership.py, minimum activation (or the product, in input order, with
``activation: product``), sums over the rules in rule order).
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from flctool.behaviour import Behaviour, require_deployable
from flctool.behaviour.base import identifier
from flctool.behaviour.checks import uncovered_gap
from flctool.behaviour.shapes import evaluated_range, is_trapezoid, set_row, trapezoids
from flctool.errors import ExportError
from flctool.export.base import Exporter, header_lines, number
from flctool.export.float_error import check_float_error

_PREFIX = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")
FLOAT_MAX = float(np.finfo(np.float32).max)


class CExporter(Exporter):
    format = "c"

    def to_string(self, behaviour: Behaviour) -> str:
        """One translation unit: the header followed by the source."""
        return self.header(behaviour) + "\n" + self.source(behaviour, include=None)

    def texts(self, behaviour: Behaviour, path: Path) -> dict[Path, str]:
        stem = path.with_suffix("") if path.suffix in (".c", ".h") else path
        header = stem.with_name(stem.name + ".h")
        source = stem.with_name(stem.name + ".c")
        return {header: self.header(behaviour),
                source: self.source(behaviour, include=header.name)}

    # -- pieces ----------------------------------------------------------------------------
    @property
    def real(self) -> str:
        return "float" if self.options.single else "double"

    def literal(self, value: float) -> str:
        if not self.options.single:
            return number(value)
        # The shortest text of the float nearest to the value; the f suffix keeps it a float.
        return f"{np.float32(_single(value))!s}f"

    def check_float_coverage(self, behaviour: Behaviour) -> None:
        """Sets that cover a range in double may leave a gap once rounded to float (a ramp's
        end and the next ramp's start rounding to the same float): refuse that export."""
        for name, variable in behaviour.inputs.items():
            rounded = variable.model_copy(update={
                "range": tuple(_single(v) for v in
                               evaluated_range(variable.range, variable.sets.values())),
                "sets": {s: tuple(_single(v) for v in q) for s, q in
                         zip(variable.sets, trapezoids(variable.sets.values()), strict=True)}})
            gap = uncovered_gap(rounded)
            if gap is not None:
                a, b = gap
                where = f"at {a!r}" if a == b else f"between {a!r} and {b!r}"
                raise ExportError(
                    f"input '{name}': rounded to float, its sets leave a gap {where} where "
                    "no set fires, so the float controller would have no output there",
                    hint="export without --float, or widen the sets so that neighbours "
                    "overlap by more than float rounding")

    def names(self) -> tuple[str, str]:
        prefix = self.options.prefix
        if not _PREFIX.match(prefix):
            raise ExportError(f"the prefix '{prefix}' cannot start a C identifier",
                              hint="use letters, digits and _, e.g. --prefix ballchase_")
        return prefix, prefix.upper()

    def header(self, behaviour: Behaviour) -> str:
        require_deployable(behaviour)
        prefix, macro = self.names()
        real = self.real
        guard = f"{macro}{identifier(behaviour.name).upper()}_H"
        enums = [f"{macro}IN_{name.upper()}" for name in behaviour.inputs]
        if len(set(enums)) != len(enums):
            raise ExportError("two inputs differ only in case, so their C names collide",
                              hint="rename one of them in the behaviour file")
        commands = [f"{macro}CMD_{name.upper()}" for name in behaviour.output.commands]
        if len(set(commands)) != len(commands):
            raise ExportError("two commands differ only in case, so their C names collide",
                              hint="rename one of them in the behaviour file")
        values = list(behaviour.output.commands.values())
        accuracy = []
        shaped = _shaped_sets(behaviour)
        if shaped and self.options.single:
            raise ExportError(
                f"set '{shaped[0]}' is a {shaped[1]}: the float export's error is measured for "
                "trapezoids only", hint="export without --float (double arithmetic)")
        if self.options.single:
            error, bound, count = check_float_error(behaviour)
            accuracy = [f" * float: the largest difference from flctool's (64-bit) output, "
                        f"measured at export on {count} states", " * (half uniform in the "
                        "ranges, half on a grid over every range, its ends and every set",
                        f" * corner), is {error:.3g}; the documented bound is {bound:.3g}."]
        about = header_lines(behaviour, self.options.provenance)
        lines = ["/*", *(f" * {line}" for line in about), " *",
                 f" * A fuzzy logic controller: {len(behaviour.inputs)} inputs, "
                 f"{behaviour.rule_count} rules, {len(behaviour.output.commands)} commands"
                 + (", each rule's memberships multiplied (activation: product)."
                    if behaviour.activation == "product" else "."),
                 " * C99, no heap, " + (f"libm's {' and '.join(shaped[2])} (link "
                                     "with -lm: the sets include "
                                     f"a {shaped[1]})." if shaped else "no libm.")
                 + " The state holds the inputs in this order; a value outside",
                 " * its range is clipped to it. A NaN input gives a NaN output, and so does an "
                 "input",
                 " * at which no set fires (which flctool's checks rule out):"]
        for i, (name, variable) in enumerate(behaviour.inputs.items()):
            unit = f" {variable.unit}" if variable.unit else ""
            lines.append(f" *   state[{i}] {name} in [{number(variable.range[0])}, "
                         f"{number(variable.range[1])}]{unit}")
        unit = f" ({behaviour.output.unit})" if behaviour.output.unit else ""
        lines += [f" * The output is {behaviour.output.name}{unit}, within [{macro}OUTPUT_MIN, "
                  f"{macro}OUTPUT_MAX]. The source", " * refuses to compile with -ffast-math: "
                  "it would reorder the sums and drop the NaN checks.", *accuracy, " */",
                  f"#ifndef {guard}", f"#define {guard}", "",
                  f"#define {macro}N_INPUTS {len(behaviour.inputs)}",
                  f"#define {macro}N_COMMANDS {len(values)}",
                  "/* The smallest and largest singleton: the output never leaves them. */",
                  f"#define {macro}OUTPUT_MIN ({self.literal(min(values))})",
                  f"#define {macro}OUTPUT_MAX ({self.literal(max(values))})", "",
                  "/* The inputs' places in the state. */",
                  "enum {", *(f"    {e} = {i}," for i, e in enumerate(enums)), "};", "",
                  "/* The commands' indices, as <prefix>command returns them, with their "
                  "singletons. */",
                  "enum {", *(f"    {e} = {k}, /* {self.literal(v)} */"
                              for k, (e, v) in enumerate(zip(commands, values, strict=True))),
                  "};", "",
                  "#ifdef __cplusplus", 'extern "C" {', "#endif", "",
                  "/* The controller's output for one state (paper eq. 1-3). */",
                  f"{real} {prefix}output(const {real} state[{macro}N_INPUTS]);", "",
                  *(["/* The command this behaviour acts by (environment.action: vote): "
                     "each command's firing",
                     "   rules sum their activations, the largest sum wins (of equal ones, "
                     "the command",
                     "   listed first), as flctool acts; -1 for a NaN input. It is not the "
                     "command nearest",
                     "   <prefix>output. */"] if behaviour.acts_by_vote else
                   ["/* The index of the command whose singleton is nearest that output (of "
                    "two equally",
                    "   near ones, the smaller singleton), as flctool's 'nearest' action picks "
                    "it; -1 for a NaN output. */"]),
                  f"int {prefix}command(const {real} state[{macro}N_INPUTS]);", "",
                  "/* Both from one inference: writes " + (
                      "the command's singleton (NaN for a NaN input)" if behaviour.acts_by_vote
                      else "the output (as <prefix>output gives it)") + " to *output",
                  "   and returns the command (as <prefix>command does). */",
                  f"int {prefix}decide(const {real} state[{macro}N_INPUTS], {real} *output);",
                  "",
                  "#ifdef __cplusplus", "}", "#endif", "", f"#endif /* {guard} */"]
        return "\n".join(lines) + "\n"

    def source(self, behaviour: Behaviour, include: str | None) -> str:
        if self.options.single:
            self.check_float_coverage(behaviour)
        prefix, macro = self.names()
        real = self.real
        lit = self.literal
        variables = list(behaviour.inputs.values())
        rows = [set_row(q) for v in variables for q in v.sets.values()]
        quads = [q for _, q in rows]
        kinds = [k for k, _ in rows]
        shaped = any(kinds)
        first = [0]
        for variable in variables:
            first.append(first[-1] + len(variable.sets))
        commands = tuple(behaviour.output.commands)
        index = {tuple(r.if_[n] for n in behaviour.input_names): commands.index(r.then)
                 for r in behaviour.rules}
        consequents = [index[a] for a in behaviour.antecedents()]
        k = len(commands)
        ctype = ("unsigned char" if k <= 256 else "unsigned short" if k <= 65536
                 else "unsigned int")
        lines = [f'#include "{include}"', ""] if include else []
        if shaped:
            lines += ["#include <math.h>", ""]
        lines += ["#if defined(__FAST_MATH__)",
                  '#error "compile without -ffast-math: it reorders the sums of eq. 3 and '
                  'removes the NaN checks"', "#endif", ""]
        lines += [
            f"#define {macro}N_SETS {first[-1]}",
            f"#define {macro}N_RULES {behaviour.rule_count}L", "",
            "/* Each input's [low, high], moved inside an end that no set fires (as flctool",
            "   evaluates it there). */",
            f"static const {real} {prefix}ranges[{macro}N_INPUTS][2] = {{",
            *(f"    {{{lit(lo)}, {lit(hi)}}}," for lo, hi in
              (evaluated_range(v.range, v.sets.values()) for v in variables)), "};", "",
            "/* Every input's sets as (pa, pb, pc, pd) (paper Sec. II); the sets of input i are",
            f"   {prefix}first_set[i] to {prefix}first_set[i + 1] - 1."
            + (f" A set whose {prefix}shapes entry is not 0 holds that shape's parameters"
               if shaped else " */"),
            *([f"   instead (see {prefix}shaped). */"] if shaped else []),
            f"static const {real} {prefix}sets[{macro}N_SETS][4] = {{",
            *(f"    {{{', '.join(lit(x) for x in q)}}}," for q in quads), "};",
            *([f"static const unsigned char {prefix}shapes[{macro}N_SETS] = {{",
               *_wrapped([str(k) for k in kinds]), "};"] if shaped else []),
            f"static const long {prefix}first_set[{macro}N_INPUTS + 1] = "
            f"{{{', '.join(map(str, first))}}};", "",
            "/* The commands' singletons c^k. */",
            f"static const {real} {prefix}singletons[{k}] = "
            f"{{{', '.join(lit(v) for v in behaviour.output.commands.values())}}};",
            "/* The smallest and largest singleton: the output never leaves them. */",
            f"static const {real} {prefix}lowest = "
            f"{lit(min(behaviour.output.commands.values()))};",
            f"static const {real} {prefix}highest = "
            f"{lit(max(behaviour.output.commands.values()))};", "",
            "/* The command of each rule, in rule order: the last input varies fastest (eq. 1). */",
            f"static const {ctype} {prefix}consequents[{macro}N_RULES] = {{",
            *_wrapped([str(c) for c in consequents]), "};", "",
            *(_shape_functions(prefix, real) if shaped else []),
            *_functions(prefix, macro, real, shaped, behaviour.activation == "product",
                        behaviour.acts_by_vote),
        ]
        return "\n".join(lines) + "\n"


def _single(value: float) -> float:
    """``value`` rounded to the nearest float, or an ExportError if it does not fit."""
    if abs(value) > FLOAT_MAX:
        raise ExportError(f"{value!r} does not fit in a float", hint="export without --float")
    return float(np.float32(value))


def _wrapped(items: list[str], width: int = 96) -> list[str]:
    lines, line = [], "   "
    for item in items:
        if len(line) + len(item) + 2 > width:
            lines.append(line)
            line = "   "
        line += f" {item},"
    return [*lines, line]


def _shaped_sets(behaviour: Behaviour) -> tuple[str, str, list[str]] | None:
    """The first set of a shape other than the trapezoid (its name and shape), and the libm
    functions the sets use (exp; pow for a bell, cos for a cosine); None if every set is a
    trapezoid."""
    found = [(name, value.kind) for v in behaviour.inputs.values()
             for name, value in v.sets.items() if not is_trapezoid(value)]
    if not found:
        return None
    kinds = {kind for _, kind in found}
    functions = ["exp", *(["pow"] if "bell" in kinds else []),
                 *(["cos"] if "cosine" in kinds else [])]
    return found[0][0], found[0][1], functions


def _shape_functions(prefix: str, real: str) -> list[str]:
    """The shapes of flctool.behaviour.shapes, coded as flctool/membership.py codes them
    (``exp``, ``pow`` and ``cos`` are libm's, as Python's and numba's are)."""
    return f"""\
static {real} {prefix}sigmoid({real} x, {real} c, {real} a)
{{
    return 1.0 / (1.0 + exp(-a * (x - c)));
}}

static {real} {prefix}gauss({real} x, {real} m, {real} s)
{{
    return exp(-((x - m) * (x - m)) / (2.0 * s * s));
}}

static {real} {prefix}s_shape({real} x, {real} a, {real} b)
{{
    {real} t;
    if (x <= a) return 0.0;
    if (x <= (a + b) / 2.0) {{
        t = (x - a) / (b - a);
        return 2.0 * t * t;
    }}
    if (x < b) {{
        t = (x - b) / (b - a);
        return 1.0 - 2.0 * t * t;
    }}
    return 1.0;
}}

static {real} {prefix}z_shape({real} x, {real} a, {real} b)
{{
    {real} t;
    if (x <= a) return 1.0;
    if (x <= (a + b) / 2.0) {{
        t = (x - a) / (b - a);
        return 1.0 - 2.0 * t * t;
    }}
    if (x < b) {{
        t = (x - b) / (b - a);
        return 2.0 * t * t;
    }}
    return 0.0;
}}

/* The membership of x in a set of shape `kind` with parameters p: 1 gauss, 2 gauss2, 3 bell,
   4 sigmoid, 5 sigmoid_difference, 6 sigmoid_product, 7 s_shape, 8 z_shape, 9 pi_shape,
   10 cosine, 11 concave, 12 spike (fuzzylite's formulas). */
static {real} {prefix}shaped(int kind, {real} x, const {real} p[4])
{{
    {real} left, right;
    switch (kind) {{
    case 1: return {prefix}gauss(x, p[0], p[1]);
    case 2:
        left = x < p[0] ? {prefix}gauss(x, p[0], p[1]) : 1.0;
        right = x > p[2] ? {prefix}gauss(x, p[2], p[3]) : 1.0;
        return left * right;
    case 3: return 1.0 / (1.0 + pow(fabs((x - p[2]) / p[0]), 2.0 * p[1]));
    case 4: return {prefix}sigmoid(x, p[0], p[1]);
    case 5: return fabs({prefix}sigmoid(x, p[0], p[1]) - {prefix}sigmoid(x, p[2], p[3]));
    case 6: return {prefix}sigmoid(x, p[0], p[1]) * {prefix}sigmoid(x, p[2], p[3]);
    case 7: return {prefix}s_shape(x, p[0], p[1]);
    case 8: return {prefix}z_shape(x, p[0], p[1]);
    case 9: return {prefix}s_shape(x, p[0], p[1]) * {prefix}z_shape(x, p[2], p[3]);
    case 10:
        if (x < p[0] - 0.5 * p[1] || x > p[0] + 0.5 * p[1]) return 0.0;
        return 0.5 * (1.0 + cos(2.0 / p[1] * 3.141592653589793 * (x - p[0])));
    case 11:
        if (p[0] <= p[1]) {{
            if (x < p[1]) return (p[1] - p[0]) / (2.0 * p[1] - p[0] - x);
        }} else if (x > p[1]) {{
            return (p[0] - p[1]) / (p[0] - 2.0 * p[1] + x);
        }}
        return 1.0;
    default: return exp(-fabs(10.0 / p[1] * (x - p[0])));
    }}
}}
""".splitlines()


def _functions(prefix: str, macro: str, real: str, shaped: bool = False,
               product: bool = False, vote: bool = False) -> list[str]:
    zero, one = ("0.0f", "1.0f") if real == "float" else ("0.0", "1.0")
    # eq. 2, input after input from alpha = 1: the minimum, or (activation: product) the
    # product multiplied in input order, as flctool's inference folds it
    combine = ("alpha *= mu[j]; /* eq. 2: product, in input order */" if product
               else "if (i == 0 || mu[j] < alpha) alpha = mu[j]; /* eq. 2: minimum */")
    membership = (f"{prefix}shapes[j] ? {prefix}shaped({prefix}shapes[j], s, {prefix}sets[j])"
                  f"\n                          : {prefix}membership(s, {prefix}sets[j])"
                  if shaped else f"{prefix}membership(s, {prefix}sets[j])")
    return f"""\
/* Trapezoid membership (paper Sec. II), written as flctool computes it: a vertical edge
   (pa == pb or pc == pd) jumps without dividing by zero. */
static {real} {prefix}membership({real} s, const {real} q[4])
{{
    {real} mu;
    if (s > q[2]) {{
        if (!(q[3] > q[2])) return {zero};
        mu = (q[3] - s) / (q[3] - q[2]);
        return mu > {zero} ? mu : {zero};
    }}
    if (s < q[1]) {{
        if (!(q[1] > q[0])) return {zero};
        mu = (s - q[0]) / (q[1] - q[0]);
        return mu > {zero} ? mu : {zero};
    }}
    return {one};
}}

/* eq. 1-3 for one state; with votes (zeroed, one per command), each firing rule's
   activation is added to its command's, in rule order. */
static {real} {prefix}infer(const {real} state[{macro}N_INPUTS], {real} *votes)
{{
    {real} mu[{macro}N_SETS];
    long active[{macro}N_SETS]; /* input i's sets with mu > 0 start at active[first_set[i]] */
    long count[{macro}N_INPUTS];
    long pick[{macro}N_INPUTS];
    {real} weighted = {zero}, total = {zero};
    long i, j;

    for (i = 0; i < {macro}N_INPUTS; ++i) {{
        {real} s = state[i];
        if (s != s) return s; /* NaN has no membership */
        if (s < {prefix}ranges[i][0]) s = {prefix}ranges[i][0];
        else if (s > {prefix}ranges[i][1]) s = {prefix}ranges[i][1];
        count[i] = 0;
        pick[i] = 0;
        for (j = {prefix}first_set[i]; j < {prefix}first_set[i + 1]; ++j) {{
            mu[j] = {membership};
            if (mu[j] > {zero}) active[{prefix}first_set[i] + count[i]++] = j;
        }}
        /* flctool checked that the sets cover the range, so some set fires; should
           rounding leave none, say so with NaN rather than read unset memory. */
        if (count[i] == 0) return {zero} / {zero};
    }}

    /* Only the rules whose sets are all active fire. An odometer over each input's active
       sets, the last input turning fastest, visits them in increasing rule index m, so the
       sums below add the rules in rule order. */
    for (;;) {{
        long m = 0;
        {real} alpha = {one};
        for (i = 0; i < {macro}N_INPUTS; ++i) {{
            j = active[{prefix}first_set[i] + pick[i]];
            m = m * ({prefix}first_set[i + 1] - {prefix}first_set[i])
                + (j - {prefix}first_set[i]);
            {combine}
        }}
        weighted += alpha * {prefix}singletons[{prefix}consequents[m]]; /* eq. 3 */
        total += alpha;
        if (votes) votes[{prefix}consequents[m]] += alpha;
        for (i = {macro}N_INPUTS - 1; i >= 0; --i) {{
            if (++pick[i] < count[i]) break;
            pick[i] = 0;
        }}
        if (i < 0) break;
    }}
    weighted /= total;
    /* eq. 3 is a convex combination; rounding may step an ulp past the singletons */
    if (weighted < {prefix}lowest) return {prefix}lowest;
    if (weighted > {prefix}highest) return {prefix}highest;
    return weighted;
}}

{real} {prefix}output(const {real} state[{macro}N_INPUTS])
{{
    return {prefix}infer(state, 0);
}}
""".splitlines() + (_vote_functions(prefix, macro, real, zero) if vote else
                    _nearest_functions(prefix, macro, real, zero))


def _nearest_functions(prefix: str, macro: str, real: str, zero: str) -> list[str]:
    """``command`` and ``decide`` for the crisp and nearest actions."""
    return f"""\
/* The command nearest an output (see the header). */
static int {prefix}nearest({real} out)
{{
    {real} gap = {zero}, d;
    int best = -1, k;
    if (out != out) return -1;
    for (k = 0; k < (int)(sizeof {prefix}singletons / sizeof {prefix}singletons[0]); ++k) {{
        d = out - {prefix}singletons[k];
        if (d < {zero}) d = -d;
        /* on a tie, the smaller singleton, as flctool's gymnasium adapter picks */
        if (best < 0 || d < gap
            || (d == gap && {prefix}singletons[k] < {prefix}singletons[best])) {{
            best = k;
            gap = d;
        }}
    }}
    return best;
}}

int {prefix}command(const {real} state[{macro}N_INPUTS])
{{
    return {prefix}nearest({prefix}output(state));
}}

int {prefix}decide(const {real} state[{macro}N_INPUTS], {real} *output)
{{
    *output = {prefix}output(state);
    return {prefix}nearest(*output);
}}""".splitlines()


def _vote_functions(prefix: str, macro: str, real: str, zero: str) -> list[str]:
    """``command`` and ``decide`` for a behaviour that acts by vote (see the header)."""
    return f"""\
/* The vote (see the header): the command, or -1 for a NaN input; *output is eq. 3's. */
static int {prefix}vote(const {real} state[{macro}N_INPUTS], {real} *output)
{{
    {real} votes[{macro}N_COMMANDS];
    int best = 0, k;
    for (k = 0; k < {macro}N_COMMANDS; ++k) votes[k] = {zero};
    *output = {prefix}infer(state, votes);
    if (*output != *output) return -1;
    for (k = 1; k < {macro}N_COMMANDS; ++k)
        if (votes[k] > votes[best]) best = k; /* of equal sums, the command listed first */
    return best;
}}

int {prefix}command(const {real} state[{macro}N_INPUTS])
{{
    {real} output;
    return {prefix}vote(state, &output);
}}

int {prefix}decide(const {real} state[{macro}N_INPUTS], {real} *output)
{{
    int command = {prefix}vote(state, output);
    if (command >= 0) *output = {prefix}singletons[command];
    return command;
}}""".splitlines()
