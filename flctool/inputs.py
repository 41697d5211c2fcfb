"""Reading a file the user named: one wording, for every command, of a file that is missing,
a folder, unreadable or not UTF-8 text (located at the line and column of its first byte
that is not).

Every command that reads a file the user names goes through :func:`read_input` (or, when it
opens the file itself, :func:`open_error` and :func:`no_such_file`), so ``flctool learn``,
``validate``, ``import``, ``infer -i`` and the rest say the same thing about the same file.
"""

from __future__ import annotations

import codecs
import errno
from pathlib import Path

from flctool.errors import InputFileError, Problem

#: The byte order marks of UTF-16 (little and big endian).
_UTF16_BOMS = (b"\xff\xfe", b"\xfe\xff")


def input_error(path: Path | str, message: str, hint: str = "", line: int | None = None,
                column: int | None = None) -> InputFileError:
    """The error about a file the user named, located in it where that is known."""
    file = str(path)
    return InputFileError([Problem((), message, hint, file=file, line=line, column=column)],
                          file)


def no_such_file(path: Path | str, what: str) -> InputFileError:
    """The wording of a path that names nothing (``what`` it should name, e.g. "behaviour
    file")."""
    return input_error(path, "no such file or directory",
                       f"check the path; it should name a {what}")


def open_error(path: Path | str, what: str, error: OSError) -> InputFileError:
    """The wording of an OSError opening or reading ``path`` (see :func:`no_such_file`)."""
    if isinstance(error, FileNotFoundError):
        return no_such_file(path, what)
    if isinstance(error, IsADirectoryError):
        return input_error(path, f"is a folder, not a {what}", "name a file in it")
    if error.errno in (errno.EACCES, errno.EPERM):
        return input_error(path, f"cannot read the {what}: permission denied",
                           "make it readable (chmod u+r), or read a copy")
    return input_error(path, f"cannot read the {what}: {error.strerror or error}")


def read_input(path: Path | str, what: str, max_chars: int | None = None) -> str:
    """The text of ``path``, decoded as UTF-8 (a UTF-8 byte order mark is kept, as YAML
    reads it). At most ``max_chars`` characters are read, and one more if the file has them,
    so a caller can refuse a file that is too long without reading all of it."""
    cap = -1 if max_chars is None else 4 * (max_chars + 1)  # a character is at most 4 bytes
    try:
        with open(path, "rb") as handle:
            data = handle.read(cap)
    except OSError as error:
        raise open_error(path, what, error) from None
    # a file cut at the cap may end inside a character: that is no error
    return decode(data, path, what, whole=len(data) != cap)


def decode(data: bytes, path: Path | str, what: str, whole: bool = True) -> str:
    """``data`` as UTF-8 text; else an error at the line and column of the first byte that is
    not UTF-8 (the start of a UTF-16 file's byte order mark names UTF-16). ``whole``: the
    data is the whole file, so a character cut at its end is an error too."""
    try:
        return codecs.getincrementaldecoder("utf-8")().decode(data, final=whole)
    except UnicodeDecodeError as error:
        if data[:2] in _UTF16_BOMS:
            raise not_utf8(path, what, 1, 1, None) from None
        start = data.rfind(b"\n", 0, error.start) + 1
        line = data.count(b"\n", 0, error.start) + 1
        column = len(data[start:error.start].decode("utf-8")) + 1
        raise not_utf8(path, what, line, column, data[error.start]) from None


def not_utf8(path: Path | str, what: str, line: int | None, column: int | None,
             byte: int | None) -> InputFileError:
    """The wording of text that is not UTF-8 at ``line``, ``column`` (the 1-based character
    of the line where ``byte``, the first that is not, stands); ``byte`` None: UTF-16, whose
    byte order mark starts the file."""
    if byte is None:
        return input_error(path, f"the {what} is UTF-16 text (it starts with a UTF-16 byte "
                           "order mark), not UTF-8", "save it as UTF-8 text", 1, 1)
    return input_error(path, f"the {what} is not UTF-8 text (byte 0x{byte:02x}; a Latin-1 "
                       "or Windows file?)", "save it as UTF-8 text", line, column)
