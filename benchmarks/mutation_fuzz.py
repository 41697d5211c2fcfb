"""Mutation fuzzing of the shipped behaviour files: how does flctool take broken input?

Each case takes one file from ``behaviours/``, applies one seeded mutation (a scalar replaced
by a hostile token, a line deleted, duplicated or re-indented, a YAML bomb, a huge size, ...)
and loads and compiles the result in a worker process, with a time and memory limit. Outcomes:

- ``ok``: loaded and compiled, and the values read are what was written;
- ``clear``: a flctool error whose every problem names a line;
- ``unlocated``: a flctool error with a problem that names no line;
- ``crash``: any other exception (a user would see a traceback);
- ``hang``: no answer within the time limit (wall clock, ``--timeout``; each answered case
  also reports the CPU time it took, which does not depend on the machine's load);
- ``silent``: loaded, but a value written as a YAML 1.2 boolean or string (``yes``,
  ``true``, ``0x10``, ``1:00``) or a decimal like ``010`` became a different number.

Usage: ``nice -n 10 python benchmarks/mutation_fuzz.py [--cases 2000] [--seed 0]``.
"""

from __future__ import annotations

import argparse
import json
import multiprocessing as mp
import random
import re
import resource
import sys
import time
from collections import Counter
from dataclasses import dataclass
from multiprocessing.connection import Connection
from pathlib import Path
from typing import Any

import yaml

ROOT = Path(__file__).resolve().parents[1]
BEHAVIOURS = sorted((ROOT / "behaviours").glob("*.yaml"))
TIMEOUT_S = 10.0
MEMORY_LIMIT = 3 * 2**30

#: Hostile scalar tokens. The second element is what YAML 1.2 (core schema) reads the token
#: as: a number, or None for "not a number" (a boolean, string or null).
TOKENS: list[tuple[str, float | None]] = [
    ("yes", None), ("no", None), ("on", None), ("off", None), ("y", None), ("n", None),
    ("true", None), ("false", None), ("True", None), ("~", None), ("null", None), ("", None),
    ("010", 10.0), ("0x10", 16.0), ("0o10", 8.0), ("1:00", None), ("1_000", None),
    ("0b11", None), ("+1", 1.0), ("-0", 0.0), (".inf", float("inf")), ("-.inf", float("-inf")),
    (".nan", None), ("1e309", float("inf")), ("1e8", 1e8), ("100000000", 1e8),
    ("-1", -1.0), ("0", 0.0), ("2.5", 2.5), ("9" * 5000, None),
    ("chase-mine", None), ("x" * 70, None), ("'quoted'", None), ("[1, 2]", None),
    ("{a: 1}", None), ("!!null ''", None), ("!!bool 3", None), ("!!int abc", None),
    ("!!float x", None), ("!!seq x", None), ("!!map x", None), ("!!str 1", None),
    ("!!binary aGk=", None), ("!!timestamp 2001-12-14", None), ("2001-12-14", None),
    ("!!python/object:os.system x", None), ("!custom 1", None), ("&a 1", 1.0), ("*nope", None),
    ("\"\\x1b[31mred\"", None), ("somemodule:Env-v0", None), ("this:Env-v0", None),
    ("1e308", 1e308), ("-1e300", -1e300), ("1e9", 1e9), ("1000000001", 1000000001.0),
]


@dataclass
class Case:
    index: int
    file: str
    kind: str
    text: str
    #: For a replaced scalar: its field path and the number YAML 1.2 reads there (or None).
    path: tuple[Any, ...] | None = None
    expect: float | None = None
    token: str | None = None
    #: The file's bytes, when the mutation is of its encoding (read from a file, not text).
    data: bytes | None = None


def _scalars(text: str) -> list[tuple[tuple[Any, ...], yaml.ScalarNode]]:
    """Every value scalar of the document with its field path."""
    found: list[tuple[tuple[Any, ...], yaml.ScalarNode]] = []

    def walk(node: yaml.Node, path: tuple[Any, ...]) -> None:
        if isinstance(node, yaml.MappingNode):
            for key, value in node.value:
                walk(value, (*path, key.value))
        elif isinstance(node, yaml.SequenceNode):
            for i, item in enumerate(node.value):
                walk(item, (*path, i))
        elif isinstance(node, yaml.ScalarNode):
            found.append((path, node))

    walk(yaml.compose(text, Loader=yaml.SafeLoader), ())
    return found


def _replace_scalar(rng: random.Random, case: Case, source: str) -> None:
    path, node = rng.choice(_scalars(source))
    token, expect = rng.choice(TOKENS)
    start, end = node.start_mark.index, node.end_mark.index
    case.text = source[:start] + token + source[end:]
    case.path, case.expect, case.token = path, expect, token


def _lines(rng: random.Random, case: Case, source: str) -> None:
    lines = source.splitlines()
    i = rng.randrange(len(lines))
    op = rng.choice(["delete", "duplicate", "indent", "dedent", "swap", "truncate", "tab",
                     "bytes", "key_typo"])
    case.kind = f"line_{op}"
    if op == "delete":
        del lines[i]
    elif op == "duplicate":
        lines.insert(i, lines[i])
    elif op == "indent":
        lines[i] = "  " + lines[i]
    elif op == "dedent":
        lines[i] = lines[i][2:] if lines[i].startswith("  ") else lines[i]
    elif op == "swap":
        j = rng.randrange(len(lines))
        lines[i], lines[j] = lines[j], lines[i]
    elif op == "truncate":
        lines = lines[:i]
    elif op == "tab":
        lines[i] = "\t" + lines[i].lstrip()
    elif op == "bytes":
        junk = "".join(chr(rng.choice([0, 7, 27, 0x85, 0x2028, 0xFEFF, 0xD7FF, 0x7F]))
                       for _ in range(rng.randint(1, 4)))
        at = rng.randint(0, len(lines[i]))
        lines[i] = lines[i][:at] + junk + lines[i][at:]
    else:
        match = re.match(r"(\s*)([A-Za-z_]+):", lines[i])
        if match:
            key = match.group(2)
            lines[i] = lines[i].replace(key, key[:-1] + "-" if len(key) > 1 else "x-", 1)
    case.text = "\n".join(lines) + "\n"


def _structural(rng: random.Random, case: Case, source: str) -> None:
    op = rng.choice(["deep", "recursive", "laughs", "wide_m", "population", "max_steps",
                     "generations", "many_rules", "big_int_key", "many_commands",
                     "trials"])
    case.kind = f"struct_{op}"
    if op == "deep":
        depth = rng.choice([200, 600, 3000])
        case.text = source + "description: " + "[" * depth + "]" * depth + "\n"
    elif op == "recursive":
        case.text = source.replace("rules: []", "rules: &r [*r]").replace(
            "flctool: 1", "flctool: 1\nx: &r [1, *r]", 1)
    elif op == "laughs":
        bomb = "a0: &a0 [lol, lol, lol, lol, lol, lol, lol, lol, lol]\n"
        for level in range(1, 10):
            bomb += f"a{level}: &a{level} [" + ", ".join([f"*a{level - 1}"] * 9) + "]\n"
        case.text = source.replace("description:", bomb + "description:", 1)
    elif op == "wide_m":
        count = rng.choice([20, 30])
        inputs = "".join(
            f"  x{i}:\n    range: [0, 1]\n    sets:\n      lo: [0, 0, 0, 1]\n"
            f"      hi: [0, 1, 1, 1]\n" for i in range(count))
        case.text = re.sub(r"(?ms)^inputs:\n.*?^(?=output:)", "inputs:\n" + inputs, source)
        case.text = re.sub(r"(?m)^environment:.*(\n  .*)*", "", case.text)
    elif op in ("population", "generations", "trials"):
        case.text = source.replace("learning:\n", f"learning:\n  {op}: 100000000\n", 1)
        if "learning:" not in source:
            case.text = source + f"learning:\n  {op}: 100000000\n"
    elif op == "max_steps":
        case.text = re.sub(r"(?m)^(  adapter: .*)$", r"\1\n  max_steps: 100000000", source)
    elif op == "many_rules":
        rule = "  - {if: {ball_size: small, pan: ahead}, then: forward}\n"
        case.text = source.replace("rules: []", "rules:\n" + rule * 20000)
    elif op == "big_int_key":
        case.text = source.replace("flctool: 1", "flctool: " + "1" * 5000, 1)
    elif op == "many_commands":
        commands = "".join(f"    c{i}: {i}\n" for i in range(100000))
        case.text = re.sub(r"(?ms)^  commands:\n(    .*\n)+", "  commands:\n" + commands,
                           source)
    else:
        case.text = source


def _encoding(rng: random.Random, case: Case, source: str) -> None:
    """The file saved in another encoding, or with a byte that is no UTF-8 in it."""
    op = rng.choice(["utf16", "latin1", "byte", "truncated"])
    case.kind = f"encoding_{op}"
    if op == "utf16":
        case.data = source.encode("utf-16")
    elif op == "latin1":
        at = rng.randrange(len(source))
        case.data = (source[:at] + "\u00e9" + source[at:]).encode("latin-1", "replace")
    elif op == "byte":
        raw = source.encode("utf-8")
        at = rng.randrange(len(raw))
        case.data = raw[:at] + bytes([rng.choice([0x80, 0xC3, 0xFF, 0xFE])]) + raw[at:]
    else:  # cut inside a multi-byte character
        case.data = (source + "# \u00e9\n").encode("utf-8")[:-2]


def make_case(index: int, seed: int) -> Case:
    rng = random.Random(f"{seed}:{index}")
    file = rng.choice(BEHAVIOURS)
    source = file.read_text(encoding="utf-8")
    case = Case(index, file.name, "scalar", source)
    roll = rng.random()
    if roll < 0.6:
        _replace_scalar(rng, case, source)
    elif roll < 0.85:
        _lines(rng, case, source)
    elif roll < 0.95:
        _structural(rng, case, source)
    else:
        _encoding(rng, case, source)
    return case


def _value_at(data: Any, path: tuple[Any, ...]) -> Any:
    for part in path:
        found = (isinstance(data, dict) and part in data) or (
            isinstance(data, list) and isinstance(part, int) and part < len(data))
        if not found:
            return _MISSING
        data = data[part]
    return data


_MISSING = object()


def run_case(case: Case) -> tuple[str, str]:
    """Load and compile one case; returns (outcome, detail)."""
    import tempfile

    from flctool.behaviour import load_behaviour, parse_behaviour
    from flctool.compile import compile_behaviour
    from flctool.errors import FlcError, SpecError

    try:
        if case.data is not None:
            with tempfile.TemporaryDirectory() as folder:
                path = Path(folder) / case.file
                path.write_bytes(case.data)
                behaviour = load_behaviour(path)
        else:
            behaviour = parse_behaviour(case.text, f"{case.file}#{case.index}")
        compile_behaviour(behaviour)
    except SpecError as error:
        if all(p.line is not None for p in error.problems):
            return "clear", str(error.problems[0])[:160]
        return "unlocated", str(error)[:300]
    except FlcError as error:
        return "clear", str(error)[:160]
    except BaseException as error:  # classifying every escape is the point
        return "crash", f"{type(error).__name__}: {str(error)[:200]}"
    if case.path is not None:
        value = _value_at(behaviour.model_dump(mode="python", by_alias=True), case.path)
        number = isinstance(value, (int, float)) and not isinstance(value, bool)
        if number and (case.expect is None or float(value) != case.expect):
            return "silent", f"{case.token!r} at {case.path} read as {value!r}"
    return "ok", ""


def _worker(conn: Connection) -> None:
    resource.setrlimit(resource.RLIMIT_AS, (MEMORY_LIMIT, MEMORY_LIMIT))
    sys.setrecursionlimit(10000)
    while True:
        case = conn.recv()
        if case is None:
            return
        start = time.process_time()
        outcome, detail = run_case(case)
        conn.send((outcome, detail, time.process_time() - start))


class Pool:
    """One worker process, replaced whenever a case hangs or kills it."""

    def __init__(self) -> None:
        self.context = mp.get_context("fork")
        self._start()

    def _start(self) -> None:
        self.conn, child = self.context.Pipe()
        self.process = self.context.Process(target=_worker, args=(child,), daemon=True)
        self.process.start()

    def run(self, case: Case, timeout: float) -> tuple[str, str, float]:
        """(outcome, detail, CPU seconds of the worker; NaN if it gave no answer)."""
        self.conn.send(case)
        if self.conn.poll(timeout):
            try:
                result: tuple[str, str, float] = self.conn.recv()
                return result
            except EOFError:
                self._restart()
                return "crash", "worker died", float("nan")
        self._restart()
        return "hang", f"no answer in {timeout:g} s", float("nan")

    def _restart(self) -> None:
        self.process.kill()
        self.process.join()
        self._start()

    def close(self) -> None:
        self.conn.send(None)
        self.process.join()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", type=int, default=2000)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--timeout", type=float, default=TIMEOUT_S,
                        help="wall-clock seconds before a case counts as a hang")
    parser.add_argument("--json", type=Path, help="write counts and examples here")
    args = parser.parse_args()
    # Imported once here, so that each forked worker starts warm.
    import flctool.behaviour
    import flctool.compile

    del flctool

    pool = Pool()
    counts: Counter[str] = Counter()
    by_kind: dict[str, Counter[str]] = {}
    examples: dict[str, list[str]] = {}
    start = time.process_time()
    cpu: list[float] = []
    for index in range(args.cases):
        case = make_case(index, args.seed)
        outcome, detail, seconds = pool.run(case, args.timeout)
        if seconds == seconds:
            cpu.append(seconds)
        counts[outcome] += 1
        by_kind.setdefault(case.kind, Counter())[outcome] += 1
        if outcome != "ok" and outcome != "clear":
            examples.setdefault(outcome, [])
            if len(examples[outcome]) < 15:
                examples[outcome].append(f"#{index} {case.file} {case.kind}: {detail}")
    pool.close()
    print(f"{args.cases} cases, seed {args.seed}, hang after {args.timeout:g} s wall "
          f"(parent CPU {time.process_time() - start:.1f} s)")
    cpu.sort()
    if cpu:
        print(f"worker CPU per answered case: median {cpu[len(cpu) // 2]:.3f} s, "
              f"99th percentile {cpu[int(len(cpu) * 0.99)]:.2f} s, max {cpu[-1]:.2f} s, "
              f"total {sum(cpu):.0f} s")
    for outcome in ("ok", "clear", "unlocated", "crash", "hang", "silent"):
        print(f"  {outcome:10} {counts[outcome]}")
    print("by mutation kind (outcomes other than ok/clear):")
    for kind, outcomes in sorted(by_kind.items()):
        bad = {k: v for k, v in outcomes.items() if k not in ("ok", "clear")}
        if bad:
            print(f"  {kind:22} {dict(bad)}")
    for outcome, lines in examples.items():
        print(f"examples of {outcome}:")
        for line in lines:
            print("   ", line)
    if args.json:
        args.json.write_text(json.dumps({"cases": args.cases, "seed": args.seed,
                                         "timeout": args.timeout, "counts": dict(counts),
                                         "max_cpu": cpu[-1] if cpu else None,
                                         "examples": examples}, indent=1))


if __name__ == "__main__":
    main()
