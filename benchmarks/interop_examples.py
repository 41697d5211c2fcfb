"""How many of the example controllers that other toolchains ship flctool imports.

    python benchmarks/interop_examples.py DIR [DIR ...] [--convert-mamdani] [--convert-linear]
        [--list]

Walks each folder for ``.fll``, ``.fis`` and ``.fcl`` files and imports each one in process
(one behaviour per output), then counts, per folder and in total:

- **exact**: imported, and the controller computes what the file says;
- **approximated**: imported only with ``--convert-mamdani`` (a Mamdani FIS, FLL or FCL
  whose output sets are replaced by singletons at their centroids, its rules rewritten where
  flctool's grid has none like them) or ``--convert-linear`` (a first-order Takagi-Sugeno
  one whose linear terms are replaced by constants fitted per rule: the import's
  ``--linear-singletons``), with the largest deviation the import measures and states, and
  whether fuzzylite 6's own output stays within it (1 % and 1e-12 allowed: the bound is
  measured on other states); the quartiles of the stated deviations (as a share of the
  output range) close the summary;
- **incomplete**: imported, but its rules leave combinations of sets without a command, so
  the controller is not deployable (it can be learned) and cannot be compared;
- **refused, clear**: refused with one of flctool's errors that names the file and a line,
  says what is not supported and gives a fix (``(fix: ...)``), for each construct when it
  lists several;
- **refused, unclear**: refused with any other exception, or with a message lacking the
  file and line or the fix. The goal is zero.

Where the fuzzylite 6 command line is installed, every import is checked against it:
fuzzylite evaluates the original file on 2,000 random states inside the ranges (flctool clips,
the file may not), and the largest difference from the imported controller (over every
output) is printed.

``--list`` prints every file's outcome and message. The example files are not part of this
repository: point it at the folders where fuzzylite (Debian: /usr/share/doc/fuzzylite/
examples), Octave's fuzzy-logic-toolkit or pyfuzzylite (its ``examples`` package) put them.
"""

from __future__ import annotations

import argparse
import re
import shutil
import subprocess
import sys
import tempfile
from collections import Counter
from pathlib import Path

import numpy as np

from flctool import compile_behaviour
from flctool.behaviour import Behaviour
from flctool.errors import FlcError, SpecError
from flctool.export import IMPORTERS
from flctool.export.imported import ImportRefusals

SUFFIXES = (".fll", ".fis", ".fcl")


#: States each imported file is compared with fuzzylite 6 on.
STATES = 2_000


def fuzzylite_outputs(path: Path, states: np.ndarray) -> np.ndarray | None:
    """fuzzylite 6's outputs (S, outputs) for the file at ``path``, or None without the
    fuzzylite command."""
    binary = shutil.which("fuzzylite")
    if binary is None:
        return None
    with tempfile.TemporaryDirectory() as folder:
        data = Path(folder) / "states.fld"
        data.write_text("\n".join(" ".join(repr(float(x)) for x in row) for row in states))
        result = subprocess.run(
            [binary, "-i", str(path), "-if", path.suffix[1:].lower(), "-of", "fld", "-d",
             str(data), "-dheader", "false", "-dinputs", "false", "-decimals", "17"],
            capture_output=True, text=True, timeout=300, check=True)
    rows = [[float(v) for v in line.split()] for line in result.stdout.splitlines() if line]
    return np.array(rows).reshape(len(states), -1)


def difference(path: Path, behaviours: list[Behaviour]) -> float | None:
    """The largest |fuzzylite 6 - flctool| over STATES random states inside the ranges
    (seed 0), over every output, or None without the fuzzylite command."""
    controllers = [compile_behaviour(b) for b in behaviours]
    first = controllers[0]
    rng = np.random.default_rng(0)
    states = rng.uniform(first.ranges[:, 0], first.ranges[:, 1], (STATES, first.n_inputs))
    got = fuzzylite_outputs(path, states)
    if got is None:
        return None
    worst = 0.0
    for k, controller in enumerate(controllers):
        worst = max(worst, float(np.max(np.abs(got[:, k] - controller.output(states)))))
    return worst


def stated(report: str) -> float:
    """The largest deviation the conversion reports (over every output)."""
    found = [float(m) for m in re.findall(
        r"from the (?:Mamdani|Takagi-Sugeno) output .*? is ([0-9.e+-]+)", report)]
    return max(found, default=float("nan"))


def outcome(path: Path, convert: dict[str, bool]) -> tuple[str, str]:
    """(exact | approximated | incomplete | clear | unclear, message) for one file."""
    importer = IMPORTERS.get(path.suffix[1:].lower())()
    try:
        behaviours = importer.from_file_all(path)
    except FlcError as error:
        exact_error = error
    except Exception as error:
        return "unclear", f"{type(error).__name__}: {error}"
    else:
        return measured(path, behaviours, "exact", "")
    suffix = path.suffix.lower()
    if any(convert.values()):
        importer = IMPORTERS.get(suffix[1:])(**convert)  # type: ignore[call-arg]
        try:
            behaviours = importer.from_file_all(path)
        except FlcError as error:
            exact_error = error
        except Exception as error:
            return "unclear", f"{type(error).__name__}: {error}"
        else:
            return measured(path, behaviours, "approximated", importer.report)
    return ("clear" if clear(exact_error, path) else "unclear"), str(exact_error)


def measured(path: Path, behaviours: list[Behaviour], kind: str, report: str
             ) -> tuple[str, str]:
    """An imported file's outcome, with fuzzylite 6's difference from it."""
    if not all(b.is_deployable for b in behaviours):
        return "incomplete", ("imported, but the rules do not give every combination of sets "
                              "a command, so the controller is not deployable")
    unevaluated = ""
    try:
        gap = difference(path, behaviours)
    except (subprocess.SubprocessError, ValueError) as error:
        gap, unevaluated = None, f"fuzzylite 6 did not evaluate the file: {error}"
    text = unevaluated or ("" if gap is None else f"max |fuzzylite 6 - flctool| = {gap:.3g}")
    if kind == "approximated":
        bound = stated(report)
        # (plus 1e-12: fuzzylite rounds differently, and some conversions state ~1e-16)
        within = "not checked" if gap is None else gap <= 1.01 * bound + 1e-12
        shares = [float(s) for s in re.findall(r"\(([0-9.]+)% of the output(?: range|'s span)",
                                                report)]
        share = f" ({max(shares):.2f}% of the output range)" if shares else ""
        text += f"; stated {bound:.4g}{share}; within it: {within}"
    return kind, text


def clear(error: FlcError, path: Path) -> bool:
    """The refusal names the file and a line, and says how to fix it (each construct, when
    it lists several)."""
    if isinstance(error, ImportRefusals):
        return all(clear(e, path) for e in error.errors)
    if isinstance(error, SpecError):
        return all(p.file == str(path) and p.line is not None and p.hint
                   for p in error.problems)
    located = re.match(re.escape(str(path)) + r":\d+: \S", str(error)) is not None
    return located and bool(error.hint)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folders", nargs="+", type=Path)
    parser.add_argument("--convert-mamdani", action="store_true",
                        help="count files that import with Mamdani outputs as singletons")
    parser.add_argument("--convert-linear", action="store_true",
                        help="count files that import with first-order Takagi-Sugeno outputs "
                        "as constants fitted per rule")
    parser.add_argument("--list", action="store_true", help="print every file's outcome")
    args = parser.parse_args()
    kinds = ("exact", "approximated", "incomplete", "clear", "unclear")
    total: Counter[str] = Counter()
    distinct: dict[bytes, str] = {}  # a file's content -> its outcome (copies count once)
    reasons: Counter[str] = Counter()  # the first construct each refused file lists
    every: Counter[str] = Counter()  # every construct each refused file lists
    alone: Counter[str] = Counter()  # the constructs that are a refused file's only one
    shares: dict[bytes, float] = {}  # an approximated file's stated share of its range
    by_folder: dict[Path, list[float]] = {}
    for folder in args.folders:
        counts: Counter[str] = Counter()
        files = sorted(p for p in folder.rglob("*") if p.suffix.lower() in SUFFIXES)
        for path in files:
            kind, message = outcome(path, {"mamdani_singletons": args.convert_mamdani,
                                           "linear_singletons": args.convert_linear})
            counts[kind] += 1
            content = path.read_bytes()
            share = re.search(r"stated \S+ \(([0-9.]+)% of the output range\)", message)
            if kind == "approximated" and share:
                shares.setdefault(content, float(share.group(1)))
                by_folder.setdefault(folder, []).append(float(share.group(1)))
            if content not in distinct:
                distinct[content] = kind
                if kind in ("clear", "unclear"):
                    found = constructs(message)
                    reasons[found[0]] += 1
                    every.update(set(found))
                    if len(found) == 1:
                        alone[found[0]] += 1
            if kind in ("exact", "approximated") and message:
                print(f"{kind}: {path}: {message}")
            if args.list:
                print(f"{kind:12} {path}: {message.splitlines()[0] if message else ''}")
        total += counts
        print(f"{folder}: {len(files)} files; " + ", ".join(f"{k} {counts[k]}" for k in kinds))
    print(f"total: {sum(total.values())} files; " + ", ".join(f"{k} {total[k]}" for k in kinds))
    unique = Counter(distinct.values())
    print(f"distinct: {len(distinct)} files; " + ", ".join(f"{k} {unique[k]}" for k in kinds))
    imported = unique["exact"] + unique["approximated"]
    print(f"imported (exact + approximated): {imported} of {len(distinct)} distinct files "
          f"({imported / max(1, len(distinct)):.1%})")
    print("stated difference as a share of the output range, quartiles (min / 25 % / median "
          "/ 75 % / max), of the approximated files:")
    for name, values in [*((str(f), v) for f, v in by_folder.items()),
                         ("distinct", list(shares.values()))]:
        if values:
            q = np.percentile(values, [0, 25, 50, 75, 100])
            print(f"  {name}: {len(values)} files; " + " / ".join(f"{v:.2f} %" for v in q))
    for title, table in (("refusals of distinct files by their first construct", reasons),
                         ("refused distinct files listing each construct", every),
                         ("refused distinct files whose only construct it is", alone)):
        print(f"{title}:")
        for text, count in table.most_common():
            print(f"  {count:4}  {text}")
    sys.exit(0)


def constructs(message: str) -> list[str]:
    """Every construct a refusal lists (one, or each line after 'N problems' / 'N
    constructs'), without the file, line, names and numbers (to group them)."""
    lines = message.splitlines()
    listed = lines[1:] if len(lines) > 1 and re.search(r": \d+ (problem|construct)",
                                                        lines[0]) else lines[:1]
    return [reason(line) for line in listed] or [""]


def reason(line: str) -> str:
    """A refusal's construct, without the file, line, names and numbers (to group them)."""
    text = re.sub(r"^.*?:\d+(:\d+)?: ", "", line.strip()).partition(" (fix:")[0]
    text = re.sub(r"'[^']*'", "'…'", text)
    return re.sub(r"-?\d[\d.e+-]*", "N", text)[:90]


if __name__ == "__main__":
    main()
