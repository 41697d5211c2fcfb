"""The code blocks of README.md and docs/ run, and the generated reference pages are complete.

The rules (which blocks run, the ``<!-- docs-test: ... -->`` markers, how output is compared)
are documented for writers in docs/getting-started.md, "How these pages are tested".
"""

from __future__ import annotations

import importlib.util
import json
import os
import re
import shutil
import subprocess
import sys
from dataclasses import dataclass, field
from pathlib import Path
from types import ModuleType

import pytest
import typer

from flctool.cli import app

from .conftest import BEHAVIOURS

ROOT = BEHAVIOURS.parent
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]
RUN_LANGUAGES = {"bash", "sh", "python", "console"}
TIMEOUT = 120  # s per block: a hung command fails the test instead of the whole run

_FENCE = re.compile(r"^(?P<indent> {0,3})(?P<fence>`{3,}|~{3,})(?P<info>[^`\n]*)$")
_MARKER = re.compile(r"^\s*<!--\s*docs-test:\s*(?P<body>.*?)\s*-->\s*$")
_BEFORE = re.compile(r'before\s+"((?:[^"\\]|\\.)*)"')
_REPLACE = re.compile(r'replace\s+"((?:[^"\\]|\\.)*)"\s+"((?:[^"\\]|\\.)*)"\s*;?\s*')


@dataclass
class Block:
    page: Path
    line: int  # 1-based line of the opening fence
    language: str
    text: str
    skip: str | None = None
    check_output: bool = False
    replacements: list[tuple[str, str]] = field(default_factory=list)
    before: list[str] = field(default_factory=list)

    @property
    def where(self) -> str:
        return f"{_display(self.page)}:{self.line}"

    def runnable(self) -> bool:
        if self.language not in RUN_LANGUAGES or self.skip is not None:
            return False
        return self.language != "console" or self.check_output

    def source(self) -> str:
        text = self.text
        for old, new in self.replacements:
            if old not in text:
                raise AssertionError(f"{self.where}: replace marker: {old!r} is not in the block")
            text = text.replace(old, new)
        return text


def _display(page: Path) -> str:
    return str(page.relative_to(ROOT)) if page.is_relative_to(ROOT) else str(page)


def _unescape(text: str) -> str:
    return text.replace('\\"', '"').replace("\\\\", "\\")


def _apply_marker(block: Block, body: str, where: str) -> None:
    directive = body.split(maxsplit=1)[0] if body else ""
    if directive == "skip":
        block.skip = body[4:].strip()
        if not block.skip:
            raise AssertionError(f"{where}: 'docs-test: skip' needs a reason")
    elif body == "check-output":
        block.check_output = True
    elif directive == "before":
        match = _BEFORE.fullmatch(body)
        if match is None:
            raise AssertionError(f'{where}: expected before "COMMANDS", got {body!r}')
        block.before.append(_unescape(match[1]))
    elif directive == "replace":
        position = 0
        while position < len(body):
            match = _REPLACE.match(body, position)
            if match is None:
                raise AssertionError(f'{where}: expected replace "OLD" "NEW", got {body!r}')
            block.replacements.append((_unescape(match[1]), _unescape(match[2])))
            position = match.end()
    else:
        raise AssertionError(f"{where}: unknown docs-test marker {body!r}")


def extract_blocks(page: Path) -> list[Block]:
    """Every fenced block of a markdown page, with the markers on the lines just before it."""
    lines = page.read_text(encoding="utf-8").splitlines()
    blocks: list[Block] = []
    i = 0
    while i < len(lines):
        opening = _FENCE.match(lines[i])
        if opening is None:
            i += 1
            continue
        fence, indent = opening["fence"], len(opening["indent"])
        info = opening["info"].strip()
        language = info.split()[0].lstrip("{.").rstrip("}") if info else ""
        body = []
        j = i + 1
        while j < len(lines) and not (lines[j].strip().startswith(fence[0] * len(fence))
                                      and lines[j].strip().strip(fence[0]) == ""):
            body.append(lines[j][indent:] if lines[j][:indent].isspace() else lines[j])
            j += 1
        block = Block(page, i + 1, language, "\n".join(body) + "\n")
        k = i - 1
        while k >= 0 and (marker := _MARKER.match(lines[k])) is not None:
            _apply_marker(block, marker["body"], f"{_display(page)}:{k + 1}")
            k -= 1
        blocks.append(block)
        i = j + 1
    return blocks


# -- running ---------------------------------------------------------------------------------
def _environment() -> dict[str, str]:
    env = dict(os.environ)
    bin_dir = str(Path(sys.executable).parent)  # flctool's entry point lives beside python
    env.update(PATH=bin_dir + os.pathsep + env.get("PATH", ""), COLUMNS="88", NO_COLOR="1",
               TERM="dumb", PYTHONHASHSEED="0", MPLBACKEND="Agg")
    env.pop("FORCE_COLOR", None)
    # docs/ros2.md's ROS 2 graphs: on this machine, in a DDS domain of this test run's own,
    # another than the ROS 2 tests' (tests/ros2_support.py): a node one of them left behind
    # in this process must not join the page's graph
    env.update(ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST",
               ROS_DOMAIN_ID=str(20 + (os.getpid() + 40) % 80))
    env.setdefault("RMW_IMPLEMENTATION", "rmw_fastrtps_cpp")
    return env


def _run(args: list[str], cwd: Path, stdin: str | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run(args, cwd=cwd, env=_environment(), input=stdin, text=True,
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=TIMEOUT,
                          check=False)


def console_commands(text: str) -> list[tuple[str, str]]:
    """A console block as (command, expected output) pairs."""
    pairs: list[tuple[str, list[str]]] = []
    lines = text.splitlines()
    i = 0
    while i < len(lines):
        line = lines[i]
        if line.startswith("$ "):
            command = line[2:]
            while command.endswith("\\") and i + 1 < len(lines):
                i += 1
                command += "\n" + lines[i]  # bash joins the lines at the backslash
            pairs.append((command, []))
        elif pairs:
            pairs[-1][1].append(line)
        elif line.strip():
            raise AssertionError(f"console block starts with output, not '$ ': {line!r}")
        i += 1
    return [(command, "\n".join(output)) for command, output in pairs]


#: The plain progress line a long command writes every few seconds when stderr is not a
#: terminal (flctool.cli.progress): whether one shows depends on the machine's speed.
_PROGRESS_LINE = re.compile(r"^\w+ generation \d+/\d+ .*\(\d+ s\)$")


def output_matches(expected: str, actual: str) -> bool:
    """Whether ``actual`` is ``expected``, where ``...`` matches any text (even lines); the
    plain progress lines of a slow run are not part of the output."""
    def normal(text: str) -> str:
        return "\n".join(line.rstrip() for line in text.strip("\n").splitlines()
                         if not _PROGRESS_LINE.match(line.rstrip()))

    pattern = ".*?".join(re.escape(part) for part in normal(expected).split("..."))
    return re.fullmatch(pattern, normal(actual), flags=re.DOTALL) is not None


def run_block(block: Block, cwd: Path) -> None:
    source = block.source()
    for setup in block.before:
        result = _run(["bash", "-e", "-o", "pipefail", "-c", setup], cwd)
        assert result.returncode == 0, (
            f"{block.where}: the before marker's commands failed:\n{result.stdout}")
    if block.language == "python":
        result = _run([sys.executable, "-"], cwd, stdin=source)
        assert result.returncode == 0, f"{block.where}: python block failed:\n{result.stdout}"
    elif block.language in ("bash", "sh"):
        result = _run(["bash", "-e", "-o", "pipefail", "-c", source], cwd)
        assert result.returncode == 0, (
            f"{block.where}: bash block exited {result.returncode}:\n{result.stdout}")
    else:
        for command, expected in console_commands(source):
            result = _run(["bash", "-o", "pipefail", "-c", command], cwd)
            assert output_matches(expected, result.stdout), (
                f"{block.where}: `{command}` printed (exit {result.returncode}):\n"
                f"{result.stdout}\n--- but the page shows:\n{expected}\n--- if the new output "
                f"is right: python -m tests.update_docs_output {_display(block.page)}")


def _workspace(tmp_path: Path) -> Path:
    shutil.copytree(BEHAVIOURS, tmp_path / "behaviours")
    shutil.copytree(ROOT / "schemas", tmp_path / "schemas")
    return tmp_path


PAGES_WITH_CODE = [p for p in PAGES if any(b.runnable() for b in extract_blocks(p))]


@pytest.mark.parametrize("page", PAGES_WITH_CODE,
                         ids=[str(p.relative_to(ROOT)) for p in PAGES_WITH_CODE])
@pytest.mark.slow
def test_page_code_blocks_run(page: Path, tmp_path: Path) -> None:
    """A page's blocks run in order in one folder, so a block sees what earlier ones made.

    docs/ros2.md's blocks start ROS 2 processes that must find each other: late in a loaded
    CI run a served robot's first inputs have twice not reached the learner within its 60 s
    reset timeout (never on a quiet machine), so that page alone runs once more, in a fresh
    folder, before it fails; both failures are reported."""
    attempts = 2 if page.name == "ros2.md" else 1
    failures: list[str] = []
    for attempt in range(attempts):
        cwd = _workspace(tmp_path / f"attempt{attempt}")
        try:
            for block in extract_blocks(page):
                if block.runnable():
                    run_block(block, cwd)
            return
        except (AssertionError, subprocess.SubprocessError) as failure:
            failures.append(f"attempt {attempt + 1}: {failure}")
    pytest.fail("\n".join(failures))


# -- the harness itself ----------------------------------------------------------------------
def test_extract_blocks_reads_markers_and_languages(tmp_path: Path) -> None:
    page = tmp_path / "page.md"
    page.write_text('text\n\n<!-- docs-test: skip starts a server -->\n```bash\nflctool serve\n'
                    '```\n\n<!-- docs-test: replace "30" "2" replace "a \\"b\\"" "c" -->\n'
                    '```python\nprint(30, \'a "b"\')\n```\n\n    indented, not a fence\n\n'
                    "<!-- docs-test: before \"echo x > in.txt\" -->\n"
                    "<!-- docs-test: check-output -->\n```console\n$ echo hi\nhi\n```\n"
                    "```yaml\nkey: 1\n```\n", encoding="utf-8")
    blocks = extract_blocks(page)
    assert [b.language for b in blocks] == ["bash", "python", "console", "yaml"]
    assert blocks[0].skip == "starts a server" and not blocks[0].runnable()
    assert blocks[1].replacements == [("30", "2"), ('a "b"', "c")]
    assert blocks[1].source() == "print(2, 'c')\n"
    assert blocks[2].before == ["echo x > in.txt"]
    assert blocks[2].check_output and blocks[2].runnable()
    assert not blocks[3].runnable()


def test_a_slow_run_s_progress_lines_are_not_output() -> None:
    expected = "finished hybrid (seed 0): 30 generations"
    slow = ("hybrid generation 30/30  validated best 1.759  training mean 1.217  (6 s)\n"
            + expected)
    assert output_matches(expected, slow)
    assert not output_matches(expected, "hybrid generation 30/30 is not a progress line\n"
                              + expected)


def test_console_commands_and_output_matching() -> None:
    pairs = console_commands("$ printf 'a\\n' \\\n  | cat\na\n$ true\n")
    assert pairs == [("printf 'a\\n' \\\n  | cat", "a"), ("true", "")]
    assert output_matches("first\n...\nlast 1.5 s", "first\nbar 1\nbar 2\nlast 1.5 s  \n")
    assert output_matches("took ... s", "took 0.27 s")
    assert not output_matches("took ... s", "took 0.27 ms")
    assert not output_matches("a\nb", "a\nc")


def test_unknown_marker_is_an_error(tmp_path: Path) -> None:
    page = ROOT / "docs" / "x.md"  # only named, never written
    block = Block(page, 1, "bash", "true\n")
    with pytest.raises(AssertionError, match="unknown docs-test marker"):
        _apply_marker(block, "skipp", "x.md:1")
    with pytest.raises(AssertionError, match="needs a reason"):
        _apply_marker(block, "skip", "x.md:1")
    block.replacements.append(("absent", "x"))
    with pytest.raises(AssertionError, match="is not in the block"):
        block.source()


def test_every_fence_is_closed() -> None:
    """An unclosed fence would swallow the rest of a page (and hide its blocks from the tests)."""
    for page in PAGES:
        fences = [line for line in page.read_text(encoding="utf-8").splitlines()
                  if _FENCE.match(line)]
        assert len(fences) % 2 == 0, f"{page.relative_to(ROOT)} has an unclosed code fence"


# -- the generated reference pages -----------------------------------------------------------
def _generator() -> ModuleType:
    spec = importlib.util.spec_from_file_location("docs_reference",
                                                  ROOT / "docs" / "hooks" / "reference.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _schema() -> dict[str, object]:
    data = json.loads((ROOT / "schemas" / "behaviour.schema.json").read_text(encoding="utf-8"))
    assert isinstance(data, dict)
    return data


def test_behaviour_reference_has_every_key_of_every_object() -> None:
    schema = _schema()
    page = _generator().behaviour_reference(schema)
    defs = schema["$defs"]
    assert isinstance(defs, dict)
    for name, node in [("root", schema), *defs.items()]:
        for key in node.get("properties", {}):
            assert f"| `{key}` |" in page, f"{name}.{key} is missing from the reference"
    for name in defs:
        assert f"## {name} {{ #def-{name.lower()} }}" in page
    assert "inputs.<name>" in page and "`environment`" in page
    for section, key in (("learning", "learner"), ("environment", "adapter")):
        assert f"`{section}` is chosen by its `{key}` key:" in page


def test_cli_reference_has_every_command_and_option() -> None:
    command = typer.main.get_command(app)
    page = _generator().cli_reference(command)
    context = command.context_class(command, info_name="flctool")
    for name in command.list_commands(context):
        sub = command.get_command(context, name)
        assert sub is not None
        assert f"## flctool {name}" in page
        if sub.epilog:  # examples, where a command has them: each example line is shown
            examples = [line.strip() for line in sub.epilog.splitlines()
                        if line.strip().startswith("flctool ")]
            assert examples and all(example in page for example in examples), name
        for param in sub.params:
            for opt in param.opts:
                if opt.startswith("-"):
                    assert re.search(rf"`[^`]*{re.escape(opt)}\b", page), (
                        f"flctool {name} {opt} is missing")


def test_learners_reference_cites_an_equation_for_every_learning_key() -> None:
    generator = _generator()
    schema = _schema()
    keys = [key for key, _ in generator.learning_keys(schema)]
    missing = [key for key in keys if key not in generator.EQUATIONS]
    assert not missing, f"add the paper's equation for {missing} to EQUATIONS in the generator"
    stale = [key for key in generator.EQUATIONS if key not in keys]
    assert not stale, f"EQUATIONS names keys the schema no longer has: {stale}"
    page = generator.learners_reference(schema)
    assert all(f"| `{key}` |" in page for key in keys)
    # who reads a key comes from the learners' models
    assert "| pitt |" in page and "| fuzzy_q, hybrid |" in page and "| all |" in page


def test_site_nav_names_every_page() -> None:
    """mkdocs --strict warns about pages left out of the nav; this says which, without mkdocs."""
    config = (ROOT / "mkdocs.yml").read_text(encoding="utf-8")
    named = set(re.findall(r":\s*([\w/.-]+\.md)\s*$", config, flags=re.MULTILINE))
    pages = {str(p.relative_to(ROOT / "docs")) for p in (ROOT / "docs").rglob("*.md")}
    generated = set(_generator().GENERATED)
    assert pages - named == set(), "add these pages to the nav in mkdocs.yml"
    assert named - pages - generated == set(), "the nav names pages that do not exist"


def test_markers_are_documented_for_writers() -> None:
    text = (ROOT / "docs" / "getting-started.md").read_text(encoding="utf-8")
    for marker in ("skip REASON", "check-output", 'replace "OLD" "NEW"', 'before "COMMANDS"'):
        assert f"docs-test: {marker}" in text
