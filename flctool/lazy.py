"""Package attributes imported on first use (PEP 562), so importing a package stays cheap.

    __getattr__ = lazy_attributes(__name__, {"Controller": "flctool.compile.controller"})

``flctool``, ``flctool.compile`` and ``flctool.envs`` use it so that ``flctool --version``,
``validate`` and a small ``infer`` do not load numpy, numba or the learners.

A package whose public face is a list of imports writes them once, under
``if TYPE_CHECKING:`` -- where type checkers and editors read them -- and hands its own file
to :func:`public_imports`, which reads that block (without running it) for the names and
their modules.
"""

from __future__ import annotations

import importlib
import sys
from collections.abc import Callable, Mapping
from typing import Any


def lazy_attributes(package: str, homes: Mapping[str, str]) -> Callable[[str], Any]:
    """A module ``__getattr__`` for ``package``: each name in ``homes`` is imported from the
    module ``homes[name]`` names when first asked for, then kept in the package."""

    def __getattr__(name: str) -> Any:
        home = homes.get(name)
        if home is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(home), name)
        setattr(sys.modules[package], name, value)  # later lookups skip this function
        return value

    return __getattr__


def public_imports(source_file: str) -> dict[str, str]:
    """Name -> module of every ``from MODULE import NAME`` under the ``if TYPE_CHECKING:`` of
    the Python file ``source_file``, in the order written (read, not run)."""
    import ast

    with open(source_file, encoding="utf-8") as handle:
        tree = ast.parse(handle.read(), source_file)
    homes: dict[str, str] = {}
    for node in tree.body:
        if isinstance(node, ast.If) and isinstance(node.test, ast.Name) and \
                node.test.id == "TYPE_CHECKING":
            for statement in node.body:
                if isinstance(statement, ast.ImportFrom) and statement.module:
                    for alias in statement.names:
                        homes[alias.asname or alias.name] = statement.module
    return homes
