"""Writing a behaviour back out: plain data (for JSON) and readable YAML.

Floats are written with ``repr``, the shortest text that reads back to the same double, so a
controller written and loaded again gives bit-for-bit the same outputs.
"""

from __future__ import annotations

from typing import Any

import yaml

from flctool.behaviour.bounded import no_collection
from flctool.behaviour.models import Behaviour
from flctool.behaviour.shapes import SHAPES


def behaviour_to_data(behaviour: Behaviour, *, defaults: bool = True) -> dict[str, Any]:
    """The behaviour as JSON-compatible data with the file's keys, in the file's order.

    ``defaults=False`` leaves out every value nobody set (e.g. the learning defaults of a
    controller imported from FLL), so the file does not present them as choices.
    """
    data: dict[str, Any] = behaviour.model_dump(mode="json", by_alias=True, exclude_none=True,
                                                exclude_unset=not defaults)
    if not data.get("description"):
        data.pop("description", None)
    if data.get("activation") == "min":  # the paper's eq. 2, left implicit as files leave it
        data.pop("activation")
    return data


class _Flow(list[Any]):
    """A list written on one line: ``[0.0, 0.0, 0.1, 0.3]``."""


class _FlowMap(dict[str, Any]):
    """A mapping written on one line: ``{if: {...}, then: forward}``."""


# libyaml's emitter writes the same text about 4x faster than the pure-Python one, which
# matters for run directories (best.yaml after every generation).
_SafeDumper: type[yaml.SafeDumper] = getattr(yaml, "CSafeDumper", yaml.SafeDumper)


class _Dumper(_SafeDumper):  # type: ignore[valid-type,misc]
    pass


_Dumper.add_representer(_Flow, lambda d, v: d.represent_sequence(
    "tag:yaml.org,2002:seq", v, flow_style=True))
_Dumper.add_representer(_FlowMap, lambda d, v: d.represent_mapping(
    "tag:yaml.org,2002:map", v.items(), flow_style=True))


def _styled(value: Any, key: str = "") -> Any:
    if isinstance(value, dict):
        if key == "rule" or (len(value) == 1 and next(iter(value)) in SHAPES):
            # a rule, or a set of a shape: {gauss: [0.5, 0.1]}
            return _FlowMap({k: _styled(v) for k, v in value.items()})
        return {k: _styled(v, k) for k, v in value.items()}
    if isinstance(value, list):
        if key == "rules":
            return [_styled(rule, "rule") for rule in value]
        return _Flow(value)
    return value


def behaviour_to_yaml(behaviour: Behaviour, header: str = "", *, defaults: bool = True) -> str:
    """A complete behaviour file; ``header`` lines become ``#`` comments at the top."""
    return data_to_yaml(behaviour_to_data(behaviour, defaults=defaults), header)


#: Rules written by one call of PyYAML's dumper (see data_to_yaml).
_RULES_AT_ONCE = 2000


def _dump(value: Any) -> str:
    with no_collection():  # see flctool.behaviour.bounded: twice as fast for a large table
        return str(yaml.dump(value if isinstance(value, list) else _styled(value),
                             Dumper=_Dumper, sort_keys=False, allow_unicode=True, width=100))


def data_to_yaml(data: dict[str, Any], header: str = "") -> str:
    """A behaviour given as data (:func:`behaviour_to_data`'s form) written as
    :func:`behaviour_to_yaml` writes it."""
    rules = data.get("rules")
    if isinstance(rules, list) and len(rules) > _RULES_AT_ONCE and "rules" in data:
        # PyYAML composes a node per value before it writes any: a table of 100,000 rules
        # would take hundreds of MB at once. The rules are written a block at a time into
        # the place the rest of the file leaves for them (a block list writes the same lines
        # at the top level as under a key: '- {if: ...}').
        placeholder = "rules: []\n"
        head = _dump({**data, "rules": []})
        if head.count(placeholder) == 1:
            blocks = [_dump([_styled(rule, "rule") for rule in rules[i:i + _RULES_AT_ONCE]])
                      for i in range(0, len(rules), _RULES_AT_ONCE)]
            body = head.replace(placeholder, "rules:\n" + "".join(blocks))
        else:
            body = _dump(data)
    else:
        body = _dump(data)
    comment = "".join(f"# {line}".rstrip() + "\n" for line in header.splitlines())
    return comment + body
