"""The error of the code generator (:class:`diagnosis.codegen.CodegenError`, defined here so that every private
module of the package can raise it without importing the package)."""

from __future__ import annotations

from bondgraph.errors import PHMError

__all__ = ["CodegenError"]


class CodegenError(PHMError, ValueError):
    """An ARR set, or an option, the code generator cannot turn into code; the message names the ARR."""
