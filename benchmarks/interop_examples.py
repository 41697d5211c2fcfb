"""How many of the example controllers that other toolchains ship flctool imports.

    python benchmarks/interop_examples.py DIR [DIR ...] [--convert-mamdani] [--list]

Walks each folder for ``.fll``, ``.fis`` and ``.fcl`` files and imports each one in process,
then counts, per folder and in total:

- **exact**: imported, and the controller computes what the file says;
- **approximated**: imported only with ``--convert-mamdani`` (a Mamdani FIS whose output sets
  are replaced by singletons at their centroids), with the largest deviation the import
  measured;
- **refused, clear**: refused with one of flctool's errors that names the file and a line,
  says what is not supported and gives a fix (``(fix: ...)``);
- **refused, unclear**: refused with any other exception, or with a message lacking the
  file and line or the fix. The goal is zero.

Where the fuzzylite 6 command line is installed, every exact import is checked against it:
fuzzylite evaluates the original file on 1,000 random states inside the ranges (flctool clips,
the file may not), and the largest difference from the imported controller is printed.

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
from flctool.errors import FlcError, SpecError
from flctool.export import IMPORTERS
from flctool.spec import Behaviour

SUFFIXES = (".fll", ".fis", ".fcl")


def fuzzylite_difference(path: Path, behaviour: Behaviour) -> float | None:
    """The largest |fuzzylite 6 - flctool| over 1,000 states inside the ranges, or None
    without the fuzzylite command."""
    binary = shutil.which("fuzzylite")
    if binary is None:
        return None
    controller = compile_behaviour(behaviour)
    rng = np.random.default_rng(0)
    states = rng.uniform(controller.ranges[:, 0], controller.ranges[:, 1],
                         (1_000, controller.n_inputs))
    with tempfile.TemporaryDirectory() as folder:
        data = Path(folder) / "states.fld"
        data.write_text("\n".join(" ".join(repr(float(x)) for x in row) for row in states))
        result = subprocess.run(
            [binary, "-i", str(path), "-if", path.suffix[1:].lower(), "-of", "fld", "-d",
             str(data), "-dheader", "false", "-dinputs", "false", "-decimals", "17"],
            capture_output=True, text=True, timeout=120, check=True)
    got = np.array([float(v) for v in result.stdout.split()])
    return float(np.max(np.abs(got - controller.output(states))))


def outcome(path: Path, convert: bool) -> tuple[str, str]:
    """(exact | approximated | clear | unclear, message) for one file."""
    importer = IMPORTERS.get(path.suffix[1:].lower())()
    try:
        behaviour = importer.from_file(path)
    except FlcError as error:
        exact_error = error
    except Exception as error:
        return "unclear", f"{type(error).__name__}: {error}"
    else:
        difference = fuzzylite_difference(path, behaviour)
        return "exact", ("" if difference is None else
                         f"max |fuzzylite 6 - flctool| = {difference:.3g}")
    if convert and path.suffix.lower() == ".fis":
        importer = IMPORTERS.get("fis")(mamdani_singletons=True)  # type: ignore[call-arg]
        try:
            importer.from_file(path)
        except FlcError:
            pass
        except Exception as error:
            return "unclear", f"{type(error).__name__}: {error}"
        else:
            return "approximated", getattr(importer, "report", "")
    return ("clear" if clear(exact_error, path) else "unclear"), str(exact_error)


def clear(error: FlcError, path: Path) -> bool:
    """The refusal names the file and a line, and says how to fix it."""
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
    parser.add_argument("--list", action="store_true", help="print every file's outcome")
    args = parser.parse_args()
    kinds = ("exact", "approximated", "clear", "unclear")
    total: Counter[str] = Counter()
    for folder in args.folders:
        counts: Counter[str] = Counter()
        files = sorted(p for p in folder.rglob("*") if p.suffix.lower() in SUFFIXES)
        for path in files:
            kind, message = outcome(path, args.convert_mamdani)
            counts[kind] += 1
            if kind == "exact" and message:
                print(f"exact: {path}: {message}")
            if args.list:
                print(f"{kind:12} {path}: {message.splitlines()[0] if message else ''}")
        total += counts
        print(f"{folder}: {len(files)} files; " + ", ".join(f"{k} {counts[k]}" for k in kinds))
    print(f"total: {sum(total.values())} files; " + ", ".join(f"{k} {total[k]}" for k in kinds))
    sys.exit(0)


if __name__ == "__main__":
    main()
