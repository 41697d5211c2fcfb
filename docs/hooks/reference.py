"""Generated reference pages of the documentation site (an mkdocs hook, see mkdocs.yml).

Three pages are written at build time, never committed, so they cannot drift from the code:

* ``reference/behaviour-file.md`` from the committed JSON Schema
  (``schemas/behaviour.schema.json``, which CI checks against the models);
* ``reference/cli.md`` from the typer app (every command, argument and option);
* ``reference/learners.md``: every ``learning:`` key from the schema next to the paper's
  equation it sets (``EQUATIONS`` below; tests/test_docs.py checks every key has one).

The functions take plain data (the schema dict, the click command) so the tests call them too.
"""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[2]
SCHEMA = ROOT / "schemas" / "behaviour.schema.json"

#: generated page (path under docs/) -> the function that writes it
GENERATED = ("reference/behaviour-file.md", "reference/cli.md", "reference/learners.md")


# -- the behaviour file, from the JSON Schema -------------------------------------------------
def _def_name(ref: str) -> str:
    return ref.rsplit("/", 1)[-1]


def _anchor(name: str) -> str:
    return f"def-{name.lower()}"


def _type(prop: dict[str, Any]) -> str:
    """A short markdown rendering of a schema node's type, linking to its definition."""
    if "$ref" in prop:
        name = _def_name(prop["$ref"])
        return f"[{name}](#{_anchor(name)})"
    if "const" in prop:
        return f"`{json.dumps(prop['const'])}`"
    if "enum" in prop:
        return " | ".join(f"`{json.dumps(v)}`" for v in prop["enum"])
    if "oneOf" in prop or "anyOf" in prop:
        options = prop.get("oneOf") or prop["anyOf"]
        return " or ".join(_type(option) for option in options)
    kind = prop.get("type")
    if kind == "array":
        if "prefixItems" in prop:
            return "[" + ", ".join(_type(item) for item in prop["prefixItems"]) + "]"
        return f"list of {_type(prop.get('items', {}))}"
    if kind == "object":
        values = prop.get("patternProperties")
        if values:
            (_pattern, value), = values.items()
            return f"map name → {_type(value)}"
        extra = prop.get("additionalProperties")
        if isinstance(extra, dict):
            return f"map string → {_type(extra)}"
        return "object"
    if kind == "null":
        return "null"
    return str(kind) if kind else "any"


_CONSTRAINTS = (("minimum", "≥ {}"), ("exclusiveMinimum", "> {}"), ("maximum", "≤ {}"),
                ("exclusiveMaximum", "< {}"), ("minItems", "at least {} items"),
                ("maxItems", "at most {} items"), ("minProperties", "at least {} entries"),
                ("minLength", "at least {} characters"), ("maxLength", "at most {} characters"))


def _constraints(prop: dict[str, Any]) -> list[str]:
    found = []
    nodes = [prop, *prop.get("anyOf", [])]
    for node in nodes:
        if node.get("type") == "array" and node.get("minItems") == node.get("maxItems"):
            continue  # a fixed-length tuple: its type already shows the length
        for key, text in _CONSTRAINTS:
            if key == "minProperties" and node.get(key) == 1:
                found.append("not empty")
            elif key in node:
                found.append(text.format(_number(node[key])))
        if "pattern" in node and node["pattern"] != "^[A-Za-z_][A-Za-z0-9_]*$":
            found.append(f"matches `{node['pattern']}`")
        elif "pattern" in node:
            found.append("an identifier")
    return found


def _number(value: Any) -> str:
    return f"{value:g}" if isinstance(value, float) else str(value)


def _default(prop: dict[str, Any], required: bool) -> str:
    if required:
        return "**required**"
    if "default" not in prop:
        return ""
    value = prop["default"]
    if isinstance(value, dict) and value and "$ref" in prop:
        return "see below"
    text = json.dumps(value, ensure_ascii=False)
    return f"`{text}`" if len(text) <= 40 else "see below"


def _cell(text: str) -> str:
    return text.replace("|", "\\|").replace("\n", " ")


def _table(node: dict[str, Any]) -> list[str]:
    required = set(node.get("required", []))
    lines = ["| key | type | default | description |", "| --- | --- | --- | --- |"]
    for key, prop in node.get("properties", {}).items():
        notes = [prop.get("description", ""), *_constraints(prop)]
        description = "; ".join(n for n in notes if n)
        lines.append(f"| `{key}` | {_cell(_type(prop))} | {_cell(_default(prop, key in required))}"
                     f" | {_cell(description)} |")
    return lines


def _children(node: dict[str, Any]) -> list[tuple[str, dict[str, Any]]]:
    """(path suffix, node) of every sub-node that may hold a reference."""
    found = []
    for key, prop in node.get("properties", {}).items():
        found.append((f".{key}", prop))
    for value in node.get("patternProperties", {}).values():
        found.append((".<name>", value))
    extra = node.get("additionalProperties")
    if isinstance(extra, dict):
        found.append((".<key>", extra))
    if isinstance(node.get("items"), dict):
        found.append(("[]", node["items"]))
    for option in node.get("anyOf", []) + node.get("oneOf", []):
        found.append(("", option))
    return found


def _def_paths(schema: dict[str, Any]) -> dict[str, list[str]]:
    """Definition name -> the YAML paths where it appears, in schema order."""
    paths: dict[str, list[str]] = {}
    stack: list[tuple[str, dict[str, Any]]] = [("", schema)]
    while stack:
        path, node = stack.pop(0)
        if "$ref" in node:
            name = _def_name(node["$ref"])
            seen = name in paths
            paths.setdefault(name, []).append(path.lstrip("."))
            if not seen:
                stack.append((path, schema["$defs"][name]))
            continue
        stack.extend((path + suffix, child) for suffix, child in _children(node))
    return paths


def behaviour_reference(schema: dict[str, Any]) -> str:
    """The behaviour-file reference page: one table per schema object, root first."""
    paths = _def_paths(schema)
    lines = [
        "# Behaviour file reference",
        "",
        "Generated from the JSON Schema `schemas/behaviour.schema.json`, which `flctool schema`",
        "writes from the models and CI checks (`flctool schema --check`); this page is rebuilt",
        "with the site, so it always shows the keys flctool accepts. The format, the fuzzy sets",
        "and the rule order are explained in [Behaviour files](../behaviour-files.md); the",
        "environments in [Environments](../environments.md).",
        "",
        "Every object forbids unknown keys: a typo is an error with its file, line and column.",
        "Names (inputs, sets, the output, commands) are identifiers: a letter or `_`, then",
        "letters, digits or `_`, at most 64 characters.",
        "",
        "## The file",
        "",
        re.sub(r":\w+:`([^`]*)`", r"`\1`", schema.get("description", "")),
        "",
        *_table(schema),
        "",
    ]
    environment = schema["properties"].get("environment", {})
    for section, key in (("learning", "learner"), ("environment", "adapter")):
        chosen = _discriminator_mapping(schema["properties"].get(section, {}))
        if chosen:
            lines += [f"`{section}` is chosen by its `{key}` key:", ""]
            lines += [f"- `{name}`: [{_def_name(ref)}](#{_anchor(_def_name(ref))})"
                      for name, ref in chosen.items()]
            lines.append("")
    for name, where in paths.items():
        node = schema["$defs"][name]
        lines += [f"## {name} {{ #{_anchor(name)} }}", ""]
        shown = sorted(set(where))
        lines += ["Appears at " + ", ".join(f"`{p}`" for p in shown) + ".", ""]
        if node.get("description"):
            lines += [node["description"], ""]
        lines += [*_table(node), ""]
    return "\n".join(lines)


def _discriminator_mapping(section: dict[str, Any]) -> dict[str, str]:
    """Plugin name -> definition reference of a section chosen by name (environment by
    ``adapter``, learning by ``learner``)."""
    for option in section.get("anyOf", [section]):
        mapping = option.get("discriminator", {}).get("mapping")
        if mapping:
            return dict(mapping)
    return {}


# -- the command line, from the typer app ------------------------------------------------------
def _help_markdown(text: str) -> list[str]:
    """Click help text as markdown: ``\\b`` paragraphs and ``$ `` lines become code blocks."""
    lines: list[str] = []
    for paragraph in re.split(r"\n\s*\n", text.strip()):
        rows = paragraph.splitlines()
        if rows and rows[0].strip() == "\b":
            rows = rows[1:]
            verbatim = True
        else:
            verbatim = any(row.lstrip().startswith("$ ") for row in rows)
        example = re.match(r"(Examples?):\s*(flctool\b.*)", " ".join(r.strip() for r in rows),
                           flags=re.DOTALL)
        if example and not verbatim:
            lines += [f"{example[1]}:", "", "```console", f"$ {example[2]}", "```", ""]
            continue
        if verbatim:
            width = min((len(r) - len(r.lstrip()) for r in rows if r.strip()), default=0)
            lines += ["```console", *(r[width:] for r in rows), "```", ""]
        else:
            lines += [" ".join(r.strip() for r in rows), ""]
    return lines


def _param_row(param: Any, context: Any) -> str:
    record = param.get_help_record(context)
    names, help_text = record if record else (param.human_readable_name, "")
    default = "**required**" if param.required else ""
    value = param.default
    unset = value is None or value is False or value in ((), [])
    if not param.required and not unset and not callable(value):
        default = f"`{value}`"
    return f"| `{names}` | {default} | {_cell(help_text or '')} |"


def cli_reference(command: Any) -> str:
    """The CLI reference page of a click group (``typer.main.get_command(app)``)."""
    root = command.context_class(command, info_name="flctool")
    lines = [
        "# Command-line reference",
        "",
        "Generated from the `flctool` command-line application when the site is built, so it",
        "lists exactly the commands and options that `flctool --help` shows.",
        "",
        *_help_markdown(command.help or ""),
        "Global options go before the command: `flctool --debug learn ...`.",
        "",
        *_params(command, root),
    ]
    for name in command.list_commands(root):
        sub = command.get_command(root, name)
        if sub is None or sub.hidden:
            continue
        context = sub.context_class(sub, info_name=name, parent=root)
        usage = " ".join(sub.collect_usage_pieces(context))
        lines += [f"## flctool {name}", "", "```text", f"flctool {name} {usage}", "```", ""]
        lines += _help_markdown(sub.help or "")
        lines += _params(sub, context)
        lines += _help_markdown(sub.epilog or "")  # e.g. the command's examples
    return "\n".join(lines)


def _params(command: Any, context: Any) -> list[str]:
    params = [p for p in command.get_params(context) if not getattr(p, "hidden", False)]
    if not params:
        return []
    lines = ["| argument or option | default | description |", "| --- | --- | --- |"]
    lines += [_param_row(p, context) for p in params]
    return [*lines, ""]


# -- learners and the paper's equations ------------------------------------------------------
#: ``learning:`` key -> the equation or section of the paper it sets (which learners read
#: it comes from the schema)
EQUATIONS: dict[str, str] = {
    "learner": ("Sec. III (fuzzy Q-learning) and IV (GA exploration): which method learns "
                "the consequents"),
    "seed": ("every random choice of the run (initial population, selection, exploration, "
             "episode starts)"),
    "population": ("experiments: individuals per generation (paper: 10); fuzzy_q: episodes "
                   "per generation"),
    "generations": "experiments: generations (paper: 30 in simulation, 20 on the robot)",
    "protocol": ("experiments: `paper` is the paper's fixed budget (population 10, 30 "
                 "generations, one trial); `auto` adds `extend` when the file gives no budget"),
    "extend": ("an addition: the budget sized by the problem as it learns; the paper runs a "
               "fixed number of generations"),
    "extend.patience": ("an addition: generations without a better selected controller after "
                        "which an extended run ends"),
    "extend.most": ("an addition: the most generations an extended run has; unset: 30 for "
                    "every 30 units of M log2 K, at least twice `generations`"),
    "prior": ("an addition, the credit learner: pseudo-episodes of no credit each rule and "
              "command starts with, before its Thompson draws follow the evidence"),
    "crossover": "GA exploration: crossover probability p_c (experiments: 0.2)",
    "mutation": "GA exploration: mutation probability p_m per gene (experiments: 0.1)",
    "pitt_crossover": ("GA exploration: the standard crossover of the Pitt GA (the hybrid takes, "
                       "gene by gene, the consequent with the larger q_m^k instead)"),
    "elites": "GA exploration: elitism, the best copied unchanged",
    "trials": ("experiments: one trial per individual per generation; fitness is the mean of "
               "`trials` trials; fuzzy_q: population × trials episodes per generation"),
    "restart_after": ("an addition against premature convergence: fresh individuals after "
                      "this many generations without a better selected controller (0: never, "
                      "as in the paper)"),
    "greedy_individual": ("an addition to the hybrid: each bred generation holds the q table's "
                          "greedy controller (each rule's strongest q_m^k) in place of one "
                          "child (false: as in the paper)"),
    "common_starts": ("experiments: the start states of a generation's trials (an addition: the "
                      "same for every individual when true)"),
    "q": "eq. 4-9: the fuzzy Q-learning of rule strengths",
    "q.alpha": "eq. 7: learning rate α of q_m^k += α ΔQ φ_m (times the trace, eq. 8-9)",
    "q.gamma": "eq. 6: discount γ of ΔQ = r + γ max Q(S', ·) − Q(S, a)",
    "q.lambda": ("eq. 8-9: trace decay λ of the replacing eligibility trace; 0 gives eq. 7 "
                 "alone"),
    "q.temperature": ("GA exploration: Boltzmann temperature T of P(k) ∝ exp(q_m^k / T): hybrid "
                      "mutation, fuzzy_q exploration"),
    "q.initial": "eq. 4: the q_m^k every rule starts with",
    "exploration": "how fuzzy_q picks each active rule's command",
    "exploration.policy": "Boltzmann over q_m^k (as the hybrid's mutation) or ε-greedy",
    "exploration.epsilon": "ε of ε-greedy",
    "exploration.decay": "multiplies T (or ε) after every generation",
    "exploration.minimum": "floor of the decayed T or ε",
    "exploration.hold": ("an addition: how many of its firings a rule keeps a drawn command "
                         "(1: a fresh draw every step, as the paper's protocol runs)"),
    "selection": ("an addition to the paper: which controller the run returns, chosen on "
                  "validation episodes instead of one noisy trial"),
    "selection.candidates": "an addition: the best distinct controllers kept for validation",
    "selection.confirmation": ("an addition: fresh episodes the returned controller is confirmed "
                               "on, the figure a run reports (seeds disjoint from all others)"),
    "selection.episodes": ("an addition: validation episodes per candidate (seeds disjoint from "
                           "training and from evaluate)"),
    "selection.race": ("an addition: racing the validated candidates (successive halving by "
                       "thirds) up to this many validation episodes before one is returned"),
    "stop": "an addition: the run's budget; the paper stops after a number of generations",
    "stop.episodes": "an addition: stop after this many episodes, selection included",
    "stop.steps": "an addition: stop after this many environment steps",
    "stop.seconds": "an addition: stop after this much training time",
    "stop.target": ("an addition: stop once the selected controller's confirmation on fresh "
                    "episodes reaches this success rate, return or fitness"),
    "sets": ("the paper's future work: evolve the antecedents (the fuzzy sets of Sec. II) "
             "with the consequents"),
    "sets.inputs": "which inputs' sets (Sec. II) are learned",
    "sets.mode": ("how a set genome becomes sets: a strong partition's gaps, or lateral shifts "
                  "of each set"),
    "sets.bound": "how far a set (Sec. II's quadruple) may move",
    "sets.bound_in": "whether bound is a fraction of the spacing or in the input's units",
    "sets.floor": "lateral: the least coverage kept, so eq. 3 never divides by near zero",
    "sets.mutation": "GA exploration: mutation probability of a set gene",
    "sets.sigma": "GA exploration: the step of a set gene's mutation",
}


def _learner_defs(schema: dict[str, Any]) -> dict[str, dict[str, Any]]:
    """Learner name -> the schema of its ``learning:`` model, in plugin order."""
    section = schema["properties"]["learning"]
    name_of = {ref: name for name, ref in _discriminator_mapping(section).items()}
    return {name_of[option["$ref"]]: schema["$defs"][_def_name(option["$ref"])]
            for option in section["oneOf"]}


def learning_keys(schema: dict[str, Any]) -> list[tuple[str, dict[str, Any]]]:
    """Every key under ``learning:`` of any learner as (dotted key, schema node), nested
    sections included: the keys every learner reads first."""
    defs = schema["$defs"]
    learners = list(_learner_defs(schema).values())
    keys: list[str] = []
    for node in learners:
        keys += [key for key in node["properties"] if key not in keys]
    keys.sort(key=lambda key: not all(key in node["properties"] for node in learners))
    found = []
    for key in keys:
        prop = next(node["properties"][key] for node in learners if key in node["properties"])
        found.append((key, prop))
        # a section, or an optional one (anyOf: the section or null)
        refs = [prop] if "$ref" in prop else [o for o in prop.get("anyOf", []) if "$ref" in o]
        for ref in refs[:1]:
            for sub, sub_prop in defs[_def_name(ref["$ref"])]["properties"].items():
                found.append((f"{key}.{sub}", sub_prop))
    return found


def _readers(schema: dict[str, Any], key: str) -> str:
    """Which learners read ``key`` (dotted keys: their section)."""
    learners = _learner_defs(schema)
    first = key.partition(".")[0]
    names = [name for name, node in learners.items() if first in node["properties"]]
    return "all" if len(names) == len(learners) else ", ".join(names)


def _nested_default(schema: dict[str, Any], key: str) -> Any:
    first, _, rest = key.partition(".")
    if first == "learner":
        return "hybrid"  # each learner's model names itself; a section without it is this
    node = next(node["properties"] for node in _learner_defs(schema).values()
                if first in node["properties"])
    prop = node[first]
    if not rest:
        return prop.get("default")
    return (prop.get("default") or {}).get(rest)


def learners_reference(schema: dict[str, Any]) -> str:
    """Every ``learning:`` key next to the paper's equation it sets."""
    lines = [
        "# Learners and the paper's equations",
        "",
        "Every key of a behaviour's `learning:` section, generated from the JSON Schema, next to",
        "the equation or protocol step of the paper (Gu, Hu & Spacek, *Learning Fuzzy Logic",
        "Controller for Reactive Robot Behaviours*) that it sets. How each learner works, the",
        "reading of eq. 9 that is implemented, run directories and measured results are in",
        "[Learning](../learning.md).",
        "",
        "The learners: `pitt` is the genetic algorithm over whole rule tables (Sec. IV,",
        "chromosome = the M consequent indices); `fuzzy_q` is fuzzy Q-learning (eq. 4-9) of one",
        "controller; `hybrid`, the paper's method, is the GA whose crossover and mutation are",
        "guided by the rule strengths q_m^k that fuzzy Q-learning updates during every trial;",
        "`credit`, an addition, tries whole tables drawn from each rule's credit, every",
        "episode's outcome shared among the rules that fired (the Michigan approach's credit",
        "over the Pitt approach's trials).",
        "Each learner reads only its own keys (\"used by\"); another learner's key is an error",
        "that names the learner reading it.",
        "",
        "| key | default | paper | used by | constraints |",
        "| --- | --- | --- | --- | --- |",
    ]
    for key, prop in learning_keys(schema):
        equation, used_by = EQUATIONS[key], _readers(schema, key)
        default = "section" if "$ref" in prop else f"`{json.dumps(_nested_default(schema, key))}`"
        constraints = ", ".join(_constraints(prop))
        lines.append(f"| `{key}` | {default} | {_cell(equation)} | {used_by} "
                     f"| {_cell(constraints)} |")
    lines += ["", *_TUNING]
    return "\n".join(lines)


_TUNING = """\
## Tuning by reward scale

The GA keys (`population`, `generations`, `crossover`, `mutation`, `elites`) see only the
trial fitness, and roulette-wheel selection shifts it, so they do not depend on the reward's
scale. The q keys do, because every q_m^k estimates a discounted return (eq. 4-6):

- **q values grow to about r / (1 − γ).** With a delayed ±1 at the end of an episode (the
  ballchase simulator) they stay within ±1; with +1 per step survived (CartPole) they
  approach 1 / (1 − γ) = 100 at γ = 0.99.
- **`q.temperature` must match the gaps between q values.** Boltzmann picks command k with
  probability ∝ exp(q_m^k / T): a T much smaller than those gaps is greedy, a T much larger is
  uniform. For rewards of size ±1 a T of 0.1–0.2 keeps the hybrid's gain over Pitt; for returns
  in the hundreds T near 1 or more is needed. Scale T with the rewards.
- **`q.initial` can make untried commands look good.** At 0 with positive rewards (every
  tried command soon has q > 0), the first command tried in a rule looks best forever;
  starting every q at the upper bound r_max / (1 − γ) (optimistic initialisation) makes each
  command be tried. With a delayed ±1 reward, 0 already lies between success and failure.
- **`q.alpha`** is a step size on ΔQ, which carries the reward's units: larger rewards make
  larger steps, so keep α × (reward scale) moderate; 0.1 suits rewards near 1.
- **`q.gamma`** sets the horizon, about 1 / (1 − γ) steps: with a reward only at the end of
  an episode of L steps, γ^L must not vanish (γ = 0.9 and L = 200 leave 7e-10 of a far
  success; `q.lambda` carries it back faster).

Measured guidance, with figures for each shipped behaviour, is in
[Learning](../learning.md); the shipped files (`behaviours/*.yaml`) show the settings that
learn them.
""".splitlines()


# -- the mkdocs hook -------------------------------------------------------------------------
def generate_pages() -> dict[str, str]:
    """Generated page path (under docs/) -> markdown."""
    import typer

    from flctool.cli import app

    schema = json.loads(SCHEMA.read_text(encoding="utf-8"))
    return {
        "reference/behaviour-file.md": behaviour_reference(schema),
        "reference/cli.md": cli_reference(typer.main.get_command(app)),
        "reference/learners.md": learners_reference(schema),
    }


def on_files(files: Any, config: Any) -> Any:
    """mkdocs hook: add the generated pages to the site (before the nav is built)."""
    from mkdocs.structure.files import File

    for path, content in generate_pages().items():
        files.append(File.generated(config, path, content=content))
    return files
