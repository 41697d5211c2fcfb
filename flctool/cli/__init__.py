"""The ``flctool`` command line. Each module registers its commands on the shared app."""

from flctool.cli import (
    evaluate,  # noqa: F401  (registers evaluate)
    experiment,  # noqa: F401  (registers experiment)
    export_commands,  # noqa: F401  (registers export, import)
    learn,  # noqa: F401  (registers learn)
    new,  # noqa: F401  (registers new)
    plot,  # noqa: F401  (registers plot)
    serve,  # noqa: F401  (registers serve)
    spec_commands,  # noqa: F401  (registers validate, show, infer, schema)
)
from flctool.cli.app import app

__all__ = ["app"]


def run() -> None:
    app()
