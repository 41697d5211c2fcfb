"""Export and import of controllers: YAML, JSON, FLL, FCL, FIS and C.

Every format is an :class:`Exporter` (and, for FLL, FCL and FIS, an :class:`Importer`)
registered by its name, loaded lazily::

    exporter = EXPORTERS.get("fll")(ExportOptions(provenance={"source": "a.yaml"}))
    exporter.to_file(behaviour, "ballchase.fll")
    behaviour = IMPORTERS.get("fll")().from_file("ballchase.fll")
"""

from __future__ import annotations

from flctool.export.base import Exporter, ExportOptions, Importer
from flctool.export.source import load_source
from flctool.plugins import registry
from flctool.registry import Registry
from flctool.spec import require_deployable

#: Built from :mod:`flctool.plugins` (the built-ins and installed ``flctool.exporters`` entries).
EXPORTERS: Registry[type[Exporter]] = registry("exporter", "export format")

IMPORTERS: Registry[type[Importer]] = Registry("import format")
IMPORTERS.register("fll", "flctool.export.fll:FllImporter")
IMPORTERS.register("fcl", "flctool.export.fcl:FclImporter")
IMPORTERS.register("fis", "flctool.export.fis:FisImporter")

__all__ = [
    "EXPORTERS",
    "IMPORTERS",
    "ExportOptions",
    "Exporter",
    "Importer",
    "load_source",
    "require_deployable",
]
