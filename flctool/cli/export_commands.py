"""``export`` and ``import``: controllers to and from YAML, JSON, FLL, FCL, FIS and C."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Annotated

import typer

from flctool.cli.app import (
    Force,
    app,
    console,
    escape,
    example,
    make_parent,
    output_format,
    say,
    user_errors,
)
from flctool.errors import FlcError
from flctool.plugins import export_suffixes

IMPORT_SUFFIXES = {".fll": "fll", ".fcl": "fcl", ".fis": "fis"}


@app.command("export", epilog=example(
    "flctool export runs/first -o controller.fll",
    "flctool export runs/first -o robot/flc.c --float",
    "flctool export behaviours/ballchase-handmade.yaml --format json",
    "flctool export runs/first --format bundle -o robot/ballchase"))
def export_controller(
    source: Annotated[Path, typer.Argument(
        metavar="CONTROLLER",
        help="A deployable behaviour file, or a run directory (its best controller).")],
    format: Annotated[str | None, typer.Option(
        "--format", "-f", help="yaml, json, fll, fcl, fis, c, or bundle (a folder: the "
        "controller, its wiring and a C and a Python harness). Default: from the suffix of "
        "-o; yaml on stdout.")] = None,
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
    from flctool.export import EXPORTERS, ExportOptions, load_source

    with user_errors():
        name = output_format(output, format, export_suffixes(), "yaml")
        exporter_class = EXPORTERS.get(name)
        if name != "c" and (single or prefix is not None):
            raise FlcError("--float and --prefix apply to the c format only",
                           hint="leave them out, or write C (--format c, or -o NAME.c)")
        if name != "fcl" and dialect is not None:
            raise FlcError("--dialect applies to the fcl format only",
                           hint="leave it out, or write FCL (--format fcl, or -o NAME.fcl)")
        behaviour, provenance = load_source(source, generation, individual)
        if name in ("fll", "fcl", "fis") and behaviour.acts_by_vote:
            say(f"'{behaviour.name}' acts by vote, which {name.upper()} cannot say: the "
                "engine computes eq. 3's output; deploy the command whose rules' activations "
                "sum highest (--format c exports it as <prefix>command)", "warning:",
                "yellow", err=True)
        exporter = exporter_class(ExportOptions(provenance=provenance,
                                                prefix="flc_" if prefix is None else prefix,
                                                single=single, dialect=dialect or "iec"))
        if output is None:
            sys.stdout.write(exporter.to_string(behaviour))
            return
        make_parent(output, "export")
        written = exporter.to_file(behaviour, output, force=force)
    for path in written:
        console.print(f"wrote {escape(str(path))}")


@app.command("import", epilog=example(
    "flctool import controller.fll -o behaviours/imported.yaml",
    "flctool import legacy.txt --format fis",
    "flctool import sugeno.fis --linear-singletons -o behaviours/sugeno.yaml"))
def import_controller(
    file: Annotated[Path, typer.Argument(help="An .fll, .fcl or .fis controller.")],
    output: Annotated[Path | None, typer.Option(
        "--output", "-o", help="Where to write the behaviour YAML (default: stdout).")] = None,
    force: Force = False,
    format: Annotated[str | None, typer.Option(
        "--format", "-f", help="fll, fcl or fis (default: from the file's suffix).")] = None,
    mamdani_singletons: Annotated[bool, typer.Option(
        "--mamdani-singletons", help="Replace a Mamdani system's output sets by "
        "singletons at their centroids (and its OR, NOT, partial or weighted rules by "
        "flctool's), and report the largest error this makes.")] = False,
    linear_singletons: Annotated[bool, typer.Option(
        "--linear-singletons", help="Replace a first-order Takagi-Sugeno output's linear "
        "terms by constants, one per rule, fitted to the first-order output (and its OR, "
        "NOT, partial or weighted rules by flctool's), and report the largest error this "
        "makes.")] = False,
) -> None:
    """Import a controller from FLL, FCL or FIS as a behaviour file."""
    from flctool.export import IMPORTERS
    from flctool.export.base import comment_safe, write_files
    from flctool.export.imported import imported_yaml
    from flctool.version import __version__

    with user_errors():
        name = output_format(file, format, IMPORT_SUFFIXES, "fll")
        if output is not None:
            # import writes a behaviour file: YAML, whatever -o is called, but not under the
            # name of another format
            implied = export_suffixes().get(output.suffix.lower())
            if implied not in (None, "yaml"):
                raise FlcError(f"import writes a behaviour file (YAML), but {output} has the "
                               f"suffix of {implied}",
                               hint="name it .yaml, or use 'flctool export' for other formats")
        importer_class = IMPORTERS.get(name)
        conversions = {"mamdani_singletons": mamdani_singletons,
                       "linear_singletons": linear_singletons}
        importer = (importer_class(**conversions)
                    if any(conversions.values()) else importer_class())
        behaviours = importer.from_file_all(file)
        if importer.report:  # on stderr: the YAML may be going to stdout
            say(importer.report, err=True)
        texts = [imported_yaml(b, f"{b.name}: imported by flctool {__version__} from "
                               f"{comment_safe(file)}") for b in behaviours]
        if output is None:
            if len(behaviours) > 1:
                raise FlcError(f"{file} has {len(behaviours)} outputs, imported as one "
                               "behaviour file each", hint="give -o NAME.yaml: each goes to "
                               "NAME_<output>.yaml")
            sys.stdout.write(texts[0])
            return
        make_parent(output, "behaviour file")
        targets = ([output] if len(behaviours) == 1 else
                   [output.with_name(f"{output.stem}_{b.name}{output.suffix or '.yaml'}")
                    for b in behaviours])
        write_files(dict(zip(targets, texts, strict=True)), force=force)
    for target in targets:
        console.print(f"wrote {escape(str(target))}")
