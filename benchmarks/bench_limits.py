"""What a hostile file costs before flctool answers: CPU and peak memory per MB of input.

Grows files of several hostile shapes -- behaviour YAML (a written-out rule grid, a dense
flow list, thousands of commands), FLL, FIS and FCL controllers of many rules for
``flctool import``, a CSV of many rows and one of a single huge cell for ``flctool infer`` --
to sizes up to the documented limits, runs the command on each in a fresh process and
measures that process alone (``resource.getrusage(RUSAGE_CHILDREN)`` of a small measuring
process around it: user + system CPU, and peak resident memory). A whole command is measured,
from the interpreter's start to its exit, error or not.

The cost per MB is the growth over the same command on a tiny file of the shape (the
interpreter and imports are paid once, whatever the size): (cost - tiny cost) / MB. The bound
of issue 28 is 1 s of CPU and 50 MB of memory per MB of input.

Usage: ``nice -n 10 python benchmarks/bench_limits.py [--sizes 1,4,16] [--json out.json]``
(``--sizes`` in MB; ``limit`` stands for the shape's documented limit).
"""

from __future__ import annotations

import argparse
import json
import random
import subprocess
import sys
import tempfile
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
MB = 1_000_000
#: CPU seconds and megabytes of peak memory per MB of input that the growth must stay under.
CPU_PER_MB, MEMORY_PER_MB = 1.0, 50.0

_MEASURE = """
import json, resource, subprocess, sys
done = subprocess.run(sys.argv[1:], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
usage = resource.getrusage(resource.RUSAGE_CHILDREN)
print(json.dumps({"cpu": usage.ru_utime + usage.ru_stime, "peak_mb": usage.ru_maxrss / 1024,
                  "code": done.returncode, "stderr": done.stderr.decode()[-300:]}))
"""


def measure(command: list[str]) -> dict[str, object]:
    """CPU seconds, peak MB and exit code of ``command`` run alone in a fresh process."""
    result = subprocess.run([sys.executable, "-c", _MEASURE, *command], check=True,
                            capture_output=True, text=True, cwd=ROOT)
    measured: dict[str, object] = json.loads(result.stdout)
    return measured


# -- hostile files ----------------------------------------------------------------------------
def _grid(sets: int, rules: int) -> str:
    """A behaviour of two inputs of ``sets`` sets each and its first ``rules`` rules."""
    def variable(name: str) -> str:
        top = sets - 1
        lines = [f"  {name}:\n    range: [0, {top}]\n    sets:\n"]
        for i in range(sets):
            lines.append(f"      s{i}: [{max(i - 1, 0)}, {i}, {i}, {min(i + 1, top)}]\n")
        return "".join(lines)

    head = (f"flctool: 1\nname: hostile\ninputs:\n{variable('a')}{variable('b')}"
            "output:\n  name: turn\n  commands:\n    left: -1\n    right: 1\nrules:\n")
    body = [f"  - {{if: {{a: s{i}, b: s{j}}}, then: {'left' if (i + j) % 2 else 'right'}}}\n"
            for i in range(sets) for j in range(sets)][:rules]
    return head + "".join(body)


def behaviour_rules(size: int) -> str:
    """A valid file that is nothing but a written-out rule grid (a large learned best.yaml)."""
    rules = max(1, size // 38)
    sets = max(2, int(rules ** 0.5) + 1)
    return _grid(sets, rules)


def behaviour_flow(size: int) -> str:
    """The densest YAML: a flow list of one-digit numbers (two characters a value)."""
    head = (Path(ROOT / "behaviours" / "ballchase-handmade.yaml").read_text(encoding="utf-8")
            .replace("description:", "description_x:", 1))
    return head + "notes: [" + "0," * max(1, (size - len(head)) // 2) + "0]\n"


def behaviour_commands(size: int) -> str:
    """Many keys: an output with tens of thousands of commands."""
    count = max(1, size // 16)
    commands = "".join(f"    c{i}: {i / count!r}\n" for i in range(count))
    return ("flctool: 1\nname: hostile\ninputs:\n  x:\n    range: [0, 1]\n    sets:\n"
            "      lo: [0, 0, 0, 1]\n      hi: [0, 1, 1, 1]\noutput:\n  name: y\n"
            f"  commands:\n{commands}")


def _exported(suffix: str) -> Callable[[int], str]:
    def export(sets: int) -> str:
        from flctool.behaviour import parse_behaviour
        from flctool.export import EXPORTERS

        behaviour = parse_behaviour(_grid(sets, sets * sets), "grid.yaml")
        exporter = EXPORTERS.get(suffix.lstrip("."))()
        [text] = exporter.texts(behaviour, Path("grid" + suffix)).values()
        return text

    def make(size: int) -> str:
        """The largest square rule grid whose export is at most ``size`` characters."""
        sets = 8
        text = export(sets)
        while True:  # grow by the ratio still missing, until the next would be too long
            bigger = max(sets + 1, int(sets * (size / len(text)) ** 0.5))
            grown = export(bigger)
            if len(grown) > size:
                return text
            sets, text = bigger, grown
    return make


def csv_rows(size: int) -> str:
    rng = random.Random(0)
    rows = [f"{rng.random():.6f},{rng.uniform(-90, 90):.4f}\n" for _ in range(size // 18)]
    return "ball_size,pan\n" + "".join(rows)


def csv_cell(size: int) -> str:
    """One row whose cell is a number of ``size`` digits (refused, with its line)."""
    return "ball_size,pan\n0.5," + "1" * size + "\n"


@dataclass(frozen=True)
class Shape:
    name: str
    make: Callable[[int], str]
    suffix: str
    limit: int  # the documented limit, in characters
    command: Callable[[Path, Path], list[str]]


def _validate(path: Path, _: Path) -> list[str]:
    return [sys.executable, "-m", "flctool", "validate", str(path)]


def _import(path: Path, out: Path) -> list[str]:
    return [sys.executable, "-m", "flctool", "import", str(path), "-o", str(out), "--force"]


def _infer(path: Path, out: Path) -> list[str]:
    return [sys.executable, "-m", "flctool", "infer",
            str(ROOT / "behaviours" / "ballchase-handmade.yaml"), "-i", str(path), "-o",
            str(out), "--force"]


def shapes() -> list[Shape]:
    from flctool.behaviour.yaml_source import MAX_FILE_CHARS
    from flctool.export.base import MAX_IMPORT_CHARS

    csv_limit = 50 * MB  # no limit: streamed; measured to the behaviour files' limit
    return [
        Shape("behaviour: rule grid", behaviour_rules, ".yaml", MAX_FILE_CHARS, _validate),
        Shape("behaviour: flow list", behaviour_flow, ".yaml", MAX_FILE_CHARS, _validate),
        Shape("behaviour: commands", behaviour_commands, ".yaml", MAX_FILE_CHARS, _validate),
        Shape("FLL: rule grid", _exported(".fll"), ".fll", MAX_IMPORT_CHARS, _import),
        Shape("FCL: rule grid", _exported(".fcl"), ".fcl", MAX_IMPORT_CHARS, _import),
        Shape("FIS: rule grid", _exported(".fis"), ".fis", MAX_IMPORT_CHARS, _import),
        Shape("CSV: rows", csv_rows, ".csv", csv_limit, _infer),
        Shape("CSV: one huge cell", csv_cell, ".csv", csv_limit, _infer),
    ]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", default="1,4,limit",
                        help="comma-separated MB, or 'limit' for the documented limit")
    parser.add_argument("--only", help="measure only shapes whose name contains this")
    parser.add_argument("--json", type=Path, help="write every measurement here")
    args = parser.parse_args()
    results = []
    print(f"{'shape':22} {'MB':>6} {'exit':>4} {'CPU s':>7} {'peak MB':>8} "
          f"{'CPU s/MB':>9} {'MB/MB':>7}")
    with tempfile.TemporaryDirectory() as folder:
        for shape in shapes():
            if args.only and args.only not in shape.name:
                continue
            path, out = Path(folder) / f"input{shape.suffix}", Path(folder) / "output"
            out = out.with_suffix(".csv" if shape.suffix == ".csv" else ".yaml")
            path.write_text(shape.make(2000), encoding="utf-8")
            tiny = measure(shape.command(path, out))
            for size_text in args.sizes.split(","):
                size = (shape.limit - 10_000 if size_text == "limit"
                        else int(float(size_text) * MB))
                text = shape.make(min(size, shape.limit))
                text = text[: shape.limit] if len(text) > shape.limit else text
                path.write_text(text, encoding="utf-8")
                megabytes = path.stat().st_size / MB
                got = measure(shape.command(path, out))
                cpu = (float(got["cpu"]) - float(tiny["cpu"])) / megabytes  # type: ignore[arg-type]
                memory = (float(got["peak_mb"]) - float(tiny["peak_mb"])) / megabytes  # type: ignore[arg-type]
                flag = "" if cpu <= CPU_PER_MB and memory <= MEMORY_PER_MB else "  OVER"
                print(f"{shape.name:22} {megabytes:6.1f} {got['code']:>4} {got['cpu']:7.2f} "
                      f"{got['peak_mb']:8.0f} {cpu:9.2f} {memory:7.1f}{flag}", flush=True)
                results.append({"shape": shape.name, "mb": megabytes, **got,
                                "tiny": tiny, "cpu_per_mb": cpu, "memory_per_mb": memory})
    if args.json:
        args.json.write_text(json.dumps(results, indent=1) + "\n", encoding="utf-8")


if __name__ == "__main__":
    main()
