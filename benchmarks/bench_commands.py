"""Whole commands as a user runs them: issue 16's goals for start-up, small calls, CSV and
evaluation memory.

    python benchmarks/bench_commands.py [--repeats 5] [--rows 1000000] [--json FILE]

Each command runs as its own process, ``--repeats`` times after one warm-up; its CPU time
(user + system) and peak resident memory come from the operating system's accounting of that
one process (GNU time's, or ``os.wait4``), and the median is quoted. Wall time is not
quoted: the machine is shared.

Goals (CPU seconds, peak MB):

1. ``flctool --version`` and ``flctool validate FILE``: <= 0.15 s.
2. ``flctool infer`` on 10 rows: <= 0.3 s; on a machine's first run (an empty numba
   cache) <= 0.8 s. Also measured, without a goal: the largest table inferred without numpy
   (``SMALL_TABLE`` rows, see flctool/cli/infer.py).
3. ``flctool infer`` on ``--rows`` rows (10^6): <= 1.5 s and <= 300 MB.
4. ``flctool evaluate``: peak memory independent of the number of episodes (10,000 against
   100,000 episodes; ratio goal <= 1.1).

Also the anchors, measured in the same run: a bare interpreter, and ``python -c "import
numpy"``; every command's CPU time is also given as a ratio to each anchor. Prints the
table and writes JSON (default: bench_commands.json beside the script). A script, never a
timed test.

flctool's bytecode is compiled first (``compileall``), as pip does for an installed package:
with an editable install and ``PYTHONDONTWRITEBYTECODE`` set, every process would otherwise
compile flctool's modules from source (about 0.05 s of each command).
"""

from __future__ import annotations

import argparse
import compileall
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from flctool.cli.infer import SMALL_TABLE

ROOT = Path(__file__).resolve().parents[1]
HANDMADE = ROOT / "behaviours" / "ballchase-handmade.yaml"
BALLCHASE = ROOT / "behaviours" / "ballchase.yaml"


@dataclass(frozen=True)
class Figure:
    cpu: float  # seconds, user + system
    peak_mb: float  # resident, MB (10^6 bytes)


GNU_TIME = Path("/usr/bin/time")


def run_once(command: list[str], env: dict[str, str] | None = None,
             stdin: Path | None = None) -> Figure:
    """One run of ``command``; its own CPU time and peak memory (not its siblings').

    CPU from ``os.wait4``. The peak through GNU time when the system has it: a child forked
    from this (large) Python process would count this process's memory in its peak until it
    execs. Without it, the child's own, which then has this process's size as a floor.
    """
    with tempfile.NamedTemporaryFile("r") as report, open(stdin or os.devnull, "rb") as source:
        timed = ([str(GNU_TIME), "-f", "%M", "-o", report.name, *command]
                 if GNU_TIME.exists() else command)
        process = subprocess.Popen(timed, stdin=source, stdout=subprocess.DEVNULL,
                                   stderr=subprocess.PIPE, env=env, cwd=ROOT)
        assert process.stderr is not None
        errors = process.stderr.read()
        _, status, usage = os.wait4(process.pid, 0)
        process.returncode = os.waitstatus_to_exitcode(status)
        if process.returncode != 0:
            raise SystemExit(f"{' '.join(command)} failed:\n"
                             f"{errors.decode(errors='replace')}")
        # CPU from wait4, to the microsecond (GNU time prints hundredths); it counts the
        # command and GNU time, which waited for it (about a millisecond).
        cpu = usage.ru_utime + usage.ru_stime
        if GNU_TIME.exists():
            peak_kib = report.read().split()[-1]
            return Figure(cpu, int(peak_kib) * 1024 / 1e6)
    # ru_maxrss is in KiB on Linux
    return Figure(cpu, usage.ru_maxrss * 1024 / 1e6)


def median_of(command: list[str], repeats: int, env: dict[str, str] | None = None,
              stdin: Path | None = None, warmup: bool = True) -> Figure:
    if warmup:
        run_once(command, env, stdin)
    runs = [run_once(command, env, stdin) for _ in range(repeats)]
    return Figure(statistics.median(r.cpu for r in runs),
                  statistics.median(r.peak_mb for r in runs))


def write_states(path: Path, rows: int) -> None:
    """A states CSV for the ballchase controller: ``rows`` rows, in blocks."""
    rng = np.random.default_rng(0)
    with path.open("w") as handle:
        handle.write("ball_size,pan\n")
        for start in range(0, rows, 100_000):
            count = min(100_000, rows - start)
            sizes = rng.uniform(0.0, 1.0, count)
            pans = rng.uniform(-90.0, 90.0, count)
            handle.write("".join(f"{s:.6f},{p:.4f}\n" for s, p in zip(sizes, pans,
                                                                         strict=True)))


def first_run_env(scratch: Path) -> dict[str, str]:
    """An environment in which flctool runs as on a machine where it never ran: an empty
    numba cache (pip compiles the bytecode of what it installs, so that is there)."""
    cache = scratch / "numba-cache"
    shutil.rmtree(cache, ignore_errors=True)
    cache.mkdir()
    return {**os.environ, "NUMBA_CACHE_DIR": str(cache)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--rows", type=int, default=1_000_000)
    parser.add_argument("--json", type=Path, default=Path(__file__).with_name(
        "bench_commands.json"))
    args = parser.parse_args()
    python = sys.executable
    flctool = [python, "-m", "flctool"]
    results: dict[str, dict[str, float]] = {}
    rows: list[tuple[str, str, str, str, str]] = []
    compileall.compile_dir(ROOT / "flctool", quiet=1)
    anchors: list[Figure] = []  # python -c pass, then python -c "import numpy"

    def record(name: str, figure: Figure, shown: str, goal: str, met: bool | None) -> None:
        ratios = [figure.cpu / a.cpu for a in anchors] if len(anchors) == 2 else []
        shown_ratios = " / ".join(f"{r:.2f}x" for r in ratios)
        results[name] = {"cpu_s": round(figure.cpu, 4), "peak_mb": round(figure.peak_mb, 1),
                         **({"cpu_to_bare_anchor": round(ratios[0], 3),
                             "cpu_to_numpy_anchor": round(ratios[1], 3)} if ratios else {})}
        rows.append((name, shown, shown_ratios, goal,
                     "-" if met is None else "yes" if met else "NO"))
        print(f"  {name}: {shown}" + (f" ({shown_ratios} the bare / numpy anchors)"
                                      if ratios else ""), flush=True)

    with tempfile.TemporaryDirectory() as folder:
        scratch = Path(folder)
        ten, many = scratch / "ten.csv", scratch / "many.csv"
        small_table = scratch / "small-table.csv"
        write_states(ten, 10)
        write_states(small_table, SMALL_TABLE)
        write_states(many, args.rows)
        r = args.repeats

        bare = median_of([python, "-c", "pass"], r)
        record("anchor: python -c pass", bare, f"{bare.cpu:.3f} s", "", None)
        anchors.append(bare)
        numpy_ = median_of([python, "-c", "import numpy"], r)
        record("anchor: python -c 'import numpy'", numpy_, f"{numpy_.cpu:.3f} s", "", None)
        anchors.append(numpy_)

        version = median_of([*flctool, "--version"], r)
        record("flctool --version", version, f"{version.cpu:.3f} s CPU", "<= 0.15 s",
               version.cpu <= 0.15)
        validate = median_of([*flctool, "validate", str(BALLCHASE)], r)
        record("flctool validate FILE", validate, f"{validate.cpu:.3f} s CPU", "<= 0.15 s",
               validate.cpu <= 0.15)

        infer = [*flctool, "infer", str(HANDMADE), "-i"]
        small = median_of([*infer, str(ten)], r)
        record("infer, 10 rows", small, f"{small.cpu:.3f} s CPU", "<= 0.3 s",
               small.cpu <= 0.3)
        firsts = [run_once([*infer, str(ten)], first_run_env(scratch)) for _ in range(r)]
        first = Figure(statistics.median(f.cpu for f in firsts),
                       statistics.median(f.peak_mb for f in firsts))
        record("infer, 10 rows, a machine's first run", first, f"{first.cpu:.3f} s CPU",
               "<= 0.8 s", first.cpu <= 0.8)
        largest_small = median_of([*infer, str(small_table)], r)
        record(f"infer, {SMALL_TABLE:,} rows (no numpy)", largest_small,
               f"{largest_small.cpu:.3f} s CPU", "", None)
        large = median_of([*infer, str(many)], max(1, r // 2))
        record(f"infer, {args.rows:,} rows", large,
               f"{large.cpu:.3f} s CPU, {large.peak_mb:.0f} MB", "<= 1.5 s, <= 300 MB",
               large.cpu <= 1.5 and large.peak_mb <= 300)

        evaluate = [*flctool, "evaluate", str(HANDMADE), "--json", "--episodes"]
        few = median_of([*evaluate, "10000"], 1)
        lots = median_of([*evaluate, "100000"], 1, warmup=False)
        ratio = lots.peak_mb / few.peak_mb
        record("evaluate, 10,000 episodes", few, f"{few.peak_mb:.0f} MB, {few.cpu:.2f} s CPU",
               "", None)
        record("evaluate, 100,000 episodes", lots,
               f"{lots.peak_mb:.0f} MB ({ratio:.2f}x), {lots.cpu:.2f} s CPU",
               "memory <= 1.1x", ratio <= 1.1)

    width = max(len(row[0]) for row in rows)
    print(f"\n{'command':<{width}}  {'figure (median)':<34} {'/ bare / numpy':<18} "
          f"{'goal':<22} met")
    for name, shown, ratio, goal, met in rows:
        print(f"{name:<{width}}  {shown:<34} {ratio:<18} {goal:<22} {met}")
    args.json.write_text(json.dumps({"repeats": args.repeats, "rows": args.rows,
                                     "results": results}, indent=2) + "\n")
    print(f"\nwrote {args.json}")


if __name__ == "__main__":
    main()
