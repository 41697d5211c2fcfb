"""pyfuzzylite 8's array inference against flctool's, on the ballchase controller.

    python -m venv /tmp/pfl8 && /tmp/pfl8/bin/pip install 'pyfuzzylite>=8,<9' 'numpy<2'
    python benchmarks/bench_pyfuzzylite8.py --python8 /tmp/pfl8/bin/python [--json PATH]

pyfuzzylite 8 infers arrays of states at once, but pins numpy < 2, so it cannot share
flctool's environment: it runs in its own interpreter (``--python8``), reading flctool's FLL
export of the controller and the states from a temporary directory, and hands back its
outputs and CPU times. Its outputs are checked equal to flctool's (within 1e-9) before any
figure is printed. Both sides: CPU time (``time.process_time``), the least of ``--repeats``,
per state, at each batch size; flctool runs its compiled kernels (``set_inference``) and,
for the record, its numpy path. Writes JSON (default: bench_pyfuzzylite8.json beside this
script).
"""

from __future__ import annotations

import argparse
import json
import subprocess
import tempfile
import time
from pathlib import Path

import common
import numpy as np

import flctool
from flctool.compile import controller as controller_module
from flctool.export.fll import FllExporter

BATCHES = (1_000, 100_000, 1_000_000)
TOLERANCE = 1e-9

# Runs in pyfuzzylite 8's interpreter: only numpy and fuzzylite there.
MEASURE = """
import json, sys, time
import numpy as np
import fuzzylite as fl
folder, repeats = sys.argv[1], int(sys.argv[2])
engine = fl.FllImporter().from_string(open(folder + "/controller.fll").read())
result = {"version": fl.__version__, "numpy": np.__version__, "batches": {}}
for path in sorted(__import__("glob").glob(folder + "/states-*.npy")):
    states = np.load(path)
    best = float("inf")
    for _ in range(repeats):
        started = time.process_time()
        for i, variable in enumerate(engine.input_variables):
            variable.value = states[:, i]
        engine.process()
        out = np.array(engine.output_variables[0].value, dtype=np.float64)
        best = min(best, time.process_time() - started)
    np.save(path.replace("states-", "out-"), out)
    result["batches"][str(len(states))] = best
print(json.dumps(result))
"""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--python8", required=True,
                        help="an interpreter with pyfuzzylite 8 (and numpy < 2) installed")
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--json", type=Path, default=Path(__file__).with_suffix(".json"))
    args = parser.parse_args()
    behaviour = flctool.load_behaviour(common.BALLCHASE)
    controller = flctool.compile_behaviour(behaviour)
    with tempfile.TemporaryDirectory() as folder:
        (Path(folder) / "controller.fll").write_text(FllExporter().to_string(behaviour))
        states = {b: common.uniform_states(controller, b, seed=b) for b in BATCHES}
        for batch, array in states.items():
            np.save(Path(folder) / f"states-{batch:08d}.npy", array)
        done = subprocess.run([args.python8, "-c", MEASURE, folder, str(args.repeats)],
                              capture_output=True, text=True, check=True)
        theirs = json.loads(done.stdout)
        outputs = {b: np.load(Path(folder) / f"out-{b:08d}.npy") for b in BATCHES}
    rows = []
    for mode in ("kernels", "numpy"):
        controller_module.set_inference(mode)
        controller.output(states[BATCHES[0]])  # the kernels loaded (or compiled) first
        for batch in BATCHES:
            expected = controller.output(states[batch])
            difference = common.check_equal(f"pyfuzzylite 8 at B = {batch}", outputs[batch],
                                            expected, TOLERANCE)
            ours = common.best_seconds(lambda b=batch: controller.output(states[b]),
                                       args.repeats)
            rows.append({"flctool_path": mode, "batch": batch,
                         "flctool_ns_per_state": ours / batch * 1e9,
                         "pyfuzzylite8_ns_per_state": theirs["batches"][str(batch)] / batch
                         * 1e9, "ratio": theirs["batches"][str(batch)] / ours,
                         "max_difference": difference})
    print(f"pyfuzzylite {theirs['version']} (numpy {theirs['numpy']}) against flctool "
          f"{flctool.__version__}, CPU ns per state, least of {args.repeats}:")
    print("| flctool path | batch | flctool | pyfuzzylite 8 | flctool faster |")
    print("| --- | ---: | ---: | ---: | ---: |")
    for row in rows:
        print(f"| {row['flctool_path']} | {row['batch']:,} | {row['flctool_ns_per_state']:,.1f} "
              f"| {row['pyfuzzylite8_ns_per_state']:,.0f} | {row['ratio']:,.1f}x |")
    common.write_json(args.json, {
        "benchmark": "bench_pyfuzzylite8", "when": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
        "machine": common.machine(), "pyfuzzylite": theirs["version"],
        "pyfuzzylite_numpy": theirs["numpy"], "repeats": args.repeats, "rows": rows,
        "timing": "CPU time, least of the repeats"})
    print(f"wrote {args.json.name}")


if __name__ == "__main__":
    main()
