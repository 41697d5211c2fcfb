"""``export`` and ``import``: controllers to and from YAML, JSON, FLL, FCL, FIS and C."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Annotated

import typer
from rich.markup import escape

from flctool import __version__
from flctool.cli.app import app, console, err_console, user_errors
from flctool.errors import ExportError
from flctool.export import EXPORTERS, IMPORTERS, ExportOptions, load_source
from flctool.export.base import comment_safe, write_files
from flctool.export.imported import imported_yaml

Force = Annotated[bool, typer.Option("--force", help="Overwrite an existing output file.")]


@app.command("export")
def export_controller(
    source: Annotated[Path, typer.Argument(
        help="A deployable behaviour file, or a run directory (its best controller).")],
    format: Annotated[str, typer.Option(
        "--format", "-f", help="yaml, json, fll, fcl, fis, c, or bundle (a folder: the "
        "controller, its wiring and a C and a Python harness).")] = "yaml",
    output: Annotated[Path | None, typer.Option(
        "--output", "-o", help="Where to write (default: stdout). For c, -o NAME writes "
        "NAME.h and NAME.c.")] = None,
    force: Force = False,
    generation: Annotated[int | None, typer.Option(
        help="Of a run directory: export the best controller of this generation.")] = None,
    individual: Annotated[int | None, typer.Option(
        help="Of a run directory: export this individual (of --generation, or the last).")]
    = None,
    single: Annotated[bool, typer.Option(
        "--float", help="c only: float instead of double arithmetic.")] = False,
    prefix: Annotated[str | None, typer.Option(
        help="c only: prefix of the C names (default flc_, giving flc_output).")] = None,
    dialect: Annotated[str | None, typer.Option(
        help="fcl only: iec (IEC 61131-7, the default) or fuzzylite (what fuzzylite 6 "
        "reads).")] = None,
) -> None:
    """Export a controller so that it runs elsewhere, with the same outputs."""
    with user_errors():
        exporter_class = EXPORTERS.get(format)
        if format != "c" and (single or prefix is not None):
            raise ExportError("--float and --prefix apply to --format c only",
                              hint="leave them out, or add --format c")
        if format != "fcl" and dialect is not None:
            raise ExportError("--dialect applies to --format fcl only",
                              hint="leave it out, or add --format fcl")
        behaviour, provenance = load_source(source, generation, individual)
        exporter = exporter_class(ExportOptions(provenance=provenance,
                                                prefix="flc_" if prefix is None else prefix,
                                                single=single, dialect=dialect or "iec"))
        if output is None:
            sys.stdout.write(exporter.to_string(behaviour))
            return
        written = exporter.to_file(behaviour, output, force=force)
    for path in written:
        console.print(f"wrote {escape(str(path))}")


@app.command("import")
def import_controller(
    file: Annotated[Path, typer.Argument(help="An .fll, .fcl or .fis controller.")],
    output: Annotated[Path | None, typer.Option(
        "--output", "-o", help="Where to write the behaviour YAML (default: stdout).")] = None,
    force: Force = False,
    format: Annotated[str | None, typer.Option(
        "--format", "-f", help="fll, fcl or fis (default: from the file's suffix).")] = None,
    mamdani_singletons: Annotated[bool, typer.Option(
        "--mamdani-singletons", help="fis only: replace a Mamdani system's output sets by "
        "singletons at their centroids, and report the largest error this makes.")] = False,
) -> None:
    """Import a controller from FLL, FCL or FIS as a behaviour file."""
    with user_errors():
        name = format or file.suffix.lstrip(".").lower()
        if format is None and name not in IMPORTERS:
            raise ExportError(f"cannot tell the format of {file} from its suffix",
                              hint="name it .fll, .fcl or .fis, or pass --format")
        importer_class = IMPORTERS.get(name)
        if mamdani_singletons and name != "fis":
            raise ExportError("--mamdani-singletons applies to FIS files only",
                              hint="leave it out")
        importer = (importer_class(mamdani_singletons=True)  # type: ignore[call-arg]
                    if mamdani_singletons else importer_class())
        behaviour = importer.from_file(file)
        report = getattr(importer, "report", "")
        if report:  # on stderr: the YAML may be going to stdout
            err_console.print(escape(report))
        text = imported_yaml(behaviour, f"{behaviour.name}: imported by flctool {__version__} "
                             f"from {comment_safe(file)}")
        if output is None:
            sys.stdout.write(text)
            return
        write_files({output: text}, force=force)
    console.print(f"wrote {escape(str(output))}")
