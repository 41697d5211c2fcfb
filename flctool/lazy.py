"""Package attributes imported on first use (PEP 562), so importing a package stays cheap.

    __getattr__ = lazy_attributes(__name__, {"Controller": "flctool.compile.controller"})

``flctool``, ``flctool.compile`` and ``flctool.envs`` use it so that ``flctool --version``,
``validate`` and a small ``infer`` do not load numpy, numba or the learners.
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
