"""Imports of optional dependencies (pandas, matplotlib) at the point of use, with an install hint.

The packages import without them; only the functions that need one import it, through
:func:`import_optional`, so a missing package surfaces as one clear :class:`ImportError`.
"""

from __future__ import annotations

import importlib
from types import ModuleType

__all__ = ["import_optional", "pandas_for"]


def import_optional(name: str, message: str) -> ModuleType:
    """Import module ``name``, or raise ``ImportError(message)`` chained to the original error.

    The top-level package is imported first, so a package blocked or missing while one of its
    submodules is still cached (``sys.modules["matplotlib"] = None``) is reported too.

    >>> import_optional("math", "unused").sqrt(4.0)
    2.0
    >>> import_optional("no_such_module_here", "no_such_module_here is needed")
    Traceback (most recent call last):
    ...
    ImportError: no_such_module_here is needed
    """
    try:
        importlib.import_module(name.partition(".")[0])
        return importlib.import_module(name)
    except ImportError as error:
        raise ImportError(message) from error


def pandas_for(method: str) -> ModuleType:
    """pandas, for the method ``method`` (named in the error when pandas is missing)."""
    return import_optional("pandas", f"pandas is needed for {method}(): pip install pandas")
