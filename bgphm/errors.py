"""The errors of the ``bgphm`` application layer: bad arguments or input found after parsing, fleet runs.

>>> from bgphm.cli import main
>>> main(["--quiet", "simulate", "rlc", "--samples", "2"])   # a UsageError: exit code 2, message on stderr
2
"""

from __future__ import annotations

from bondgraph.errors import PHMError, PHMWarning

__all__ = [
    "EXIT_FAILURE", "EXIT_OK", "EXIT_USAGE", "FleetError", "FleetWarning", "MissingExtraError", "UsageError",
]

#: The exit codes of ``bgphm``: success, anything unexpected (an interrupted run too), bad usage or input.
EXIT_OK, EXIT_FAILURE, EXIT_USAGE = 0, 1, 2


class UsageError(PHMError, ValueError):
    """Bad arguments or input found after parsing (exit code 2)."""


class MissingExtraError(PHMError, ImportError, ValueError):
    """An optional dependency is not installed; the message names the extra that installs it.

    It is an ``ImportError`` for code that expects one, and a :class:`~bondgraph.errors.PHMError`, so
    the command line ends with one line and exit code 2.
    """


class FleetError(PHMError, ValueError):
    """A fleet run that cannot start or go on: a scheduler out of reach, no worker, no fleet output."""


class FleetWarning(PHMWarning, UserWarning):
    """A fleet run goes on, but not as well as it could (e.g. workers with Dask's malloc setting)."""
