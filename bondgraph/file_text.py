"""A model file's text, refused before it is read when it is larger than a limit.

JSON and YAML parsers take all of a file into memory, so :mod:`bondgraph.io` and
:mod:`bondgraph.bgt_format` look at a file's size first; the error names the file and the limit's constant.

>>> import tempfile
>>> from pathlib import Path
>>> path = Path(tempfile.mkdtemp()) / "m.json"
>>> _ = path.write_text("{}")
>>> read_limited(path, limit=10, error=ValueError, what="JSON model", constant="bondgraph.io.MAX_FILE_BYTES")
'{}'
>>> read_limited(path, limit=1, error=ValueError, what="JSON model", constant="bondgraph.io.MAX_FILE_BYTES")
Traceback (most recent call last):
...
ValueError: ...m.json: 2 bytes, larger than the limit of 1 bytes for a JSON model (bondgraph.io.MAX_FILE_BYTES)
"""

from __future__ import annotations

from pathlib import Path

__all__ = ["read_limited"]


def read_limited(path: Path, *, limit: int, error: type[Exception], what: str, constant: str) -> str:
    """The UTF-8 text of ``path``; ``error`` (one line naming the file) when it cannot be read or is larger than
    ``limit`` bytes, a ``what`` whose limit is the constant named ``constant``."""
    try:
        size = path.stat().st_size
    except OSError as exc:
        raise error(f"{path}: cannot be read ({exc})") from None
    if size > limit:  # refused before it is read: the parsers would take all of it into memory
        raise error(f"{path}: {size} bytes, larger than the limit of {limit} bytes for a {what} ({constant})")
    try:
        return path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise error(f"{path}: cannot be read ({exc})") from None
