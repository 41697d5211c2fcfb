"""The wire protocol shared by the robot link and the reference robot side."""

from __future__ import annotations

import pytest

from flctool.envs.robot_protocol import ProtocolError, decode, printable


@pytest.mark.parametrize(("text", "shown"), [
    ("plain", "plain"), ("\x1b[31mred\x1b[0m", "red"), ("\x1b]0;title\x07x", "x"),
    ("a\x00b\nc", "a?b?c"), ("\x9b2Jz", "z"), ("x" * 400, "x" * 300 + "..."),
])
def test_printable_strips_terminal_control(text: str, shown: str) -> None:
    assert printable(text) == shown


def test_deeply_nested_json_is_a_protocol_error() -> None:
    with pytest.raises(ProtocolError, match="nested too deep"):
        decode(b"[" * 100_000 + b"]" * 100_000)
