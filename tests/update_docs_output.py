"""Rewrite the expected output of a page's ``check-output`` console blocks from real runs.

    python -m tests.update_docs_output docs/tutorial.md [docs/getting-started.md ...]

For a change that alters what a command prints (a learner's results, a new summary line):
the page's blocks run in order in a temporary folder, exactly as tests/test_docs.py runs them,
and each command's output replaces the one on the page. What varies from run to run is written
as ``...``: progress bars and training times. Review the diff before committing it: the page's
prose may need the new figures too.
"""

from __future__ import annotations

import re
import sys
import tempfile
from pathlib import Path

from tests.test_docs import Block, _run, _workspace, console_commands, extract_blocks, run_block

_VARYING = ((re.compile(r"^\w+ gen ━.*$", re.MULTILINE), "..."),
            # a slow run's plain progress lines (tests.test_docs ignores them)
            (re.compile(r"^\w+ generation \d+/\d+ .*\(\d+ s\)\n", re.MULTILINE), ""),
            (re.compile(r"; [\d.]+ s of training"), "; ... s of training"))


def _expected(output: str) -> str:
    for pattern, replacement in _VARYING:
        output = pattern.sub(replacement, output)
    return output.rstrip("\n")


def _rewrite(block: Block, cwd: Path) -> str:
    for setup in block.before:
        _run(["bash", "-e", "-o", "pipefail", "-c", setup], cwd)
    parts = []
    shown = [command for command, _ in console_commands(block.text)]
    run = [command for command, _ in console_commands(block.source())]  # replace markers
    for command, actual in zip(shown, run, strict=True):
        parts.append("$ " + command)
        output = _expected(_run(["bash", "-o", "pipefail", "-c", actual], cwd).stdout)
        if output:
            parts.append(output)
    return "\n".join(parts) + "\n"


def update_page(page: Path) -> None:
    """Run ``page``'s blocks and write it back with the new expected outputs."""
    lines = page.read_text(encoding="utf-8").split("\n")
    with tempfile.TemporaryDirectory() as folder:
        cwd = _workspace(Path(folder))
        offset = 0
        for block in extract_blocks(page):
            if not block.runnable():
                continue
            if block.language != "console":
                run_block(block, cwd)
                continue
            start = block.line + offset  # the first line inside the fence, 0-based
            end = start + block.text.count("\n")
            new = _rewrite(block, cwd).split("\n")[:-1]
            lines[start:end] = new
            offset += len(new) - (end - start)
    page.write_text("\n".join(lines), encoding="utf-8")


if __name__ == "__main__":
    for name in sys.argv[1:]:
        update_page(Path(name).resolve())
