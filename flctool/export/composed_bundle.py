"""The deployment bundle of a composed behaviour: the arbiter and every part, in C, with one
function that runs the composition.

``flctool export COMPOSED --format bundle -o DIR`` writes, besides ``controller.yaml`` (the
composition, parts inlined) and ``wiring.json`` (the channels in order, the arbiter's and each
part's inputs as places among them, their commands):

- ``arbiter.h`` / ``arbiter.c`` (prefix ``flc_arbiter_``) and ``part_<name>.h`` /
  ``part_<name>.c`` (prefix ``flc_<name>_``): the C export of each controller;
- ``composed.h`` / ``composed.c``: ``flc_composed_step(readings, &part, &output, &command)``
  -- the arbiter's nearest command names the part, the part's controller reads its inputs
  from the same readings, and its output and nearest command are returned, as the pitch
  world runs a composition (envs/pitch_compose.py);
- ``harness.c`` and ``harness.py``: one line of channel readings in, ``part_index part_name
  output command_index command_name`` out; the tests check both against flctool.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from flctool.behaviour import Behaviour, require_deployable
from flctool.behaviour.base import identifier
from flctool.behaviour.environment import PitchConfig
from flctool.errors import ExportError
from flctool.export.base import ExportOptions
from flctool.export.c_source import CExporter
from flctool.export.yaml_format import YamlExporter
from flctool.version import __version__

#: The composed wiring file's format version.
COMPOSED_WIRING_VERSION = 1


def parts_of(behaviour: Behaviour) -> dict[str, Behaviour]:
    """The composition's parts by command name, validated (they are inlined when loaded)."""
    from flctool.behaviour.load import behaviour_from_data

    environment = behaviour.environment
    assert isinstance(environment, PitchConfig)
    parts = {}
    for name, data in environment.compose.items():
        if not isinstance(data, dict):
            raise ExportError(f"the part '{name}' was not loaded",
                              hint="export the composed behaviour from its file")
        parts[name] = behaviour_from_data(data)
        require_deployable(parts[name])
    return parts


def composed_wiring(behaviour: Behaviour, parts: dict[str, Behaviour]) -> dict[str, Any]:
    """Channels in order (the arbiter's inputs', then what only the parts read) and where
    each controller's inputs are among them."""
    environment = behaviour.environment
    assert isinstance(environment, PitchConfig)
    channels = [environment.channel_of(name) for name in behaviour.input_names]
    entries = []
    commands = list(behaviour.output.commands)
    for name, part in parts.items():
        part_env = part.environment
        sensors = part_env.channel_of if isinstance(part_env, PitchConfig) else str
        places = []
        for input_name in part.input_names:
            channel = sensors(input_name)
            if channel not in channels:
                channels.append(channel)
            places.append(channels.index(channel))
        entries.append({"name": name, "index": commands.index(name),
                        "prefix": f"flc_{identifier(name)}_", "inputs": places,
                        "commands": [{"index": k, "name": c, "value": v} for k, (c, v) in
                                     enumerate(part.output.commands.items())]})
    return {"wiring": COMPOSED_WIRING_VERSION, "flctool": __version__, "name": behaviour.name,
            "composed": True, "channels": channels,
            "arbiter": {"inputs": [channels.index(environment.channel_of(n))
                                   for n in behaviour.input_names],
                        "commands": [{"index": k, "name": c, "value": v} for k, (c, v) in
                                     enumerate(behaviour.output.commands.items())]},
            "parts": sorted(entries, key=lambda e: int(e["index"]))}


def composed_texts(behaviour: Behaviour, path: Path, options: ExportOptions,
                   ) -> dict[Path, str]:
    require_deployable(behaviour)
    if behaviour.acts_by_vote:
        raise ExportError("the composition's environment.action is vote, which the bundle "
                          "does not compute (its arbiter runs the nearest command's part)",
                          hint="set environment.action to nearest")
    parts = parts_of(behaviour)
    wires = composed_wiring(behaviour, parts)
    texts = {path / "controller.yaml": YamlExporter(options).to_string(behaviour),
             path / "wiring.json": json.dumps(wires, indent=2) + "\n"}
    texts.update(CExporter(ExportOptions(provenance=options.provenance,
                                         prefix="flc_arbiter_")).texts(
        behaviour, path / "arbiter"))
    for entry in wires["parts"]:
        texts.update(CExporter(ExportOptions(prefix=entry["prefix"])).texts(
            parts[entry["name"]], path / f"part_{identifier(entry['name'])}"))
    texts[path / "composed.h"] = _composed_header(wires)
    texts[path / "composed.c"] = _composed_source(wires)
    texts[path / "harness.c"] = _c_harness(wires)
    texts[path / "harness.py"] = _python_harness(wires)
    return texts


def _composed_header(wires: dict[str, Any]) -> str:
    channels = "\n".join(f" *   readings[{i}] {c}" for i, c in enumerate(wires["channels"]))
    return f"""\
/* {wires['name']}: a composed behaviour, written by flctool {wires['flctool']}.
 * The readings hold the channels in this order:
{channels}
 */
#ifndef FLC_COMPOSED_H
#define FLC_COMPOSED_H

#define FLC_COMPOSED_N_CHANNELS {len(wires['channels'])}
#define FLC_COMPOSED_N_PARTS {len(wires['parts'])}

#ifdef __cplusplus
extern "C" {{
#endif

/* One step: the arbiter's nearest command names the part that runs (*part, its command
   index in the arbiter); the part's controller reads its inputs from the same readings and
   gives its output (*output) and nearest command (*command). Returns 0, or -1 when an
   output is NaN (a NaN reading). */
int flc_composed_step(const double readings[FLC_COMPOSED_N_CHANNELS], int *part,
                      double *output, int *command);

#ifdef __cplusplus
}}
#endif

#endif /* FLC_COMPOSED_H */
"""


def _composed_source(wires: dict[str, Any]) -> str:
    includes = ['#include "composed.h"', '#include "arbiter.h"'] + [
        f'#include "part_{identifier(e["name"])}.h"' for e in wires["parts"]]
    arbiter = ", ".join(map(str, wires["arbiter"]["inputs"]))
    cases = []
    for entry in wires["parts"]:
        prefix, macro = entry["prefix"], entry["prefix"].upper()
        places = ", ".join(map(str, entry["inputs"]))
        cases.append(f"""\
    case {entry['index']}: {{ /* {entry['name']} */
        static const int places[{macro}N_INPUTS] = {{{places}}};
        double state[{macro}N_INPUTS];
        for (i = 0; i < {macro}N_INPUTS; ++i) state[i] = readings[places[i]];
        *output = {prefix}output(state);
        *command = {prefix}command(state);
        return *command < 0 ? -1 : 0;
    }}""")
    body = "\n".join(cases)
    return f"""\
/* {wires['name']}: the composition step, written by flctool {wires['flctool']}. */
{chr(10).join(includes)}

int flc_composed_step(const double readings[FLC_COMPOSED_N_CHANNELS], int *part,
                      double *output, int *command)
{{
    static const int arbiter_places[FLC_ARBITER_N_INPUTS] = {{{arbiter}}};
    double arbiter_state[FLC_ARBITER_N_INPUTS];
    int i;
    for (i = 0; i < FLC_ARBITER_N_INPUTS; ++i) arbiter_state[i] = readings[arbiter_places[i]];
    *part = flc_arbiter_command(arbiter_state);
    *output = 0.0;
    *command = -1;
    switch (*part) {{
{body}
    default:
        return -1;
    }}
}}
"""


def _c_harness(wires: dict[str, Any]) -> str:
    n = len(wires["channels"])
    names = ", ".join(json.dumps(e["name"]) for e in wires["parts"])
    width = max(len(e["commands"]) for e in wires["parts"])
    padded = ["{" + ", ".join([json.dumps(c["name"]) for c in e["commands"]] +
                              ['""'] * (width - len(e["commands"]))) + "}"
              for e in wires["parts"]]
    return f"""\
/* {wires['name']}: the deployment harness of a composed behaviour, written by flctool
 * {wires['flctool']}. Reads one line of {n} channel readings (composed.h names them) and
 * prints
 *     part_index part_name output command_index command_name
 * Build: cc -std=c99 -O2 -o harness *.c */
#include <stdio.h>
#include <stdlib.h>
#include "composed.h"

static const char *const part_names[FLC_COMPOSED_N_PARTS] = {{{names}}};
static const char *const command_names[FLC_COMPOSED_N_PARTS][{width}] = {{{', '.join(padded)}}};

int main(void)
{{
    char line[65536];
    double readings[FLC_COMPOSED_N_CHANNELS], output = 0.0;
    int i, part, command;
    while (fgets(line, sizeof line, stdin) != NULL) {{
        char *at = line, *end;
        for (i = 0; i < FLC_COMPOSED_N_CHANNELS; ++i) {{
            readings[i] = strtod(at, &end);
            if (end == at) {{
                fprintf(stderr, "harness: expected {n} numbers per line\\n");
                return 1;
            }}
            at = end;
        }}
        if (flc_composed_step(readings, &part, &output, &command) != 0 || part < 0) {{
            printf("-1 none nan -1 none\\n");
            continue;
        }}
        printf("%d %s %.17g %d %s\\n", part, part_names[part], output, command,
               command_names[part][command]);
    }}
    return 0;
}}
"""


def _python_harness(wires: dict[str, Any]) -> str:
    return f'''\
"""{wires['name']}: the deployment harness of a composed behaviour, written by flctool
{wires['flctool']}.

Needs flctool (pip install flctool). Reads one line of channel readings (wiring.json's
``channels``, in order) and prints ``part_index part_name output command_index
command_name``; as a module, ``decide(readings)`` returns the same five values.
"""

import json
import sys
from pathlib import Path

import numpy as np

from flctool import compile_behaviour, load_behaviour
from flctool.export.composed_bundle import parts_of

HERE = Path(__file__).resolve().parent
WIRING = json.loads((HERE / "wiring.json").read_text(encoding="utf-8"))
BEHAVIOUR = load_behaviour(HERE / "controller.yaml")
ARBITER = compile_behaviour(BEHAVIOUR)
PARTS = {{name: compile_behaviour(part) for name, part in parts_of(BEHAVIOUR).items()}}


def _nearest(values, output):
    """The index of the nearest singleton; of two equally near, the smaller singleton."""
    order = np.argsort(values, kind="stable")
    return int(order[int(np.argmin(np.abs(values[order] - output)))])


def decide(readings):
    """(part index, part name, output, command index, command name) for one reading line."""
    raw = np.asarray(readings, dtype=np.float64).reshape(-1)
    arbiter = WIRING["arbiter"]
    chosen = ARBITER.output(raw[arbiter["inputs"]][None, :])[0]
    k = _nearest(np.array([c["value"] for c in arbiter["commands"]]), chosen)
    entry = next(e for e in WIRING["parts"] if e["index"] == k)
    output = float(PARTS[entry["name"]].output(raw[entry["inputs"]][None, :])[0])
    j = _nearest(np.array([c["value"] for c in entry["commands"]]), output)
    return k, entry["name"], output, j, entry["commands"][j]["name"]


def main():
    width = len(WIRING["channels"])
    for line in sys.stdin:
        numbers = [float(v) for v in line.split()[:width]]
        if len(numbers) < width:
            sys.exit(f"harness: expected {{width}} numbers per line")
        k, name, output, j, command = decide(numbers)
        print(f"{{k}} {{name}} {{output!r}} {{j}} {{command}}")


if __name__ == "__main__":
    main()
'''
