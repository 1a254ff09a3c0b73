"""The error of the ``bgphm`` commands: bad arguments or input found after parsing.

>>> from bgphm.cli import main
>>> main(["--quiet", "simulate", "rlc", "--samples", "2"])   # a UsageError: exit code 2, message on stderr
2
"""

from __future__ import annotations

from bondgraph.errors import PHMError


class UsageError(PHMError, ValueError):
    """Bad arguments or input found after parsing (exit code 2)."""
