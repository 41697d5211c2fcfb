"""Export and import of controllers: YAML, JSON, FLL, FCL, FIS and C.

Every format is an :class:`Exporter` (and, for FLL, FCL and FIS, an :class:`Importer`)
registered by its name, loaded lazily::

    exporter = EXPORTERS.get("fll")(ExportOptions(provenance={"source": "a.yaml"}))
    exporter.to_file(behaviour, "ballchase.fll")
    behaviour = IMPORTERS.get("fll")().from_file("ballchase.fll")
"""

from __future__ import annotations

from flctool.export.base import Exporter, ExportOptions, Importer, require_deployable
from flctool.export.source import load_source
from flctool.registry import Registry

EXPORTERS: Registry[type[Exporter]] = Registry("export format")
EXPORTERS.register("yaml", "flctool.export.yaml_format:YamlExporter")
EXPORTERS.register("json", "flctool.export.json_format:JsonExporter")
EXPORTERS.register("fll", "flctool.export.fll:FllExporter")
EXPORTERS.register("fcl", "flctool.export.fcl:FclExporter")
EXPORTERS.register("fis", "flctool.export.fis:FisExporter")
EXPORTERS.register("c", "flctool.export.c_source:CExporter")
EXPORTERS.register("bundle", "flctool.export.bundle:BundleExporter")

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
