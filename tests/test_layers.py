"""The package's lower layers import only what stands below them (docs/architecture.md), read
from the code's own import statements, those under ``TYPE_CHECKING`` and inside functions
included; and no module takes a name from the public face (``from flctool import x``)."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "flctool"

#: What each lower module or package may import of flctool; a package may import itself.
BELOW = {
    "errors": set(), "atomic": set(), "dirlock": set(), "lazy": set(), "version": set(),
    "membership": set(),
    "registry": {"errors"}, "inputs": {"errors"},
    "plugins": {"errors", "registry"}, "tabular": {"errors", "inputs"},
    "behaviour": {"errors", "registry", "inputs", "plugins", "membership"},
}


def _imported(path: Path) -> set[str]:
    """The flctool modules ``path`` imports (``flctool.a.b`` -> ``flctool.a.b``)."""
    found: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            found.add(node.module)
        elif isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
    return {name for name in found if name == "flctool" or name.startswith("flctool.")}


def _files(part: str) -> list[Path]:
    folder = PACKAGE / part
    return sorted(folder.rglob("*.py")) if folder.is_dir() else [PACKAGE / f"{part}.py"]


@pytest.mark.parametrize("part", sorted(BELOW))
def test_a_lower_layer_imports_only_what_stands_below_it(part: str) -> None:
    allowed = BELOW[part] | {part}
    upward = {f"{path.relative_to(PACKAGE)} -> {name}" for path in _files(part)
              for name in _imported(path)
              if name != "flctool" and name.split(".")[1] not in allowed}
    assert not upward, sorted(upward)


def test_no_module_takes_a_name_from_the_public_face() -> None:
    taken = []
    for path in sorted(PACKAGE.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ImportFrom) and node.level == 0 and node.module == "flctool":
                names = [a.name for a in node.names if not (PACKAGE / a.name).is_dir()
                         and not (PACKAGE / f"{a.name}.py").is_file()]
                taken += [f"{path.relative_to(PACKAGE)}: {name}" for name in names]
    assert not taken, taken
