"""Export and import of controllers: YAML, JSON, FLL, FCL, FIS and C.

Every format is an :class:`Exporter` (and, for FLL, FCL and FIS, an :class:`Importer`)
registered by its name, loaded lazily::

    export_file(behaviour, "ballchase.fll")            # the format named by the suffix
    text = export_text(behaviour, "c", ExportOptions(single=True))
    behaviour = import_behaviour("ballchase.fll")

    exporter = EXPORTERS.get("fll")(ExportOptions(provenance={"source": "a.yaml"}))
    exporter.to_file(behaviour, "ballchase.fll")
    behaviour = IMPORTERS.get("fll")().from_file("ballchase.fll")
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

from flctool.behaviour import Behaviour, require_deployable
from flctool.errors import ExportError
from flctool.export.base import Exporter, ExportOptions, Importer
from flctool.export.source import load_source
from flctool.plugins import export_suffixes, registry
from flctool.registry import Registry

#: Built from :mod:`flctool.plugins` (the built-ins and installed ``flctool.exporters`` entries).
EXPORTERS: Registry[type[Exporter]] = registry("exporter", "export format")

IMPORTERS: Registry[type[Importer]] = Registry("import format")
IMPORTERS.register("fll", "flctool.export.fll:FllImporter")
IMPORTERS.register("fcl", "flctool.export.fcl:FclImporter")
IMPORTERS.register("fis", "flctool.export.fis:FisImporter")



def export_text(behaviour: Behaviour, format: str, options: ExportOptions | None = None) -> str:
    """A deployable ``behaviour`` as the text of the export ``format`` (a name of
    :data:`EXPORTERS`: yaml, json, fll, fcl, fis, c, or an installed one)."""
    return EXPORTERS.get(format)(options).to_string(behaviour)


def export_file(behaviour: Behaviour, path: str | Path, format: str | None = None,
                options: ExportOptions | None = None, *, force: bool = False) -> list[Path]:
    """Write a deployable ``behaviour`` to ``path`` in ``format`` (by default the one the
    suffix names: .fll, .c, ...), atomically, refusing to replace a file unless ``force``;
    returns the files written (C writes a .c and a .h)."""
    name = format or _format_of(Path(path), export_suffixes())
    return EXPORTERS.get(name)(options).to_file(behaviour, path, force=force)


def import_behaviour(path: str | Path, format: str | None = None) -> Behaviour:
    """The controller in the FLL, FCL or FIS file ``path`` as a behaviour (``format`` by
    default from the suffix)."""
    name = format or _format_of(Path(path), {f".{name}": name for name in IMPORTERS.names()})
    return IMPORTERS.get(name)().from_file(path)


def _format_of(path: Path, suffixes: Mapping[str, str]) -> str:
    found = suffixes.get(path.suffix.lower())
    if found is None:
        raise ExportError(f"cannot tell the format of {path} from its suffix",
                          hint=f"name it {', '.join(sorted(suffixes))}, or give the format")
    return found


__all__ = [
    "EXPORTERS",
    "IMPORTERS",
    "ExportOptions",
    "Exporter",
    "Importer",
    "export_file",
    "export_text",
    "import_behaviour",
    "load_source",
    "require_deployable",
]
