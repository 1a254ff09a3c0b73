"""Text that reaches a terminal: control characters shown, never obeyed.

A file name, a column or an asset id is the user's text, and a terminal obeys what it prints: an
escape sequence in a file name could clear the screen, retitle the window or hide the rest of a
line.  :func:`visible` replaces every control character (C0 but newline and tab, DEL, C1), every
bidirectional override and every lone surrogate (a file name's bytes that are not UTF-8) by its
Python escape; :func:`terminal_streams` applies it to everything a command prints.

>>> visible("motor\\x1b[2J-7.csv\\u202e")
'motor\\\\x1b[2J-7.csv\\\\u202e'
"""

from __future__ import annotations

import contextlib
import re
import sys
from collections.abc import Iterator

__all__ = ["terminal_streams", "visible"]

# C0 controls but tab and newline, DEL and C1, the bidirectional embeddings, overrides and isolates,
# and lone surrogates (undecodable bytes of a file name)
_HIDDEN = re.compile("[\x00-\x08\x0b-\x1f\x7f-\x9f\u061c\u200e\u200f\u202a-\u202e\u2066-\u2069\ud800-\udfff]")


def visible(text: str) -> str:
    """``text`` with each control character, bidirectional override or lone surrogate as its escape."""
    return _HIDDEN.sub(lambda m: m.group().encode("unicode_escape", "backslashreplace").decode("ascii")
                       if not 0xD800 <= ord(m.group()) <= 0xDFFF else f"\\u{ord(m.group()):04x}", text)


class _VisibleStream:
    """A text stream that writes :func:`visible` text to ``stream`` (every other attribute is the stream's)."""

    def __init__(self, stream):
        self._stream = stream

    def write(self, text: str) -> int:
        self._stream.write(visible(text))
        return len(text)

    def __getattr__(self, name):
        return getattr(self._stream, name)


@contextlib.contextmanager
def terminal_streams() -> Iterator[None]:
    """Within it, ``sys.stdout`` and ``sys.stderr`` print only :func:`visible` text."""
    saved = sys.stdout, sys.stderr
    sys.stdout, sys.stderr = _VisibleStream(sys.stdout), _VisibleStream(sys.stderr)
    try:
        yield
    finally:
        sys.stdout, sys.stderr = saved
