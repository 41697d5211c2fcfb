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

Where GNU Octave with its fuzzy-logic-toolkit is installed, every imported ``.fis`` file (exact
or approximated) is also evaluated there (``readfis`` / ``evalfis``) on the same 2,000
states, in one Octave process for all files (each distinct file once, a time limit of
``--octave-timeout`` seconds for the whole run), and compared with the imported controller
the same way: the largest difference over every output against the stated bound (0 for an
exact import), 1 % and 1e-12 allowed. A file Octave fails to read or evaluate is counted
as not runnable in Octave, not as a failure.

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
import time
from collections import Counter
from dataclasses import dataclass
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


@dataclass
class Sample:
    """An imported file's STATES random states inside the ranges (seed 0), the imported
    controller's outputs on them (S, outputs) and the stated bound (0 when exact)."""

    states: np.ndarray
    outputs: np.ndarray
    bound: float = 0.0


def sample(behaviours: list[Behaviour]) -> Sample:
    """The states an import is checked on and flctool's outputs there."""
    controllers = [compile_behaviour(b) for b in behaviours]
    first = controllers[0]
    rng = np.random.default_rng(0)
    states = rng.uniform(first.ranges[:, 0], first.ranges[:, 1], (STATES, first.n_inputs))
    return Sample(states, np.column_stack([c.output(states) for c in controllers]))


def largest(got: np.ndarray, want: np.ndarray) -> float:
    """The largest |got - want| over every state and output (nan if either is nan there)."""
    return float(np.max(np.abs(got.reshape(want.shape) - want)))


def difference(path: Path, drawn: Sample) -> float | None:
    """The largest |fuzzylite 6 - flctool| over the sample's states, over every output, or
    None without the fuzzylite command."""
    got = fuzzylite_outputs(path, drawn.states)
    return None if got is None else largest(got, drawn.outputs)


#: The Octave script: for each file i, readfis + evalfis on states<i>.txt, writing
#: out<i>.txt (renamed into place when complete) or error<i>.txt.
OCTAVE_SCRIPT = """\
pkg load fuzzy-logic-toolkit;
for i = 1:%d
  try
    fis = readfis(sprintf('file%%d.fis', i));
    y = evalfis(load(sprintf('states%%d.txt', i)), fis);
    f = fopen(sprintf('part%%d.txt', i), 'w');
    fprintf(f, '%%.17g\\n', y');
    fclose(f);
    rename(sprintf('part%%d.txt', i), sprintf('out%%d.txt', i));
  catch err
    f = fopen(sprintf('error%%d.txt', i), 'w');
    fprintf(f, '%%s', err.message);
    fclose(f);
  end_try_catch
endfor
"""


def octave_outputs(files: list[tuple[bytes, np.ndarray]], timeout: float
                   ) -> list[np.ndarray | str] | None:
    """Octave fuzzy-logic-toolkit's ``evalfis`` outputs (S, outputs) for each (FIS file
    content, states), or the reason it gave none; one Octave process for all, stopped after
    ``timeout`` seconds. None without Octave."""
    octave = shutil.which("octave-cli") or shutil.which("octave")
    if octave is None:
        return None
    with tempfile.TemporaryDirectory() as name:
        folder = Path(name)
        for i, (content, states) in enumerate(files, 1):
            (folder / f"file{i}.fis").write_bytes(content)
            np.savetxt(folder / f"states{i}.txt", states, fmt="%.17g")
        (folder / "check.m").write_text(OCTAVE_SCRIPT % len(files))
        stopped = ""
        try:
            result = subprocess.run(
                [octave, "--no-gui", "--quiet", "--no-init-file", "--no-history",
                 "check.m"], cwd=folder, capture_output=True, text=True, timeout=timeout,
                check=False)
            if "package" in result.stderr and "not installed" in result.stderr:
                return None
            if result.returncode != 0:
                stopped = (f"Octave stopped (exit {result.returncode}): "
                           f"{result.stderr.strip()[-300:]}")
        except subprocess.TimeoutExpired:
            stopped = f"not evaluated within the {timeout:g} s allowed for Octave"
        got: list[np.ndarray | str] = []
        for i in range(1, len(files) + 1):
            out, error = folder / f"out{i}.txt", folder / f"error{i}.txt"
            if out.exists():
                got.append(np.array([float(v) for v in out.read_text().split()]))
            elif error.exists():
                got.append("Octave: " + " ".join(error.read_text().split()))
            else:
                got.append(stopped or "Octave gave no output")
    return got


def stated(report: str) -> float:
    """The largest deviation the conversion reports (over every output)."""
    found = [float(m) for m in re.findall(
        r"from the (?:Mamdani|Takagi-Sugeno) output .*? is ([0-9.e+-]+)", report)]
    return max(found, default=float("nan"))


def outcome(path: Path, convert: dict[str, bool]) -> tuple[str, str, Sample | None]:
    """(exact | approximated | incomplete | clear | unclear, message, the sample an import
    is checked on) for one file."""
    importer = IMPORTERS.get(path.suffix[1:].lower())()
    try:
        behaviours = importer.from_file_all(path)
    except FlcError as error:
        exact_error = error
    except Exception as error:
        return "unclear", f"{type(error).__name__}: {error}", None
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
            return "unclear", f"{type(error).__name__}: {error}", None
        else:
            return measured(path, behaviours, "approximated", importer.report)
    return ("clear" if clear(exact_error, path) else "unclear"), str(exact_error), None


def measured(path: Path, behaviours: list[Behaviour], kind: str, report: str
             ) -> tuple[str, str, Sample | None]:
    """An imported file's outcome, with fuzzylite 6's difference from it."""
    if not all(b.is_deployable for b in behaviours):
        return "incomplete", ("imported, but the rules do not give every combination of sets "
                              "a command, so the controller is not deployable"), None
    unevaluated = ""
    drawn = sample(behaviours)
    try:
        gap = difference(path, drawn)
    except (subprocess.SubprocessError, ValueError) as error:
        gap, unevaluated = None, f"fuzzylite 6 did not evaluate the file: {error}"
    text = unevaluated or ("" if gap is None else f"max |fuzzylite 6 - flctool| = {gap:.3g}")
    if kind == "approximated":
        bound = drawn.bound = stated(report)
        within = "not checked" if gap is None else within_bound(gap, bound)
        shares = [float(s) for s in re.findall(r"\(([0-9.]+)% of the output(?: range|'s span)",
                                                report)]
        share = f" ({max(shares):.2f}% of the output range)" if shares else ""
        text += f"; stated {bound:.4g}{share}; within it: {within}"
    return kind, text, drawn


def within_bound(gap: float, bound: float) -> bool:
    """Whether a reference engine's difference stays within the stated bound: 1 % allowed
    (the bound is measured on other states), and 1e-12 (engines round differently, and some
    conversions state ~1e-16)."""
    return gap <= 1.01 * bound + 1e-12


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
    parser.add_argument("--octave-timeout", type=float, default=1800, metavar="SECONDS",
                        help="time allowed for the one Octave process that evaluates every "
                        "imported FIS file (default 1800)")
    args = parser.parse_args()
    kinds = ("exact", "approximated", "incomplete", "clear", "unclear")
    total: Counter[str] = Counter()
    distinct: dict[bytes, str] = {}  # a file's content -> its outcome (copies count once)
    reasons: Counter[str] = Counter()  # the first construct each refused file lists
    every: Counter[str] = Counter()  # every construct each refused file lists
    alone: Counter[str] = Counter()  # the constructs that are a refused file's only one
    shares: dict[bytes, float] = {}  # an approximated file's stated share of its range
    by_folder: dict[Path, list[float]] = {}
    fis_files: list[tuple[Path, Path, bytes, Sample]] = []  # (folder, file, content, sample)
    for folder in args.folders:
        counts: Counter[str] = Counter()
        files = sorted(p for p in folder.rglob("*") if p.suffix.lower() in SUFFIXES)
        for path in files:
            kind, message, drawn = outcome(path, {"mamdani_singletons": args.convert_mamdani,
                                                  "linear_singletons": args.convert_linear})
            counts[kind] += 1
            content = path.read_bytes()
            if drawn is not None and path.suffix.lower() == ".fis":
                fis_files.append((folder, path, content, drawn))
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
    octave_check(args.folders, fis_files, args.octave_timeout, args.list)
    for title, table in (("refusals of distinct files by their first construct", reasons),
                         ("refused distinct files listing each construct", every),
                         ("refused distinct files whose only construct it is", alone)):
        print(f"{title}:")
        for text, count in table.most_common():
            print(f"  {count:4}  {text}")
    sys.exit(0)


def octave_check(folders: list[Path], fis_files: list[tuple[Path, Path, bytes, Sample]],
                 timeout: float, listing: bool) -> None:
    """Evaluates every imported FIS file in Octave (each distinct one once) and prints, per
    folder, in total and over distinct files: imported, checked by Octave, within the bound,
    beyond it (each with both numbers) and not runnable in Octave."""
    distinct = {content: drawn for _, _, content, drawn in fis_files}
    started = time.monotonic()
    got = octave_outputs([(c, d.states) for c, d in distinct.items()], timeout)
    if got is None:
        print("Octave check: skipped (octave-cli / octave with the fuzzy-logic-toolkit "
              "package is not installed)")
        return
    elapsed = time.monotonic() - started
    results = dict(zip(distinct, got, strict=True))
    heads = ("FIS imported", "checked by Octave", "within the bound", "beyond it",
             "not runnable in Octave")
    total: Counter[str] = Counter()
    unique: Counter[str] = Counter()
    seen: set[bytes] = set()
    print(f"Octave fuzzy-logic-toolkit (readfis / evalfis on the same {STATES:,} states, "
          f"{len(distinct)} distinct FIS files in one process, {elapsed:.0f} s):")
    for folder in folders:
        counts: Counter[str] = Counter()
        for where, path, content, drawn in fis_files:
            if where != folder:
                continue
            found = results[content]
            counts[heads[0]] += 1
            if not isinstance(found, str) and found.size != drawn.outputs.size:
                found = f"Octave gave {found.size} numbers for {drawn.outputs.size} outputs"
            if isinstance(found, str):
                verdict = heads[4]
                print(f"  not runnable in Octave: {path}: {found[:200]}")
            else:
                gap = largest(found, drawn.outputs)
                verdict = heads[2] if within_bound(gap, drawn.bound) else heads[3]
                if verdict == heads[3]:
                    bad = int(np.sum(~np.isfinite(found)))
                    print(f"  beyond the bound in Octave: {path}: max |Octave - flctool| = "
                          f"{gap:.4g}, stated {drawn.bound:.4g}"
                          + (f" ({bad} outputs not finite in Octave)" if bad else ""))
                elif listing:
                    print(f"  {path}: max |Octave - flctool| = {gap:.4g}, "
                          f"stated {drawn.bound:.4g}")
            counts[verdict] += 1
            if verdict != heads[4]:
                counts[heads[1]] += 1
            if content not in seen:
                seen.add(content)
                unique.update({heads[0]: 1, verdict: 1,
                               **({heads[1]: 1} if verdict != heads[4] else {})})
        total += counts
        print(f"  {folder}: " + ", ".join(f"{h} {counts[h]}" for h in heads))
    print("  total: " + ", ".join(f"{h} {total[h]}" for h in heads))
    print("  distinct: " + ", ".join(f"{h} {unique[h]}" for h in heads))


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
