"""A deployment bundle: the controller, its wiring, and a harness per target.

``flctool export SOURCE --format bundle -o DIR`` writes the folder DIR with:

- ``controller.yaml``: the deployable behaviour (the Python target loads it with flctool);
- ``<name>.h`` / ``<name>.c``: the C export (double, prefix ``flc_``);
- ``wiring.json``: where each input comes from (an observation index, or a sensor's name),
  its unit and range, the commands with their singletons, and how the crisp output becomes
  an action (the environment's ``action`` setting, and a Gymnasium environment's action
  indices);
- ``harness.c`` and ``harness.py``: read one raw observation per line on stdin (the whole
  Gymnasium observation vector, or the sensors' values in the wiring's order), wire it into
  the controller's state, and print ``output command_index command_name action`` per line.

The harnesses are the wiring executed, not re-implemented by hand: both are generated from the
same wiring, and the tests check them against each other and against flctool.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from flctool.behaviour import Behaviour, require_deployable
from flctool.behaviour.base import identifier
from flctool.errors import ExportError
from flctool.export.base import Exporter, ExportOptions, write_files
from flctool.export.c_source import CExporter
from flctool.export.yaml_format import YamlExporter
from flctool.version import __version__

#: The wiring file's format version.
WIRING_VERSION = 1


def wiring(behaviour: Behaviour) -> dict[str, Any]:
    """The controller's connections to the world, as ``wiring.json`` holds them."""
    environment = behaviour.environment
    adapter = environment.adapter if environment is not None else None
    if adapter is not None and behaviour.acts_by_vote:
        raise ExportError("the behaviour's environment.action is vote, which the bundle's "
                          "harnesses do not compute (they execute the crisp output or the "
                          "nearest command)",
                          hint="export --format c (its <prefix>command is the vote), or "
                          "set environment.action to nearest (or crisp)")
    inputs = []
    observations = getattr(environment, "observations", {}) or {}
    for i, (name, variable) in enumerate(behaviour.inputs.items()):
        source: dict[str, Any]
        if adapter == "gymnasium":
            source = {"observation_index": observations.get(name, i)}
        else:  # the ballchase simulator and the robot link name their sensors as inputs
            source = {"sensor": name}
        inputs.append({"name": name, "state_index": i, "range": list(variable.range),
                       "unit": variable.unit or "", "source": source})
    commands = behaviour.output.commands
    actions = getattr(environment, "actions", {}) or {}
    command_list = []
    for k, (name, value) in enumerate(commands.items()):
        entry: dict[str, Any] = {"index": k, "name": name, "value": value}
        if name in actions:
            entry["action"] = actions[name]
        command_list.append(entry)
    if adapter == "gymnasium" and actions:
        action = {"kind": "discrete", "execute": "nearest",
                  "about": "the Gymnasium action of the command nearest the crisp output"}
    elif adapter == "gymnasium":
        action = {"kind": "box", "execute": "crisp",
                  "about": "the crisp output is the Gymnasium action"}
    elif getattr(environment, "action", "crisp") == "nearest":
        action = {"kind": "command", "execute": "nearest",
                  "about": "the robot executes the command nearest the crisp output"}
    else:
        action = {"kind": "crisp", "execute": "crisp",
                  "about": "the robot executes the crisp output (e.g. blending the two "
                  "neighbouring commands)"}
    return {"wiring": WIRING_VERSION, "flctool": __version__, "name": behaviour.name,
            "environment": {"adapter": adapter, "id": getattr(environment, "id", None)},
            "inputs": inputs,
            "output": {"name": behaviour.output.name, "unit": behaviour.output.unit or "",
                       "range": [min(commands.values()), max(commands.values())]},
            "commands": command_list, "action": action}


class BundleExporter(Exporter):
    format = "bundle"

    def to_string(self, behaviour: Behaviour) -> str:
        require_deployable(behaviour)
        raise ExportError("a bundle is a folder of several files",
                          hint="give the folder to write with -o DIR")

    def texts(self, behaviour: Behaviour, path: Path) -> dict[Path, str]:
        require_deployable(behaviour)
        if getattr(behaviour.environment, "compose", None):
            from flctool.export.composed_bundle import composed_texts

            return composed_texts(behaviour, path, self.options)
        wires = wiring(behaviour)
        stem = identifier(behaviour.name)
        c_files = CExporter(ExportOptions(provenance=self.options.provenance)).texts(
            behaviour, path / stem)
        texts = {path / "controller.yaml": YamlExporter(self.options).to_string(behaviour),
                 path / "wiring.json": json.dumps(wires, indent=2) + "\n",
                 **c_files,
                 path / "harness.c": c_harness(wires, f"{stem}.h"),
                 path / "harness.py": python_harness(wires)}
        return texts

    def to_file(self, behaviour: Behaviour, path: str | Path, *, force: bool = False
                ) -> list[Path]:
        folder = Path(path)
        if folder.exists() and not folder.is_dir():
            raise ExportError(f"{folder} is a file; a bundle is a folder",
                              hint="give a folder name with -o")
        texts = self.texts(behaviour, folder)  # everything checked before the folder is made
        if not folder.parent.is_dir():
            raise ExportError(f"cannot write {folder}: the folder {folder.parent} does not "
                              "exist", hint=f"create it first (mkdir -p {folder.parent})")
        try:
            folder.mkdir(exist_ok=True)
        except OSError as exc:
            raise ExportError(f"cannot create {folder}: {exc.strerror or exc}",
                              hint="choose another path with -o") from None
        return write_files(texts, force=force)


def _source_indices(wires: dict[str, Any]) -> list[int]:
    """Where each input is in the harness's input line: its observation index, or (for
    named sensors) its place in the wiring's input list."""
    return [int(i["source"].get("observation_index", i["state_index"]))
            for i in wires["inputs"]]


def c_harness(wires: dict[str, Any], header: str) -> str:
    """A C99 program: raw observations on stdin, one line each, to actions on stdout."""
    indices = _source_indices(wires)
    width = max(indices) + 1
    names = ", ".join(json.dumps(c["name"]) for c in wires["commands"])
    discrete = wires["action"]["kind"] == "discrete"
    actions = ", ".join(str(c.get("action", -1)) for c in wires["commands"])
    if discrete:
        act = 'printf("%d", flc_actions[k]);'
    elif wires["action"]["kind"] == "command":
        act = 'printf("%s", k < 0 ? "none" : flc_command_names[k]);'
    else:
        act = 'printf("%.17g", out);'
    return f"""\
/* {wires['name']}: the deployment harness written by flctool {wires['flctool']}.
 * Reads one raw observation per line ({width} numbers: {_describe(wires)}),
 * wires it into the controller's state and prints
 *     output command_index command_name action
 * where action is: {wires['action']['about']}.
 * Build: cc -std=c99 -O2 -o harness harness.c {header[:-2]}.c */
#include <stdio.h>
#include <stdlib.h>
#include "{header}"

static const int flc_sources[FLC_N_INPUTS] = {{{', '.join(map(str, indices))}}};
static const char *const flc_command_names[FLC_N_COMMANDS] = {{{names}}};
static const int flc_actions[FLC_N_COMMANDS] = {{{actions}}};

int main(void)
{{
    char line[65536];
    double raw[{width}], state[FLC_N_INPUTS], out;
    int i, k;
    while (fgets(line, sizeof line, stdin) != NULL) {{
        char *at = line, *end;
        for (i = 0; i < {width}; ++i) {{
            raw[i] = strtod(at, &end);
            if (end == at) {{
                fprintf(stderr, "harness: expected {width} numbers per line\\n");
                return 1;
            }}
            at = end;
        }}
        for (i = 0; i < FLC_N_INPUTS; ++i) state[i] = raw[flc_sources[i]];
        out = flc_output(state);
        k = flc_command(state);
        printf("%.17g %d %s ", out, k, k < 0 ? "none" : flc_command_names[k]);
        {act}
        printf("\\n");
    }}
    (void)flc_actions;
    (void)flc_command_names;
    return 0;
}}
"""


def _describe(wires: dict[str, Any]) -> str:
    parts = []
    for item in wires["inputs"]:
        source = item["source"]
        where = (f"observation[{source['observation_index']}]" if "observation_index" in source
                 else f"sensor '{source['sensor']}'")
        parts.append(f"{item['name']} = {where}")
    return "; ".join(parts)


def python_harness(wires: dict[str, Any]) -> str:
    """A Python program with flctool: the same input and output lines as the C harness."""
    return f'''\
"""{wires['name']}: the deployment harness written by flctool {wires['flctool']}.

Needs flctool (pip install flctool). As a program it reads one raw observation per line on
stdin ({_describe(wires)}) and prints ``output command_index command_name action``;
as a module, ``decide(observation)`` returns the same four values.
"""

import json
import sys
from pathlib import Path

import numpy as np

from flctool import compile_behaviour, load_behaviour

HERE = Path(__file__).resolve().parent
WIRING = json.loads((HERE / "wiring.json").read_text(encoding="utf-8"))
CONTROLLER = compile_behaviour(load_behaviour(HERE / "controller.yaml"))
SOURCES = [int(i["source"].get("observation_index", i["state_index"]))
           for i in WIRING["inputs"]]
VALUES = np.array([c["value"] for c in WIRING["commands"]])
#: command indices sorted by singleton: on a tie the smaller singleton is nearest
ORDER = np.argsort(VALUES, kind="stable")


def decide(observation):
    """(output, command index, command name, action) for one raw observation."""
    raw = np.asarray(observation, dtype=np.float64).reshape(-1)
    state = raw[SOURCES]
    if np.isnan(state).any():
        return float("nan"), -1, "none", None
    output = float(CONTROLLER.output(state[None, :])[0])
    k = int(ORDER[int(np.argmin(np.abs(VALUES[ORDER] - output)))])
    command = WIRING["commands"][k]
    kind = WIRING["action"]["kind"]
    action = (command["action"] if kind == "discrete" else
              command["name"] if kind == "command" else output)
    return output, k, command["name"], action


def main():
    width = max(SOURCES) + 1
    for line in sys.stdin:
        numbers = [float(v) for v in line.split()[:width]]
        if len(numbers) < width:
            sys.exit(f"harness: expected {{width}} numbers per line")
        output, k, name, action = decide(numbers)
        shown = repr(action) if isinstance(action, float) else action
        print(f"{{output!r}} {{k}} {{name}} {{shown}}")


if __name__ == "__main__":
    main()
'''
