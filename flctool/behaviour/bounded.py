"""Keeping the cost of reading a large file linear in its size.

Reading a file builds one Python object per value (hundreds of thousands for a file of a few
megabytes) and none of them is garbage until the file is read. CPython's cyclic garbage
collector is triggered by every 700 allocations and then traverses the objects it tracks, so
it turns reading into work that grows faster than the file: a 3.7 MB behaviour file took
8.4 s to read with the collector on, 1.1 s without it. Reading builds plain lists, dicts and
strings, which make no reference cycles, so nothing is lost by pausing the collector while a
file is read; it runs again (and catches up) when the reading ends, however it ends.
"""

from __future__ import annotations

import gc
from collections.abc import Iterator
from contextlib import contextmanager


@contextmanager
def no_collection() -> Iterator[None]:
    """Pause the cyclic garbage collector inside the block (nested blocks are fine)."""
    was_enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was_enabled:
            gc.enable()
